/* accept_int.h - the pairwise tests of the acceptance policy, shared by
 * accept.c and retime.c (lib/engine; not installed).  Moved here from
 * accept.c unchanged (issue 27): every verdict is the same bit for bit
 * (tests/unit/test_accept.c test_same_verdicts_as_reference). */
#ifndef TRAJD_ACCEPT_INT_H
#define TRAJD_ACCEPT_INT_H

#include <math.h>
#include <stdint.h>

#include "accept.h"

/* Timestamps closer than this are "the same time" (seconds), as in engine_input.c. */
#define ACCEPT_SAME_TIME_S 1e-9
/* Positions closer than this at the same time are a duplicate (metres). */
#define ACCEPT_SAME_POS_M 1e-9
/* No slot (no waypoint before p in a test). */
#define NO_SLOT 0xffu

/* fmax and fmin (NaN: the other), inline instead of libm's calls; of two
 * zeros either (the callers compare non-negative values) */
static inline double max_of(double x, double y)
{
    return isnan(x) ? y : (y > x ? y : x);
}

static inline double min_of(double x, double y)
{
    return isnan(x) ? y : (y < x ? y : x);
}

/* what the tests need of p -> b: dist(), the velocity and its norm as the
 * acceleration test writes them ((b - p) / dt per axis; |v| for the free
 * turn's sqrt(fmin(s1, s2)), which is fmin of the norms: sqrt is monotonic) */
static inline void pair_of(const engine_waypoint_t *p, const engine_waypoint_t *b, accept_pair_t *q)
{
    double dt = b->t_s - p->t_s, d2 = 0, s = 0;
    for (int k = 0; k < ENGINE_AXES; k++) {
        double dk = b->pos_m[k] - p->pos_m[k];
        d2 += dk * dk;
        q->v[k] = dk / dt;
        s += q->v[k] * q->v[k];
    }
    q->d = sqrt(d2);
    q->vn = sqrt(s);
    q->c = q->d / dt;
}

/* index of the pair of slots x != y in accept_t.pair: either order */
static inline unsigned pair_index(unsigned x, unsigned y)
{
    unsigned lo = x < y ? x : y, hi = x < y ? y : x;
    return hi * (hi - 1) / 2 + lo;
}

/* the bits of accept_t.known of the pairs with slot s */
static inline uint64_t slot_pairs(unsigned s)
{
    uint64_t m = 0;
    for (unsigned x = 0; x < s; x++) /* pairs (x, s): s (s - 1) / 2 + x */
        m |= (uint64_t)1 << (s * (s - 1) / 2 + x);
    for (unsigned y = s + 1; y < ACCEPT_SLOTS; y++) /* pairs (s, y) */
        m |= (uint64_t)1 << (y * (y - 1) / 2 + s);
    return m;
}

/* the pair x -> y (slots, y offered after x), computed on first use.  Kept
 * once for both orders: y -> x has the same v, d and vn bit for bit (both
 * differences change sign, exactly) and c of the other sign, so c is kept
 * as |c| (a chord speed is only asked of a later y) */
static inline const accept_pair_t *pair(accept_t *a, unsigned x, unsigned y)
{
    unsigned ix = pair_index(x, y);
    accept_pair_t *q = &a->pair[ix];
    if (!(a->known >> ix & 1u)) {
        pair_of(&a->wp[x], &a->wp[y], q);
        q->c = fabs(q->c);
        a->known |= (uint64_t)1 << ix;
    }
    return q;
}

static inline double pair_dist(accept_t *a, unsigned x, unsigned y)
{
    return pair(a, x, y)->d;
}

/* chord speed x -> y; only for y later than x */
static inline double chord_speed(accept_t *a, unsigned x, unsigned y)
{
    return pair(a, x, y)->c;
}

/* the time order of b after p (dt = t_b - t_p): 0, or EBACKWARDS, ESAMETIME,
 * EUNCONFIRMED for an interval above max_gap_s unless gaps_ok; *gap: above */
