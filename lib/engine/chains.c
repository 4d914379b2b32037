/* chains.c - the acceptance policy's chain search (see accept.h): the
 * longest consistent chains from the anchor through c, the oldest waypoint
 * held, and skipping it (lw, lo), and of the longest the smoothest (their
 * costs cw, co: the least largest implied acceleration along them).
 *
 * The lengths (accept_longest_len): the most waypoints after a step on a
 * consistent chain depends on the waypoints after the step alone, so it is
 * kept by slot while verdicts take waypoints off the front of the window
 * and the anchor moves onto one of them, and brought up to date as a
 * waypoint arrives (it adds one to a step's count exactly where a chain
 * one longer ends at it).  A verdict then reads lw and lo off the
 * anchor's steps: O(window) where longest_both searched the window anew,
 * O(window^3), for every verdict.
 *
 * The costs (accept_longest_cost) matter only where lw == lo (which of two
 * as long chains bends the track less): then over the longest chains
 * alone.  Where a cost is NaN (NaN or overflowing input), the order in
 * which longest_both compared the chains decides, so it does
 * (accept_longest_both: its dynamic programme over the steps, the best
 * chain ending with each step, kept and extended as waypoints arrive).
 *
 * A pair's chord and velocity and a triple's acceleration test are
 * computed once while their waypoints are held (accept_int.h pair(),
 * triple()).  Every value is the same expression of the same waypoints as
 * before, so every verdict is the same (tests/unit/test_accept_same.c
 * drives this and the policy before it, tests/helpers/accept_prev/).
 */
#include <string.h>

#include "accept_int.h"

const accept_pair_t *accept_pair_new(accept_t *a, unsigned x, unsigned y)
{
    unsigned ix = pair_index(x, y);
    accept_pair_t *q = &a->pair[ix];
    pair_of(&a->wp[x], &a->wp[y], q);
    q->c = fabs(q->c);
    a->pknown |= (uint64_t)1 << ix;
    return q;
}

int accept_triple_new(accept_t *a, unsigned x, unsigned p, unsigned y)
{
    const accept_pair_t *q1 = pair(a, x, p), *q2 = pair(a, p, y);
    double d1 = a->wp[p].t_s - a->wp[x].t_s, dt = a->wp[y].t_s - a->wp[p].t_s;
    int ok = !(a->cfg.max_accel_m_s2 > 0 && accel_test(a, q1, q2, d1, dt));
    uint16_t bit = (uint16_t)(1u << x);
    a->tknown[p][y] |= bit;
    a->tok[p][y] = (uint16_t)(ok ? a->tok[p][y] | bit : a->tok[p][y] & ~bit);
    return ok;
}

/*
 * accept_longest_both: the dynamic programme of the policy before, over
 * the steps between the nodes (the anchor, then the window): the best chain
 * ending with each step i -> j, from the best ones ending with a step
 * h -> i whose triple h -> i -> j passes.  A cell reads only the nodes up
 * to j, so a search over the same nodes and more (the same anchor and
 * waypoint before it, no stamp changed, the speed limit passing and failing
 * the same steps) keeps the cells it had and computes those of the steps
 * into the new nodes alone, each in the order the whole search takes them:
 * every cell is the same bit for bit, NaN and ties included.  A triple is
 * judged only where it can change a cell.
 */

/* chain (len, cost) better than (l2, c2): longer, or as long and smoother */
static int better(unsigned len, double cost, unsigned l2, double c2)
{
    return len > l2 || (len == l2 && cost < c2);
}

/* a chain (lh, ch) extended by one step, whatever its cost, can be better
 * than (lij, cij), the cell it would replace (lh 0: no chain; lij 0: empty):
 * its cost is max_of(ch, c) >= ch, or c where ch is NaN */
static int may_improve(unsigned lh, double ch, unsigned lij, double cij)
{
    if (!lh)
        return 0;
    if (!lij || lh + 1 > lij)
        return 1;
    return lh + 1 == lij && !isnan(cij) && (isnan(ch) || ch < cij);
}

/* step x -> y (slots): 0 if its time test fails (or a gap), 1 if its speed
 * test does, 2 if both pass */
