/* accept.c - the acceptance policy, judged with both neighbours; see accept.h.
 *
 * Every test looks at pairs of waypoints (a chord and its speed, the
 * velocities on both sides of a waypoint) and triples (the acceleration
 * test), and a verdict may ask for the longest chains among the waypoints
 * held (chains.c).  The waypoints therefore live in slots (accept_t.wp),
 * and the chord and velocity of a pair of slots, the acceleration test of
 * a triple, are computed once, when a test first needs them, and kept
 * while the waypoints are held (accept_int.h pair(), triple()): a test is
 * then a few loads.  Each cached value is the same expression of the same
 * waypoints as before the cache, so every verdict is the same bit for bit
 * (tests/unit/test_accept.c drives this and the former code,
 * tests/helpers/accept_ref.h, with random dirty tracks;
 * tests/unit/test_accept_same.c this and the policy before its chain
 * search was made incremental, tests/helpers/accept_prev/).
 */
#include "accept.h"

#include <math.h>
#include <string.h>

#include "accept_int.h"

void accept_init(accept_t *a, const accept_config_t *cfg)
{
    memset(a, 0, sizeof *a);
    a->cfg = *cfg;
    if (a->cfg.window < 1)
        a->cfg.window = 1;
    if (a->cfg.window > ACCEPT_WINDOW_MAX)
        a->cfg.window = ACCEPT_WINDOW_MAX;
    if (a->cfg.confirm < 1)
        a->cfg.confirm = 1;
    if (a->cfg.confirm > a->cfg.window)
        a->cfg.confirm = a->cfg.window;
    a->cfg.rules = cfg->rules & ACCEPT_RULES_FORMER ? 0u
                   : cfg->rules                     ? cfg->rules
                                                    : ACCEPT_RULES_ALL;
}

void accept_reset(accept_t *a)
{
    a->npend = 0;
    a->open = 0;
    a->have_a0 = 0;
    a->have_burst = 0;
    a->run_n = a->run_head = 0;
    a->run_verdict = a->standing = a->have_refused = 0;
    a->npace = 0;
}

void accept_close(accept_t *a)
{
    a->open = 0;
    a->have_a0 = 0;
    a->have_burst = 0;
    a->run_n = a->run_head = 0; /* judged at the close (engine_finish) */
    a->run_verdict = a->standing = 0;
    a->npace = 0;
}

double accept_dist(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    double d2 = 0;
    for (int k = 0; k < ENGINE_AXES; k++)
        d2 += (q->pos_m[k] - p->pos_m[k]) * (q->pos_m[k] - p->pos_m[k]);
    return sqrt(d2);
}

static int same(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    return fabs(p->t_s - q->t_s) <= ACCEPT_SAME_TIME_S && accept_dist(p, q) <= ACCEPT_SAME_POS_M;
}

/* a free slot for the waypoint offered (newest: offered last, see
 * accept_forget_as): none of the window, the anchor (a0, a1) and burst; its
 * pairs are forgotten */
static unsigned new_slot(accept_t *a, int newest)
{
    unsigned used = 0, s = 0;
    for (unsigned i = 0; i < a->npend; i++)
        used |= 1u << a->pend[i];
    if (a->open)
        used |= 1u << a->a1;
    if (a->open && a->have_a0)
        used |= 1u << a->a0;
    if (a->have_burst)
        used |= 1u << a->burst;
    while (used >> s & 1u)
        s++;
    accept_forget_as(a, s, newest);
    return s;
}

int accept_offer(accept_t *a, const engine_waypoint_t *wp)
{
    unsigned s;

    if (a->open && same(&a->wp[a->a1], wp))
        return ENGINE_DUPLICATE;
    if (a->run_n > a->run_head && fabs(a->run_t[a->run_n - 1] - wp->t_s) <= ACCEPT_SAME_TIME_S &&
        accept_dist(&a->wp[a->a1], wp) <= ACCEPT_SAME_POS_M)
        return ENGINE_DUPLICATE; /* the last repeat of a run again */
    for (unsigned i = 0; i < a->npend; i++)
        if (same(&a->wp[a->pend[i]], wp))
            return ENGINE_DUPLICATE;
    if (a->npend == ACCEPT_WINDOW_MAX) /* cannot happen: verdicts are taken first */
        return -ENGINE_EFULL;
    s = new_slot(a, 1);
    a->wp[s] = *wp;
    a->pend[a->npend++] = (unsigned char)s;
    return 0;
}

/* lower median of the chord speeds between consecutive waypoints held (and
 * from the anchor to the first), forward intervals only; 0 if none, or if
 * there are fewer than ACCEPT_PACE_CHORDS of them (but before any kept
 * interval in a full window, at the close, or with a window too short to
 * hold that many: a short track's or window's chords are all there is):
 * one outlier
 * among the waypoints held has two chords (into it and out of it), and
 * with two or three chords those are the lower median, so an outlier would
 * set the limit that judges it (a 300 m spike between two fixes of a walk
 * passed as its own pace, 100 m/s; before the first kept interval too,
 * test_accept test_spike_before_first_interval) */