static inline int time_test(const accept_t *a, double dt, int gaps_ok, int *gap)
{
    if (dt < -ACCEPT_SAME_TIME_S)
        return ENGINE_EBACKWARDS;
    if (dt <= ACCEPT_SAME_TIME_S)
        return ENGINE_ESAMETIME;
    *gap = dt > a->cfg.max_gap_s;
    return *gap && !gaps_ok ? ENGINE_EUNCONFIRMED : 0;
}

/* |v2 - v1| across p (q1: pre -> p, q2: p -> b) */
static inline double dv_norm(const accept_pair_t *q1, const accept_pair_t *q2)
{
    double dv2 = 0;
    for (int k = 0; k < ENGINE_AXES; k++)
        dv2 += (q2->v[k] - q1->v[k]) * (q2->v[k] - q1->v[k]);
    return sqrt(dv2);
}

/* the acceleration test of pre -> p -> b (d1, dt: the two intervals, dvn:
 * dv_norm): 2 |v2 - v1| / (d1 + dt) <= amax, plus a free turn when learned */
static inline int accel_test(const accept_t *a, const accept_pair_t *q1, const accept_pair_t *q2,
                             double d1, double dt, double dvn)
{
    double allow = a->cfg.max_accel_m_s2 * 0.5 * (d1 + dt);
    if (a->cfg.learned) {
        /* a turn is free, a change of speed along the track is not */
        if ((a->cfg.rules & ACCEPT_RULE_VECTOR) && fabs(q2->vn - q1->vn) > allow)
            return ENGINE_EACCEL;
        allow += 2.0 * min_of(q1->vn, q2->vn);
    }
    return dvn > allow ? ENGINE_EACCEL : 0;
}

/*
 * The test of b following p (slots; pre: the slot before p, or NO_SLOT), as
 * accept_check, and with gaps_ok an interval above max_gap_s passes too
 * (time order and speed only: an acceleration over a gap means nothing).
 * That is what "mutually consistent" means for waypoints that confirm a new
 * trajectory: a sparse or slipped track (every interval a gap) still
 * confirms itself, a lone waypoint at t = 1e9 among waypoints at t ~ 100
 * does not (they are earlier than it).  With cost, a passed test also gives
 * the implied acceleration of pre -> p -> b, gap or not (0 without pre).
 */
static inline int judge(accept_t *a, unsigned pre, unsigned p, unsigned b, double vlim, int gaps_ok,
                        double *cost)
{
    double dt = a->wp[b].t_s - a->wp[p].t_s, d1, dvn;
    int gap = 0, r = time_test(a, dt, gaps_ok, &gap), acc;
    const accept_pair_t *q1, *q2;

    if (r)
        return r;
    q2 = pair(a, p, b);
    if (vlim > 0 && q2->d > vlim * dt)
        return ENGINE_ESPEED;
    acc = a->cfg.max_accel_m_s2 > 0 && !gap;
    if (pre == NO_SLOT || (!acc && !cost)) {
        if (cost)
            *cost = 0;
        return 0;
    }
    /* pre is earlier than p by more than 1 ns: it was checked so */
    q1 = pair(a, pre, p);
    d1 = a->wp[p].t_s - a->wp[pre].t_s;
    dvn = dv_norm(q1, q2);
    if (acc && accel_test(a, q1, q2, d1, dt, dvn))
        return ENGINE_EACCEL;
    if (cost)
        *cost = 2.0 * dvn / (d1 + dt);
    return 0;
}

static inline int check(accept_t *a, unsigned pre, unsigned p, unsigned b, double vlim, int gaps_ok)
{
    return judge(a, pre, p, b, vlim, gaps_ok, NULL);
}

/* accept_check's test, between slots: an interval above max_gap_s fails */
static inline int check0(accept_t *a, unsigned pre, unsigned p, unsigned b, double vlim)
{
    return judge(a, pre, p, b, vlim, 0, NULL);
}

/* accept.c: the stamp re-estimate of c (retime.c), for drop() */
double accept_retime(accept_t *a, unsigned pre, double vlim);
/* accept.c: the smoothing re-estimate of c about to be kept (retime.c) */
double accept_retime_soft(accept_t *a, unsigned pre, double vlim);
/* accept.c: the better of the two for a fix about to be refused (retime.c) */
double accept_retime_either(accept_t *a, unsigned pre, double vlim);

#endif
