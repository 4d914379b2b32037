/*
 * engine_tick.c - the play-out stage: engine_tick.  The output's state
 * machine walks the queued cubics (engine_solve.c) with the forward-
 * difference stepper (fdiff.h) on the period grid: it waits for enough
 * lookahead (start_slack auto learns how much; the tests, and the output's
 * state and stall, in engine_play.c), starts a trajectory directly or
 * through a transfer (engine_xfer.c; the start itself, the ends at rest and
 * the underruns counted: engine_play.c), steps on the unit grid
 * while nothing asks for another rate (else the time scaling,
 * engine_scale.c) and fills the setpoint, one path for every tick: the rate
 * decision of a plain step is kept for the ticks it provably holds
 * (plain_window).  It owns engine_out_t
 * (engine_int.h: mode, position, current segment and stepper, tick count,
 * cycle, track, flags, the last setpoint, the decision kept).
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "accept.h"
#include "catchup.h"
#include "fdiff.h"
#include "lsq.h"
#include "silence.h"
#include "timescale.h"

/* out_eval leaves the output in the stepper's rows (on_fd): copied here
 * for whoever writes them or holds (engine_out_t), with the curve's speed
 * as out_eval computed it every tick before. */
void out_sync(engine_t *e)
{
    if (!e->out.on_fd)
        return;
    fdiff_get(&e->out.fd, e->out.pos, e->out.vel, e->out.acc);
    e->scale.cspeed = out_cspeed(e);
    e->out.on_fd = 0;
}

double out_cspeed(const engine_t *e)
{
    if (!e->out.on_fd)
        return e->scale.cspeed; /* scale_eval's (or out_sync's) */
    double v2 = 0;
    for (int k = 0; k < AX; k++) /* rate 1: the curve's own speed */
        v2 += e->out.fd.f[FDIFF_VEL + k] * e->out.fd.f[FDIFF_VEL + k];
    return sqrt(v2);
}

/* Two doubles, for the stepper's rows (fdiff.h keeps them in pairs). */
typedef double row2_t __attribute__((vector_size(16)));
typedef long long bits2_t __attribute__((vector_size(16)));

