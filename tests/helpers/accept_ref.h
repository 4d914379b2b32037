/*
 * accept_ref.h - the acceptance policy as it was before its pair cache
 * (lib/engine/accept.c up to commit 61f59e6: every test recomputes its
 * chord speeds and velocities from the waypoints, the window is an array
 * shifted on each verdict; with the early take of a fix that outvotes a
 * spike among the waypoints held, aref_outvotes_held, and the window's
 * pace from ACCEPT_PACE_CHORDS chords before any kept interval too, added
 * to both), kept
 * as the reference: test_accept drives it
 * and lib/engine/accept.c with the same random dirty tracks and checks the
 * verdicts are the same, and bench_engine times the two side by side.
 * Header-only (static functions), the same accept_config_t and verdicts.
 */
#ifndef TRAJD_ACCEPT_REF_H
#define TRAJD_ACCEPT_REF_H

#include <math.h>
#include <string.h>

#include "accept.h"

typedef struct {
    accept_config_t cfg;
    engine_waypoint_t pend[ACCEPT_WINDOW_MAX];
    unsigned npend;
    int open;
    int have_a0;
    engine_waypoint_t a0, a1;
    int started;
    double vhist[ACCEPT_HIST];
    unsigned nhist, hnext;
    int full;
    int have_burst;
    engine_waypoint_t burst;
} aref_t;

/* Timestamps closer than this are "the same time" (seconds), as in engine_input.c. */
#define AREF_SAME_TIME_S 1e-9
/* Positions closer than this at the same time are a duplicate (metres). */
#define AREF_SAME_POS_M 1e-9

static inline void aref_init(aref_t *a, const accept_config_t *cfg)
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
}

static inline void aref_reset(aref_t *a)
{
    a->npend = 0;
    a->open = 0;
    a->have_a0 = 0;
    a->have_burst = 0;
}

static inline void aref_close(aref_t *a)
{
    a->open = 0;
    a->have_a0 = 0;
    a->have_burst = 0;
}

static inline double aref_dist(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    double d2 = 0;
    for (int k = 0; k < ENGINE_AXES; k++)
        d2 += (q->pos_m[k] - p->pos_m[k]) * (q->pos_m[k] - p->pos_m[k]);
    return sqrt(d2);
}

/* chord speed p -> q; only for q later than p */
static inline double aref_chord_speed(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    return aref_dist(p, q) / (q->t_s - p->t_s);
}

static inline int aref_same(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    return fabs(p->t_s - q->t_s) <= AREF_SAME_TIME_S && aref_dist(p, q) <= AREF_SAME_POS_M;
}

static inline int aref_offer(aref_t *a, const engine_waypoint_t *wp)
{
    if (a->open && aref_same(&a->a1, wp))
        return ENGINE_DUPLICATE;
    for (unsigned i = 0; i < a->npend; i++)
        if (aref_same(&a->pend[i], wp))
            return ENGINE_DUPLICATE;
    if (a->npend == ACCEPT_WINDOW_MAX) /* cannot happen: verdicts are taken first */
        return -ENGINE_EFULL;
    a->pend[a->npend++] = *wp;
    return 0;
}

static inline double aref_recent_speed(const aref_t *a)
{
    double m = 0;
    for (unsigned i = 0; i < a->nhist; i++)
        if (a->vhist[i] > m)
            m = a->vhist[i];
    return m;
}

/* lower median of the chord speeds between consecutive waypoints held (and
 * from the anchor to the first), forward intervals only; 0 if none, or if
 * there are fewer than ACCEPT_PACE_CHORDS of them once kept intervals give a
 * recent speed: one outlier among the waypoints held has two chords (into
 * it and out of it), and with two or three chords those are the lower
 * median, so an outlier would set the limit that judges it (a 300 m spike
 * between two fixes of a walk passed as its own pace, 100 m/s) */
