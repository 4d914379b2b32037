/*
 * engine_play.c - the play-out stage's trajectory boundaries (engine_tick.c
 * makes the ticks between them): a trajectory started from rest or after a
 * transfer (play_start, on one clock at rate 0: clock_start), the curve
 * available to it looked up once (play_find_avail), its ends at rest (its
 * end marker, a stop or clear braked to rest, a curve that does not end at
 * rest braked short of its end), and underruns counted; the wait for a
 * start or a resumption (play_enough_ahead, play_rebuffering), the output's
 * state (play_state) and whether its steps are stalled (play_stalled), for
 * engine_tick.c.  The state is
 * engine_out_t's and engine_scale_t's (engine_int.h), owned by the play-out.
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>

#include "accept.h"
#include "delay.h"
#include "lsq.h"
#include "silence.h"
#include "timescale.h"

/* An underrun begins: what its log line tells; counted now, or (while the
 * silence may turn out to be the input's end: silence.h) once a newer
 * waypoint comes (play_underrun_counted). */
void play_count_underrun(engine_t *e)
{
    e->out.und_t = e->sil.last_t;
    e->out.und_traj = e->sil.traj;
    /* what its log line tells (engine_status_t underrun_*) */
    engine_delay_t d;
    engine_delay(e, &d);
    e->st.underrun_t_s = e->out.t;
    e->st.underrun_newest_t_s = e->sil.last_t;
    e->st.underrun_next_t_s = NAN;
    e->st.underrun_slack_s = d.interval_s + d.slack_s;
    e->st.underrun_curve_t_s = e->scale.avail_t;
    e->st.underrun_lookahead_s = d.lookahead_s;
    e->st.underrun_silence_s = NAN;
    e->st.underrun_judging = accept_pending(&e->in.policy);
    e->st.underrun_judging_t_s = accept_first_t(&e->in.policy);
    e->out.und_pending = engine_silence_pending(e);
    if (!e->out.und_pending)
        play_underrun_counted(e);
}

/* The underrun is one (the input came later than its timestamps said):
 * counted, and (start_slack auto) the next start waits one waypoint more,
 * up to ENGINE_SLACK_AUTO_MAX. */
void play_underrun_counted(engine_t *e)
{
    e->out.und_pending = 0;
    e->st.underruns++;
    play_slack_learn(e);
}

void play_slack_learn(engine_t *e)
{
    if (e->slack_auto && e->slack_learn < e->slack_more) {
        e->slack_learn++;
        e->st.lookahead = e->lookahead + e->slack_learn;
    }
    /* D as the input now needs (delay.h), the interval learnt in it: stated
     * anew, and logged, with it */
    if (e->slack_auto || e->cfg.delay_s > 0)
        engine_delay_grow(e);
}

/* The output stands where it is, at rest. */
void play_hold_here(engine_t *e)
{
    out_sync(e); /* the position stays */
    for (int k = 0; k < AX; k++)
        e->out.vel[k] = e->out.acc[k] = 0.0;
}

/* Back on the unit grid with rate 1 (every start from HOLD). */
void play_unit_reset(engine_t *e)
{
    e->scale.on = 0;
    e->scale.s_off = 0.0;
    e->scale.ts.rate = 1.0;
    e->scale.ts.acc = 0.0;
    e->scale.end_brake = 0;
    e->out.reserve_slow = 0;
}

/* A stop or clear has brought the output to rest: drop what was queued at
 * the request, stand here (FINISHED after a stop, WAITING after a clear). */
void play_stop_at_rest(engine_t *e)
{
    if (e->out.mode == OUT_XFER)
        xfer_track_time(e); /* the track time the transfer showed, kept at rest (its own
                               time, from 0, stepped t_s back: 5.4 s to 0.1 s) */
    /* the waypoints beyond the rest point: dropped (st.dropped), the end of
     * the segment it rests in among them */
    size_t n = e->scale.drop_n < e->queue.len ? e->scale.drop_n : e->queue.len;
    e->st.dropped += queue_waypoints(e, 0, n);
    if (e->out.mode == OUT_STREAM && e->out.cur.kind == QE_SEG && !e->local &&
        e->out.t < e->out.cur.t1_s - 1e-9)
        e->st.dropped++;
    while (e->scale.drop_n && e->queue.len)
        queue_pop(e);
    e->scale.drop_n = 0;
    e->out.mode = OUT_HOLD;
    e->xfer.lead = 0;
    play_hold_here(e);
    e->out.finished = e->scale.stop_req == STOP_STOP;
    e->scale.stop_req = STOP_NONE;
    e->out.underrun = 0;
    play_unit_reset(e);
}

/* The queue head is a trajectory's end marker: rest on its point, FINISHED. */
void play_rest_at_end(engine_t *e, const qent_t *h)
{
    out_sync(e);
    for (int k = 0; k < AX; k++)
        e->out.pos[k] = h->seg.c[k][0];
    e->out.t = h->t1_s;
    queue_pop(e);
    play_hold_here(e);
    e->out.mode = OUT_HOLD;
    e->out.finished = 1;
    e->out.underrun = 0;
    if (e->scale.stop_req)
        play_stop_at_rest(e);
}