static unsigned char step_of(accept_t *a, unsigned x, unsigned y, double vlim)
{
    double dt = a->wp[y].t_s - a->wp[x].t_s;
    int gap = 0;
    if (time_test(a, dt, 0, &gap))
        return 0;
    return vlim > 0 && pair(a, x, y)->d > vlim * dt ? 1 : 2;
}

/* how many of the nodes of the last search nd[0..m-1] starts with, unchanged
 * and searched alike (the same pre, every step's tests the same with vlim):
 * all of them, or 0 */
static unsigned kept_nodes(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre,
                           double vlim)
{
    accept_search_t *s = &a->search;

    if (!s->m || s->m > m || s->pre != pre || (pre != NO_SLOT && s->pre_since != a->since[pre]))
        return 0;
    for (unsigned i = 0; i < s->m; i++)
        if (s->nd[i] != nd[i] || s->since[i] != a->since[nd[i]])
            return 0;
    if (memcmp(&s->vlim, &vlim, sizeof vlim) != 0) {
        for (unsigned j = 1; j < s->m; j++)
            for (unsigned i = 0; i < j; i++)
                if (s->step[i][j] && step_of(a, nd[i], nd[j], vlim) != s->step[i][j])
                    return 0;
        s->vlim = vlim;
    }
    return s->m;
}

void accept_longest_both(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre,
                         double vlim, unsigned best[2], double cost[2])
{
    accept_search_t *s = &a->search;
    unsigned from = kept_nodes(a, nd, m, pre, vlim);
    int acc = a->cfg.max_accel_m_s2 > 0;

    if (!from) {
        memset(s->len, 0, sizeof s->len);
        s->best[0] = s->best[1] = 1;
        s->cost[0] = s->cost[1] = 0;
        s->pre = (unsigned char)pre;
        s->pre_since = pre != NO_SLOT ? a->since[pre] : 0;
        s->vlim = vlim;
    }
    for (unsigned j = from; j < m; j++) {
        s->nd[j] = nd[j];
        s->since[j] = a->since[nd[j]];
        for (unsigned i = 0; i < j; i++)
            s->step[i][j] = step_of(a, nd[i], nd[j], vlim);
    }
    /* the first steps, from the anchor: judge() with pre */
    for (unsigned j = from ? from : 1; j < m; j++) {
        double c = 0;
        if (s->step[0][j] != 2 || (pre != NO_SLOT && !triple(a, pre, nd[0], nd[j], &c) && acc))
            continue;
        s->len[j >= 2][0][j] = 2;
        s->cst[j >= 2][0][j] = c;
    }
    for (unsigned i = 1; i < m; i++)
        for (unsigned h = 0; h < i; h++) {
            unsigned char *lh = &s->len[0][h][i], *l2 = &s->len[1][h][i];
            if (!*lh && !*l2)
                continue;
            if (i >= from) /* a chain not seen before: the best so far, in order */
                for (unsigned k = 0; k < 2; k++)
                    if (s->len[k][h][i] &&
                        better(s->len[k][h][i], s->cst[k][h][i], s->best[k], s->cost[k])) {
                        s->best[k] = s->len[k][h][i];
                        s->cost[k] = s->cst[k][h][i];
                    }
            for (unsigned j = i + 1 > from ? i + 1 : from; j < m; j++) {
                double c;
                if (s->step[i][j] != 2 ||
                    (!may_improve(*lh, s->cst[0][h][i], s->len[0][i][j], s->cst[0][i][j]) &&
                     !may_improve(*l2, s->cst[1][h][i], s->len[1][i][j], s->cst[1][i][j])))
                    continue;
                if (!triple(a, nd[h], nd[i], nd[j], &c) && acc)
                    continue;
                for (unsigned k = 0; k < 2; k++) {
                    double ck;
                    if (!s->len[k][h][i])
                        continue;
                    ck = max_of(s->cst[k][h][i], c);
                    if (!s->len[k][i][j] ||
                        better(s->len[k][h][i] + 1u, ck, s->len[k][i][j], s->cst[k][i][j])) {
                        s->len[k][i][j] = (unsigned char)(s->len[k][h][i] + 1);
                        s->cst[k][i][j] = ck;
                    }
                }
            }
        }
    s->m = m;
    best[0] = s->best[0], best[1] = s->best[1];
    cost[0] = s->cost[0], cost[1] = s->cost[1];
}

