/* stops.c - a run of repeats is a stop or stale (ACCEPT_RULE_STOPS, issue
 * 27); see accept.h.
 *
 * A machine at rest reports the same position again and again; a frozen
 * receiver does too, while the object it tracks moves on.  The repeats of
 * the anchor (the last waypoint kept) within ACCEPT_STALE_POS_M leave the
 * window as they come and wait here as a run (their times and seqs: the
 * position is the anchor's), so a run of any length costs one slot.  Its
 * verdict:
 *   - stale (every repeat refused, ENGINE_ESTALE) if the object was moving
 *     into the anchor (profiles with stale detection) and the next waypoint
 *     with a new position follows the anchor as if it had kept moving (the
 *     anchor's tests pass, and its chord speed from the anchor is at least
 *     half the pace into it): an AIS re-reception, a frozen fix;
 *   - a stop otherwise: the trajectory ends at rest on the anchor (the
 *     first repeat's verdict, ACCEPT_HALT, kept as dwell), the repeats are
 *     kept as the dwell (ACCEPT_DWELL), and the last one starts a new
 *     trajectory from rest (ACCEPT_START, the first waypoint of the next
 *     solve).  The curve so comes to rest where the object stood, and the
 *     C2 solve is split there; every other knot keeps it.
 * A repeat is stale only if the object is known to move: with no stale
 * detection (profile machine), or if the object was not moving into the
 * anchor (slower than ACCEPT_STALE_MIN_SPEED_M_S, or a trajectory's first
 * waypoint), the run is a stop at once, and the output comes to rest on
 * the anchor without waiting.  Else a run as long as the window (at least
 * ACCEPT_STOP_RUN repeats) with no new position makes it a stop if stopping dead from the recent pace within the
 * anchor's interval takes at most ACCEPT_STALE_STOP_M_S2, 1 g (a standing
 * object is data: waiting for its next new position, the output ran out of
 * curve short of the stop and stood in underrun as long as the object stood:
 * a walk); an object that could not have stopped so waits for the next new
 * position (a boat at 3.8 m/s and 5 Hz whose receiver froze:
 * tests/oracle/test_fault_injection.py)
 * (the output, out of curve, slows down to rest meanwhile as for any late
 * waypoint), or the close (a stop), or ACCEPT_RUN_MAX repeats (stale).
 */
#include "accept.h"

#include <string.h>

#include "accept_int.h"

#define SAME_TIME_S 1e-9

/* slot q repeats the anchor's position, later than t_last (the distance
 * from the pair cache: accept_dist's, bit for bit) */
static int repeats_anchor(accept_t *a, unsigned q, double t_last)
{
    return a->wp[q].t_s - t_last > SAME_TIME_S && pair_dist(a, a->a1, q) <= ACCEPT_STALE_POS_M;
}

static double last_time(const accept_t *a)
{
    return a->run_n > a->run_head ? a->run_t[a->run_n - 1] : a->wp[a->a1].t_s;
}

/* the repeats of the anchor at the head of the window into the run */
static void migrate(accept_t *a)
{
    while (a->npend && a->run_n < ACCEPT_RUN_MAX && repeats_anchor(a, a->pend[0], last_time(a))) {
        const engine_waypoint_t *w = &a->wp[a->pend[0]];
        a->run_t[a->run_n] = w->t_s;
        a->run_seq[a->run_n++] = w->seq;
        a->npend--;
        memmove(a->pend, a->pend + 1, a->npend);
    }
}

/* the object, moving at its recent pace into the anchor, cannot have stopped
 * dead within the anchor's interval (profiles with stale detection) */
static int cannot_stop(const accept_t *a)
{
    double v, h;
    if (!a->cfg.stale || !a->have_a0)
        return 0;
    v = accept_recent_median(a);
    h = a->wp[a->a1].t_s - a->wp[a->a0].t_s;
    return v >= ACCEPT_STALE_MIN_SPEED_M_S && h > 0 && v / h > ACCEPT_STOP_MAX_M_S2;
}

/* the object, moving at its recent pace into the anchor, could have stopped
 * dead within the anchor's interval at no more than ACCEPT_STALE_STOP_M_S2
 * (1 g): a walker, a machine; a boat at 3.8 m/s and 5 Hz (19 m/s^2) is more
 * likely a frozen receiver, whose next new position tells */
static int stops_gently(const accept_t *a)
{
    double v, h;
    if (!a->have_a0)
        return 1;
    v = accept_recent_median(a);
    h = a->wp[a->a1].t_s - a->wp[a->a0].t_s;
    return h > 0 && v / h <= ACCEPT_STALE_STOP_M_S2;
}

/* the object was moving into the anchor (profiles with stale detection):
 * its repeats may be stale, and only the next new position tells */
