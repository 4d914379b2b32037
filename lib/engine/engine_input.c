/*
 * engine_input.c - the input stage: engine_push and engine_finish.  A
 * waypoint is validated (finite, within range), counted against the
 * capacity (EFULL), offered to the acceptance policy (accept.h), and each
 * verdict carried out: a waypoint kept goes on to the solver stage
 * (engine_solve.c) as the next node of the trajectory being received; a gap,
 * re-anchor or stop closes it and opens the next; a refusal is counted and
 * kept for engine_rejection_next.  It owns engine_input_t (engine_int.h: the
 * trajectory being received, its last two waypoints, the acceptance policy,
 * the rejections kept) and notes the object's motion for the transfers
 * (transfer_motion_note).
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "accept.h"
#include "lsq.h"
#include "catchup.h"
#include "silence.h"
#include "transfer.h"

/* Timestamps closer than this are "the same time" (seconds). */
#define ENGINE_SAME_TIME_S 1e-9

/* Positions closer than this at the same time are a duplicate (metres). */
#define ENGINE_SAME_POS_M 1e-9

/* |t| above this is absurd for a track clock (about 31700 years). */
#define ENGINE_T_ABS_MAX_S 1e12

size_t input_buffered(const engine_t *e)
{
    /* the C2 local methods queue three pieces per interval */
    size_t n = e->queue.len + (size_t)e->solve.pend; /* built, held for the next */
    size_t q = e->local >= 3 ? (n + 2) / 3 : n;
    return q + (size_t)(e->solve.nodes - e->solve.seg_next) +
           (e->smooth ? (size_t)lsq_smooth_pending(&e->solve.sm) : 0) +
           accept_pending(&e->in.policy) + e->pick.n;
}

/* Close the input trajectory: its last segments and END entry (the solver). */
static int close_input(engine_t *e)
{
    if (!e->in.open)
        return 0;
    e->in.open = 0;
    return solve_close(e);
}

static void open_input(engine_t *e, const engine_waypoint_t *wp)
{
    e->in.open = 1;
    e->st.tracks++;
    e->out.finished = 0;
    memcpy(e->in.first_r, wp->pos_m, sizeof(e->in.first_r));
    solve_open(e);
}

/*
 * Acceleration implied by the previous two waypoints and this one (dt after
 * the last): the change of mean velocity over the two intervals divided by
 * half their sum, i.e. the second divided difference times 2.  It is what
 * the C2 curve through the three has to produce somewhere near the middle
 * one, whatever the end conditions; a timestamp off by a fraction of the
 * interval makes it large because both intervals around the bad stamp are
 * divided into the same distances.  O(1), no state beyond the two.
 */
static double implied_accel(const engine_t *e, const engine_waypoint_t *wp, double dt)
{
    double d1 = e->in.last_t - e->in.prev_t, a2 = 0;

    for (int k = 0; k < AX; k++) {
        double v1 = (e->in.last_r[k] - e->in.prev_r[k]) / d1;
        double v2 = (wp->pos_m[k] - e->in.last_r[k]) / dt;
        double a = 2.0 * (v2 - v1) / (d1 + dt);
        a2 += a * a;
    }
    return sqrt(a2);
}

static int reject(engine_t *e, int code)
{
    if (code == ENGINE_EFULL) {
        /* flow control, not bad data: its own counter (rejected means refused) */
        e->st.full++;
        return -code;
    }
    e->st.rejected++;
    e->st.rejected_by[code]++;
    return -code;
}

/* Count a refused waypoint and keep it for engine_rejection_next. */
static int reject_wp(engine_t *e, int code, const engine_waypoint_t *wp)
{
    engine_rejection_t *r;

    if (e->in.rej_len == ENGINE_REJECTIONS_KEPT) {
        /* the oldest unread one makes room (its count stays in rejected_by) */
        e->in.rej_head = (e->in.rej_head + 1) % ENGINE_REJECTIONS_KEPT;
        e->in.rej_len--;
        e->st.rejections_unreported++;
    }
    r = &e->in.rej[(e->in.rej_head + e->in.rej_len) % ENGINE_REJECTIONS_KEPT];
    e->in.rej_len++;
    r->seq = wp->seq;
    r->reason = code;
    r->t_s = wp->t_s;
    memcpy(r->pos_m, wp->pos_m, sizeof r->pos_m);
    return reject(e, code);
}

int engine_rejection_next(engine_t *e, engine_rejection_t *r)
{
    if (!e->in.rej_len)
        return 0;
    *r = e->in.rej[e->in.rej_head];
    e->in.rej_head = (e->in.rej_head + 1) % ENGINE_REJECTIONS_KEPT;
    e->in.rej_len--;
    return 1;
}

/* Param uniform: the ratio of the last kept waypoint's two intervals h1, h2
 * (its velocity steps by it: ENGINE_UNIFORM_RATIO_WARN). */