/*
 * The lengths alone (accept_longest_len): more[x][y], the most nodes after y
 * on a consistent chain x -> y -> ..., reads the nodes after y alone (the
 * steps from y on and the triples x -> y -> k, y -> k -> l, ...), so it
 * stays true while nodes leave the front of the list (a verdict, a repeat
 * taken into a run) and the anchor moves onto a node of it.  A node x
 * appended at the end adds one to more[i][j] exactly where a chain from
 * i -> j of one more node ends at x: i -> j -> x itself (more was 0), or
 * i -> j -> k -> ... where more[j][k] is one less and grows too (a chain
 * ending at x, less x, is a chain: it was at most as long as more).  Then
 * lw = 2 + more[anchor][c] and lo the largest 2 + more[anchor][q] over the
 * later q, each where the anchor's own test of the step passes.
 */

/* node pos of the list is slot s, unchanged since (each change of a slot is
 * its own tick of accept_t.clock, so the tick names the slot too) */
static int same_node(const accept_t *a, unsigned pos, unsigned s)
{
    return a->reach.since[pos] == a->since[s];
}

/* the triple x -> p -> y passes (slots; no acceleration limit: all do) */
static int triple_ok(accept_t *a, unsigned x, unsigned p, unsigned y, int acc)
{
    return !acc || triple_passes(a, x, p, y);
}

/* more[nd i][nd j] from the nodes after j (positions of the list) */
static unsigned char more_of(accept_t *a, unsigned i, unsigned j, int acc)
{
    accept_reach_t *r = &a->reach;
    unsigned x = r->nd[i], p = r->nd[j], best = 0;
    for (unsigned k = j + 1; k < r->m; k++) {
        unsigned y = r->nd[k], v = r->more[p][y] + 1u;
        if (r->step[p][y] == 2 && v > best && triple_ok(a, x, p, y, acc))
            best = v;
    }
    return (unsigned char)best;
}

/* the list's node at pos becomes slot s (its steps from the window's
 * earlier nodes judged with vlim) */
static void set_node(accept_t *a, unsigned pos, unsigned s, double vlim)
{
    accept_reach_t *r = &a->reach;
    r->nd[pos] = (unsigned char)s;
    r->since[pos] = a->since[s];
    for (unsigned i = 1; i < pos; i++)
        r->step[r->nd[i]][s] = step_of(a, r->nd[i], s, vlim);
}

/* passing()'s triples of the slots u not known yet, computed (the step
 * p -> y once) */
static __attribute__((noinline)) void passing_new(accept_t *a, unsigned u, unsigned p, unsigned y)
{
    const accept_pair_t *q2 = pair(a, p, y);
    double dt = a->wp[y].t_s - a->wp[p].t_s;
    unsigned ok = 0;
    for (unsigned m = u; m; m &= m - 1) {
        unsigned x = (unsigned)__builtin_ctz(m);
        const accept_pair_t *q1 = pair(a, x, p);
        double d1 = a->wp[p].t_s - a->wp[x].t_s;
        ok |= (unsigned)!accel_test(a, q1, q2, d1, dt) << x;
    }
    a->tknown[p][y] = (uint16_t)(a->tknown[p][y] | u);
    a->tok[p][y] = (uint16_t)((a->tok[p][y] & ~u) | ok);
}

/* the slots x of the set e whose triple x -> p -> y passes (those not
 * known yet computed) */
static inline unsigned passing(accept_t *a, unsigned e, unsigned p, unsigned y, int acc)
{
    unsigned u;
    if (!acc)
        return e;
    u = e & ~(unsigned)a->tknown[p][y];
    if (__builtin_expect(u != 0, 0))
        passing_new(a, u, p, y);
    return e & a->tok[p][y];
}

/* more[x][y] set to v (by with it) */
static void set_more(accept_reach_t *r, unsigned x, unsigned y, unsigned v)
{
    uint16_t keep = (uint16_t) ~(1u << x);
    for (unsigned u = 0; u <= ACCEPT_NODES; u++)
        r->by[y][u] &= keep;
    r->more[x][y] = (unsigned char)v;
    r->by[y][v] = (uint16_t)(r->by[y][v] | 1u << x);
}

