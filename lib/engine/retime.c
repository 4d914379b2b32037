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
 * follows it (counted: engine_status retimed, retime_max_s).
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

/*
 * ACCEPT_RULE_RETIME: c (slot pend[0]) follows the anchor at its position
 * but not at its stamp (its own acceleration test or the next one's fails):
 * its time re-estimated at the local pace, the path length from the anchor
 * through the waypoints held in time order over their time.  Taken with
 * that time if the shift is within ACCEPT_RETIME_FRAC of its shorter
 * interval and c then follows the anchor and is followed by the next.
 */
double accept_retime(accept_t *a, unsigned pre, double vlim)
{
    unsigned c = a->pend[0], a1 = a->a1, prev = c, last = c, m = 1;
    double t0 = a->wp[a1].t_s, tc = a->wp[c].t_s, s = pair_dist(a, a1, c), tot = s, t, bound,
           t_hi = INFINITY, h[ACCEPT_WINDOW_MAX + 1];

    h[0] = tc - t0;
    for (unsigned i = 1; i < a->npend; i++) {
        unsigned q = a->pend[i];
        if (a->wp[q].t_s - a->wp[prev].t_s <= ACCEPT_SAME_TIME_S ||
            a->wp[q].t_s - t0 > a->cfg.max_gap_s)
            break;
        tot += pair_dist(a, prev, q);
        h[m++] = a->wp[q].t_s - a->wp[prev].t_s;
        prev = last = q;
    }
    for (unsigned i = 1; i < m; i++) /* the intervals sorted: m <= 9 */
        for (unsigned j = i; j > 0 && h[j - 1] > h[j]; j--) {
            double x = h[j];
            h[j] = h[j - 1];
            h[j - 1] = x;
        }
    if (last != c && tot > 0) {
        /* on the path of its neighbours (a fix off it is no jitter) */
        unsigned n1 = a->pend[1];
        if (!on_path(a, a1, c, n1))
            return 0;
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
    a->wp[c].t_s = t;
    a->known &= ~slot_pairs(c);
    /* c then follows the anchor (the waypoint after it, if any, is judged
     * on its own: its stamp may be off too); or, where the anchor's own
     * stamp was off within the limits, c follows the anchor at the speed
     * limit and the waypoint after it follows c */
    if (check0(a, pre, a1, c, vlim) == 0 || (a->npend > 1 && check0(a, NO_SLOT, a1, c, vlim) == 0 &&
                                             check(a, a1, c, a->pend[1], vlim, 0) == 0)) {
        return t - tc;
    }
    a->wp[c].t_s = tc;
    a->known &= ~slot_pairs(c);
    return 0;
}