/* A closed trajectory whose curve does not end at rest, braked to rest just
 * before its end: finish here, where the output stands (no jump to the end). */
void play_finish_here(engine_t *e)
{
    while (e->queue.len) {
        int end = q_head(e)->kind == QE_END && q_head(e)->traj == e->out.traj;
        queue_pop(e);
        if (end)
            break;
    }
    e->out.mode = OUT_HOLD;
    play_hold_here(e);
    e->out.finished = 1;
    e->out.underrun = 0;
    play_unit_reset(e);
}

/* Where the solved curve of the output's trajectory ends, from the queue
 * (once per trajectory; queue_segment and queue_end keep it up to date). */
void play_find_avail(engine_t *e)
{
    e->scale.avail_t = e->out.cur.t1_s;
    e->scale.avail_kcum = e->out.cur.kcum;
    e->scale.avail_ucum = e->out.cur.ucum;
    e->scale.avail_closed = 0;
    e->scale.avail_rest = 0;
    /* The loop below stops at the first entry of another trajectory or at
     * the first END.  The queue holds the trajectories in order (join.c
     * traj_past): with no END queued, or one only, at the queue's end, the
     * output's trajectory is a run from the head found by a binary search
     * (an upload of thousands of segments: not looked through one by one),
     * and the loop's answer is its last entry's (and, that one an END, the
     * segment's before it). */
    size_t len = e->queue.len;
    if (len && queue_at(e, 0)->traj == e->out.traj &&
        (e->queue.ends == 0 || (e->queue.ends == 1 && queue_at(e, len - 1)->kind == QE_END))) {
        size_t lo = 0, hi = len; /* the first index past the output's trajectory */
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (queue_at(e, mid)->traj > e->out.traj)
                hi = mid;
            else
                lo = mid + 1;
        }
        const qent_t *q = queue_at(e, lo - 1), *s = q;
        e->scale.avail_t = q->t1_s;
        if (q->kind == QE_END) {
            e->scale.avail_closed = 1;
            e->scale.avail_rest = q->seg.c[0][1] <= ENGINE_REST_SPEED_M_S;
            s = lo >= 2 ? queue_at(e, lo - 2) : NULL; /* (a SEG: one END only) */
        }
        if (s) {
            e->scale.avail_kcum = s->kcum;
            e->scale.avail_ucum = s->ucum;
        }
        return;
    }
    for (size_t i = 0; i < e->queue.len; i++) {
        const qent_t *q = queue_at(e, i);
        if (q->traj != e->out.traj)
            break;
        e->scale.avail_t = q->t1_s;
        if (q->kind == QE_SEG) {
            e->scale.avail_kcum = q->kcum;
            e->scale.avail_ucum = q->ucum;
        }
        if (q->kind == QE_END) {
            e->scale.avail_closed = 1;
            e->scale.avail_rest = q->seg.c[0][1] <= ENGINE_REST_SPEED_M_S;
            break;
        }
    }
}

/* One clock: a trajectory is entered at rate 0 like every other
 * (scaled_rest, TIMESCALE.md "Handovers": locked at once, its acceleration
 * would step by k''(0) rho^2), behind the play time by the sub-tick phase
 * past its first waypoint (and by what the waypoints came late); the
 * catch-up of clocked_step wins the lag back and locks on the clock. */
static void clock_start(engine_t *e)
{
    scale_rest(e);
    e->clk.locked = 0;
    scale_eval(e);
    e->out.t = e->out.origin_t;
}

/* Begin streaming the trajectory at the queue head (tick 0 of it). */
void play_start(engine_t *e, int new_flag)
{
    qent_t *h = q_head(e);

    if (new_flag) {
        e->out.track++;
        e->out.flags_pending |= ENGINE_SP_NEW_TRACK;
    }
    e->out.have_pos = 1;
    e->out.underrun = 0;
    if (h->kind == QE_END) {
        /* a trajectory with no segment: rest on its point */
        play_rest_at_end(e, h);
        return;
    }
    e->out.origin_t = h->seg.t0_s;
    e->out.traj = h->traj;
    play_take_segment(e);
    play_find_avail(e);
    e->out.n = 0;
    e->out.seg_n0 = 0;
    e->scale.s_off = 0.0;
    play_seed_cur(e, 0);
    out_eval(e);
    e->out.t = e->out.origin_t;
    e->out.mode = OUT_STREAM;
    if (e->clk.on) {
        clock_start(e);
    } else if (e->scale.on) {
        /* from a scaled transfer: go on scaled from the start */
        e->scale.s = 0.0;
        scale_eval(e);
    }
}

void play_xfer_end(engine_t *e)
{
    if (!e->xfer.lead) {
        play_start(e, 0);
        return;
    }
    /* rest on the start, its track time: step_once starts the trajectory
     * from here (led: the same track) once it is due */
    fdiff_eval(&e->out.cur.seg, 1.0, e->out.pos, NULL, NULL);
    e->out.on_fd = 0;
    e->out.t = e->xfer.to_t;
    e->out.mode = OUT_HOLD;
    play_hold_here(e);
    play_unit_reset(e);
}