static void note_uniform(engine_t *e, double h1, double h2)
{
    double r = h1 > h2 ? h1 / h2 : h2 / h1;
    if (!(r >= 1.0))
        return; /* cannot happen: kept intervals are positive */
    if (r > e->st.uniform_ratio_max) {
        e->st.uniform_ratio_max = r;
        e->st.uniform_ratio_t_s = e->in.last_t;
    }
    if (r > ENGINE_UNIFORM_RATIO_WARN)
        e->st.uniform_irregular++;
}

/* Append a waypoint the acceptance policy kept to the trajectory being received. */
static int keep(engine_t *e, const engine_waypoint_t *wp)
{
    int rc;

    if (!e->in.open) {
        open_input(e, wp);
        e->in.have_prev = 0;
    } else {
        double d1 = wp->t_s - e->in.last_t, v2 = 0;
        for (int k = 0; k < AX; k++)
            v2 += (wp->pos_m[k] - e->in.last_r[k]) * (wp->pos_m[k] - e->in.last_r[k]);
        transfer_motion_note(&e->xfer.motion, sqrt(v2) / d1,
                             e->in.have_prev ? implied_accel(e, wp, d1) : 0.0);
        if (e->in.have_prev && e->cfg.param == ENGINE_PARAM_UNIFORM)
            note_uniform(e, e->in.last_t - e->in.prev_t, d1);
        e->in.have_prev = 1;
        e->in.prev_t = e->in.last_t;
        memcpy(e->in.prev_r, e->in.last_r, sizeof(e->in.prev_r));
    }
    e->in.last_t = wp->t_s;
    memcpy(e->in.last_r, wp->pos_m, sizeof(e->in.last_r));
    if (e->smooth) {
        lsq_smooth_push(&e->solve.sm, wp->t_s, wp->pos_m);
        rc = solve_drain(e);
    } else {
        rc = solve_add_node(e, wp->t_s, wp->pos_m, wp->has_vel == 1 ? wp->vel_m_s : NULL);
    }
    if (rc == 0 && e->mult && e->solve.nodes == 1) {
        /* the first point twice more */
        if ((rc = solve_add_node(e, wp->t_s, wp->pos_m, NULL)) == 0)
            rc = solve_add_node(e, wp->t_s, wp->pos_m, NULL);
    }
    if (rc < 0) {
        /* cannot happen with finite data (diagonally dominant systems);
         * end the trajectory with what is queued rather than stream garbage */
        e->in.open = 0;
        solve_abort(e);
        accept_close(&e->in.policy);
        return reject_wp(e, -rc, wp);
    }
    e->st.accepted++;
    e->st.last_seq = wp->seq;
    return 0;
}

/* Carry out every verdict the acceptance policy can give now. */
static int judge(engine_t *e, int closing)
{
    accept_verdict_t v;
    int rc = 0;

    while (accept_decide_counted(&e->in.policy, closing, &v, &e->st)) { /* stops.c */
        switch (v.kind) {
        case ACCEPT_TAKE:
            if (keep(e, &v.wp) < 0)
                rc = -ENGINE_ENUMERIC;
            break;
        case ACCEPT_START:
            e->in.gap_s = 0;
            if (e->in.open) {
                if (v.gap) {
                    e->st.gaps++;
                    e->in.gap_s = v.wp.t_s - e->in.last_t;
                } else if (!v.stop) {
                    e->st.reanchors++;
                    e->st.reanchor_t_s = v.wp.t_s; /* what its log line tells */
                    e->st.reanchor_from_t_s = e->in.last_t;
                    e->st.reanchor_seq = v.wp.seq;
                }
                if (close_input(e) < 0)
                    rc = -ENGINE_ENUMERIC;
            } else if (e->st.tracks > 0 && v.wp.t_s - e->in.last_t > e->cfg.max_gap_s) {
                /* after a trajectory a silence (or a finish) closed: the gap
                 * is still the one the transfer crosses (counted at its
                 * arrival, silence.c) */
                e->in.gap_s = v.wp.t_s - e->in.last_t;
            }
            if (v.stop != ACCEPT_STOP_HALT && keep(e, &v.wp) < 0)
                rc = -ENGINE_ENUMERIC;
            break;
        case ACCEPT_DROP: reject_wp(e, v.reason, &v.wp); break;
        }
    }
    return rc;
}

