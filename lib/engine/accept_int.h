/* accept_int.h - the pairwise tests of the acceptance policy, shared by
 * accept.c and retime.c (lib/engine; not installed).  Moved here from
 * accept.c unchanged (issue 27): every verdict is the same bit for bit
 * (tests/unit/test_accept.c test_same_verdicts_as_reference). */
#ifndef TRAJD_ACCEPT_INT_H
#define TRAJD_ACCEPT_INT_H

#include <math.h>
#include <stdint.h>
#include <string.h>

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

/* index of the pair of slots x != y in accept_t.pair: either order
 * (max (max - 1) / 2 + min) */
static inline unsigned pair_index(unsigned x, unsigned y)
{
    /* rows of 16: the index a shift and an add */
    static const unsigned char ix[ACCEPT_SLOTS][16] = {
        {0, 0, 1, 3, 6, 10, 15, 21, 28, 36, 45},     {0, 0, 2, 4, 7, 11, 16, 22, 29, 37, 46},
        {1, 2, 0, 5, 8, 12, 17, 23, 30, 38, 47},     {3, 4, 5, 0, 9, 13, 18, 24, 31, 39, 48},
        {6, 7, 8, 9, 0, 14, 19, 25, 32, 40, 49},     {10, 11, 12, 13, 14, 0, 20, 26, 33, 41, 50},
        {15, 16, 17, 18, 19, 20, 0, 27, 34, 42, 51}, {21, 22, 23, 24, 25, 26, 27, 0, 35, 43, 52},
        {28, 29, 30, 31, 32, 33, 34, 35, 0, 44, 53}, {36, 37, 38, 39, 40, 41, 42, 43, 44, 0, 54},
        {45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 0},
    };
    return ix[x][y];
}

/* slot s holds a new waypoint, or its stamp changed: its pairs and triples,
 * and a chain search over it, are no longer known (accept_t.since).  With
 * newest, s holds the waypoint offered last, and the triples x -> p -> y
 * that start at s keep their bits: none is asked before slots p and y are
 * given waypoints offered after it (a triple follows the order of offers:
 * the slot before the anchor, the anchor, the window; but for
 * accept_anchor_at's anchor, not newest), which clears their rows and
 * columns here */
static inline void accept_forget_as(accept_t *a, unsigned s, int newest)
{
    /* the bits of accept_t.pknown of the pairs with slot s */
    static const uint64_t with[ACCEPT_SLOTS] = {
        0x0020101020844bull, 0x00402020410895ull, 0x00804040821126ull, 0x01008081042238ull,
        0x020101020843c0ull, 0x04020204107c00ull, 0x080404081f8000ull, 0x1008080fe00000ull,
        0x20100ff0000000ull, 0x401ff000000000ull, 0x7fe00000000000ull,
    };
    uint16_t keep = (uint16_t) ~(1u << s);
    a->since[s] = ++a->clock;
    a->pknown &= ~with[s];
    if (!newest)
        for (unsigned p = 0; p < ACCEPT_SLOTS; p++)
            for (unsigned y = 0; y < 16; y++)
                a->tknown[p][y] &= keep;
    memset(a->tknown[s], 0, sizeof a->tknown[s]);
    for (unsigned x = 0; x < ACCEPT_SLOTS; x++)
        a->tknown[x][s] = 0;
}

static inline void accept_forget(accept_t *a, unsigned s)
{
    accept_forget_as(a, s, 0);
}

/* chains.c: pair() and triple() computing what they do not know yet */
const accept_pair_t *accept_pair_new(accept_t *a, unsigned x, unsigned y);
int accept_triple_new(accept_t *a, unsigned x, unsigned p, unsigned y);

/* the pair x -> y (slots, y offered after x), computed on first use.  Kept
 * once for both orders: y -> x has the same v, d and vn bit for bit (both
 * differences change sign, exactly) and c of the other sign, so c is kept
 * as |c| (a chord speed is only asked of a later y) */