/* ---- the wait for a start (engine_tick.c step_once, decide) ---- */

/* The newest interval of the input (0: fewer than two nodes). */
static double last_interval(const engine_t *e)
{
    return e->solve.nodes >= 2 ? nt(e, e->solve.nodes - 1) - nt(e, e->solve.nodes - 2) : 0.0;
}

/* start_slack auto: the curve kept ahead of the output beyond what the
 * solver needs, track seconds: twice a stop from full rate at the input's
 * top speed (the curve may be faster than its chords), a few ticks, and the
 * newest interval once per underrun seen. */
static double brake_s(const engine_t *e)
{
    double v = e->solve.vmax_in > ENGINE_SCALE_V_FLOOR_M_S ? e->solve.vmax_in
                                                           : ENGINE_SCALE_V_FLOOR_M_S;
    return 2.0 * ts_stop_dist(1.0, 0.0, e->cfg.scale_accel_m_s2 / v, e->cfg.scale_jerk_m_s3 / v) +
           (TS_MARGIN_TICKS + 2) * e->period_s + e->slack_learn * last_interval(e);
}

/* start_slack auto: an output stopped by an underrun at s stays stopped
 * until the curve surely built ahead of it is longer than brake_s (or the
 * buffer holds the most slack, or the input is closed).  Not span_max, as
 * at a start: after a long hole in the input that would hold it for as long
 * as the hole. */
int play_rebuffering(const engine_t *e, double s)
{
    uint64_t in = e->solve.nodes + (e->smooth ? lsq_smooth_pending(&e->solve.sm) : 0) +
                  accept_pending(&e->in.policy);

    if (e->scale.avail_closed || e->out.cur.kind != QE_SEG ||
        in >= e->out.cur.node + 2 + e->lookahead + e->slack_more)
        return 0;
    /* the curve is built at least up to the node la_steady + 1 before the
     * newest one, whatever the fragment phase */
    uint64_t back = (uint64_t)e->la_steady + 1;
    if (e->solve.nodes <= back)
        return 1;
    return !(nt(e, e->solve.nodes - 1 - back) - (e->out.origin_t + s) >=
             brake_s(e) - e->slack_learn * last_interval(e));
}

/*
 * The output may start (or resume after an underrun) on the segment h only
 * once the lookahead is buffered beyond it, or its trajectory is closed.
 */
int play_enough_ahead(const engine_t *e, const qent_t *h, double *lag)
{
    /* waypoints received: nodes, plus those the smoother still holds (SMOOTH) */
    /* and those the acceptance policy still judges: their verdicts come
     * within the start slack, so they count as lookahead (accept.h) */
    uint64_t in = e->solve.nodes + (e->smooth ? lsq_smooth_pending(&e->solve.sm) : 0) +
                  accept_pending(&e->in.policy);

    if (e->queue.ends > 0 || h->kind != QE_SEG)
        return 1;
    if (in < h->node + 2 + e->lookahead + e->slack_learn)
        return 0;
    /* issue 26: start_slack auto, or delay_s: once the output will stand D
     * behind the newest waypoint after its ramp from rest (delay.h) */
    return !(e->slack_auto || e->cfg.delay_s > 0) || engine_delay_ready(e, lag);
}

engine_state_t play_state(const engine_t *e)
{
    if (e->out.mode == OUT_STREAM)
        return e->out.underrun ? ENGINE_STATE_UNDERRUN : ENGINE_STATE_STREAMING;
    if (e->out.mode == OUT_XFER)
        return ENGINE_STATE_STREAMING;
    if (e->in.open || e->queue.len || accept_pending(&e->in.policy))
        return ENGINE_STATE_WAITING;
    return e->out.finished ? ENGINE_STATE_FINISHED : ENGINE_STATE_WAITING;
}

/* 1 if further steps cannot change anything until new input arrives. */
int play_stalled(const engine_t *e)
{
    const qent_t *h = e->queue.len ? &e->queue.ent[e->queue.head] : NULL; /* q_head, read only */

    if (engine_silence_soon(e))
        return 0; /* issue 26: a silent end may come without a push (silence.h) */
    if (e->out.mode == OUT_HOLD) {
        double target[AX], t0, gap;
        return (!h || !h->first || !play_enough_ahead(e, h, NULL)) &&
               !xfer_lead_target(e, target, &t0, &gap);
    }
    if (e->out.mode == OUT_STREAM && e->scale.on && at_rest(e) && !e->scale.stop_req &&
        !e->scale.end_brake) {
        double A, J, target = scale_target(e);
        if (!(target > 0))
            return 1;
        scale_limits(e, &A, &J);
        return ts_rate_max(scale_remaining(e, e->scale.s), A, J) < ts_dead_band(J, e->period_s);
    }
    return 0;
}