int engine_waypoint_check(const engine_config_t *cfg, const engine_waypoint_t *wp)
{
    for (int k = 0; k < AX; k++)
        if (!isfinite(wp->pos_m[k]))
            return -ENGINE_ENOTFINITE;
    if (!isfinite(wp->t_s))
        return -ENGINE_ENOTFINITE;
    if (wp->has_vel == 1) {
        /* the source's velocity (the local methods): finite, and no faster
         * than the speed limit in force (without one: max_abs_m per second) */
        double v2 = 0, lim = engine_config_max_speed(cfg);
        for (int k = 0; k < AX; k++) {
            if (!isfinite(wp->vel_m_s[k]))
                return -ENGINE_ENOTFINITE;
            v2 += wp->vel_m_s[k] * wp->vel_m_s[k];
        }
        if (!(lim > 0))
            lim = cfg->max_abs_m;
        if (sqrt(v2) > lim)
            return -ENGINE_ESPEED;
    }
    for (int k = 0; k < AX; k++)
        if (fabs(wp->pos_m[k]) > cfg->max_abs_m)
            return -ENGINE_ERANGE;
    if (fabs(wp->t_s) > ENGINE_T_ABS_MAX_S)
        return -ENGINE_ERANGE;
    return 0;
}

/* A waypoint that passed the checks to the acceptance, and its verdicts. */
static int offer(engine_t *e, const engine_waypoint_t *wp)
{
    int rc = accept_offer(&e->in.policy, wp);
    if (rc == ENGINE_DUPLICATE) {
        e->st.duplicates++;
        return ENGINE_DUPLICATE;
    }
    if (rc < 0)
        return reject(e, -rc); /* cannot happen: judge() empties the window below */
    return judge(e, 0);
}

int engine_push(engine_t *e, const engine_waypoint_t *wp)
{
    int rc = engine_waypoint_check(&e->cfg, wp);

    if (rc < 0)
        return reject_wp(e, -rc, wp);
    /* room for this waypoint (and for the copies MULTIPLE adds) */
    if (input_buffered(e) + 1 + (e->mult ? 4 : 0) > e->cfg.capacity) {
        if (engine_repeat_refused(&e->in.full, wp))
            return -ENGINE_EFULL; /* the same waypoint offered again: counted once */
        return reject(e, ENGINE_EFULL);
    }
    engine_repeat_taken(&e->in.full);
    engine_silence_push(e, wp);  /* issue 26: its arrival (silence.h) */
    engine_lag_push(e, wp->t_s); /* ... and a sample of the sender's time (catchup.h) */
    if (e->pick.pending) {       /* held until the lookahead is picked (engine_pick) */
        if (!e->pick.n)
            e->pick.first_ns = INT64_MIN; /* (the next tick's) */
        e->pick.wp[e->pick.n++] = *wp;
        if (e->pick.n < ENGINE_PICK_N)
            return 0;
        engine_pick_flush(e);
        return 0; /* (each held one's verdict is counted as it is given) */
    }
    return offer(e, wp);
}

/*
 * delay_s set (issue 31: "max_lookahead = 1 and 2, or the matching
 * delay_s, pick them"): max_lookahead is the most lookahead the solver may
 * take; of the lookaheads up to it, the longest whose D (delay.h) fits
 * within delay_s at the input's interval, read from its first
 * ENGINE_PICK_N waypoints (the longest of their intervals), and with the
 * stop reserve at the speed limit in force (as engine_delay_check sizes it:
 * a delay_s is accepted only where that fits), is taken: a fragment size,
 * or a local method where none fits (engine_config_resolve).  Those
 * waypoints are held for it (their
 * arrivals, samples of the sender's time and of its silence, noted as they
 * came) and then offered in turn; where none fits, or on one clock (the
 * clock's D), the configuration stays as it was.  Done once, before any
 * waypoint is judged, so that nothing the setup makes anew holds anything.
 */
static void engine_pick(engine_t *e)
{
    double h = 0.0;
    for (unsigned i = 1; i < e->pick.n; i++)
        h = fmax(h, e->pick.wp[i].t_s - e->pick.wp[i - 1].t_s);
    if (!(h > 0) || e->clk.on)
        return;
    engine_config_t c = e->pick.asked, r;
    c.max_lookahead = engine_lookahead_for_delay(&c, h, 0.0);
    /* (the candidate resolved in engine_lookahead_for_delay; the asked
     * configuration passed engine_config_check in engine_new) */
    if (c.max_lookahead == e->pick.asked.max_lookahead || engine_config_resolve(&c, &r) < 0)
        return;
    (void)engine_setup(e, &r); /* out of memory: as it was */
}

void engine_pick_flush(engine_t *e)
{
    if (!e->pick.pending)
        return;
    e->pick.pending = 0;
    engine_pick(e);
    unsigned n = e->pick.n;
    e->pick.n = 0;
    for (unsigned i = 0; i < n; i++)
        (void)offer(e, &e->pick.wp[i]); /* counted there, as at a push */
}

int engine_finish(engine_t *e)
{
    engine_pick_flush(e);
    if (e->out.und_pending)
        play_underrun_counted(e); /* the output ran short before the end was told */
    int rj = judge(e, 1);
    int rc = close_input(e);

    accept_close(&e->in.policy);
    if (!e->queue.len && e->out.mode == OUT_HOLD && !e->in.open)
        e->out.finished = 1; /* nothing left to stream: the input is over */
    return rc < 0 ? rc : rj < 0 ? rj : 0;
}
