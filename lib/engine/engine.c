/*
 * engine.c - waypoints in, fixed-rate setpoints out; see engine.h.
 *
 * The engine in stages, each in its file, joined by a queue of finished
 * segments (their state: engine_int.h):
 *
 *   configuration (engine_settings.c): the settings, their defaults and the
 *          resolution of fragment, overlap and lookahead;
 *   input  (engine_input.c: engine_push / engine_finish): validation and
 *          the acceptance policy (accept.h) of each waypoint;
 *   solver (engine_solve.c): nodes, the fragment window (frag.h) and the
 *          cubic per axis (fdiff_seg_t) of every segment whose control
 *          values are final, queued; a closed trajectory queues an END;
 *   play-out (engine_tick.c: engine_tick): walks the queued cubics with the
 *          forward-difference stepper (fdiff.h) on the period grid; waits,
 *          underruns, finishes (a trajectory's start and its ends at rest:
 *          engine_play.c); its time scaling (engine_scale.c) and its
 *          transfers to a new trajectory's start (engine_xfer.c);
 *          its start waits until the output will stand the play-out delay
 *          D behind the input (delay_run.c, delay.h), and a silence of the
 *          input ends the trajectory so that its tail plays out (silence.c);
 *   commands (engine_cmd.c): stop, clear, halt, override, clock, position.
 *
 * This file creates and frees an engine, reports its status and computes
 * a curve offline.  All memory is taken in engine_new; push, tick, finish,
 * clear never allocate.
 */
#include "engine.h"
#include "engine_int.h"
#include "silence.h"
#include "catchup.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accept.h"
#include "frag.h"
#include "lsq.h"
#include "transfer.h"

int engine_setup(engine_t *e, const engine_config_t *cfg)
{
    size_t ring = 16;
    unsigned la = engine_cfg_lookahead(cfg);
    /* the slack must fit the buffer: capacity >= lookahead + F + 8 (checked) */
    unsigned room = cfg->capacity - (la + cfg->fragment + 8);
    unsigned more = ENGINE_SLACK_AUTO_MAX - engine_cfg_slack_min(cfg);
    if (room < more)
        more = room;
    /* nodes from the oldest unbuilt segment (lags the newest by the lookahead
     * plus the copies of MULTIPLE) to the newest, with margin */
    while (ring < 2 * ((size_t)cfg->fragment + la + more) + 16)
        ring *= 2;
    /* each accepted waypoint yields at most one segment (the C2 local
     * methods three), each trajectory one END: twice (four times) the
     * capacity always fits */
    size_t qcap = (engine_cfg_local(cfg) >= 3 ? 4 : 2) * (size_t)cfg->capacity + 8;
    double *nt = calloc(ring, sizeof(double)), *nr = calloc(ring * AX, sizeof(double));
    double *nv = calloc(ring * AX, sizeof(double)), *na = calloc(ring * AX, sizeof(double));
    unsigned char *nk = calloc(ring, 1);
    frag_t *fw = frag_new(cfg->fragment, cfg->overlap, engine_cfg_frag_delta(cfg), ring);
    qent_t *qe = calloc(qcap, sizeof(qent_t));
    size_t *qs = calloc(qcap, sizeof(size_t));
    if (!nt || !nr || !nv || !na || !nk || !fw || !qe || !qs) {
        free(nt), free(nr), free(nv), free(na), free(nk), frag_free(fw), free(qe), free(qs);
        return -1;
    }
    free(e->solve.node_t), free(e->solve.node_r), free(e->solve.node_v), free(e->solve.node_a);
    free(e->solve.node_vk), frag_free(e->solve.fw), free(e->queue.ent), free(e->queue.slow);
    e->solve.node_t = nt, e->solve.node_r = nr, e->solve.node_v = nv, e->solve.node_a = na;
    e->solve.node_vk = nk, e->solve.fw = fw, e->queue.ent = qe, e->queue.slow = qs;
    e->solve.ring = ring;
    e->queue.cap = qcap;

    e->cfg = *cfg;
    e->lookahead = la;
    e->la_steady = engine_cfg_steady_lookahead(cfg) + engine_cfg_smooth_extra(cfg);
    e->slack_auto = cfg->start_slack == ENGINE_AUTO;
    e->slack_more = more;
    e->pstar = engine_cfg_uses_pstar(cfg);
    e->held = cfg->ends == ENGINE_ENDS_HELD || cfg->ends == ENGINE_ENDS_MULTIPLE;
    e->mult = cfg->ends == ENGINE_ENDS_MULTIPLE;
    e->smooth = cfg->method == ENGINE_METHOD_SMOOTH;
    e->axis_lim = solve_cfg_axis_limited(cfg);
    e->axis_jerk = engine_cfg_axis_jerk(cfg);
    e->axis_accel = solve_cfg_axis_accel(cfg);
    e->local = engine_cfg_local(cfg);
    accept_config_t ac = {
        .max_speed_m_s = engine_config_max_speed(cfg),
        .max_accel_m_s2 = engine_config_max_accel(cfg),
        .max_gap_s = cfg->max_gap_s,
        .learned = cfg->profile == ENGINE_PROFILE_AUTO,
        .stale = cfg->profile != ENGINE_PROFILE_MACHINE && cfg->profile != ENGINE_PROFILE_NONE,
        .window = cfg->start_slack < ACCEPT_WINDOW_MAX ? cfg->start_slack : ACCEPT_WINDOW_MAX,
        .confirm = cfg->confirm,
        .rules = ACCEPT_RULES_OF(cfg->profile == ENGINE_PROFILE_NONE), /* accept.h */
        .at_arrival = engine_cfg_accept_lag(cfg) == 0, /* max_lookahead 1 (issue 31) */
    };
    if (ac.window < ac.confirm)
        ac.window = ac.confirm;
    accept_init(&e->in.policy, &ac);
    e->st.lookahead = la;
    return 0;
}