static inline row2_t row2_at(const double *p)
{
    row2_t v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* A pair stored (the widths the stepper's rows are loaded in: a load across
 * two stores waits for them to reach the cache). */
static inline void row2_put(double *p, row2_t v)
{
    memcpy(p, &v, sizeof v);
}

/* Seed the stepper at tick n (relative time tau in [cur_t0, cur_t1)) for
 * seg, cur's segment or the queue slot it was just copied from. */
static void seed_at(engine_t *e, int64_t n, const fdiff_seg_t *seg)
{
    double tau = tau_of(e, n);
    double u0 = (tau - e->out.cur_t0) / seg->dur_s;
    fdiff_seed(&e->out.fd, seg, u0, e->period_s / seg->dur_s);
}

/* Seed cur at tick n (relative time tau in [cur_t0, cur_t1)). */
void play_seed_cur(engine_t *e, int64_t n)
{
    seed_at(e, n, &e->out.cur.seg);
}

/* Make the queue head (a SEG) the current segment, relative to origin_t.
 * Returns its segment as the queue slot just freed holds it (cur's copy,
 * unchanged until the next push): read there in the same tick, the loads
 * do not wait on the copy's stores (a load across two of them cannot be
 * forwarded from the store buffer). */
const fdiff_seg_t *play_take_segment(engine_t *e)
{
    const qent_t *q = q_head(e);
    double shift = q->shift, t0 = q->seg.t0_s, t1 = q->t1_s;
    e->out.cur = *q;
    queue_pop(e);
    if (!is_exactly(shift, 0.0))
        e->out.origin_t += shift; /* where a join met it (join.c) */
    e->out.cur_t0 = t0 - e->out.origin_t;
    e->out.cur_t1 = t1 - e->out.origin_t;
    return &q->seg;
}

/* One forward step of cur (with a re-seed at deterministic ticks). */
static inline void step_cur(engine_t *e, int64_t n)
{
    if ((uint64_t)(n - e->out.seg_n0) % FDIFF_RESEED_STEPS == 0)
        play_seed_cur(e, n);
    else
        fdiff_step(&e->out.fd);
    out_eval(e);
}

static int unit_cross(engine_t *e, int64_t n, double tau);

/* One tick on the unit grid (rate 1): the forward-difference stepper.
 * Returns 1 if it left the current segment (or transfer). */
static inline int unit_step(engine_t *e)
{
    int64_t n = e->out.n + 1;
    double tau = tau_of(e, n);
    if (e->out.mode == OUT_STREAM && tau < e->out.cur_t1) {
        e->out.n = n;
        step_cur(e, n);
        e->out.t = e->out.origin_t + tau;
        e->out.underrun = 0;
        return 0;
    }
    return unit_cross(e, n, tau);
}

/* unit_step at the end of a segment, or of a transfer. */
__attribute__((noinline)) static int unit_cross(engine_t *e, int64_t n, double tau)
{
    if (e->out.mode == OUT_XFER) {
        if (tau >= e->out.cur_t1) {
            /* not reached: scale_remaining() brakes the transfer to rate 0 before its
             * end; should it be, the trajectory is entered at rate 0 as well */
            scale_rest(e);
            play_xfer_end(e); /* the transfer ends exactly on its start */
            return 1;
        }
        e->out.n = n;
        step_cur(e, n);
        return 0;
    }
    const fdiff_seg_t *seg;
    for (;;) {
        qent_t *h = q_head(e);
        if (h && h->traj != e->out.traj)
            h = NULL;
        if (!h) {
            /* the solved curve ended under a moving output: cannot happen
             * while scale_remaining() is right (the scaling brakes before); hold
             * and go on scaled from rest */
            if (!e->out.underrun)
                play_count_underrun(e);
            e->out.underrun = 1;
            e->st.underrun_ticks++;
            e->st.hard_stops++;
            play_hold_here(e);
            e->scale.on = 1;
            e->scale.s = tau_of(e, e->out.n);
            e->scale.ts.rate = 0.0;
            e->scale.ts.acc = 0.0;
            return 1;
        }
        if (h->kind == QE_END) {
            play_rest_at_end(e, h);
            return 1;
        }
        seg = play_take_segment(e);
        if (tau < e->out.cur_t1)
            break;
        /* shorter than a period: no tick falls in it */
    }
    e->out.n = n;
    e->out.seg_n0 = n;
    seed_at(e, n, seg); /* cur's, read where it was copied from */
    out_eval(e);
    e->out.t = e->out.origin_t + tau;
    e->out.underrun = 0;
    return 1;
}

/* A moving output's tick, as the rate decision goes. */
enum { GO_UNIT, GO_CLOCKED, GO_REBUFFER, GO_SCALED };

typedef struct {
    double s, A, J, R, target;
    double Rc; /* the speed cap ahead (scale_ceil_room) for GO_SCALED: worked out once */
} decision_t;

/*
 * The rate decision of a moving output (a transfer or a trajectory): on the
 * unit grid while nothing asks for another rate and the curve ahead is long
 * enough to stop in (GO_UNIT), else the time scaling (GO_SCALED, the target
 * rate in d), one clock (GO_CLOCKED) or a rebuffering after an underrun.
 * Sets end_brake where the curve's end must be braked for, and steers a lag
 * (engine_lag_target): plain_verify undoes both.
 */
static int decide(engine_t *e, decision_t *d)
{
    double A, J, s = out_s(e), R;
    scale_limits(e, &A, &J);
    /* the reserve both rooms keep, worked out once (with per-axis limits it
     * scans the queue ahead) */
    double res = scale_slowing_reserve(e, scale_conv_speed(e));
    R = scale_remaining_gross(e, s) - res;
    d->s = s;
    d->A = A;
    d->J = J;
    d->R = R;
    if (e->out.mode == OUT_STREAM && e->scale.avail_closed && !e->scale.avail_rest &&
        !e->scale.end_brake &&
        (ts_stop_dist(e->scale.ts.rate, e->scale.ts.acc, A, J) >=
             R - e->scale.ts.rate * e->period_s ||
         (e->scale.on && at_rest(e) && !scale_moves(e, R, A, J))))
        /* the curve does not end at rest: brake before its end; at rest with
         * less curve left than one tick of motion and its stop need, no input
         * can come to lengthen it: finish here, not wait for ever */
        e->scale.end_brake = 1;
    if (e->clk.on && e->out.mode == OUT_STREAM)
        return GO_CLOCKED;
    double target = scale_target(e);
    /* start_slack auto: an output stopped by an underrun resumes once it is
     * as far behind the newest waypoint as at the start (play_enough_ahead) */
    if (e->slack_auto && e->out.underrun && e->out.mode == OUT_STREAM && !(e->scale.ts.rate > 0) &&
        target > 0 && play_rebuffering(e, s))
        return GO_REBUFFER;
    d->Rc = scale_ceil_room_gross(e, s, A, J) - res;
    double Rm = fmin(R, d->Rc);                      /* the speed cap ahead too */
    target = engine_lag_target(e, target, Rm, A, J); /* a lag won back (catchup.h) */
    d->target = target;
    if (!e->scale.on && is_exactly(target, 1.0) &&
        (isinf(Rm) || ts_stop_dist(1.0, 0.0, A, J) < Rm - e->period_s))
        return GO_UNIT;
    return GO_SCALED;
}

/* The last tick on the unit grid inside cur from the current one n: the
 * largest m >= n with tau_of(m) < cur_t1 (n itself if none), as unit_step
 * compares them (tau_of is monotonic in its tick, so the guess from the
 * division is moved to it by the comparison itself).  A segment longer than
 * 2^31 ticks, or NaN, gives n: its kept steps go the long way (step_once). */
static int64_t grid_last(const engine_t *e)
{
    int64_t n = e->out.n;
    double x = (e->out.cur_t1 - e->scale.s_off) / e->period_s - (double)n;
    if (!(x < 0x1p31))
        return n;
    int64_t m = n + (x > 1.0 ? (int64_t)x : 0);
    while (m > n && !(tau_of(e, m) < e->out.cur_t1))
        m--;
    while (tau_of(e, m + 1) < e->out.cur_t1)
        m++;
    return m;
}

/* kept_last and fast_last (engine_out_t) from plain_last, seg_last and the
 * re-seed grid of step_cur. */
static inline void fast_bound(engine_t *e)
{
    int64_t n = e->out.n, kept, last;
    uint64_t j = (uint64_t)(n - e->out.seg_n0); /* steps since the seed */
    if (j >= FDIFF_RESEED_STEPS)                /* (the division only past the first re-seed) */
        j %= FDIFF_RESEED_STEPS;
    kept = e->out.seg_last < e->out.plain_last ? e->out.seg_last : e->out.plain_last;
    last = n + (int64_t)(FDIFF_RESEED_STEPS - 1 - j);
    e->out.kept_last = kept;
    e->out.fast_last = e->out.plain_check || e->out.f_negz ? INT64_MIN : kept < last ? kept : last;
}

/* x is exactly 1.0 (is_exactly(x, 1.0)): its bits are 1.0's, the only
 * double equal to it; one integer comparison. */
static inline int is_one_bits(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return b == UINT64_C(0x3ff0000000000000);
}

/* x is exactly 0.0 (is_exactly(x, 0.0)): +0.0 or -0.0, all bits but the
 * sign clear. */
static inline int is_zero_bits(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return (b << 1) == 0;
}

/*
 * The rate decision kept.  On the unit grid inside a segment, decide()
 * re-derives every tick that nothing asks for another rate: two divisions
 * and the stopping distance ts_stop_dist against the buffer's remaining
 * capacity (scale_remaining()) and the speed cap ahead (scale_ceil_room()).
 * plain_window decides once, after a tick, for how many ticks ahead that
 * answer cannot change: while the stopping distance stays short of the
 * remaining capacity with two ticks to spare, at the segment's bound on the
 * curve's speed (conv_speed): the check each of those ticks would make
 * passes at any speed above it.  The last tick of the window may leave the
 * segment (its decision is made before, inside it); after it the window is
 * decided again for the next segment.
 *
 * The answer is keyed on the engine's state, not closed by each call that
 * changes it: a change counter bumped by every call would need every call,
 * present and future, to bump it, and a forgotten one would be a wrong
 * setpoint.  The decision reads, besides what the tick itself advances (n,
 * s, the segment: the window counts them), only state that a call between
 * ticks can change in one of these ways: the queue grows or is emptied (a
 * push, a finish, a silent end, a clear, a halt: queue.len), a waypoint's
 * stamp is a new sample of the sender's time and so of the lag (every push
 * that passes engine_waypoint_check: lag.seen_ns at the next tick), a stop
 * or clear (stop_req), the override, one clock (clk.on), a halt (the mode).
 * plain_holds compares exactly those, so no call can forget to close the
 * window.  A new input of the decision must be added there: the test hook
 * engine_plain_check recomputes the decision on every kept tick
 * (tests/unit/test_engine_tick.c).  A live re-anchor's wait for its new
 * curve (join_wait_rate, which moves with the output's own time) keeps no
 * window while one may begin (join_may_wait).
 */
static void plain_window(engine_t *e)
{
    e->out.plain_last = e->out.kept_last = e->out.fast_last = INT64_MIN; /* none kept */
    if (e->out.mode != OUT_STREAM || e->scale.on || e->clk.on || e->out.underrun ||
        !e->out.have_pos || e->scale.stop_req || e->scale.end_brake || e->out.cur.join ||
        !is_one_bits(e->scale.override) || !is_one_bits(e->scale.ts.rate) ||
        !is_zero_bits(e->scale.ts.acc) || scale_ceil_here(e) < 1.0 ||
        /* (engine_lag_pending's own first answers without the call) */
        ((e->lag.steer || (e->lag.have && !e->lag.ahead)) && engine_lag_pending(e)) ||
        join_may_wait(e))
        return;
    /* scale_remaining() is finite: a REST end too is left at rate 0 */
    /* decide's check, ts_stop_dist(1, 0, a/v, j/v) < v K - (margin + 1) T
     * with v = conv_speed (the same on every tick of the window: the
     * segment's) and K the capacity left (scale_remaining()) */
    /* with per-axis jerk limits the rooms keep a reserve for a stop's jerk
     * (engine_scale.c stop_jerk_reserve) that moves with the segments the
     * stop may reach: decided on every tick */
    if (e->axis_jerk)
        return;
    double v = scale_conv_speed(e);
    double d = e->out.cur.stop1 * (1 + 1e-9); /* queue_segment's, at v */
    double in_cur = e->out.cur_t1 - tau_of(e, e->out.n);
    double k = (in_cur > 0 ? in_cur / v : 0.0) + (e->scale.avail_kcum - e->out.cur.kcum);
    /* with per-axis limits the rooms keep scale_slowing_reserve, which grows
     * as slower-converted segments come within reach: at most the onset and
     * release part of the stop from rate 1, d - v / (2 a), kept whole here
     * (without it, windows kept rate 1 where decide() braked) */
    double slow = solve_axis_limited(e) ? fmax(d - 0.5 * v / e->cfg.scale_accel_m_s2, 0.0) : 0.0;
    /* K falls by T / v per tick: the ticks for which it stays above */
    double room = (k - (d + scale_rise_reserve(e, v) + (TS_MARGIN_TICKS + 1) * e->period_s) / v) *
                      v -
                  slow;
    /* and the speed cap ahead (ceil_room), which falls by T per tick too */
    if (e->queue.slow_len) { /* (INFINITY without one) */
        double A, J;
        scale_limits(e, &A, &J); /* not in a stop: a / v and the jerk's */
        room = fmin(room, scale_ceil_room(e, tau_of(e, e->out.n), A, J) - d - e->period_s - slow);
    }
    if (!(room > 0) || !isfinite(d))
        return;
    double x = room / e->period_s; /* floor(x) - 2 ticks, x > 0: floor is the cast */
    if (!(x >= 3.0))
        return;
    int64_t left = x < 0x1p60 ? (int64_t)x - 2 : INT64_C(1) << 60;
    if (e->scale.avail_closed && queue_later_traj(e)) { /* not past where a join may be due */
        int64_t j = join_ticks_left(e);
        left = j < left ? j : left;
    }
    e->out.plain_last = e->out.n + left;
    e->out.plain_qlen = e->queue.len;
    e->out.plain_seen = e->lag.seen_ns;
    e->out.seg_last = grid_last(e);
    fast_bound(e);
}

/* The key of the decision plain_window kept: the state a call between
 * ticks may change it by is as it was then (see there), where this is 0.
 * The differences or'ed, one test and one branch for them all (each
 * field's own would be a load, a test and a branch), more's flags too. */
static inline uint64_t plain_key_diff(const engine_t *e, unsigned more)
{
    uint64_t b;
    memcpy(&b, &e->scale.override, sizeof b);
    return (uint64_t)(e->out.plain_qlen ^ e->queue.len) |
           (uint64_t)(e->out.plain_seen ^ e->lag.seen_ns) |
           (b ^ UINT64_C(0x3ff0000000000000)) /* is_one_bits */ |
           ((unsigned)(e->out.mode ^ OUT_STREAM) | (unsigned)e->scale.stop_req |
            (unsigned)e->clk.on | more);
}

/* The key holds, and nothing was pushed since the last tick (lag.pending,
 * sil.fresh): a kept step engine_tick makes without tick_steps' notes. */
static inline int plain_key_quiet(const engine_t *e)
{
    return plain_key_diff(e, (unsigned)e->lag.pending | (unsigned)e->sil.fresh) == 0;
}

/* The decision plain_window kept still holds for the step from tick n. */
static inline int plain_holds(const engine_t *e)
{
    return e->out.n < e->out.plain_last && plain_key_diff(e, 0) == 0;
}

/* Test hook: the decision made again on a kept tick, its side effects
 * undone, and counted wrong unless it is a plain step as kept. */
__attribute__((noinline)) static void plain_verify(engine_t *e)
{
    if (e->out.plain_check != 1)
        return;
    int end_brake = e->scale.end_brake, steer = e->lag.steer;
    double lag_s = e->st.lag_s;
    uint64_t catchups = e->st.catchups;
    decision_t d;
    e->out.plain_kept++;
    if (decide(e, &d) != GO_UNIT || e->scale.end_brake != end_brake || e->lag.steer != steer)
        e->out.plain_wrong++;
    e->scale.end_brake = end_brake;
    e->lag.steer = steer;
    e->st.lag_s = lag_s;
    e->st.catchups = catchups;
}

void engine_plain_check(engine_t *e, int on, uint64_t *kept, uint64_t *wrong)
{
    e->out.plain_check = on;
    if (e->out.last_plain)
        fast_bound(e);
    else /* plain_tick only after a plain setpoint (fill_sp_flags) */
        e->out.fast_last = INT64_MIN;
    if (kept)
        *kept = e->out.plain_kept;
    if (wrong)
        *wrong = e->out.plain_wrong;
}

/* A moving output's step as decide() says; 1 unless a plain step that
 * stayed in its segment. */
static int step_decided(engine_t *e)
{
    decision_t d;
    switch (decide(e, &d)) {
    case GO_UNIT: return unit_step(e);
    case GO_CLOCKED: scale_clocked_step(e, d.R, d.A, d.J); break;
    case GO_REBUFFER:
        scale_step(e, 0.0, d.R, scale_ceil_room(e, d.s, d.A, d.J), d.A, d.J);
        if (!e->out.underrun) { /* still in the same underrun */
            e->out.underrun = 1;
            e->st.underrun_ticks++;
        }
        break;
    default: scale_step(e, d.target, d.R, d.Rc, d.A, d.J); break;
    }
    return 1;
}

/* A step whose rate decision is kept (plain_holds): a plain step on the
 * unit grid, the window decided again once it leaves the segment. */
static inline void step_kept(engine_t *e)
{
    e->out.cycle++;
    if (__builtin_expect(e->out.plain_check != 0, 0)) {
        plain_verify(e);
        /* test hook 2: the decision made anyway, and followed */
        if (e->out.plain_check == 2 ? step_decided(e) : unit_step(e))
            plain_window(e);
        return;
    }
    if (unit_step(e))
        plain_window(e); /* a new segment: decided again for it */
    else
        fast_bound(e); /* past a re-seed */
}

/* A transfer from rest begins (xfer_start), its first tick made scaled. */
static void begin_xfer(engine_t *e, const double *target, double gap_s, double lead_t_s)
{
    xfer_start(e, target, gap_s, lead_t_s);
    scale_rest(e);
    e->out.n++;
    scale_eval(e);
}

/* One tick of the output state machine. */
static void step_once(engine_t *e)
{
    if (plain_holds(e)) {
        step_kept(e);
        return;
    }
    e->out.cycle++;
    e->out.plain_last = e->out.kept_last = e->out.fast_last = INT64_MIN;
    if (e->out.mode == OUT_HOLD) {
        qent_t *h = q_head(e);
        double lag = NAN; /* the start's ramp, if play_enough_ahead simulated it */
        if (!h || !h->first || !play_enough_ahead(e, h, &lag) ||
            (!e->out.have_pos && e->out.need_pos)) {
            double target[AX], t0, gap;
            if (xfer_lead_target(e, target, &t0, &gap)) {
                /* issue 26: on to its start while its output is not due */
                play_unit_reset(e);
                begin_xfer(e, target, gap, t0);
                return;
            }
            play_hold_here(e);
            return;
        }
        if (!e->out.have_pos) {
            /* no position known and none required: the start is the last resort */
            for (int k = 0; k < AX; k++)
                e->out.pos[k] = h->seg.c[k][0];
            e->out.t = h->seg.t0_s;
            e->out.have_pos = 1;
        }
        double d2 = 0, target[AX]; /* the trajectory's start */
        for (int k = 0; k < AX; k++) {
            target[k] = h->seg.c[k][0];
            d2 += (target[k] - e->out.pos[k]) * (target[k] - e->out.pos[k]);
        }
        int xfer = sqrt(d2) > ENGINE_TRANSFER_TOL_M;
        if (e->clk.on) {
            /* one clock: not before the play time reaches the start, less
             * the transfer that leads there */
            double lead = 0.0;
            int capped = 0;
            if (xfer)
                lead = xfer_duration(e, target, h->gap_s, &capped);
            if ((long double)e->clk.play_ns * 1e-9L < (long double)h->seg.t0_s - lead) {
                play_hold_here(e);
                return;
            }
        }
        /* where a lead transfer left it: the same track */
        int led = e->xfer.lead && !xfer;
        e->xfer.lead = 0;
        play_unit_reset(e);
        engine_delay_note(e, lag); /* issue 26: the D this start holds */
        if (xfer) {
            begin_xfer(e, target, h->gap_s, NAN);
        } else {
            if (!e->clk.on)
                scale_rest(e);
            play_start(e, !led);
        }
        return;
    }
    /* issue 32: a re-anchor joined moving (join.c); none without a later
     * trajectory queued (join_try's first answer, asked first) */
    if (queue_later_traj(e) && join_wanted(e))
        (void)join_try(e);
    step_decided(e);
    if (e->out.cur.join) /* a join's setpoints are a transfer's (fill_sp_flags) */
        e->out.flags_pending |= ENGINE_SP_TRANSFER;
    plain_window(e);
}

/* The setpoint's fields, as fill_sp and last_setpoint give them. */
static void put_sp(const engine_t *e, engine_setpoint_t *sp, int64_t now_ns, const double *pos,
                   const double *vel, const double *acc, engine_state_t s, uint32_t flags,
                   double age_s)
{
    sp->now_ns = now_ns;
    sp->t_s = e->out.t;
    for (int k = 0; k < AX; k++) { /* + 0.0: a zero is +0.0 (positive_zeros) */
        sp->pos_m[k] = pos[k] + 0.0;
        sp->vel_m_s[k] = vel[k] + 0.0;
        sp->acc_m_s2[k] = acc[k] + 0.0;
    }
    sp->state = s;
    sp->flags = flags;
    sp->cycle = e->out.cycle;
    sp->track = e->out.track;
    sp->age_s = age_s;
}

/* A plain setpoint: streaming on the unit grid, no flag, no clock; all of
 * it is in the stepper and the output's counters (last_setpoint). */
static int plain_sp(const engine_t *e)
{
    /* (the flags that must be clear or'ed: one branch for them) */
    return e->out.on_fd && e->out.have_pos &&
           ((unsigned)(e->out.mode ^ OUT_STREAM) | e->out.flags_pending |
            (unsigned)e->out.underrun | (unsigned)e->scale.on | (unsigned)e->clk.on) == 0;
}

static void fill_sp_flags(engine_t *e, int64_t now_ns, engine_setpoint_t *sp);

/* The setpoint's pos_m, vel_m_s and acc_m_s2, one run of nine doubles: the
 * stepper's values as its row f holds them. */
_Static_assert(offsetof(engine_setpoint_t, vel_m_s) ==
                       offsetof(engine_setpoint_t, pos_m) + AX * sizeof(double) &&
                   offsetof(engine_setpoint_t, acc_m_s2) ==
                       offsetof(engine_setpoint_t, vel_m_s) + AX * sizeof(double) &&
                   AX == 3 && FDIFF_AXES == AX && FDIFF_POS == 0 && FDIFF_VEL == AX &&
                   FDIFF_ACC == 2 * AX,
               "fill_plain stores the stepper's f as pos_m, vel_m_s and acc_m_s2");

/* A plain setpoint (plain_sp): what fill_sp_flags would make of it (put_sp).
 * Everything it reads is read before the first store to sp (which may alias
 * the engine, for all the compiler knows), and in the widths it was stored
 * in: a load wider than the store that just wrote it, or across two stores
 * (the tick's counter loaded with the track as one 8-byte pair), is not
 * forwarded from the store buffer and waits for the stores to reach the
 * cache.  The stepper's values are read as the aligned pairs it stores
 * (+ 0.0 as put_sp adds), and whether one of them is -0.0 noted (f_negz)
 * from the same sums. */
static inline void fill_plain(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    const double *f = e->out.fd.f;
    const row2_t z = {0.0, 0.0};
    bits2_t b[5];
    memcpy(b, f, sizeof b);
    row2_t r0 = (row2_t)b[0] + z, r2 = (row2_t)b[1] + z, r4 = (row2_t)b[2] + z,
           r6 = (row2_t)b[3] + z, r8 = (row2_t)b[4] + z;
    double t = e->out.t;
    uint32_t cycle = e->out.cycle, track = e->out.track;
    /* f holds a -0.0 (f_negz): the one double whose bits + 0.0 changes (a
     * NaN a step makes is quiet, and stays as it is) */
    bits2_t nz = ((bits2_t)r0 ^ b[0]) | ((bits2_t)r2 ^ b[1]) | ((bits2_t)r4 ^ b[2]) |
                 ((bits2_t)r6 ^ b[3]) | ((bits2_t)r8 ^ b[4]);
    int negz = (nz[0] | nz[1]) != 0;

    e->out.f_negz = negz;
    if (negz)
        e->out.fast_last = INT64_MIN; /* not plain_tick's until a seed without */
    e->out.last_plain = 1;            /* last_sp is not written: last_setpoint */
    sp->now_ns = now_ns;
    sp->t_s = t;
    char *run = (char *)sp + offsetof(engine_setpoint_t, pos_m);
    memcpy(run, &r0, sizeof r0);
    memcpy(run + 2 * sizeof(double), &r2, sizeof r2);
    memcpy(run + 4 * sizeof(double), &r4, sizeof r4);
    memcpy(run + 6 * sizeof(double), &r6, sizeof r6);
    sp->acc_m_s2[2] = r8[0];
    sp->state = ENGINE_STATE_STREAMING;
    sp->flags = 0;
    sp->cycle = cycle;
    sp->track = track;
    sp->age_s = NAN;
}

/* The setpoint of this tick (put_sp; positive zeros). */
static inline void fill_sp(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    if (plain_sp(e))
        fill_plain(e, now_ns, sp);
    else
        fill_sp_flags(e, now_ns, sp);
}

/* fill_sp with the state and flags worked out. */
__attribute__((noinline)) static void fill_sp_flags(engine_t *e, int64_t now_ns,
                                                    engine_setpoint_t *sp)
{
    engine_state_t s = play_state(e);

    /* No position known yet: the first waypoint is the last resort (unless a
     * position is required), adopted once and for all, so the output never
     * jumps from it to somewhere else (a new start is reached by a transfer). */
    if (!e->out.have_pos && e->out.mode == OUT_HOLD && !e->out.need_pos) {
        qent_t *h = q_head(e);
        if (h)
            for (int k = 0; k < AX; k++)
                e->out.pos[k] = h->seg.c[k][0];
        else if (e->in.open && e->solve.nodes)
            memcpy(e->out.pos, nr(e, 0), sizeof(e->out.pos));
        else if (e->in.open) /* SMOOTH: no node yet, the first waypoint as received */
            memcpy(e->out.pos, e->in.first_r, sizeof(e->out.pos));
        if (h)
            e->out.t = h->seg.t0_s;
        else if (e->in.open && e->solve.nodes)
            e->out.t = nt(e, 0);
        if (h || e->in.open)
            e->out.have_pos = 1;
    }
    if (e->out.mode == OUT_XFER)
        xfer_track_time(e);
    else if (e->out.mode == OUT_STREAM && e->out.cur.join)
        join_track_time(e);
    uint32_t flags = e->out.flags_pending;
    e->out.flags_pending = 0;
    if (e->out.mode == OUT_HOLD || (e->scale.on && at_rest(e)))
        flags |= ENGINE_SP_HOLD;
    else if (s != ENGINE_STATE_STREAMING && s != ENGINE_STATE_UNDERRUN)
        flags |= ENGINE_SP_HOLD;
    if (e->out.mode == OUT_XFER || (e->out.mode == OUT_STREAM && e->out.cur.join))
        flags |= ENGINE_SP_TRANSFER;
    if (!e->out.have_pos)
        flags |= ENGINE_SP_NO_POSITION;
    if (e->out.mode != OUT_HOLD && e->scale.on)
        flags |= ENGINE_SP_SCALED;
    double age_s = NAN;
    if (e->clk.on && e->out.have_pos)
        age_s = (double)((long double)e->clk.now_ns * 1e-9L - (long double)e->out.t);
    put_sp(e, sp, now_ns, out_pos(e), out_vel(e), out_acc(e), s, flags, age_s);
    if (!e->out.have_pos)
        for (int k = 0; k < AX; k++)
            sp->pos_m[k] = NAN; /* not a position: see ENGINE_SP_NO_POSITION */
    e->out.last_plain = 0;
    e->out.last_sp = *sp;
    /* the next kept step makes the plain setpoint's state again (kept_tick:
     * out_eval, last_plain), not plain_tick (fast_last) */
    e->out.fast_last = INT64_MIN;
}

/* The setpoint of the last call that stepped (fill_sp): a plain one made
 * again from the stepper, which no call between ticks moves (a halt
 * writes pos, not the stepper's rows; the tick counters and out.t only a
 * tick changes); any other as kept: the 120-byte copy is not made on every
 * plain tick. */
static void last_setpoint(const engine_t *e, engine_setpoint_t *sp)
{
    if (!e->out.last_plain) {
        *sp = e->out.last_sp;
        return;
    }
    const double *f = e->out.fd.f;
    put_sp(e, sp, e->out.last_now, f + FDIFF_POS, f + FDIFF_VEL, f + FDIFF_ACC,
           ENGINE_STATE_STREAMING, 0, NAN);
}

/*
 * A kept step inside its segment that is no re-seed (fast_last), one period
 * on with nothing pushed since, and its plain setpoint: what step_once
 * (step_kept, unit_step, fdiff_step) and fill_sp (fill_plain) make of it,
 * in one run: fdiff_step's additions, lane by lane, on the rows loaded as
 * the aligned pairs they are stored in (p2's z with v2's x as a pair too),
 * and the setpoint's pairs f's sums (put_sp's + 0.0 changes none of them:
 * fast_last keeps a stepper seeded with a -0.0 in f off this path, and a
 * step makes none in f then, engine_out_t f_negz).  The setpoint
 * is stored once f is, before d2 and d3 are loaded: for all the compiler
 * knows sp may alias the engine, so the loads stay after the stores and f's
 * sums need no register past them (sp never points into the engine, opaque
 * to its callers: the loads do not wait on them).
 */
static inline void plain_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    fdiff_t *fd = &e->out.fd;
    int64_t n = e->out.n + 1;
    double t = e->out.origin_t + tau_of(e, n);
    uint32_t cycle = e->out.cycle + 1, track = e->out.track;
    uint64_t setpoints = e->st.setpoints + 1;
    /* f += d1, d1's pairs of p1 and v1 kept for d1 += d2 */
    row2_t d10 = row2_at(fd->d1), d12 = row2_at(fd->d1 + 2), d14 = row2_at(fd->d1 + 4);
    row2_t f0 = row2_at(fd->f) + d10, f2 = row2_at(fd->f + 2) + d12, f4 = row2_at(fd->f + 4) + d14,
           f6 = row2_at(fd->f + 6) + row2_at(fd->d1 + 6),
           f8 = row2_at(fd->f + 8) + row2_at(fd->d1 + 8);
    row2_put(fd->f, f0);
    row2_put(fd->f + 2, f2);
    row2_put(fd->f + 4, f4);
    row2_put(fd->f + 6, f6);
    row2_put(fd->f + 8, f8);
    e->out.n = n;
    e->out.cycle = cycle;
    e->out.last_now = now_ns;
    e->out.t = t;
    /* on_fd, no underrun and last_plain hold already (fast_last) */
    e->st.setpoints = setpoints;

    /* (the track first, the cycle last: not merged into one 8-byte store,
     * which the compiler would build in a vector register) */
    row2_t r[4] = {f0, f2, f4, f6};
    sp->track = track;
    sp->now_ns = now_ns;
    sp->t_s = t;
    memcpy((char *)sp + offsetof(engine_setpoint_t, pos_m), r, sizeof r);
    sp->acc_m_s2[2] = f8[0];
    sp->state = ENGINE_STATE_STREAMING;
    sp->flags = 0;
    sp->age_s = NAN;
    sp->cycle = cycle;

    /* d1 += d2, then d2 += d3 (p2's z beside v2's x, which stays) */
    row2_t d20 = row2_at(fd->d2), d22 = row2_at(fd->d2 + 2), d24 = row2_at(fd->d2 + 4);
    row2_put(fd->d1, d10 + d20);
    row2_put(fd->d1 + 2, d12 + d22);
    row2_put(fd->d1 + 4, d14 + d24);
    row2_put(fd->d2, d20 + row2_at(fd->d3));
    d22[0] += fd->d3[2];
    row2_put(fd->d2 + 2, d22);
}

