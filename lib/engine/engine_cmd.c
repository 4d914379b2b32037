/*
 * engine_cmd.c - the commands an engine takes between ticks (engine.h):
 * stop, clear, halt, override, clock, position, counters.  The lifecycle
 * owner (lifecycle.h) is the one caller in the daemon; the stages they act on are in
 * engine_input.c, engine_solve.c, engine_tick.c, engine_scale.c (engine.c).
 */
#include <math.h>
#include <string.h>

#include "engine.h"
#include "engine_int.h"

/* Forget the trajectory being received: the next waypoint opens a new one.
 * Its waypoints not in the queue yet are counted: dropped (nodes, the
 * smoother's: accepted), unjudged (those still being judged). */
static void drop_input(engine_t *e)
{
    e->st.dropped += (uint64_t)(e->solve.nodes - e->solve.seg_next) +
                     (e->smooth ? (uint64_t)lsq_smooth_pending(&e->solve.sm) : 0);
    e->st.unjudged += accept_pending(&e->in.policy); /* no verdict: not accepted */
    e->st.unjudged += e->pick.n; /* held for delay_s's pick (engine_pick): not judged */
    e->pick.n = 0;
    accept_reset(&e->in.policy);
    e->in.open = 0;
    e->solve.nodes = 0;
    e->solve.seg_next = 0;
    e->solve.pend = 0; /* a segment held for the next one (queue_segment): dropped too */
    frag_reset(e->solve.fw);
    if (e->smooth)
        lsq_smooth_reset(&e->solve.sm);
}

/*
 * Stop or clear: the input is dropped now; an output that stands still
 * drops the queue now too, a moving one brakes along its path (target rate
 * 0 in the time scaling) and drops what was queued at this call once at
 * rest (stop_at_rest).
 */
static void request_stop(engine_t *e, int kind)
{
    drop_input(e);
    e->out.underrun = 0;
    if (e->out.mode == OUT_HOLD) {
        e->st.dropped += queue_waypoints(e, 0, e->queue.len);
        e->queue.head = 0;
        e->queue.len = 0;
        e->queue.slow_len = 0;
        e->queue.beyond = 0;
        e->queue.ends = 0;
        e->out.finished = kind == STOP_STOP;
        e->scale.stop_req = STOP_NONE;
        e->scale.drop_n = 0;
        return;
    }
    e->out.finished = 0;
    e->scale.stop_req = kind; /* the later command decides the state at rest, as when holding */
    e->scale.drop_n = e->queue.len;
}

int engine_stop(engine_t *e)
{
    request_stop(e, STOP_STOP);
    return 0;
}

void engine_clear(engine_t *e)
{
    request_stop(e, STOP_CLEAR);
}

int engine_set_override(engine_t *e, double ratio)
{
    if (!(ratio >= 0 && ratio <= TS_RATE_MAX))
        return -ENGINE_ERANGE;
    e->scale.override = ratio;
    return 0;
}

int engine_set_clock(engine_t *e, const engine_clock_t *clk)
{
    if (!(clk->delay_ns >= 0) || !(fabs(clk->rate - 1.0) <= ENGINE_CLOCK_RATE_TOL) ||
        !(clk->catchup >= 0 && clk->catchup <= 1))
        return -ENGINE_ERANGE;
    e->clk.on = 1;
    e->clk.now_ns = clk->now_ns;
    e->clk.delay_ns = clk->delay_ns;
    e->clk.rate = clk->rate;
    e->clk.catchup = clk->catchup;
    e->clk.play_ns = clk->now_ns - clk->delay_ns;
    return 0;
}

int engine_set_catchup(engine_t *e, double catchup)
{
    if (!(catchup >= 0 && catchup <= 1))
        return -ENGINE_ERANGE;
    e->clk.catchup = catchup;
    return 0;
}

int engine_set_position(engine_t *e, const double pos_m[ENGINE_AXES])
{
    for (int k = 0; k < AX; k++) {
        if (!isfinite(pos_m[k]))
            return -ENGINE_ENOTFINITE;
        if (fabs(pos_m[k]) > e->cfg.max_abs_m)
            return -ENGINE_ERANGE;
    }
    if (e->out.mode != OUT_HOLD)
        return -ENGINE_ESTATE;
    out_sync(e); /* written here, not in the stepper (engine_out_t) */
    for (int k = 0; k < AX; k++) {
        e->out.pos[k] = pos_m[k];
        e->out.vel[k] = e->out.acc[k] = 0.0;
    }
    e->out.have_pos = 1;
    return 0;
}

void engine_require_position(engine_t *e, int on)
{
    e->out.need_pos = on != 0;
    /* holding: the position it had is not trusted any more */
    if (e->out.need_pos && e->out.mode == OUT_HOLD)
        e->out.have_pos = 0;
}

int engine_has_position(const engine_t *e)
{
    return e->out.have_pos;
}

void engine_reset_counters(engine_t *e)
{
    uint32_t last_seq = e->st.last_seq;

    memset(&e->st, 0, sizeof(e->st));
    e->st.last_seq = last_seq;
    e->st.lookahead = e->lookahead + e->slack_learn;
    engine_status_underrun_none(&e->st);
}

int engine_halt(engine_t *e, const double pos_m[ENGINE_AXES])
{
    for (int k = 0; k < AX; k++) {
        if (!isfinite(pos_m[k]))
            return -ENGINE_ENOTFINITE;
        if (fabs(pos_m[k]) > e->cfg.max_abs_m)
            return -ENGINE_ERANGE;
    }
    drop_input(e);
    e->st.dropped += queue_waypoints(e, 0, e->queue.len);
    e->queue.head = e->queue.len = e->queue.ends = 0;
    e->queue.slow_head = e->queue.slow_len = e->queue.beyond = 0;
    e->scale.stop_req = STOP_NONE;
    e->scale.drop_n = 0;
    e->out.mode = OUT_HOLD;
    e->xfer.lead = 0; /* a transfer that led is given up with the rest */
    e->out.finished = 0;
    e->out.underrun = 0;
    e->scale.end_brake = 0;
    e->scale.on = 0;
    e->scale.s_off = 0.0;
    e->scale.ts.rate = 1.0;
    e->scale.ts.acc = 0.0;
    e->clk.locked = 0;
    out_sync(e); /* written here, not in the stepper (engine_out_t) */
    for (int k = 0; k < AX; k++) {
        e->out.pos[k] = pos_m[k];
        e->out.vel[k] = e->out.acc[k] = 0.0;
    }
    e->out.have_pos = 1;
    return 0;
}