/* slot s appended to the list: more brought up to date (above).  By rows j
 * from the last, the slots i < j whose more[nd i][nd j] grows (g), from the
 * steps j -> k whose more grew already (grew[nd j]: their positions k); a
 * more[j][k] that grew is its old value plus one, the value a more[i][j]
 * grows from */
static void append_node(accept_t *a, unsigned s, double vlim, int acc)
{
    accept_reach_t *r = &a->reach;
    unsigned x = r->m, before[ACCEPT_NODES + 1];
    uint16_t grew[ACCEPT_SLOTS] = {0}; /* by slot p: the positions k whose more[p][nd k] grew */

    set_node(a, x, s, vlim);
    before[0] = 0;
    for (unsigned i = 0; i < x; i++)
        before[i + 1] = before[i] | 1u << r->nd[i];
    for (unsigned j = x - 1; j >= 1; j--) {
        unsigned p = r->nd[j], g = 0, e;
        const uint16_t *byp = r->by[p];
        if (r->step[p][s] == 2 && (e = byp[0] & before[j]) != 0) /* i -> j -> x, more was 0 */
            g = passing(a, e, p, s, acc);
        for (unsigned m = grew[p]; m; m &= m - 1) { /* i -> j -> k ... x */
            unsigned y = r->nd[__builtin_ctz(m)];
            if (r->step[p][y] != 2)
                continue;
            e = byp[r->more[p][y]] & before[j] & ~g;
            if (e)
                g |= passing(a, e, p, y, acc);
        }
        for (unsigned m = g; m; m &= m - 1) {
            unsigned i = (unsigned)__builtin_ctz(m), v = r->more[i][p];
            r->more[i][p] = (unsigned char)(v + 1);
            r->by[p][v] = (uint16_t)(r->by[p][v] & ~(1u << i));
            r->by[p][v + 1] = (uint16_t)(r->by[p][v + 1] | 1u << i);
            grew[i] = (uint16_t)(grew[i] | 1u << j);
        }
    }
    for (unsigned i = 0; i < x; i++)
        r->more[r->nd[i]][s] = 0;
    memset(r->by[s], 0, sizeof r->by[s]);
    r->by[s][0] = (uint16_t)before[x];
    r->m = x + 1;
}

/* how many waypoints of the window nd[1..m-1] the list ends with, in order
 * and unchanged (0: none, or the list must be built anew), *anchor 1 if
 * the list holds nd[0] before them; the steps checked with vlim */
static unsigned kept_tail(accept_t *a, const unsigned char *nd, unsigned m, double vlim,
                          int *anchor)
{
    accept_reach_t *r = &a->reach;
    unsigned p = 1, w;

    *anchor = 0;
    while (p < r->m && !same_node(a, p, nd[1]))
        p++;
    w = r->m - p;
    if (!w || w > m - 1)
        return 0;
    for (unsigned i = 1; i < w; i++)
        if (!same_node(a, p + i, nd[1 + i]))
            return 0;
    for (unsigned q = 0; q < p; q++)
        *anchor |= same_node(a, q, nd[0]);
    if (memcmp(&r->vlim, &vlim, sizeof vlim) != 0) {
        for (unsigned j = p + 1; j < r->m; j++)
            for (unsigned i = p; i < j; i++) {
                unsigned x = r->nd[i], y = r->nd[j];
                if (r->step[x][y] && step_of(a, x, y, vlim) != r->step[x][y])
                    return 0;
            }
        r->vlim = vlim;
    }
    return w;
}