engine_t *engine_new(const engine_config_t *cfg_in, int *err)
{
    engine_t *e;
    engine_config_t r;
    const engine_config_t *cfg = &r;

    if (engine_config_check_resolve(cfg_in, &r, NULL) < 0) {
        if (err)
            *err = ENGINE_ECONFIG;
        return NULL;
    }
    e = calloc(1, sizeof(*e));
    if (!e || engine_setup(e, cfg) < 0)
        goto nomem;
    /* delay_s set: its lookahead is picked from the first waypoints
     * (engine_input.c engine_pick) */
    e->pick.pending = cfg_in->delay_s > 0 && !e->smooth;
    e->pick.asked = *cfg_in;
    if (e->smooth) {
        e->solve.sm_mem = calloc(lsq_smooth_mem_len(cfg->smooth_window, cfg->smooth_ctrl, AX),
                                 sizeof(double));
        if (!e->solve.sm_mem || lsq_smooth_init(&e->solve.sm, cfg->smooth_window, cfg->smooth_ctrl,
                                                AX, e->solve.sm_mem) < 0)
            goto nomem;
    }
    e->period_s = (double)cfg->period_ns * 1e-9;
    e->period_lo = cfg->period_ns - cfg->period_ns / 2;
    e->xfer.cfg.speed_m_s = cfg->transfer_speed_m_s;
    e->xfer.cfg.accel_m_s2 = cfg->transfer_accel_m_s2;
    e->xfer.cfg.max_s = cfg->max_gap_s;
    e->xfer.cfg.vmax_m_s = engine_config_max_speed(cfg);
    if (cfg->cap_speed_m_s > 0) { /* the caller's cap: transfers keep within it too */
        if (!(e->xfer.cfg.vmax_m_s > 0) || e->xfer.cfg.vmax_m_s > cfg->cap_speed_m_s)
            e->xfer.cfg.vmax_m_s = cfg->cap_speed_m_s;
        if (e->xfer.cfg.speed_m_s > cfg->cap_speed_m_s)
            e->xfer.cfg.speed_m_s = cfg->cap_speed_m_s;
    }
    e->xfer.cfg.period_s = e->period_s;
    transfer_motion_reset(&e->xfer.motion);
    engine_status_underrun_none(&e->st);
    e->scale.ts.rate = 1.0;
    e->scale.stop_dv = -1.0; /* set by each scaled tick */
    e->scale.override = 1.0;
    e->clk.catchup = CATCHUP_DEFAULT; /* relative time too (catchup.h) */
    if (err)
        *err = 0;
    return e;
nomem:
    engine_free(e);
    if (err)
        *err = ENGINE_ENOMEM;
    return NULL;
}

void engine_free(engine_t *e)
{
    if (!e)
        return;
    free(e->solve.node_t);
    free(e->solve.node_r);
    free(e->solve.node_v);
    free(e->solve.node_a);
    free(e->solve.node_vk);
    frag_free(e->solve.fw);
    free(e->queue.ent);
    free(e->queue.slow);
    free(e->solve.sm_mem);
    free(e);
}