/* A kept step inside its segment, one period on with nothing pushed since,
 * that plain_tick does not make: a re-seed, or one the test hook checks
 * (step_kept as step_once makes it, and the setpoint as fill_sp would make
 * it; plain_sp holds: a kept step inside its segment is on the grid, leaves
 * no underrun and no flag pending, and the key holds the rest). */
static void kept_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    e->out.last_now = now_ns;
    step_kept(e);
    if (__builtin_expect(e->out.plain_check != 0, 0))
        fill_sp(e, now_ns, sp); /* the test hooks' steps checked the long way */
    else
        fill_plain(e, now_ns, sp);
    e->st.setpoints++;
}

static inline int tick_steps(engine_t *e, int64_t now_ns, int64_t k, engine_setpoint_t *sp);

static int tick_other(engine_t *e, int64_t now_ns, engine_setpoint_t *sp);

/*
 * One tick, one path: the periods since the last call counted (one period,
 * the usual case, without the 64-bit division), the steps made (step_once,
 * whose rate decision is kept while it holds: plain_window) and the
 * setpoint filled (fill_sp, its flag logic skipped for a plain one).  A step
 * that keeps its decision inside its segment, one period on with nothing
 * pushed since, is made without the frame of tick_steps: by plain_tick (a
 * run of loads, one imul, the stepper's additions and the setpoint's
 * stores), here, or kept_tick for a re-seed and the test hook's checked
 * steps (tick_other).  Everything else is tick_other's, a tail call: the
 * plain tick saves no register.
 */
