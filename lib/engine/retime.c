/* retime.c - a fix whose position follows the path but whose stamp does
 * not (ACCEPT_RULE_RETIME, issue 27; see accept.h).
 *
 * ADS-B stamps carry the receiver's time of arrival, AIS stamps are cut to
 * the second, a GNSS logger writes a fix late now and then: the position
 * is right, its time is not, and the curve, forced through every waypoint
 * at its time, turns the error into an acceleration spike (459 m/s^2 on a
 * straight line whose 1 s chords alternate 100 m / 280 m).  Where the
 * policy would refuse such a fix (for its speed or acceleration), its
 * stamp is estimated again at the pace of the path around it, and the fix
 * kept at that time if then it follows the anchor and the next waypoint
 * follows it (counted: engine_status retimed, retime_max_s).  A fast
 * object's fix (ADS-B) is re-stamped at the pace of the path already when
 * its stamp bends the pace, kept or not (ACCEPT_RULE_SMOOTH,
 * accept_retime_soft): a stamp 0.1 s late at 250 m/s is 25 m off, which
 * the curve through it at its stamp turns into 100 m/s^2.
 */
#include <math.h>

#include "accept_int.h"

/* q (slot) lies on the path from p to r: its detour from their chord is at
 * most ACCEPT_RETIME_DETOUR of it (a fix off the path is no jitter) */
static int on_path(accept_t *a, unsigned p, unsigned q, unsigned r)
{
    double d = pair_dist(a, p, r);
    return pair_dist(a, p, q) + pair_dist(a, q, r) - d <= ACCEPT_RETIME_DETOUR * d;
}

/* c's time set to t (its pairs forgotten) */
static void set_time(accept_t *a, unsigned c, double t)
{
    a->wp[c].t_s = t;
    accept_forget(a, c);
}

/* q, held after prev, goes on c's run: later than prev and within max_gap_s
 * of the anchor's time t0 */
static int run_goes_on(const accept_t *a, unsigned prev, unsigned q, double t0)
{
    return a->wp[q].t_s - a->wp[prev].t_s > ACCEPT_SAME_TIME_S &&
           a->wp[q].t_s - t0 <= a->cfg.max_gap_s;
}

/*
 * c's (slot pend[0]) time re-estimated at the local pace, into *tp: the
 * path length from the anchor through the waypoints held in time order
 * over their time.  1 if the shift is within ACCEPT_RETIME_FRAC of c's
 * shorter intervals and c stays between the anchor and the next waypoint;
 * 0 if not, or if there is no estimate (c off its neighbours' path, or
 * nothing after it and no pace into the anchor).
 */
static int estimate(accept_t *a, double *tp)
{
    unsigned c = a->pend[0], a1 = a->a1, prev = c, last = c, m = 1;
    double t0 = a->wp[a1].t_s, tc = a->wp[c].t_s, s = pair_dist(a, a1, c), tot = s, t, bound,
           t_hi = INFINITY, h[ACCEPT_WINDOW_MAX + 1];

    h[0] = tc - t0;
    for (unsigned i = 1; i < a->npend; i++) {
        unsigned q = a->pend[i];
        if (!run_goes_on(a, prev, q, t0))
            break;
        tot += pair_dist(a, prev, q);
        h[m++] = a->wp[q].t_s - a->wp[prev].t_s;
        prev = last = q;
    }
    if (last != c && tot > 0) {
        /* on the path of its neighbours (a fix off it is no jitter) */
        unsigned n1 = a->pend[1];
        if (!on_path(a, a1, c, n1))
            return 0;
        for (unsigned i = 1; i < m; i++) /* the intervals sorted: m <= 9 */
            for (unsigned j = i; j > 0 && h[j - 1] > h[j]; j--) {
                double x = h[j];
                h[j] = h[j - 1];
                h[j - 1] = x;
            }
        t = t0 + (a->wp[last].t_s - t0) * s / tot;
        bound = ACCEPT_RETIME_FRAC * h[(m - 1) / 2]; /* the lower median interval */
        t_hi = a->wp[n1].t_s;
    } else if (a->npend == 1 && a->have_a0 && chord_speed(a, a->a0, a1) > 0) {
        /* the last waypoint (at the close): at the pace into the anchor */
        t = t0 + s / chord_speed(a, a->a0, a1);
        bound = ACCEPT_RETIME_FRAC * (a->wp[a1].t_s - a->wp[a->a0].t_s);
    } else {
        return 0;
    }
    if (!(fabs(t - tc) > ACCEPT_SAME_TIME_S) || !(fabs(t - tc) <= bound) ||
        !(t - t0 > ACCEPT_SAME_TIME_S) || !(t_hi - t > ACCEPT_SAME_TIME_S))
        return 0;
    *tp = t;
    return 1;
}