void engine_status(const engine_t *e, engine_status_t *st)
{
    size_t b = input_buffered(e);

    *st = e->st;
    st->state = play_state(e);
    st->buffered = (uint32_t)b;
    st->free = b >= e->cfg.capacity ? 0 : (uint32_t)(e->cfg.capacity - b);
    st->lookahead = e->lookahead + e->slack_learn;
    st->stalled = (uint32_t)play_stalled(e);
    /* (only what a stalled engine waits for: not worked out on every tick) */
    st->silence_at_ns = st->stalled ? engine_silence_at_ns(e) : INT64_MAX;
    st->rate = e->out.mode == OUT_HOLD ? 0.0 : e->scale.ts.rate;
    st->override = e->scale.override;
    st->judging = accept_pending(&e->in.policy);
    st->ahead_s = 0;
    if (e->queue.len) {
        const qent_t *tail = queue_at(e, e->queue.len - 1);
        double ahead = tail->t1_s - e->out.t;
        st->ahead_s = ahead > 0 ? ahead : 0;
    }
}

static inline void prefetch_range(const void *p, size_t n)
{
    const char *b = p;
    for (size_t k = 0; k < n; k += 64)
        __builtin_prefetch(b + k, 0, 3);
}

void engine_prefetch(const engine_t *e)
{
    prefetch_range(&e->cfg, sizeof e->cfg);
    prefetch_range(&e->in, 64);
    __builtin_prefetch(&e->in.policy.npend, 0, 3);
    __builtin_prefetch(&e->in.policy.run_n, 0, 3);
    __builtin_prefetch(&e->in.rej_len, 0, 3);
    prefetch_range(&e->solve, 128);
    /* queue, out, scale, delay, sil, lag, pick's head and st lie in a row */
    prefetch_range(&e->queue, (size_t)((const char *)(&e->st + 1) - (const char *)&e->queue));
}

void engine_status_add_counts(engine_status_t *st, const engine_status_t *more)
{
#define ADD(f) st->f += more->f
    ADD(accepted), ADD(dropped), ADD(unjudged), ADD(duplicates), ADD(rejected);
    for (int i = 0; i < ENGINE_ERROR_COUNT; i++)
        ADD(rejected_by[i]);
    ADD(underruns), ADD(underrun_ticks), ADD(skipped_ticks), ADD(gaps), ADD(tracks);
    ADD(setpoints), ADD(full), ADD(hard_stops), ADD(reanchors), ADD(transfers);
    ADD(transfer_s), ADD(transfers_capped), ADD(rejections_unreported), ADD(uniform_irregular);
    ADD(stops), ADD(stop_fixes), ADD(retimed), ADD(silent_ends), ADD(catchups);
    ADD(axis_lost_s), ADD(axis_slowed), ADD(axis_lag_stops), ADD(delay_grown);
    ADD(reserve_slowed), ADD(transfers_moving), ADD(axis_beyond), ADD(limits_lost_s);
    ADD(limits_slowed);
#undef ADD
    if (more->uniform_ratio_max > st->uniform_ratio_max) {
        st->uniform_ratio_max = more->uniform_ratio_max;
        st->uniform_ratio_t_s = more->uniform_ratio_t_s;
    }
    if (more->retime_max_s > st->retime_max_s)
        st->retime_max_s = more->retime_max_s;
}

int engine_axis_lag_over(engine_t *e)
{
    int over = e->axis_lag_over;
    e->axis_lag_over = 0;
    return over;
}

/* ---- offline ------------------------------------------------------------- */

int engine_curve(const engine_config_t *cfg, const engine_waypoint_t *wp, size_t n,
                 fdiff_seg_t *seg, size_t max_seg, size_t *nseg)
{
    int err = 0, rc = 0;
    engine_t *e = engine_new(cfg, &err);
    size_t i, out = 0;

    *nseg = 0;
    if (!e)
        return -err;
    for (i = 0; i <= n; i++) {
        if (i < n) {
            rc = engine_push(e, &wp[i]);
            if (rc == -ENGINE_EFULL) {
                rc = -ENGINE_ENUMERIC; /* cannot happen: the queue is drained below */
                break;
            }
        } else {
            engine_finish(e);
        }
        while (e->queue.len) {
            qent_t *h = q_head(e);
            if (h->kind == QE_SEG) {
                if (out == max_seg) {
                    rc = -ENGINE_ECONFIG;
                    goto out;
                }
                seg[out++] = h->seg;
            }
            queue_pop(e);
        }
    }
    rc = 0;
out:
    *nseg = out;
    engine_free(e);
    return rc;
}