int engine_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    /* A plain step (fast_last: inside the segment, no re-seed, so a window
     * and an earlier tick), one period on (d in [p - p/2, 2 p - p/2), as
     * the division would round: one unsigned comparison, d below p - p/2
     * wraps above p), with nothing pushed since: lag_note has nothing to
     * note, and a silent end is noticed at the next tick that decides, as
     * it always was (checked every tick, the silent ends of 2 of the 30
     * frozen outputs, gpxpy_cerknicko-jezero smooth, come a few ticks
     * earlier) */
    if (__builtin_expect(e->out.n < e->out.fast_last, 1) &&
        __builtin_expect((uint64_t)(now_ns - e->out.last_now) - (uint64_t)e->period_lo <
                             (uint64_t)e->cfg.period_ns,
                         1) &&
        plain_key_quiet(e)) {
        plain_tick(e, now_ns, sp);
        return 0;
    }
    return tick_other(e, now_ns, sp);
}

/* engine_tick but for a plain step. */
__attribute__((noinline)) static int tick_other(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    int64_t k = 1, d = now_ns - e->out.last_now, p = e->cfg.period_ns;

    /* A kept step inside its segment (kept_last) that plain_tick does not
     * make (fast_last): a re-seed, or the test hook's; as engine_tick's */
    if (e->out.n < e->out.kept_last && (uint64_t)d - (uint64_t)e->period_lo < (uint64_t)p &&
        plain_key_quiet(e)) {
        kept_tick(e, now_ns, sp);
        return 0;
    }
    if (__builtin_expect(e->pick.n != 0, 0)) {
        /* the waypoints held for delay_s's pick (engine_input.c) wait for
         * the rest of them no longer than the silence that would end their
         * trajectory waits at least (silence.h: SILENCE_INTERVALS times its
         * interval; one alone, max_gap_s) */
        double h = e->pick.n >= 2 ? e->pick.wp[1].t_s - e->pick.wp[0].t_s : 0.0;
        double wait = h > 0 ? fmin(SILENCE_INTERVALS * h, e->cfg.max_gap_s) : e->cfg.max_gap_s;
        if (e->pick.first_ns == INT64_MIN)
            e->pick.first_ns = now_ns;
        else if ((double)(now_ns - e->pick.first_ns) * 1e-9 > wait)
            engine_pick_flush(e);
    }
    if (e->out.have_now) {
        /* ticks on the period grid since the last call (rounded) */
        if ((uint64_t)d - (uint64_t)e->period_lo < (uint64_t)p) {
            k = 1;
        } else if (d < 0) {
            last_setpoint(e, sp);
            return -ENGINE_ESTATE;
        } else {
            k = (d + p / 2) / p;
        }
        if (k == 0) {
            last_setpoint(e, sp);
            sp->now_ns = now_ns;
            e->st.setpoints++;
            return 0;
        }
    }
    return tick_steps(e, now_ns, k, sp);
}