/*
 * ACCEPT_RULE_RETIME: c (slot pend[0]) follows the anchor at its position
 * but not at its stamp (its own acceleration test or the next one's fails):
 * its time re-estimated (estimate()), taken with that time if c then
 * follows the anchor and is followed by the next.
 */
double accept_retime(accept_t *a, unsigned pre, double vlim)
{
    unsigned c = a->pend[0], a1 = a->a1;
    double tc = a->wp[c].t_s, t;

    if (!estimate(a, &t))
        return 0;
    set_time(a, c, t);
    /* c then follows the anchor (the waypoint after it, if any, is judged
     * on its own: its stamp may be off too); or, where the anchor's own
     * stamp was off within the limits, c follows the anchor at the speed
     * limit and the waypoint after it follows c */
    if (check0(a, pre, a1, c, vlim) == 0 || (a->npend > 1 && check0(a, NO_SLOT, a1, c, vlim) == 0 &&
                                             check(a, a1, c, a->pend[1], vlim, 0) == 0)) {
        return t - tc;
    }
    set_time(a, c, tc);
    return 0;
}

/* the change of speed implied across p (slots x, p, y in time order):
 * 2 | |v2| - |v1| | / (dt1 + dt2), what a stamp error makes of a steady pace */
static double speed_change(accept_t *a, unsigned x, unsigned p, unsigned y)
{
    double d1 = a->wp[p].t_s - a->wp[x].t_s, d2 = a->wp[y].t_s - a->wp[p].t_s;
    return 2.0 * fabs(chord_speed(a, p, y) - chord_speed(a, x, p)) / (d1 + d2);
}

/* the pace of the last k (<= ACCEPT_RETIME_PACE) kept intervals of the open
 * trajectory up to time t_end: their path length over the time from the
 * first of them (0 if fewer, or no time) */
static double pace_of(const accept_t *a, unsigned k, double t_end)
{
    enum { R = ACCEPT_RETIME_PACE + 1 };
    if (a->npace < k + 1)
        return 0;
    unsigned last = (a->npace - 1) % R, first = (a->npace - 1 - k) % R;
    double dt = t_end - a->pace_t[first];
    return dt > ACCEPT_SAME_TIME_S ? (a->pace_s[last] - a->pace_s[first]) / dt : 0;
}

/* the pace of the last ACCEPT_RETIME_PACE kept intervals, to the last one's
 * stamp (as stamped) */
static double kept_pace(const accept_t *a)
{
    enum { R = ACCEPT_RETIME_PACE + 1 };
    return a->npace ? pace_of(a, ACCEPT_RETIME_PACE, a->pace_t[(a->npace - 1) % R]) : 0;
}

/*
 * ACCEPT_RULE_SMOOTH: c (slot pend[0]) is about to be kept, but with the
 * anchor (and a0 before it) or with the next waypoint it implies a change
 * of speed above ACCEPT_RETIME_SOFT x max_accel_m_s2 (the curve through
 * kept triples stays within 3 x their implied acceleration: accept.h).
 * Its time is then estimated again: at the pace of the last kept intervals
 * from the anchor, pulled towards its own stamp by ACCEPT_RETIME_GAIN (the
 * stamps still tell the time, their jitter averages out over about
 * 1 / ACCEPT_RETIME_GAIN fixes); taken if the shift is within
 * ACCEPT_RETIME_FRAC of c's shorter interval, c stays between the anchor
 * and the next waypoint, and c still follows the anchor.  Returns the shift
 * (0: kept as stamped).
 */
double accept_retime_soft(accept_t *a, unsigned pre, double vlim)
{
    unsigned c = a->pend[0], a1 = a->a1, n1;
    double soft = ACCEPT_RETIME_SOFT * a->cfg.max_accel_m_s2, t0, tc, t, pace, dt;

    if (!(a->cfg.rules & ACCEPT_RULE_SMOOTH) || !(soft > 0) || pre == NO_SLOT || a->npend < 2)
        return 0;
    n1 = a->pend[1];
    t0 = a->wp[a1].t_s;
    tc = a->wp[c].t_s;
    if (!(a->wp[n1].t_s - tc > ACCEPT_SAME_TIME_S) || !(tc - t0 > ACCEPT_SAME_TIME_S) ||
        a->wp[n1].t_s - t0 > a->cfg.max_gap_s)
        return 0;
    if (!(speed_change(a, pre, a1, c) > soft) && !(speed_change(a, a1, c, n1) > soft))
        return 0;
    pace = kept_pace(a);
    if (!(pace >= ACCEPT_RETIME_SOFT_SPEED_M_S) || !on_path(a, a1, c, n1))
        return 0;
    /* c's stamp, and the later stamps held less their path from c at the
     * pace: the time each tells for c, averaged */
    {
        unsigned prev = c, cnt = 1;
        double path = 0, meas = tc;
        for (unsigned i = 1; i < a->npend; i++) {
            unsigned q = a->pend[i];
            if (!run_goes_on(a, prev, q, t0))
                break;
            path += pair_dist(a, prev, q);
            meas += a->wp[q].t_s - path / pace;
            cnt++;
            prev = q;
        }
        t = t0 + pair_dist(a, a1, c) / pace;
        t += ACCEPT_RETIME_GAIN * (meas / cnt - t);
    }
    dt = min_of(tc - t0, a->wp[n1].t_s - tc);
    if (!(fabs(t - tc) > ACCEPT_SAME_TIME_S) || !(fabs(t - tc) <= ACCEPT_RETIME_SOFT_SHIFT * dt) ||
        !(t - t0 > ACCEPT_SAME_TIME_S) || !(a->wp[n1].t_s - t > ACCEPT_SAME_TIME_S))
        return 0;
    set_time(a, c, t);
    if (check0(a, pre, a1, c, vlim) == 0)
        return t - tc;
    set_time(a, c, tc);
    return 0;
}