static int moving(const accept_t *a)
{
    const engine_waypoint_t *p0, *p1 = &a->wp[a->a1];
    if (!a->cfg.stale || !a->have_a0)
        return 0;
    p0 = &a->wp[a->a0];
    return accept_dist(p0, p1) >= ACCEPT_STALE_MIN_SPEED_M_S * (p1->t_s - p0->t_s);
}

/* f (the first new position after the run) follows the anchor as if the
 * object had kept moving across the repeats: they were stale */
static int kept_moving(accept_t *a, const engine_waypoint_t *f)
{
    const engine_waypoint_t *p0, *p1 = &a->wp[a->a1];
    double v_in, dt;
    if (!a->cfg.stale || !a->have_a0)
        return 0;
    p0 = &a->wp[a->a0];
    v_in = accept_dist(p0, p1) / (p1->t_s - p0->t_s);
    dt = f->t_s - p1->t_s;
    if (!(v_in > 0) || !(dt > SAME_TIME_S))
        return 0;
    return accept_check(a, p0, p1, f, accept_speed_limit(a)) == 0 &&
           accept_dist(p1, f) / dt >= 0.5 * v_in;
}

static void emit(accept_t *a, accept_verdict_t *v, int kind, int reason)
{
    unsigned i = a->run_head++;
    memset(v, 0, sizeof *v);
    v->kind = kind;
    v->reason = reason;
    v->wp = a->wp[a->a1];
    v->wp.t_s = a->run_t[i];
    v->wp.seq = a->run_seq[i];
}

int accept_run_decide(accept_t *a, int closing, accept_verdict_t *v)
{
    int has_f, more, last;

    if (!a->open)
        return -1;
    if (a->run_verdict == 0 || a->run_verdict == 2)
        migrate(a);
    if (a->run_head == a->run_n) {
        a->run_n = a->run_head = 0;
        a->run_verdict = 0;
        return -1;
    }
    /* a new position after the run (else the window holds more repeats:
     * the run outgrew ACCEPT_RUN_MAX) */
    has_f = a->npend && !repeats_anchor(a, a->pend[0], a->run_t[a->run_n - 1]);
    more = a->npend && !has_f;
    if (!a->run_verdict) {
        if (a->standing)
            a->run_verdict = 2;
        else if (has_f)
            a->run_verdict = kept_moving(a, &a->wp[a->pend[0]]) ? 1 : 2;
        else if (closing)
            a->run_verdict = 2;
        else if (more)
            a->run_verdict = cannot_stop(a) ? 1 : 2;
        else if (!moving(a))
            a->run_verdict = 2; /* stale only if the object is known to move */
        else if (a->run_n >= ACCEPT_STOP_RUN && a->run_n >= a->cfg.window && stops_gently(a))
            a->run_verdict = 2;
        else
            return 0;
    }
    if (a->run_verdict == 1) {
        emit(a, v, ACCEPT_DROP, ENGINE_ESTALE);
        return 1;
    }
    last = a->run_head + 1 == a->run_n;
    if (last && !has_f && !more && !closing)
        return 0; /* the last repeat so far may start the next trajectory */
    if (last && has_f) {
        /* the object moves again: from rest, here */
        int halted = a->standing;
        emit(a, v, ACCEPT_START, 0);
        v->stop = halted ? ACCEPT_STOP_AFTER : ACCEPT_STOP_ONE;
        accept_anchor_at(a, &v->wp);
        a->standing = 0;
        a->run_n = a->run_head = 0;
        a->run_verdict = 0;
        return 1;
    }
    emit(a, v, a->standing ? ACCEPT_DWELL : ACCEPT_HALT, 0);
    a->standing = 1;
    return 1;
}

/* Count a verdict's share of engine_status (stops, stop_fixes, retimed). */
static void accept_count(engine_status_t *st, const accept_verdict_t *v)
{
    if (v->kind == ACCEPT_HALT || v->kind == ACCEPT_DWELL) {
        st->accepted++; /* kept: the dwell of a stop */
        st->stop_fixes++;
    }
    if (v->kind == ACCEPT_HALT || (v->kind == ACCEPT_START && v->stop == ACCEPT_STOP_ONE))
        st->stops++;
    if (v->kind == ACCEPT_TAKE && (v->shift_s > 0 || v->shift_s < 0)) {
        double s = v->shift_s < 0 ? -v->shift_s : v->shift_s;
        st->retimed++;
        if (s > st->retime_max_s)
            st->retime_max_s = s;
    }
}

int accept_decide_counted(accept_t *a, int closing, accept_verdict_t *v, engine_status_t *st)
{
    while (accept_decide(a, closing, v)) {
        accept_count(st, v);
        if (v->kind == ACCEPT_DWELL)
            continue;
        if (v->kind == ACCEPT_HALT) {
            v->kind = ACCEPT_START;
            v->stop = ACCEPT_STOP_HALT;
        }
        return 1;
    }
    return 0;
}