static double window_median_speed(accept_t *a, double floor)
{
    double v[ACCEPT_WINDOW_MAX];
    unsigned n = 0, p = a->open ? a->a1 : NO_SLOT, mid, below = 0;
    unsigned most = a->npend ? (a->npend - 1) / 2 : 0; /* mid, at most */

    /* the caller keeps the larger of floor and the result, so floor and 0
     * (below) are the same answer, and the median counts only above floor:
     * where n - mid chords are (at most mid are not), so the chords are
     * given up as soon as more than mid are not (n is at most npend) */
    for (unsigned i = 0; i < a->npend; i++) {
        unsigned q = a->pend[i];
        double dt = p == NO_SLOT ? 0 : a->wp[q].t_s - a->wp[p].t_s;
        if (p != NO_SLOT && dt > ACCEPT_SAME_TIME_S && dt <= a->cfg.max_gap_s) {
            v[n] = chord_speed(a, p, q);
            below += !(v[n++] > floor);
            if (below > most)
                return floor;
        }
        p = q;
    }
    if (!n ||
        ((a->nhist || (!a->full && a->cfg.window > ACCEPT_PACE_CHORDS)) && n < ACCEPT_PACE_CHORDS))
        return 0;
    mid = (n - 1) / 2;
    if (below > mid)
        return floor;
    /* the lower median, v[mid] of v sorted: with two chords, one of them
     * an outlier's, the smaller one.  The chord whose rank spans mid (as
     * many below it as mid at most, and more up to it): no branch on the
     * values to mispredict, as a sort has */
    for (unsigned i = 0; i < n; i++) {
        unsigned lt = 0, le = 0;
        for (unsigned j = 0; j < n; j++) {
            lt += v[j] < v[i];
            le += v[j] <= v[i];
        }
        if (lt <= mid && mid < le)
            return v[i];
    }
    /* not reached (chords are finite, some v[i] is the median); as the sort */
    for (unsigned i = 1; i < n; i++)
        for (unsigned j = i; j > 0 && v[j - 1] > v[j]; j--) {
            double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
    return v[mid];
}

double accept_speed_limit(accept_t *a)
{
    double cap = a->cfg.max_speed_m_s, learned, vref;

    if (!a->cfg.learned)
        return cap;
    vref = max_of(a->vrecent, window_median_speed(a, a->vrecent));
    learned = max_of(ACCEPT_LEARN_FLOOR_M_S, ACCEPT_LEARN_FACTOR * vref);
    return cap > 0 ? min_of(cap, learned) : learned;
}

int accept_check(const accept_t *a, const engine_waypoint_t *pre, const engine_waypoint_t *p,
                 const engine_waypoint_t *b, double vlim)
{
    double dt = b->t_s - p->t_s;
    int gap = 0, r = time_test(a, dt, 0, &gap);
    accept_pair_t q1, q2;

    if (r)
        return r;
    pair_of(p, b, &q2);
    if (vlim > 0 && q2.d > vlim * dt)
        return ENGINE_ESPEED;
    if (!(a->cfg.max_accel_m_s2 > 0) || !pre)
        return 0;
    pair_of(pre, p, &q1);
    return accel_test(a, &q1, &q2, p->t_s - pre->t_s, dt);
}

/* chain (len, cost) better than (l2, c2): longer, or as long and smoother */
static int better(unsigned len, double cost, unsigned l2, double c2)
{
    return len > l2 || (len == l2 && cost < c2);
}

/*
 * Longest consistent chain that starts at nd[0] (preceded by pre) and whose
 * second waypoint, if any, has an index in jmin..jmax; among the longest,
 * the smoothest (the least largest implied acceleration along it, in *cost).
 * nd: slots, m <= ACCEPT_WINDOW_MAX + 1.  len[i][j], cst[i][j]: the best
 * such chain ending with the step nd[i] -> nd[j] (len 0: none).
 */
static unsigned longest(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre,
                        unsigned jmin, unsigned jmax, double vlim, int gaps_ok, double *cost)
{
    unsigned char len[ACCEPT_WINDOW_MAX + 1][ACCEPT_WINDOW_MAX + 1];
    double cst[ACCEPT_WINDOW_MAX + 1][ACCEPT_WINDOW_MAX + 1];
    unsigned best = 1;
    double best_cost = 0;

    memset(len, 0, sizeof len);
    for (unsigned j = jmin; j < m && j <= jmax; j++)
        if (judge(a, pre, nd[0], nd[j], vlim, gaps_ok, &cst[0][j]) == 0)
            len[0][j] = 2;
    for (unsigned i = 1; i < m; i++)
        for (unsigned h = 0; h < i; h++) {
            if (!len[h][i])
                continue;
            if (better(len[h][i], cst[h][i], best, best_cost)) {
                best = len[h][i];
                best_cost = cst[h][i];
            }
            for (unsigned j = i + 1; j < m; j++) {
                double c;
                if (judge(a, nd[h], nd[i], nd[j], vlim, gaps_ok, &c))
                    continue;
                c = max_of(cst[h][i], c);
                if (!len[i][j] || better(len[h][i] + 1u, c, len[i][j], cst[i][j])) {
                    len[i][j] = (unsigned char)(len[h][i] + 1);
                    cst[i][j] = c;
                }
            }
        }
    if (cost)
        *cost = best_cost;
    return best;
}

/* 1 if nd[0..m-1] (slots) in order is one consistent chain (nd[0] preceded by pre) */
static int chain_all(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre, double vlim,
                     int gaps_ok)
{
    for (unsigned i = 0; i + 1 < m; i++) {
        if (check(a, pre, nd[i], nd[i + 1], vlim, gaps_ok))
            return 0;
        pre = nd[i];
    }
    return 1;
}

/* q follows p (slots) across a plausible gap: beyond max_gap_s, but not far
 * in time (ACCEPT_FAR_GAP_FACTOR) and covered within the speed limit */
static int plausible_gap(accept_t *a, unsigned p, unsigned q, double vlim)
{
    double dt = a->wp[q].t_s - a->wp[p].t_s;
    return dt > a->cfg.max_gap_s && dt <= ACCEPT_FAR_GAP_FACTOR * a->cfg.max_gap_s &&
           (!(vlim > 0) || pair_dist(a, p, q) <= vlim * dt);
}

/* the fastest of the last kept chord speeds */
static double recent_max_speed(const accept_t *a)
{
    double m = 0;
    for (unsigned i = 0; i < a->nhist; i++)
        if (a->vhist[i] > m)
            m = a->vhist[i];
    return m;
}

/* take the oldest waypoint out of the window into v */
static void pop(accept_t *a, accept_verdict_t *v, accept_kind_t kind, int reason)
{
    unsigned c = a->pend[0];

    memset(v, 0, sizeof *v);
    v->kind = kind;
    v->reason = reason;
    v->wp = a->wp[c];
    a->npend--;
    for (unsigned i = 0; i < a->npend; i++)
        a->pend[i] = a->pend[i + 1];
    a->have_burst = kind == ACCEPT_DROP && reason == ENGINE_EUNCONFIRMED;
    if (kind == ACCEPT_DROP &&
        (reason == ENGINE_ESPEED || reason == ENGINE_EACCEL || reason == ENGINE_EUNCONFIRMED)) {
        a->have_refused = 1; /* ACCEPT_RULE_NORETURN: refused for its position */
        a->refused_reason = reason;
        a->refused = a->wp[c];
    } else if (kind == ACCEPT_START) {
        a->have_refused = 0;
    }
    if (a->have_burst)
        a->burst = (unsigned char)c;
    if (kind == ACCEPT_TAKE || kind == ACCEPT_START) {
        /* ACCEPT_RULE_SMOOTH: the path length kept (retime.c kept_pace) */
        unsigned k = a->npace % (ACCEPT_RETIME_PACE + 1);
        double s0 = a->npace ? a->pace_s[(a->npace - 1) % (ACCEPT_RETIME_PACE + 1)] : 0;
        if (kind == ACCEPT_START)
            a->npace = 0, k = 0, s0 = 0;
        a->pace_t[k] = a->wp[c].t_s - a->shift_now; /* as stamped */
        a->pace_s[k] = kind == ACCEPT_TAKE && a->npace ? s0 + pair_dist(a, a->a1, c) : 0;
        a->npace++;
    }
    if (kind == ACCEPT_TAKE) {
        /* the fastest: the larger of it and the new chord, unless the one
         * it replaces may have been it (then all of them again) */
        double gone = a->vhist[a->hnext], now = chord_speed(a, a->a1, c);
        int evict = a->nhist == ACCEPT_HIST;
        a->vhist[a->hnext] = now;
        a->hnext = (a->hnext + 1) % ACCEPT_HIST;
        if (a->nhist < ACCEPT_HIST)
            a->nhist++;
        if (evict && !(gone < a->vrecent))
            a->vrecent = recent_max_speed(a);
        else if (now > a->vrecent)
            a->vrecent = now;
        a->a0 = a->a1;
        a->have_a0 = 1;
        a->a1 = (unsigned char)c;
    } else if (kind == ACCEPT_START) {
        v->gap = a->open && v->wp.t_s - a->wp[a->a1].t_s > a->cfg.max_gap_s;
        a->open = 1;
        a->have_a0 = 0;
        a->a1 = (unsigned char)c;
    }
}

/* lower median of the chord speeds of the last kept intervals (0 if none) */
double accept_recent_median(const accept_t *a)
{
    double v[ACCEPT_HIST];
    unsigned n = a->nhist;

    if (!n)
        return 0;
    memcpy(v, a->vhist, n * sizeof v[0]);
    for (unsigned i = 1; i < n; i++) /* insertion sort: n <= ACCEPT_HIST */
        for (unsigned j = i; j > 0 && v[j - 1] > v[j]; j--) {
            double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
    return v[(n - 1) / 2];
}

/*
 * Stale repeat of the anchor while moving: 1 = drop c as stale, 0 = not
 * stale (judge it as any other), -1 = wait for a waypoint with a new position.
 */
static int stale_verdict(accept_t *a, int full, double vlim)
{
    unsigned c = a->pend[0], a1 = a->a1;
    double v_in;

    if (!a->cfg.stale || !a->open || !a->have_a0 || pair_dist(a, a1, c) > ACCEPT_STALE_POS_M ||
        a->wp[c].t_s - a->wp[a1].t_s <= ACCEPT_SAME_TIME_S)
        return 0;
    v_in = chord_speed(a, a->a0, a1);
    if (v_in < ACCEPT_STALE_MIN_SPEED_M_S)
        return 0;
    for (unsigned i = 1; i < a->npend; i++) {
        unsigned f = a->pend[i];
        if (pair_dist(a, a1, f) <= ACCEPT_STALE_POS_M)
            continue; /* the run goes on */
        if (a->wp[f].t_s - a->wp[a1].t_s > ACCEPT_SAME_TIME_S &&
            check0(a, a->a0, a1, f, vlim) == 0 && chord_speed(a, a1, f) >= 0.5 * v_in)
            return 1;
        return 0;
    }
    if (!full)
        return -1;
    /* the window holds nothing but repeats: a run longer than the window.
     * An object that stood there stopped dead within one interval from its
     * recent pace (the median of the last kept chords: one noisy step of a
     * moored boat is no pace); beyond ACCEPT_STALE_STOP_M_S2 no vehicle
     * does that, a frozen receiver does (the anchor's own interval, so every
     * repeat of the run gets the same verdict) */
    v_in = accept_recent_median(a);
    return v_in >= ACCEPT_STALE_MIN_SPEED_M_S &&
           v_in / (a->wp[a1].t_s - a->wp[a->a0].t_s) > ACCEPT_STALE_STOP_M_S2;
}

/* 0 if slots p and q are surely farther apart than ACCEPT_STALE_POS_M (an
 * axis differs by more than twice that: their distance, as pair() rounds
 * it, is then more than ACCEPT_STALE_POS_M), without their pair */
static int near_pos(const accept_t *a, unsigned p, unsigned q)
{
    return fabs(a->wp[q].pos_m[0] - a->wp[p].pos_m[0]) <= 2.0 * ACCEPT_STALE_POS_M;
}

/*
 * 1 if a later waypoint held repeats c's position (a frozen receiver starts
 * repeating after c): c is the one that was stamped when the position was
 * fixed, the repeats are the stale ones, so c is kept over them even where
 * a chain through a repeat would bend the track less (keep the good fix;
 * the repeats then meet stale_verdict with c as the anchor).
 */
static int repeated_later(accept_t *a)
{
    unsigned c = a->pend[0];
    if (!a->cfg.stale)
        return 0;
    for (unsigned i = 1; i < a->npend; i++)
        if (near_pos(a, c, a->pend[i]) && pair_dist(a, c, a->pend[i]) <= ACCEPT_STALE_POS_M &&
            a->wp[a->pend[i]].t_s - a->wp[c].t_s > ACCEPT_SAME_TIME_S)
            return 1;
    return 0;
}

/* q (a slot) repeats the position of c, the oldest waypoint held (profiles
 * with stale detection): a frozen receiver's copy of c, no evidence of its
 * own for or against c (it may follow the anchor only because it is stamped
 * later) */
static int repeats_c(accept_t *a, unsigned q)
{
    return a->cfg.stale && q != a->pend[0] && near_pos(a, a->pend[0], q) &&
           pair_dist(a, a->pend[0], q) <= ACCEPT_STALE_POS_M;
}

/* 1 if c failed the anchor on speed alone while the learned limit rests on
 * fewer than ACCEPT_PACE_CHORDS kept intervals (at the start of a track:
 * its floor, or a slow first interval's pace) and the window is not full:
 * GNSS noise over a short interval may pass for speed then, so c waits for
 * the full window, whose chords give the pace
 * (tests/oracle/test_fault_injection.py test_gpx_faults) */
static int thin_pace(accept_t *a, int r)
{
    return r == ENGINE_ESPEED && a->cfg.learned && a->nhist < ACCEPT_PACE_CHORDS && !a->full;
}

/*
 * 1 if a waypoint held after c continues the anchor (a chain skipping c
 * exists): c, which does not follow the anchor, is then dropped whatever
 * comes later (the full window's verdict: lo >= 2 and r != 0).
 */
static int continues_anchor(accept_t *a, unsigned pre, double vlim, unsigned from)
{
    for (unsigned i = from; i < a->npend; i++)
        if (!repeats_c(a, a->pend[i]) && check0(a, pre, a->a1, a->pend[i], vlim) == 0)
            return 1;
    return 0;
}

/*
 * 1 if c (which follows the anchor) is followed, past waypoints that cannot
 * take its place, by one that continues it: the waypoints between neither
 * follow the anchor nor are anything but repeats of c's position (stale
 * profiles), so every chain skipping c is one shorter than the chain
 * through it, and the full window would take c.  One outlier after a good
 * fix so holds it one interval, not a window.
 */
static int taken_past_outliers(accept_t *a, double vlim, unsigned from, unsigned *stop)
{
    unsigned c = a->pend[0], pre = a->have_a0 ? a->a0 : NO_SLOT;
    for (unsigned j = from; j < a->npend; j++) {
        unsigned q = a->pend[j];
        *stop = j;
        if (check(a, a->a1, c, q, vlim, 0) == 0)
            return j >= 2;
        if (!repeats_c(a, q) && check0(a, pre, a->a1, q, vlim) == 0)
            return 0; /* q could replace c: the full window compares them */
    }
    *stop = 0;
    return 0;
}

/* nd (slots: the anchor, then the n waypoints held) without c's later
 * repeats, into nr: the chains that skip c leave them out too (a frozen
 * receiver's copies of c, stamped later, would otherwise outvote the fix
 * they copy: a chain through them is as long as the run).  Returns their
 * count. */
static unsigned without_repeats(accept_t *a, const unsigned char *nd, unsigned n, unsigned char *nr)
{
    unsigned m = 0;
    for (unsigned i = 0; i <= n; i++)
        if (i < 2 || !repeats_c(a, nd[i]))
            nr[m++] = nd[i];
    return m;
}

/* the longest chains from the anchor through c (lw, cost cw) and skipping
 * it (lo, co) among the waypoints held: longest() both ways, computed once
 * per verdict (outvotes_held, then decide_full on the same window); their
 * lengths first, the costs only where the lengths tie (chain_costs) */
typedef struct {
    int known, costs;
    unsigned lw, lo;
    double cw, co;
} chains_t;

/* ch's lengths, computed first if not known (nd: the anchor and the
 * window, slots); its costs are 0 where a length is 1 (no chain: the cost
 * longest() gives then), else known only if ch->costs */
static const chains_t *chains(accept_t *a, const unsigned char *nd, unsigned pre, double vlim,
                              chains_t *ch)
{
    unsigned char nr[ACCEPT_WINDOW_MAX + 1];
    unsigned n = a->npend, m;

    if (ch->known)
        return ch;
    m = n + 1;
    for (unsigned i = 2; i <= n; i++)
        if (repeats_c(a, nd[i])) {
            m = without_repeats(a, nd, n, nr);
            break;
        }
    if (m == n + 1) { /* no repeats of c: the same waypoints both ways */
        unsigned l[2];
        accept_longest_len(a, nd, m, pre, vlim, l);
        ch->lw = l[0], ch->lo = l[1], ch->cw = ch->co = 0;
    } else {
        ch->lw = longest(a, nd, n + 1, pre, 1, 1, vlim, 0, &ch->cw); /* through c */
        ch->lo = longest(a, nr, m, pre, 2, m - 1, vlim, 0, &ch->co); /* skipping c */
        ch->costs = 1;
    }
    ch->known = 1;
    return ch;
}

/* ch (known) with its costs */
static const chains_t *chain_costs(accept_t *a, const unsigned char *nd, unsigned pre, double vlim,
                                   chains_t *ch)
{
    if (!ch->costs) { /* no repeats of c (chains) */
        unsigned l[2] = {ch->lw, ch->lo};
        double cl[2];
        if (!accept_longest_cost(a, nd, a->npend + 1, pre, vlim, l, cl))
            accept_longest_both(a, nd, a->npend + 1, pre, vlim, l, cl);
        ch->cw = cl[0], ch->co = cl[1];
        ch->costs = 1;
    }
    return ch;
}

/*
 * 1 if c (which follows the anchor) is continued by a later waypoint held
 * and the longest chain through c is longer than every chain that skips
 * it, among the waypoints held (nd: the anchor and the window, slots): the
 * full window's verdict, given now.  A spike that the learned limit lets
 * follow the anchor (taken_past_outliers then waits) but that nothing held
 * continues is one waypoint against c's two: without this, c would wait
 * for the full window (the output drains its start slack meanwhile:
 * visnjan, tests/oracle/test_fault_injection.py test_spike_rides_through).
 */
static int outvotes_held(accept_t *a, const unsigned char *nd, unsigned pre, double vlim,
                         chains_t *ch)
{
    const chains_t *c = chains(a, nd, pre, vlim, ch);
    return c->lw >= 3 && c->lw > c->lo;
}

/*
 * The reason for dropping c, which does not follow the anchor (r: ESPEED or
 * EACCEL from accept_check): ENGINE_EUNCONFIRMED if c is one of a burst of
 * mutually consistent waypoints off the trajectory (a new trajectory that
 * was not confirmed, far in space): c is consistent (within max_gap_s) with
 * the burst waypoint dropped just before it, or with a later waypoint held
 * that does not follow the anchor either, for its speed or acceleration
 * (not a repeat of c, not one beyond a gap).  A lone spike, consistent
 * with nothing held, keeps r.  Only the reason: the verdict is the same.
 */
static int drop_reason(accept_t *a, unsigned pre, double vlim, int r)
{
    unsigned c = a->pend[0];

    if (r != ENGINE_ESPEED && r != ENGINE_EACCEL)
        return r;
    if (a->have_burst && check(a, NO_SLOT, a->burst, c, vlim, 0) == 0)
        return ENGINE_EUNCONFIRMED;
    for (unsigned i = 1; i < a->npend; i++) {
        unsigned q = a->pend[i];
        int rq;
        if (repeats_c(a, q) || check(a, NO_SLOT, c, q, vlim, 0) != 0)
            continue;
        rq = check0(a, pre, a->a1, q, vlim);
        if (rq == ENGINE_ESPEED || rq == ENGINE_EACCEL)
            return ENGINE_EUNCONFIRMED;
    }
    return r;
}

/* no trajectory open: start one on a chain of confirm (or what there is at
 * the close), else drop c */
static int decide_closed(accept_t *a, int closing, int full, double vlim, accept_verdict_t *v)
{
    const unsigned char *nd = a->pend;
    unsigned n = a->npend, k = a->cfg.confirm, u, vbest = 0;
    int r;

    if (n >= k && chain_all(a, nd, n, NO_SLOT, vlim, 1)) {
        pop(a, v, ACCEPT_START, 0);
        return 1;
    }
    if (!full)
        return 0;
    u = longest(a, nd, n, NO_SLOT, 1, n, vlim, 1, NULL);
    for (unsigned s = 1; s < n; s++) {
        unsigned l = longest(a, nd + s, n - s, NO_SLOT, 1, n, vlim, 1, NULL);
        if (l > vbest)
            vbest = l;
    }
    /* nothing to abandon: at the close, the chain there is will do; a
     * waypoint a plausible gap before the next one is a trajectory of
     * its own; a full window with no two waypoints consistent (all
     * stamped alike, say) has no chain to prefer: the oldest starts it
     * (the later ones are then judged against it), not whichever is
     * oldest when the input closes */
    if ((u >= vbest && (u >= k || closing || vbest <= 1)) ||
        (n >= 2 && plausible_gap(a, nd[0], nd[1], vlim))) {
        pop(a, v, ACCEPT_START, 0);
        return 1;
    }
    r = n >= 2 ? check0(a, NO_SLOT, nd[0], nd[1], vlim) : 0;
    pop(a, v, ACCEPT_DROP, r ? r : ENGINE_EUNCONFIRMED);
    return 1;
}

static int drop(accept_t *a, unsigned pre, double vlim, int reason, accept_verdict_t *v);

/* keep c, re-stamped if its stamp bends the pace (ACCEPT_RULE_SMOOTH) */
/* keep c, its stamp moved by shift (0: as stamped) */
static int take_at(accept_t *a, double shift, accept_verdict_t *v)
{
    a->shift_now = shift;
    pop(a, v, ACCEPT_TAKE, 0);
    a->shift_now = 0;
    v->shift_s = shift;
    return 1;
}

static int take(accept_t *a, unsigned pre, double vlim, accept_verdict_t *v)
{
    return take_at(a, accept_retime_soft(a, pre, vlim), v);
}

/* an open trajectory, the full window's verdict on c (r: c after the
 * anchor, nd: the anchor and the window, slots) */
static int decide_full(accept_t *a, int closing, double vlim, unsigned pre, int r,
                       const unsigned char *nd, chains_t *ch, accept_verdict_t *v)
{
    unsigned n = a->npend, k = a->cfg.confirm;
    const chains_t *c = chains(a, nd, pre, vlim, ch);
    unsigned lw = c->lw, lo = c->lo;
    double cw, co;

    if (lw == lo && lw >= 2) /* as long: the smoother one, by their costs */
        c = chain_costs(a, nd, pre, vlim, ch);
    cw = c->cw, co = c->co;

    /* keep c unless a longer chain skips it, or one as long and smoother
     * (of two fixes that cannot both be right, the one that bends the
     * track less) */
    if (r == 0 && (!better(lo, co, lw, cw) || (lw >= lo && repeated_later(a))))
        return take(a, pre, vlim, v);
    if (lo < 2) {
        /* nothing held continues the anchor: re-anchor on k consistent */
        unsigned u = longest(a, nd + 1, n, NO_SLOT, 1, n, vlim, 1, NULL);
        /* at the close, what is left confirms itself if it is all one
         * chain that the anchor reaches within the speed limit */
        if (u >= k || plausible_gap(a, nd[0], nd[1], vlim) ||
            (closing && u == n && check(a, NO_SLOT, nd[0], nd[1], vlim, 1) == 0)) {
            pop(a, v, ACCEPT_START, 0);
            return 1;
        }
    }
    if (r != 0)
        r = drop_reason(a, pre, vlim, r);
    else if (n >= 2)
        r = check0(a, nd[0], nd[1], nd[2], vlim);
    if (r == 0 && lo == lw)
        r = ENGINE_EACCEL; /* as long a chain bends less without it */
    return drop(a, pre, vlim, r ? r : ENGINE_EUNCONFIRMED, v);
}

/*
 * accept_decide with a trajectory open and c alone in a window not yet full
 * (every waypoint of a clean track waits here for its next neighbour): the
 * general path below, left with what can give a verdict then.  A stale
 * verdict needs a later waypoint or a full window (a repeat of the anchor
 * waits: stale_verdict -1, which needs no speed limit then); chain_all, the
 * early drops and takes need a second waypoint; so only a START after a gap
 * is possible, when confirm is 1, and for that the test of c after the
 * anchor is EUNCONFIRMED exactly when its time test is (the other tests come
 * after it and give other errors).  So no speed limit and no acceleration.
 */
static int decide_one(accept_t *a, accept_verdict_t *v)
{
    double dt = a->wp[a->pend[0]].t_s - a->wp[a->a1].t_s;
    int gap = 0;

    if (stale_verdict(a, 0, 0) < 0)
        return 0;
    if (a->cfg.confirm == 1 && time_test(a, dt, 0, &gap) == ENGINE_EUNCONFIRMED &&
        a->wp[a->pend[0]].t_s > a->wp[a->a1].t_s) {
        pop(a, v, ACCEPT_START, 0);
        return 1;
    }
    return 0;
}

/* 1 if fixes p and b both carry the source's velocity and their chord
 * disagrees with its mean beyond ACCEPT_VEL_* (accept.h) */
static int vel_disagrees(const accept_t *a, unsigned p, unsigned b)
{
    const engine_waypoint_t *P = &a->wp[p], *B = &a->wp[b];
    double dt = B->t_s - P->t_s, e2 = 0;

    if (P->has_vel != 1 || B->has_vel != 1 || !(dt > 0))
        return 0;
    for (int k = 0; k < ENGINE_AXES; k++) {
        double d = (B->pos_m[k] - P->pos_m[k]) / dt - 0.5 * (P->vel_m_s[k] + B->vel_m_s[k]);
        e2 += d * d;
    }
    double amax = a->cfg.max_accel_m_s2 > 0 ? a->cfg.max_accel_m_s2 : ACCEPT_VEL_ACCEL_M_S2;
    double tol = 0.25 * amax * dt + 2.0 * ACCEPT_VEL_POS_NOISE_M / dt + ACCEPT_VEL_NOISE_M_S;
    return sqrt(e2) > tol;
}

/* decide_one with at_arrival: c kept now if it follows the anchor and agrees
 * with the source's velocity (accept.h); else as decide_one */
static int decide_arrival(accept_t *a, accept_verdict_t *v)
{
    unsigned pre = a->have_a0 ? a->a0 : NO_SLOT, c = a->pend[0];
    double vlim = accept_speed_limit(a);

    if (stale_verdict(a, 0, vlim) == 0 && pair_dist(a, a->a1, c) > ACCEPT_STALE_POS_M &&
        check0(a, pre, a->a1, c, vlim) == 0 && !vel_disagrees(a, a->a1, c))
        return take(a, pre, vlim, v);
    return decide_one(a, v);
}

void accept_anchor_at(accept_t *a, const engine_waypoint_t *wp)
{
    unsigned s;
    a->have_a0 = 0; /* the slot of a0 may be taken */
    a->open = 0;
    s = new_slot(a, 0);
    a->wp[s] = *wp;
    a->a1 = (unsigned char)s;
    a->open = 1;
    a->have_refused = 0;
    a->pace_t[0] = wp->t_s; /* ACCEPT_RULE_SMOOTH: the pace starts here */
    a->pace_s[0] = 0;
    a->npace = 1;
}

/* drop c (an open trajectory) for reason, unless its position follows the
 * path and only its stamp is off: then it is kept re-stamped (retime) */
static int drop(accept_t *a, unsigned pre, double vlim, int reason, accept_verdict_t *v)
{
    double shift = 0;
    if ((a->cfg.rules & ACCEPT_RULE_RETIME) &&
        (reason == ENGINE_ESPEED || reason == ENGINE_EACCEL)) {
        shift = accept_retime_either(a, pre, vlim);
    }
    if (shift > 0 || shift < 0)
        return take_at(a, shift, v);
    pop(a, v, ACCEPT_DROP, reason);
    return 1;
}

/*
 * The waypoints of the last wait (accept_t.wait) still held first, with
 * the same anchor, slot before it and speed limit: their count, else 0.
 * What that call found of them holds again (every test is a function of
 * the waypoints and the speed limit): c's test after the anchor, chain_all
 * failing among them, accept_retime_late keeping c as it stands, the scans
 * of continues_anchor and taken_past_outliers over them.
 */
static unsigned waited(const accept_t *a, unsigned pre, double vlim)
{
    const accept_wait_t *w = &a->wait;
    if (!w->valid || w->a1 != a->a1 || w->since_a1 != a->since[a->a1] || w->pre != pre ||
        (pre != NO_SLOT && w->since_pre != a->since[pre]) || a->npend < w->n ||
        memcmp(&w->vlim, &vlim, sizeof vlim) != 0)
        return 0;
    for (unsigned i = 0; i < w->n; i++)
        if (w->pend[i] != a->pend[i] || w->since[i] != a->since[a->pend[i]])
            return 0;
    return w->n;
}

/* 1 if accept_run_decide would find no run of repeats and start none (it
 * returns -1 then, and changes nothing): no trajectory open, or no run
 * held nor judged and the oldest waypoint held (if any) no repeat of the
 * anchor later than it (stops.c repeats_anchor) */
static int no_run(accept_t *a)
{
    unsigned q;
    if (!a->open)
        return 1;
    if (a->run_n || a->run_verdict)
        return 0;
    if (!a->npend)
        return 1;
    q = a->pend[0];
    return !(a->wp[q].t_s - a->wp[a->a1].t_s > ACCEPT_SAME_TIME_S &&
             pair_dist(a, a->a1, q) <= ACCEPT_STALE_POS_M);
}

int accept_decide(accept_t *a, int closing, accept_verdict_t *v)
{
    unsigned char nd[ACCEPT_WINDOW_MAX + 1];
    unsigned pre = a->open && a->have_a0 ? a->a0 : NO_SLOT;
    unsigned n = a->npend, k = a->cfg.confirm, wn, scan = 0, tpo = 0;
    int full = closing || n >= a->cfg.window;
    chains_t ch = {0};
    double vlim;
    int r;

    a->full = full; /* window_median_speed */
    if ((a->cfg.rules & ACCEPT_RULE_STOPS) && !no_run(a)) {
        int rr = accept_run_decide(a, closing, v);
        if (rr >= 0)
            return rr;
        n = a->npend;
        full = closing || n >= a->cfg.window;
        a->full = full;
    }
    if (!n)
        return 0;
    if ((a->cfg.rules & ACCEPT_RULE_NORETURN) && a->open && a->have_refused &&
        a->wp[a->pend[0]].t_s - a->refused.t_s > ACCEPT_SAME_TIME_S &&
        accept_dist(&a->refused, &a->wp[a->pend[0]]) <= ACCEPT_STALE_POS_M) {
        int why = a->refused_reason; /* a refused fix does not return by repetition */
        pop(a, v, ACCEPT_DROP, why);
        return 1;
    }
    if (a->open && n < 2 && !full)
        return a->cfg.at_arrival ? decide_arrival(a, v) : decide_one(a, v);
    vlim = accept_speed_limit(a);
    if (!a->open)
        return decide_closed(a, closing, full, vlim, v);

    /* an open trajectory: the anchor a1 (after a0) and the window */
    r = stale_verdict(a, full, vlim);
    if (r < 0)
        return 0;
    if (r > 0) {
        pop(a, v, ACCEPT_DROP, ENGINE_ESTALE);
        return 1;
    }
    nd[0] = a->a1;
    memcpy(nd + 1, a->pend, n);
    wn = waited(a, pre, vlim);
    a->wait.valid = 0;
    r = wn ? a->wait.r : check0(a, pre, nd[0], nd[1], vlim); /* chain_all's first step */
    /* (after a wait with r == 0, chain_all failed among its waypoints) */
    if (n >= 2 && r == 0 && !wn && chain_all(a, nd + 1, n, nd[0], vlim, 0))
        return take(a, pre, vlim, v);
    if (r == ENGINE_EUNCONFIRMED && a->wp[nd[1]].t_s > a->wp[nd[0]].t_s && n >= k &&
        chain_all(a, nd + 1, k, NO_SLOT, vlim, 1)) {
        /* after a gap: nothing later can continue the anchor (all are later
         * than c, which is beyond max_gap_s), so k consistent waypoints are
         * all it takes */
        pop(a, v, ACCEPT_START, 0);
        return 1;
    }
    /* verdicts the full window would give, as soon as they are certain: a
     * bad fix must not hold the good ones around it for a whole window (the
     * output draws on its start slack meanwhile) */
    if (r != 0 && !thin_pace(a, r)) {
        if (continues_anchor(a, pre, vlim, wn && a->wait.scan ? a->wait.scan : 1))
            return drop(a, pre, vlim, drop_reason(a, pre, vlim, r), v);
        scan = n;
    }
    if (r == 0 && n >= 2 && !wn) { /* a fix written late, re-stamped now (retime.c) */
        double shift = accept_retime_late(a, pre, vlim);
        if (shift > 0 || shift < 0)
            return take_at(a, shift, v);
    }
    if (r == 0 && (!wn || !a->wait.tpo) && taken_past_outliers(a, vlim, wn ? wn : 1, &tpo))
        return take(a, pre, vlim, v);
    if (r == 0 && wn && a->wait.tpo)
        tpo = a->wait.tpo; /* it stopped among them: the same answer */
    if (r == 0 && n >= 3 && outvotes_held(a, nd, pre, vlim, &ch))
        return take(a, pre, vlim, v);
    if (!full) { /* a wait: kept for the next call (waited) */
        a->wait.valid = 1;
        a->wait.r = r;
        a->wait.a1 = (unsigned char)a->a1;
        a->wait.since_a1 = a->since[a->a1];
        a->wait.pre = (unsigned char)pre;
        a->wait.since_pre = pre != NO_SLOT ? a->since[pre] : 0;
        a->wait.vlim = vlim;
        a->wait.n = n;
        a->wait.scan = scan;
        a->wait.tpo = tpo;
        memcpy(a->wait.pend, a->pend, n);
        for (unsigned i = 0; i < n; i++)
            a->wait.since[i] = a->since[a->pend[i]];
        return 0;
    }
    return decide_full(a, closing, vlim, pre, r, nd, &ch, v);
}