static inline double aref_window_median_speed(const aref_t *a)
{
    double v[ACCEPT_WINDOW_MAX];
    unsigned n = 0;
    const engine_waypoint_t *p = a->open ? &a->a1 : NULL;

    for (unsigned i = 0; i < a->npend; i++) {
        const engine_waypoint_t *q = &a->pend[i];
        if (p && q->t_s - p->t_s > AREF_SAME_TIME_S && q->t_s - p->t_s <= a->cfg.max_gap_s)
            v[n++] = aref_chord_speed(p, q);
        p = q;
    }
    if (!n ||
        ((a->nhist || (!a->full && a->cfg.window > ACCEPT_PACE_CHORDS)) && n < ACCEPT_PACE_CHORDS))
        return 0;
    /* insertion sort: n <= ACCEPT_WINDOW_MAX */
    for (unsigned i = 1; i < n; i++)
        for (unsigned j = i; j > 0 && v[j - 1] > v[j]; j--) {
            double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
    /* the lower median: with two chords, one of them an outlier's, the
     * smaller one */
    return v[(n - 1) / 2];
}

static inline double aref_speed_limit(const aref_t *a)
{
    double cap = a->cfg.max_speed_m_s, learned, vref;

    if (!a->cfg.learned)
        return cap;
    vref = fmax(aref_recent_speed(a), aref_window_median_speed(a));
    learned = fmax(ACCEPT_LEARN_FLOOR_M_S, ACCEPT_LEARN_FACTOR * vref);
    return cap > 0 ? fmin(cap, learned) : learned;
}

/*
 * aref_check, and with gaps_ok an interval above max_gap_s passes too (time
 * order and speed only: an acceleration over a gap means nothing).  That is
 * what "mutually consistent" means for waypoints that confirm a new
 * trajectory: a sparse or slipped track (every interval a gap) still
 * confirms itself, a lone waypoint at t = 1e9 among waypoints at t ~ 100
 * does not (they are earlier than it).
 */
static inline int aref_check_g(const aref_t *a, const engine_waypoint_t *pre,
                               const engine_waypoint_t *p, const engine_waypoint_t *b, double vlim,
                               int gaps_ok)
{
    double dt = b->t_s - p->t_s, amax = a->cfg.max_accel_m_s2;

    if (dt < -AREF_SAME_TIME_S)
        return ENGINE_EBACKWARDS;
    if (dt <= AREF_SAME_TIME_S)
        return ENGINE_ESAMETIME;
    if (dt > a->cfg.max_gap_s) {
        if (!gaps_ok)
            return ENGINE_EUNCONFIRMED;
        pre = NULL;
    }
    if (vlim > 0 && aref_dist(p, b) > vlim * dt)
        return ENGINE_ESPEED;
    if (amax > 0 && pre) {
        /* pre is earlier than p by more than 1 ns: it was checked so */
        double d1 = p->t_s - pre->t_s, dv2 = 0, s1 = 0, s2 = 0, allow;
        for (int k = 0; k < ENGINE_AXES; k++) {
            double v1 = (p->pos_m[k] - pre->pos_m[k]) / d1;
            double v2 = (b->pos_m[k] - p->pos_m[k]) / dt;
            dv2 += (v2 - v1) * (v2 - v1);
            s1 += v1 * v1;
            s2 += v2 * v2;
        }
        /* 2 |v2 - v1| / (d1 + dt) <= amax, plus a free turn when learned */
        allow = amax * 0.5 * (d1 + dt);
        if (a->cfg.learned)
            allow += 2.0 * sqrt(fmin(s1, s2));
        if (sqrt(dv2) > allow)
            return ENGINE_EACCEL;
    }
    return 0;
}

static inline int aref_check(const aref_t *a, const engine_waypoint_t *pre,
                             const engine_waypoint_t *p, const engine_waypoint_t *b, double vlim)
{
    return aref_check_g(a, pre, p, b, vlim, 0);
}

/* |implied acceleration| of pre -> p -> b (0 without pre); forward intervals */
static inline double aref_accel_of(const engine_waypoint_t *pre, const engine_waypoint_t *p,
                                   const engine_waypoint_t *b)
{
    double d1, d2, dv2 = 0;

    if (!pre)
        return 0;
    d1 = p->t_s - pre->t_s;
    d2 = b->t_s - p->t_s;
    for (int k = 0; k < ENGINE_AXES; k++) {
        double dv = (b->pos_m[k] - p->pos_m[k]) / d2 - (p->pos_m[k] - pre->pos_m[k]) / d1;
        dv2 += dv * dv;
    }
    return 2.0 * sqrt(dv2) / (d1 + d2);
}

/* chain (len, cost) better than (l2, c2): longer, or as long and smoother */
static inline int aref_better(unsigned len, double cost, unsigned l2, double c2)
{
    return len > l2 || (len == l2 && cost < c2);
}

/*
 * Longest consistent chain that starts at nd[0] (preceded by pre) and whose
 * second waypoint, if any, has an index in jmin..jmax; among the longest,
 * the smoothest (the least largest implied acceleration along it, in *cost).
 * m <= ACCEPT_WINDOW_MAX + 1.  len[i][j], cst[i][j]: the best such chain
 * ending with the step nd[i] -> nd[j] (len 0: none).
 */
static inline unsigned aref_longest(const aref_t *a, const engine_waypoint_t *const *nd, unsigned m,
                                    const engine_waypoint_t *pre, unsigned jmin, unsigned jmax,
                                    double vlim, int gaps_ok, double *cost)
{
    unsigned len[ACCEPT_WINDOW_MAX + 1][ACCEPT_WINDOW_MAX + 1];
    double cst[ACCEPT_WINDOW_MAX + 1][ACCEPT_WINDOW_MAX + 1];
    unsigned best = 1;
    double best_cost = 0;

    memset(len, 0, sizeof len);
    for (unsigned j = jmin; j < m && j <= jmax; j++)
        if (aref_check_g(a, pre, nd[0], nd[j], vlim, gaps_ok) == 0) {
            len[0][j] = 2;
            cst[0][j] = aref_accel_of(pre, nd[0], nd[j]);
        }
    for (unsigned i = 1; i < m; i++)
        for (unsigned h = 0; h < i; h++) {
            if (!len[h][i])
                continue;
            if (aref_better(len[h][i], cst[h][i], best, best_cost)) {
                best = len[h][i];
                best_cost = cst[h][i];
            }
            for (unsigned j = i + 1; j < m; j++) {
                double c;
                if (aref_check_g(a, nd[h], nd[i], nd[j], vlim, gaps_ok))
                    continue;
                c = fmax(cst[h][i], aref_accel_of(nd[h], nd[i], nd[j]));
                if (!len[i][j] || aref_better(len[h][i] + 1, c, len[i][j], cst[i][j])) {
                    len[i][j] = len[h][i] + 1;
                    cst[i][j] = c;
                }
            }
        }
    if (cost)
        *cost = best_cost;
    return best;
}

/* 1 if nd[0..m-1] in order is one consistent chain (nd[0] preceded by pre) */
static inline int aref_chain_all(const aref_t *a, const engine_waypoint_t *const *nd, unsigned m,
                                 const engine_waypoint_t *pre, double vlim, int gaps_ok)
{
    for (unsigned i = 0; i + 1 < m; i++) {
        if (aref_check_g(a, pre, nd[i], nd[i + 1], vlim, gaps_ok))
            return 0;
        pre = nd[i];
    }
    return 1;
}

/* q follows p across a plausible gap: beyond max_gap_s, but not far in time
 * (ACCEPT_FAR_GAP_FACTOR) and covered within the speed limit */
static inline int aref_plausible_gap(const aref_t *a, const engine_waypoint_t *p,
                                     const engine_waypoint_t *q, double vlim)
{
    double dt = q->t_s - p->t_s;
    return dt > a->cfg.max_gap_s && dt <= ACCEPT_FAR_GAP_FACTOR * a->cfg.max_gap_s &&
           (!(vlim > 0) || aref_dist(p, q) <= vlim * dt);
}

/* take the oldest waypoint out of the window into v */
static inline void aref_pop(aref_t *a, accept_verdict_t *v, accept_kind_t kind, int reason)
{
    memset(v, 0, sizeof *v);
    v->kind = kind;
    v->reason = reason;
    v->wp = a->pend[0];
    a->npend--;
    memmove(&a->pend[0], &a->pend[1], a->npend * sizeof a->pend[0]);
    a->have_burst = kind == ACCEPT_DROP && reason == ENGINE_EUNCONFIRMED;
    if (a->have_burst)
        a->burst = v->wp;
    if (kind == ACCEPT_TAKE) {
        a->vhist[a->hnext] = aref_chord_speed(&a->a1, &v->wp);
        a->hnext = (a->hnext + 1) % ACCEPT_HIST;
        if (a->nhist < ACCEPT_HIST)
            a->nhist++;
        a->a0 = a->a1;
        a->have_a0 = 1;
        a->a1 = v->wp;
    } else if (kind == ACCEPT_START) {
        v->gap = a->open && v->wp.t_s - a->a1.t_s > a->cfg.max_gap_s;
        a->open = 1;
        a->have_a0 = 0;
        a->a1 = v->wp;
    }
}

/* lower median of the chord speeds of the last kept intervals (0 if none) */
static inline double aref_recent_median_speed(const aref_t *a)
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
static inline int aref_stale_verdict(const aref_t *a, int full, double vlim)
{
    const engine_waypoint_t *c = &a->pend[0];
    double v_in;

    if (!a->cfg.stale || !a->open || !a->have_a0 || aref_dist(&a->a1, c) > ACCEPT_STALE_POS_M ||
        c->t_s - a->a1.t_s <= AREF_SAME_TIME_S)
        return 0;
    v_in = aref_chord_speed(&a->a0, &a->a1);
    if (v_in < ACCEPT_STALE_MIN_SPEED_M_S)
        return 0;
    for (unsigned i = 1; i < a->npend; i++) {
        const engine_waypoint_t *f = &a->pend[i];
        if (aref_dist(&a->a1, f) <= ACCEPT_STALE_POS_M)
            continue; /* the run goes on */
        if (f->t_s - a->a1.t_s > AREF_SAME_TIME_S && aref_check(a, &a->a0, &a->a1, f, vlim) == 0 &&
            aref_chord_speed(&a->a1, f) >= 0.5 * v_in)
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
    v_in = aref_recent_median_speed(a);
    return v_in >= ACCEPT_STALE_MIN_SPEED_M_S &&
           v_in / (a->a1.t_s - a->a0.t_s) > ACCEPT_STALE_STOP_M_S2;
}

/*
 * 1 if a later waypoint held repeats c's position (a frozen receiver starts
 * repeating after c): c is the one that was stamped when the position was
 * fixed, the repeats are the stale ones, so c is kept over them even where
 * a chain through a repeat would bend the track less (keep the good fix;
 * the repeats then meet stale_verdict with c as the anchor).
 */
static inline int aref_repeated_later(const aref_t *a)
{
    const engine_waypoint_t *c = &a->pend[0];
    if (!a->cfg.stale)
        return 0;
    for (unsigned i = 1; i < a->npend; i++)
        if (aref_dist(c, &a->pend[i]) <= ACCEPT_STALE_POS_M &&
            a->pend[i].t_s - c->t_s > AREF_SAME_TIME_S)
            return 1;
    return 0;
}

/* q repeats the position of c, the oldest waypoint held (profiles with stale
 * detection): a frozen receiver's copy of c, no evidence of its own for or
 * against c (it may follow the anchor only because it is stamped later) */
static inline int aref_repeats_c(const aref_t *a, const engine_waypoint_t *q)
{
    return a->cfg.stale && q != &a->pend[0] && aref_dist(&a->pend[0], q) <= ACCEPT_STALE_POS_M;
}

/*
 * 1 if a waypoint held after c continues the anchor (a chain skipping c
 * exists): c, which does not follow the anchor, is then dropped whatever
 * comes later (the full window's verdict: lo >= 2 and r != 0).
 */
static inline int aref_continues_anchor(const aref_t *a, const engine_waypoint_t *pre, double vlim)
{
    for (unsigned i = 1; i < a->npend; i++)
        if (!aref_repeats_c(a, &a->pend[i]) && aref_check(a, pre, &a->a1, &a->pend[i], vlim) == 0)
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
static inline int aref_taken_past_outliers(const aref_t *a, double vlim)
{
    const engine_waypoint_t *c = &a->pend[0];
    for (unsigned j = 1; j < a->npend; j++) {
        const engine_waypoint_t *q = &a->pend[j];
        if (aref_check_g(a, &a->a1, c, q, vlim, 0) == 0)
            return j >= 2;
        if (!aref_repeats_c(a, q) &&
            aref_check(a, a->have_a0 ? &a->a0 : NULL, &a->a1, q, vlim) == 0)
            return 0; /* q could replace c: the full window compares them */
    }
    return 0;
}

/* accept.c outvotes_held: c continued by a later waypoint held, and the
 * longest chain through c longer than every chain skipping it (and c's
 * later repeats) among the waypoints held */
static inline int aref_outvotes_held(const aref_t *a, const engine_waypoint_t *const *nd,
                                     const engine_waypoint_t *pre, double vlim)
{
    const engine_waypoint_t *nr[ACCEPT_WINDOW_MAX + 1];
    unsigned n = a->npend, m = 0, lw;
    for (unsigned i = 0; i <= n; i++)
        if (i < 2 || !aref_repeats_c(a, nd[i]))
            nr[m++] = nd[i];
    lw = aref_longest(a, nd, n + 1, pre, 1, 1, vlim, 0, NULL);
    return lw >= 3 && lw > aref_longest(a, nr, m, pre, 2, m - 1, vlim, 0, NULL);
}

/*
 * The reason for dropping c, which does not follow the anchor (r: ESPEED or
 * EACCEL from aref_check): ENGINE_EUNCONFIRMED if c is one of a burst of
 * mutually consistent waypoints off the trajectory (a new trajectory that
 * was not confirmed, far in space): c is consistent (within max_gap_s) with
 * the burst waypoint dropped just before it, or with a later waypoint held
 * that does not follow the anchor either, for its speed or acceleration
 * (not a repeat of c, not one beyond a gap).  A lone spike, consistent
 * with nothing held, keeps r.  Only the reason: the verdict is the same.
 */
static inline int aref_drop_reason(const aref_t *a, const engine_waypoint_t *pre, double vlim,
                                   int r)
{
    const engine_waypoint_t *c = &a->pend[0];

    if (r != ENGINE_ESPEED && r != ENGINE_EACCEL)
        return r;
    if (a->have_burst && aref_check_g(a, NULL, &a->burst, c, vlim, 0) == 0)
        return ENGINE_EUNCONFIRMED;
    for (unsigned i = 1; i < a->npend; i++) {
        const engine_waypoint_t *q = &a->pend[i];
        int rq;
        if (aref_repeats_c(a, q) || aref_check_g(a, NULL, c, q, vlim, 0) != 0)
            continue;
        rq = aref_check(a, pre, &a->a1, q, vlim);
        if (rq == ENGINE_ESPEED || rq == ENGINE_EACCEL)
            return ENGINE_EUNCONFIRMED;
    }
    return r;
}

static inline int aref_decide(aref_t *a, int closing, accept_verdict_t *v)
{
    const engine_waypoint_t *nd[ACCEPT_WINDOW_MAX + 1];
    const engine_waypoint_t *pre = a->open && a->have_a0 ? &a->a0 : NULL;
    unsigned n = a->npend, k = a->cfg.confirm;
    int full = closing || n >= a->cfg.window;
    double vlim;
    int r;

    a->full = full;
    if (!n)
        return 0;
    vlim = aref_speed_limit(a);
    if (!a->open) {
        unsigned u, vbest = 0;
        for (unsigned i = 0; i < n; i++)
            nd[i] = &a->pend[i];
        if (n >= k && aref_chain_all(a, nd, n, NULL, vlim, 1)) {
            aref_pop(a, v, ACCEPT_START, 0);
            return 1;
        }
        if (!full)
            return 0;
        u = aref_longest(a, nd, n, NULL, 1, n, vlim, 1, NULL);
        for (unsigned s = 1; s < n; s++) {
            unsigned l = aref_longest(a, nd + s, n - s, NULL, 1, n, vlim, 1, NULL);
            if (l > vbest)
                vbest = l;
        }
        /* nothing to abandon: at the close, the chain there is will do; a
         * waypoint a plausible gap before the next one is a trajectory of
         * its own */
        if ((u >= vbest && (u >= k || closing || vbest <= 1)) ||
            (n >= 2 && aref_plausible_gap(a, nd[0], nd[1], vlim))) {
            aref_pop(a, v, ACCEPT_START, 0);
            return 1;
        }
        r = n >= 2 ? aref_check(a, NULL, nd[0], nd[1], vlim) : 0;
        aref_pop(a, v, ACCEPT_DROP, r ? r : ENGINE_EUNCONFIRMED);
        return 1;
    }

    /* an open trajectory: the anchor a1 (after a0) and the window */
    r = aref_stale_verdict(a, full, vlim);
    if (r < 0)
        return 0;
    if (r > 0) {
        aref_pop(a, v, ACCEPT_DROP, ENGINE_ESTALE);
        return 1;
    }
    nd[0] = &a->a1;
    for (unsigned i = 0; i < n; i++)
        nd[i + 1] = &a->pend[i];
    if (n >= 2 && aref_chain_all(a, nd, n + 1, pre, vlim, 0)) {
        aref_pop(a, v, ACCEPT_TAKE, 0);
        return 1;
    }
    r = aref_check(a, pre, &a->a1, nd[1], vlim);
    if (r == ENGINE_EUNCONFIRMED && a->pend[0].t_s > a->a1.t_s && n >= k &&
        aref_chain_all(a, nd + 1, k, NULL, vlim, 1)) {
        /* after a gap: nothing later can continue the anchor (all are later
         * than c, which is beyond max_gap_s), so k consistent waypoints are
         * all it takes */
        aref_pop(a, v, ACCEPT_START, 0);
        return 1;
    }
    /* verdicts the full window would give, as soon as they are certain: a
     * bad fix must not hold the good ones around it for a whole window (the
     * output draws on its start slack meanwhile) */
    if (r != 0 &&
        !(r == ENGINE_ESPEED && a->cfg.learned && a->nhist < ACCEPT_PACE_CHORDS && !full) &&
        aref_continues_anchor(a, pre, vlim)) {
        aref_pop(a, v, ACCEPT_DROP, aref_drop_reason(a, pre, vlim, r));
        return 1;
    }
    if (r == 0 &&
        (aref_taken_past_outliers(a, vlim) || (n >= 3 && aref_outvotes_held(a, nd, pre, vlim)))) {
        aref_pop(a, v, ACCEPT_TAKE, 0);
        return 1;
    }
    if (!full)
        return 0;
    {
        double cw, co;
        const engine_waypoint_t *nr[ACCEPT_WINDOW_MAX + 1];
        unsigned m = 0;
        /* chains skipping c leave out c's repeats too: a frozen receiver's
         * copies of c, stamped later, would otherwise outvote the fix they
         * copy (a chain through them is as long as the run) */
        for (unsigned i = 0; i <= n; i++)
            if (i < 2 || !aref_repeats_c(a, nd[i]))
                nr[m++] = nd[i];
        unsigned lw = aref_longest(a, nd, n + 1, pre, 1, 1, vlim, 0, &cw); /* through c */
        unsigned lo = aref_longest(a, nr, m, pre, 2, m - 1, vlim, 0, &co); /* skipping c */
        /* keep c unless a longer chain skips it, or one as long and smoother
         * (of two fixes that cannot both be right, the one that bends the
         * track less) */
        if (r == 0 && (!aref_better(lo, co, lw, cw) || (lw >= lo && aref_repeated_later(a)))) {
            aref_pop(a, v, ACCEPT_TAKE, 0);
            return 1;
        }
        if (lo < 2) {
            /* nothing held continues the anchor: re-anchor on k consistent */
            unsigned u = aref_longest(a, nd + 1, n, NULL, 1, n, vlim, 1, NULL);
            /* at the close, what is left confirms itself if it is all one
             * chain that the anchor reaches within the speed limit */
            if (u >= k || aref_plausible_gap(a, &a->a1, nd[1], vlim) ||
                (closing && u == n && aref_check_g(a, NULL, &a->a1, nd[1], vlim, 1) == 0)) {
                aref_pop(a, v, ACCEPT_START, 0);
                return 1;
            }
        }
        if (r != 0)
            r = aref_drop_reason(a, pre, vlim, r);
        else if (n >= 2)
            r = aref_check(a, &a->a1, nd[1], nd[2], vlim);
        if (r == 0 && lo == lw)
            r = ENGINE_EACCEL; /* as long a chain bends less without it */
        aref_pop(a, v, ACCEPT_DROP, r ? r : ENGINE_EUNCONFIRMED);
        return 1;
    }
}

#endif