void accept_longest_len(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre, double vlim,
                        unsigned len[2])
{
    accept_reach_t *r = &a->reach;
    int acc = a->cfg.max_accel_m_s2 > 0, anchor = 0;
    unsigned w = m >= 2 ? kept_tail(a, nd, m, vlim, &anchor) : 0;

    if (w) { /* the anchor, the window's nodes kept, then the new ones */
        unsigned p = r->m - w;
        memmove(r->nd + 1, r->nd + p, w);
        memmove(r->since + 1, r->since + p, w * sizeof r->since[0]);
        r->nd[0] = nd[0];
        r->since[0] = a->since[nd[0]];
        r->m = 1 + w;
        if (!anchor) /* a new anchor: its more from the nodes after it */
            for (unsigned j = w; j >= 1; j--)
                set_more(r, nd[0], r->nd[j], more_of(a, 0, j, acc));
        for (unsigned j = 1 + w; j < m; j++)
            append_node(a, nd[j], vlim, acc);
    } else { /* anew */
        r->vlim = vlim;
        r->m = m;
        for (unsigned j = 0; j < m; j++)
            set_node(a, j, nd[j], vlim);
        for (unsigned j = m - 1; j >= 1; j--) {
            memset(r->by[nd[j]], 0, sizeof r->by[nd[j]]);
            for (unsigned i = 0; i < j; i++) {
                unsigned v = more_of(a, i, j, acc);
                r->more[nd[i]][nd[j]] = (unsigned char)v;
                r->by[nd[j]][v] = (uint16_t)(r->by[nd[j]][v] | 1u << nd[i]);
            }
        }
    }
    len[0] = len[1] = 1;
    for (unsigned j = 1; j < m; j++) {
        unsigned v = 2u + r->more[nd[0]][nd[j]];
        if ((j >= 2 && v <= len[1]) || judge(a, pre, nd[0], nd[j], vlim, 0, NULL))
            continue;
        len[j >= 2] = v;
    }
}

/*
 * The costs (accept_longest_cost): of the chains of the longest length, the
 * least largest implied acceleration, which is what longest_both's cells
 * hold where no cost is NaN (a cell keeps the longest chain, and of those
 * the smoothest: max and min of numbers, in any order).  The longest chains
 * are those whose every step k after i -> j has more[j][k] = more[i][j] - 1:
 * their costs, memoised per step, from the end.
 */
typedef struct {
    unsigned char done[ACCEPT_NODES][ACCEPT_NODES];
    double cost[ACCEPT_NODES][ACCEPT_NODES];
    int nan; /* a NaN cost was met: the search as a whole decides */
} tight_t;

/* the least cost after step i -> j (positions) of the longest chains, 0 if
 * none continues it */
static double tight_cost(accept_t *a, tight_t *t, unsigned i, unsigned j, int acc)
{
    accept_reach_t *r = &a->reach;
    unsigned x = r->nd[i], p = r->nd[j], v = r->more[x][p];
    double best = 0;
    int found = 0;

    if (!v)
        return 0;
    if (t->done[i][j])
        return t->cost[i][j];
    for (unsigned k = j + 1; k < r->m; k++) {
        unsigned y = r->nd[k];
        double c, ck;
        if (r->more[p][y] + 1u != v || r->step[p][y] != 2 || (acc && !triple_passes(a, x, p, y)))
            continue;
        c = triple_cost(a, x, p, y);
        ck = tight_cost(a, t, j, k, acc);
        if (isnan(c))
            t->nan = 1;
        ck = c > ck ? c : ck;
        if (!found || ck < best)
            best = ck, found = 1;
    }
    t->done[i][j] = 1;
    t->cost[i][j] = best;
    return best;
}

int accept_longest_cost(accept_t *a, const unsigned char *nd, unsigned m, unsigned pre, double vlim,
                        const unsigned len[2], double cost[2])
{
    accept_reach_t *r = &a->reach;
    int acc = a->cfg.max_accel_m_s2 > 0;
    int found[2] = {0, 0};
    tight_t t;

    if (r->m != m || memcmp(r->nd, nd, m) != 0)
        return 0; /* not the lengths of these nodes: the search as a whole */
    memset(t.done, 0, sizeof t.done);
    t.nan = 0;
    cost[0] = cost[1] = 0;
    for (unsigned j = 1; j < m; j++) {
        unsigned k = j >= 2;
        double c, ct;
        if (len[k] < 2 || 2u + r->more[nd[0]][nd[j]] != len[k] ||
            judge(a, pre, nd[0], nd[j], vlim, 0, &c))
            continue;
        ct = tight_cost(a, &t, 0, j, acc);
        if (isnan(c))
            t.nan = 1;
        ct = c > ct ? c : ct;
        if (!found[k] || ct < cost[k])
            cost[k] = ct, found[k] = 1;
    }
    return !t.nan;
}