/* engine_tick's k steps, with what each tick notes first. */
static inline int tick_steps(engine_t *e, int64_t now_ns, int64_t k, engine_setpoint_t *sp)
{
    int64_t i;

    e->out.have_now = 1;
    e->out.last_now = now_ns;
    /* issue 26: the sender's time (catchup.h), and a silent end
     * (silence.h); not called where they would answer at once: lag_note
     * with the same input trajectory and no push pending, silence_tick with
     * no push since and no silence pending (engine_silence_pending's first
     * tests) */
    if (e->lag.traj != e->solve.traj || e->lag.pending)
        engine_lag_note(e, now_ns);
    if (e->sil.fresh || (e->sil.arrived && (e->in.open || accept_pending(&e->in.policy))))
        (void)engine_silence_tick(e, now_ns);
    for (i = 0; i < k; i++) {
        if (e->clk.on) /* the play time of each step, the last one's given */
            e->clk.play_ns = e->clk.now_ns - e->clk.delay_ns -
                             (int64_t)llround((double)(k - 1 - i) * e->clk.rate *
                                              (double)e->cfg.period_ns);
        step_once(e);
        if (i + 1 < k && play_stalled(e)) {
            /* Nothing can change before the next push: the remaining steps
             * are identical holds.  Count them instead of looping (a clock
             * jump of hours must not cost hours of steps). */
            int64_t rest = k - 1 - i;
            e->out.cycle += (uint32_t)rest;
            if (e->out.mode != OUT_HOLD && e->scale.on)
                e->out.n += rest; /* as each scaled step at rest would (the grid of s_off) */
            if (e->out.mode == OUT_STREAM && e->out.underrun)
                e->st.underrun_ticks += (uint64_t)rest;
            break;
        }
    }
    if (k > 1) {
        e->st.skipped_ticks += (uint64_t)(k - 1);
        e->out.flags_pending |= ENGINE_SP_SKIPPED;
    }
    fill_sp(e, now_ns, sp);
    e->st.setpoints++;
    return 0;
}