/*
 * ACCEPT_RULE_LATE: c (slot pend[0]) follows the anchor, and so does the next
 * waypoint held, n1, but n1 does not follow c: two fixes that cannot both be
 * kept at their stamps (the full window holds both, a window of intervals,
 * before its chains break the tie; the output underran meanwhile).  Where
 * the interval into c is longer than the one into the anchor and the one
 * after it shorter, each by ACCEPT_LATE_MIN of it (regular stamps are not
 * late: a rough track's noisy pace is left to the window), where c's
 * position lies on the path from the anchor to n1 and its stamp is later
 * than the pace of the last kept intervals puts it, by more than
 * ACCEPT_LATE_MIN of the interval into the anchor (a fix written late), it
 * is re-stamped at that pace and kept now, if then it follows the anchor
 * and n1 follows it.  Returns the shift (0: not so).
 */
double accept_retime_late(accept_t *a, unsigned pre, double vlim)
{
    unsigned c = a->pend[0], a1 = a->a1, n1;

    if (!(a->cfg.rules & ACCEPT_RULE_LATE) || a->npend < 2 || pre == NO_SLOT)
        return 0;
    n1 = a->pend[1];
    /* the last ACCEPT_LATE_PACE kept intervals, to the anchor's time as it
     * stands (re-stamped: its new time), so that a boat slowing down is timed
     * at its speed, not at the one of 10 intervals ago */
    double pace = pace_of(a, ACCEPT_LATE_PACE, a->wp[a1].t_s), t0 = a->wp[a1].t_s,
           tc = a->wp[c].t_s, t1 = a->wp[n1].t_s;
    /* (two fixes stamped alike are same_time, not late) */
    if (!(t1 - tc > ACCEPT_SAME_TIME_S) || check(a, a1, c, n1, vlim, 0) == 0 ||
        check0(a, pre, a1, n1, vlim) != 0)
        return 0;
    /* the stamps' own sign of a late write: a long interval into c and a
     * short one after it, against the interval into the anchor */
    double h = t0 - a->wp[pre].t_s;
    if (!(pace > 0) || !(h > 0) || !(tc - t0 > (1.0 + ACCEPT_LATE_MIN) * h) ||
        !(t1 - tc < (1.0 - ACCEPT_LATE_MIN) * h) || !on_path(a, a1, c, n1))
        return 0;
    double t = t0 + pair_dist(a, a1, c) / pace;
    if (!(tc - t > ACCEPT_LATE_MIN * h) || !(tc - t <= ACCEPT_RETIME_FRAC * h) ||
        !(t - t0 > ACCEPT_SAME_TIME_S) || !(t1 - t > ACCEPT_SAME_TIME_S))
        return 0;
    set_time(a, c, t);
    if (check0(a, pre, a1, c, vlim) == 0 && check(a, a1, c, n1, vlim, 0) == 0)
        return t - tc;
    set_time(a, c, tc);
    return 0;
}

/*
 * A fix about to be refused for its speed or acceleration (drop()): both
 * estimates, accept_retime_soft's (the pace kept) and accept_retime's (the
 * pace of the waypoints held), and of those that keep it, the one that
 * bends the pace at the anchor less.  Returns the shift (0: refused).
 */
double accept_retime_either(accept_t *a, unsigned pre, double vlim)
{
    unsigned c = a->pend[0];
    double tc = a->wp[c].t_s, s1 = accept_retime_soft(a, pre, vlim), s2, b1 = 0, b2;

    if (!(s1 > 0 || s1 < 0))
        return accept_retime(a, pre, vlim);
    if (pre == NO_SLOT)
        return s1;
    b1 = speed_change(a, pre, a->a1, c);
    set_time(a, c, tc);
    s2 = accept_retime(a, pre, vlim);
    if (!(s2 > 0 || s2 < 0)) {
        set_time(a, c, tc + s1);
        return s1;
    }
    b2 = speed_change(a, pre, a->a1, c);
    if (b2 < b1)
        return s2;
    set_time(a, c, tc + s1);
    return s1;
}