static inline const accept_pair_t *pair(accept_t *a, unsigned x, unsigned y)
{
    unsigned ix = pair_index(x, y);
    if (__builtin_expect(a->pknown >> ix & 1u, 1))
        return &a->pair[ix];
    return accept_pair_new(a, x, y);
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

/* the acceleration test of pre -> p -> b (d1, dt: the two intervals):
 * 2 |v2 - v1| / (d1 + dt) <= amax, plus a free turn when learned (|v2 - v1|,
 * dv_norm, computed only where the change of speed passes) */
static inline int accel_test(const accept_t *a, const accept_pair_t *q1, const accept_pair_t *q2,
                             double d1, double dt)
{
    double allow = a->cfg.max_accel_m_s2 * 0.5 * (d1 + dt);
    if (a->cfg.learned) {
        /* a turn is free, a change of speed along the track is not */
        if ((a->cfg.rules & ACCEPT_RULE_VECTOR) && fabs(q2->vn - q1->vn) > allow)
            return ENGINE_EACCEL;
        allow += 2.0 * min_of(q1->vn, q2->vn);
    }
    return dv_norm(q1, q2) > allow ? ENGINE_EACCEL : 0;
}

/* the acceleration test of x -> p -> y (slots, in time order, no gap
 * between p and y), computed on first use and kept while the three are
 * held: 1 if it passes (or there is no acceleration limit), *cost the
 * implied acceleration 2 |v2 - v1| / (dt1 + dt2), as judge() has them (the
 * cost computed again: asked far less often than the test) */
static inline int triple(accept_t *a, unsigned x, unsigned p, unsigned y, double *cost)
{
    const accept_pair_t *q1 = pair(a, x, p), *q2 = pair(a, p, y);
    int ok = __builtin_expect(a->tknown[p][y] >> x & 1u, 1) ? (int)(a->tok[p][y] >> x & 1u)
                                                            : accept_triple_new(a, x, p, y);
    double d1 = a->wp[p].t_s - a->wp[x].t_s, dt = a->wp[y].t_s - a->wp[p].t_s;
    *cost = 2.0 * dv_norm(q1, q2) / (d1 + dt);
    return ok;
}

/* triple()'s cost alone */
static inline double triple_cost(accept_t *a, unsigned x, unsigned p, unsigned y)
{
    const accept_pair_t *q1 = pair(a, x, p), *q2 = pair(a, p, y);
    double d1 = a->wp[p].t_s - a->wp[x].t_s, dt = a->wp[y].t_s - a->wp[p].t_s;
    return 2.0 * dv_norm(q1, q2) / (d1 + dt);
}

/* triple() without its cost */
static inline int triple_passes(accept_t *a, unsigned x, unsigned p, unsigned y)
{
    return __builtin_expect(a->tknown[p][y] >> x & 1u, 1) ? (int)(a->tok[p][y] >> x & 1u)
                                                          : accept_triple_new(a, x, p, y);
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
    double dt = a->wp[b].t_s - a->wp[p].t_s;
    int gap = 0, r = time_test(a, dt, gaps_ok, &gap), acc;

    if (r)
        return r;
    if (vlim > 0 && pair(a, p, b)->d > vlim * dt)
        return ENGINE_ESPEED;
    acc = a->cfg.max_accel_m_s2 > 0 && !gap;
    if (pre == NO_SLOT || (!acc && !cost)) {
        if (cost)
            *cost = 0;
        return 0;
    }
    /* pre is earlier than p by more than 1 ns: it was checked so (over a
     * gap the acceleration test is not asked, its cost is) */
    if (!cost)
        return acc && !triple_passes(a, pre, p, b) ? ENGINE_EACCEL : 0;
    if (acc && !triple_passes(a, pre, p, b))
        return ENGINE_EACCEL;
    *cost = triple_cost(a, pre, p, b);
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

/* chains.c: longest() from nd[0] through nd[1] (best[0], cost[0]) and
 * skipping it (best[1], cost[1]), between slots, no gaps (accept.c) */
void accept_longest_both(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre,
                         double vlim, unsigned best[2], double cost[2]);
/* chains.c: the lengths of those chains alone (len[0], len[1]), as
 * accept_longest_both gives them */
void accept_longest_len(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre, double vlim,
                        unsigned len[2]);
/* chains.c: their costs (cost[0], cost[1]) given their lengths len from
 * accept_longest_len on the same nd, pre and vlim just before; 0 if a cost
 * is NaN (then accept_longest_both's are the costs) */
int accept_longest_cost(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre, double vlim,
                        const unsigned len[2], double cost[2]);
/* accept.c: the stamp re-estimate of c (retime.c), for drop() */
double accept_retime(accept_t *a, unsigned pre, double vlim);
/* accept.c: the smoothing re-estimate of c about to be kept (retime.c) */
double accept_retime_soft(accept_t *a, unsigned pre, double vlim);
/* accept.c: a late fix that ties with the next one, re-stamped (retime.c) */
double accept_retime_late(accept_t *a, unsigned pre, double vlim);
/* accept.c: the better of the two for a fix about to be refused (retime.c) */
double accept_retime_either(accept_t *a, unsigned pre, double vlim);

#endif
