/*
 * engine_scale.c - the time scaling stage of the play-out (timescale.h,
 * TIMESCALE.md, CLOCK.md): the output off the unit grid, its rate chosen
 * each tick within the limits converted at the curve's speed, the braking
 * capacity left on the solved curve, the speed cap ahead, stops and clears
 * braked to rest, handovers at rate 0, and one clock (locked on the play
 * time or catching up).  It owns engine_scale_t (engine_int.h: the rate, the
 * scaled track time, the override, the stop request, what is known of the
 * curve ahead) and engine_clk_t (the clock).
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "delay.h"
#include "fdiff.h"
#include "timescale.h"

/* A transfer's or REST end's point closer than this to where the output
 * came to rest is taken as reached (rest_handover; metres). */
#define ENGINE_HANDOVER_TOL_M 1e-6

/* The play time (now - D), absolute, and relative to origin_t: epoch
 * seconds in a double are only good to 2.4e-7 s, so the difference is taken
 * in long double from the integer nanoseconds. */
static double play_abs(const engine_t *e)
{
    return (double)((long double)e->clk.play_ns * 1e-9L);
}

static double play_rel(const engine_t *e)
{
    return (double)((long double)e->clk.play_ns * 1e-9L - (long double)e->out.origin_t);
}

/* Scaled output: the curve at s by Horner, then the chain rule
 * (timescale.h): v = k' r, a = k'' r^2 + k' dr/dt. */
void scale_eval(engine_t *e)
{
    double u = (e->scale.s - e->out.cur_t0) / e->out.cur.seg.dur_s, cv[AX], ca[AX], v2 = 0;
    double r = e->scale.ts.rate, ra = e->scale.ts.acc;

    if (u < 0)
        u = 0;
    if (u > 1)
        u = 1;
    e->out.on_fd = 0; /* the output is written here (engine_out_t) */
    fdiff_eval(&e->out.cur.seg, u, e->out.pos, cv, ca);
    for (int k = 0; k < AX; k++) {
        e->out.vel[k] = cv[k] * r;
        e->out.acc[k] = ca[k] * r * r + cv[k] * ra;
        v2 += cv[k] * cv[k];
    }
    e->scale.cspeed = sqrt(v2);
}

static double stop_jerk_speed(const engine_t *e, double A, double jerk);

/* Queue entry i, among the first scan, when it is a segment of the output's
 * trajectory (else NULL): the curve a braking or a ramp may reach, which
 * scale_slowing_reserve, stop_jerk_speed, accel_ahead and stop_jerk_now look
 * through. */
static const qent_t *seg_ahead(const engine_t *e, size_t i, size_t scan)
{
    if (i >= e->queue.len || i >= scan)
        return NULL;
    const qent_t *q = queue_at(e, i);
    return q->kind == QE_SEG && q->traj == e->out.traj ? q : NULL;
}

static double clocked_target(const engine_t *e, double s);

/* With per-axis jerk limits, a braking to rest: a stop, or a target of 0 (a
 * feed hold, the braking for the curve's end, or on one clock an output
 * ahead of its play time by more than the clock's rate over its gain: the
 * clock stepped back). */
static int brakes_to_rest(const engine_t *e)
{
    if (!e->axis_jerk)
        return 0;
    if (e->scale.stop_req || !(scale_target(e) > 0))
        return 1;
    return e->clk.on && e->out.mode == OUT_STREAM && !(clocked_target(e, out_s(e)) > 0);
}

#define STOP_JERK_SCAN 64 /* queue entries a stop looks through (stop_jerk_speed) */

/*
 * The reserve of stop_jerk_reserve, grown before it is needed.  A stop whose
 * braking at the jerk here (J, distance d) would reach a faster segment q
 * converts its jerk at q's speed and needs dq: the need steps from d to dq
 * where the output comes within d of q.  Planned for that step only once it
 * came, a braking for the curve's end reached a segment of ceiling 0 at rate
 * 0.0165 (3.8 m/s on a 3 m/s axis, fuzz_engine
 * axis-bound-passed-while-scaled-at-60-s: the stop's jerk fell 2.6 times one
 * tick before the end braking began, the room fell by 0.015 and 0.0096 was
 * missing).  So the reserve for q grows at half the output's pace over the
 * 2 (dq - d) of track before that point, from 0 to dq - d: the braking meets
 * it without a step.  Each segment faster than every nearer one is looked
 * at (a slower one beyond a faster one needs less).
 */
static double stop_jerk_ahead(const engine_t *e, double A, double J, double d)
{
    if (e->out.mode != OUT_STREAM)
        return 0.0;
    double jerk = e->cfg.scale_jerk_m_s3, r = e->scale.ts.rate, acc = e->scale.ts.acc;
    double t = e->out.t, vseen = jerk / J, res = 0.0;
    const qent_t *q;
    for (size_t i = 0; (q = seg_ahead(e, i, STOP_JERK_SCAN)); i++) {
        if (!(q->vmax > vseen))
            continue; /* one no faster than a nearer one needs less */
        vseen = q->vmax;
        double dq = ts_stop_dist(r, acc, A, jerk / vseen);
        double grown = 0.5 * (t + 2.0 * dq - d - q->seg.t0_s);
        if (dq > d && grown > 0)
            res = fmax(res, fmin(dq - d, grown));
    }
    return res;
}

/* With per-axis jerk limits a stop converts its jerk at the fastest segment
 * it may reach (stop_jerk_speed), which may be less than the streaming's
 * jerk here: the rooms ahead (to the curve's end, to each ceiling) are
 * planned for a braking at that jerk, so that a stop asked for now still
 * fits them.  The braking itself keeps the jerk here: it starts where the
 * weaker one would need to, and the extra distance that one needs from the
 * state now (d: at J) is kept in reserve.  Planned at the jerk here, a stop
 * near a trajectory's rest end entered a segment of ceiling 0.399 at rate 0.58
 * (3.56 m/s^3 on a 2 m/s^3 axis), and another reached the rest end itself at
 * rate 0.03 and handed over there with the curve's acceleration left (3.8
 * m/s^3 on 2; both fuzz_lifecycle). */
static double stop_jerk_reserve(const engine_t *e, double A, double J, double d)
{
    if (!e->axis_jerk || e->scale.stop_req)
        return 0.0;
    double jerk = e->cfg.scale_jerk_m_s3, Jp = jerk / stop_jerk_speed(e, A, jerk), res = 0.0;
    if (Jp < J) {
        double dp = ts_stop_dist(e->scale.ts.rate, e->scale.ts.acc, A, Jp);
        res = dp > d ? dp - d : 0.0;
    }
    return fmax(res, stop_jerk_ahead(e, A, J, d));
}

/* Queue entries looked through for the slowest-converted segment a braking
 * may reach. */
#define SLOW_SCAN 64

/*
 * The capacity of the curve ahead (scale_remaining) is in the units of the
 * limits here, v K: right for the r^2/2 that a braking at a / v takes off,
 * not for the onset and release of that braking at the jerk J (converted at
 * the segment's fastest speed, not at v), which run through track time at
 * about the rate.  Entering a segment whose acceleration limit is converted
 * at a lower speed v' (a larger A in rate units), the room is re-expressed
 * as v' K, and the need with it but for that part: a braking planned to the
 * tick lost its room at the boundary and reached the curve's end moving
 * (1.39 m/s^2 on a 1 m/s^2 axis, fuzz_lifecycle with per-axis limits).  Kept
 * in reserve with per-axis limits, where they hold as hard limits: that part
 * of the stopping distance (ts_stop_dist less r^2/(2 A)) at v_min, times
 * v/v_min, less that part here; v_min the lowest conversion speed of the
 * segments the braking may reach (those starting within twice its distance).
 * Kept as that part here times 1 - v_min/v (the shortfall in the units there
 * taken for the units here), a braking for the curve's end where the
 * conversion fell from 23 to 4.8 m/s reached the end at 0.68 m/s (21 m/s^2
 * on a 4 m/s^2 axis, fuzz_engine).  The room
 * to the ceilings ahead (scale_ceil_room) keeps it too: a stop near a rest end
 * lost that room at each boundary and entered a segment of ceiling 0.099 at
 * rate 0.151.  Without per-axis limits the scaling's acceleration is a target
 * the monitor holds only with its margin, and the play-out is left as it was.
 */
double scale_slowing_reserve(const engine_t *e, double v)
{
    double r = e->scale.ts.rate, A, J, res = 0.0;
    if (e->out.mode != OUT_STREAM || !(r > 0) || !e->queue.len || !solve_axis_limited(e))
        return 0.0;
    scale_limits(e, &A, &J);
    double acc = e->scale.ts.acc, d = ts_stop_dist(r, acc, A, J), onset = d - 0.5 * r * r / A;
    double end = e->out.t + 2.0 * d, vmin = v;
    const qent_t *q;
    for (size_t i = 0; (q = seg_ahead(e, i, SLOW_SCAN)) && !(q->seg.t0_s > end); i++)
        if (q->av > 0 && q->av < vmin)
            vmin = q->av;
    if (vmin < v) {
        /* there the onset is that segment's (its A, v / vmin times the A
         * here in rate units, at the jerk here), and the room v K is vmin K:
         * in the units here it counts v / vmin times */
        double Aj = A * v / vmin, onset_j = ts_stop_dist(r, acc, Aj, J) - 0.5 * r * r / Aj;
        res = fmax(onset_j * v / vmin - (onset > 0 ? onset : 0.0), 0.0);
    }
    return res + stop_jerk_reserve(e, A, J, d);
}

/*
 * Track time still available ahead of s (relative) before the output must
 * be at rest, with TS_MARGIN_TICKS in reserve; INFINITY when the curve ahead
 * ends at rest anyway (a transfer, a closed trajectory with rest ends).
 *
 * Not the plain track time left: the limits are a / v in rate units, so
 * braking on a part of the curve at speed v removes r^2/2 at a / v per unit
 * of track time (d(r^2/2)/ds = dr/dt).  What the curve ahead can absorb is
 * the capacity K = sum of dur / v over it (each segment at its fastest,
 * seg_speed_max, so K is a lower bound), and the output can stop within
 * it from r iff r^2/2 <= a K.  Expressed for ts_step, whose limits are
 * converted at the speed here, that is track time v_here K: more than is
 * left where the curve ahead is slower, less where it is faster.  With the
 * plain track time, a curve speeding up 8x in its last solved segment
 * (bspline + uniform on gpxpy_cerknicko-jezero.csv) was reached at 0.8 of
 * its rate and ended under the moving output (a hard stop).
 */
double scale_remaining(const engine_t *e, double s)
{
    return scale_remaining_gross(e, s) - scale_slowing_reserve(e, scale_conv_speed(e));
}

double scale_remaining_gross(const engine_t *e, double s)
{
    if (e->out.mode == OUT_XFER)
        return e->out.cur_t1 - s; /* left at rate 0 (handover) */
    /* the braking capacity left, in the units of the limits here */
    double in_cur = e->out.cur_t1 - s, v = scale_conv_speed(e), k;
    k = (in_cur > 0 ? in_cur / v : 0.0) + (e->scale.avail_kcum - e->out.cur.kcum);
    /* the margin scales with the rate: standing still needs none, so a
     * buffer shorter than the margin never deadlocks the output */
    return v * k - e->scale.ts.rate * (scale_rise_reserve(e, v) + TS_MARGIN_TICKS * e->period_s);
}

/*
 * The speed cap ahead (ENGINE_SPEED_CAP, TIMESCALE.md "Speed cap"), as a
 * distance for ts_step like scale_remaining(): the output must enter each slow
 * segment ahead (rate ceiling c) at a rate of at most c.  The braking that
 * comes to rest within the track time D to its start plus what a braking at
 * -A from c still needs, ts_stop_dist(c, -A), passes c within D (it passes c
 * decelerating at most at A, and needs at least that much more from there).
 * D as in scale_remaining(): the capacity to the segment's start at the limits
 * here, less the same reserve.  INFINITY if no slow segment is ahead.
 */
double scale_ceil_room(const engine_t *e, double s, double A, double J)
{
    return scale_ceil_room_gross(e, s, A, J) - scale_slowing_reserve(e, scale_conv_speed(e));
}

double scale_ceil_room_gross(const engine_t *e, double s, double A, double J)
{
    double R = INFINITY;

    if (e->out.mode != OUT_STREAM || !e->queue.slow_len)
        return R;
    if (e->axis_jerk && !e->scale.stop_req) {
        /* the ceilings planned for a stop's jerk (stop_jerk_reserve, which
         * scale_ceil_room's scale_slowing_reserve includes): passed at that
         * jerk too */
        double jerk = e->cfg.scale_jerk_m_s3, Jp = jerk / stop_jerk_speed(e, A, jerk);
        J = Jp < J ? Jp : J;
    }
    double in_cur = e->out.cur_t1 - s, v = scale_conv_speed(e);
    double k0 = (in_cur > 0 ? in_cur / v : 0.0) - e->out.cur.kcum;
    double margin = e->scale.ts.rate * TS_MARGIN_TICKS * e->period_s;
    /* the reserve for the rises of the limits: to reach a segment only those
     * before it count (to its end: its own rise too), not every one to the
     * queue's end (scale_rise_reserve).  With all of them, on a curve whose
     * limits alternate piece by piece (the local C2 Hermite's three pieces,
     * per-axis jerk limits of 2 m/s^3) the next capped piece was always
     * too near: the output crawled at rate 0.02 (tests/oracle/test_axis_limits.py) */
    double rfac = scale_rise_per_u(e, e->scale.ts.rate, v);
    double res_all = e->scale.ts.rate * scale_rise_reserve(e, v) + margin;
    for (size_t i = 0; i < e->queue.slow_len; i++) {
        const qent_t *q = &e->queue.ent[e->queue.slow[(e->queue.slow_head + i) % e->queue.cap]];
        if (q->traj != e->out.traj)
            break;
        double kstart = q->kcum - q->seg.dur_s / q->av, base = v * (k0 + kstart);
        /* the distance to a segment's start grows along the queue, the
         * reserve to it is at most res_all, and the stop term is >= 0: past
         * where even res_all leaves R, none binds (the per-axis limits cap
         * most segments of a track, and a replay may queue thousands:
         * without this every tick looked at each) */
        if (base - res_all >= R)
            break;
        double du = q->ucum - e->out.cur.ucum;
        double to = base - (du > 0 ? rfac * du : 0.0) - margin;
        R = fmin(R, to + ts_stop_dist(q->ceil, -A, A, J));
    }
    return R;
}

/* The jerk of a stop or clear (m/s^3): at least a / T, so that the braking
 * reaches its full deceleration within one tick and the stop ends within
 * v^2/(2 a) + v T of path (a jerk j adds v a/(2 j) of onset: TIMESCALE.md,
 * "Stop distance"); with per-axis jerk limits the scaling's own, j. */
static double stop_jerk(const engine_t *e)
{
    if (e->axis_jerk)
        return e->cfg.scale_jerk_m_s3;
    return fmax(e->cfg.scale_jerk_m_s3, e->cfg.scale_accel_m_s2 / e->period_s);
}

/* The speed a stop's jerk is converted at, with per-axis jerk limits: the
 * fastest of the segments it may still reach, at least the current
 * segment's fastest, as outside a stop.  Those it may reach start within
 * its stopping distance at the jerk converted at that speed: the scan takes
 * each faster segment within the distance and widens the distance for it
 * (one pass: the speed and the distance only grow), so the stop planned at
 * that jerk ends within the segments it was converted over.  The braking's
 * release is planned on this jerk: one that shrank on the way (a faster
 * segment entered, or the curve's speed here growing) left its deceleration
 * unreleased at rest, cleared in one tick (2.25 m/s^3 on a 2 m/s^3 axis where
 * it shrank by 0.14 %, fuzz_lifecycle).  The window's far end does not move
 * on as the output brakes towards it: the jerk only grows over a stop.  Its
 * earlier form, twice the distance at the jerk here, took in segments the
 * stop here could not reach: a clear on slow pieces with pieces of 87 and
 * 166 m/s queued just beyond its stop had its jerk cut 87 times, released
 * its braking for that jerk and entered them at rate 0.133, five times
 * their ceiling (1.77 m/s^2 on a 1 m/s^2 axis, fuzz_engine
 * clear-jerk-cut-by-fast-segments-ahead). */
static double stop_jerk_speed(const engine_t *e, double A, double jerk)
{
    double v = scale_jerk_speed(e);
    if (e->out.mode != OUT_STREAM)
        return v; /* a transfer: one segment */
    double r = e->scale.ts.rate, acc = e->scale.ts.acc;
    double end = e->out.t + ts_stop_dist(r, acc, A, jerk / v);
    const qent_t *q;
    for (size_t i = 0; (q = seg_ahead(e, i, STOP_JERK_SCAN)) && !(q->seg.t0_s > end); i++)
        if (q->vmax > v) {
            v = q->vmax;
            end = e->out.t + ts_stop_dist(r, acc, A, jerk / v);
        }
    return v;
}

/* Queue entries looked through for a lower acceleration limit ahead. */
#define ACCEL_AHEAD_SCAN 64

/*
 * issue 32: with per-axis limits, the most a step that speeds up may take
 * the rate's acceleration to: the A here, and what each segment ahead leaves
 * as far as the jerk can take the acceleration down before the output gets
 * there, A_j + J t_j (t_j the least time to reach segment j, its distance at
 * TS_RATE_MAX; J the lower of the jerks here and there), never below what
 * the jerk can take it down to in this tick (a limit learnt late is followed
 * at the jerk).  Each queued segment's av anticipates only the next
 * segment's (engine_solve.c queue_now): where the limits shrink over several
 * segments in a row, a ramp at the A here entered them with ten times their
 * A (1.16 m/s^2 on a 1 m/s^2 axis, fuzz_engine).  scale_step applies it to
 * a step that speeds up more only: brakings and rooms keep the A here.
 */
static double accel_ahead(const engine_t *e, double A, double J, double acc)
{
    if (!e->axis_lim || e->out.mode != OUT_STREAM || e->scale.stop_req)
        return A;
    double jerk = e->cfg.scale_jerk_m_s3, a = e->cfg.scale_accel_m_s2, A0 = A;
    const qent_t *q;
    for (size_t i = 0; (q = seg_ahead(e, i, ACCEL_AHEAD_SCAN)); i++) {
        double t = (q->seg.t0_s - e->out.t) / TS_RATE_MAX;
        if (!(J * t < A))
            break; /* (beyond, only a jerk lower than here could bind) */
        double v = q->vmax > ENGINE_SCALE_V_FLOOR_M_S ? q->vmax : ENGINE_SCALE_V_FLOOR_M_S;
        double Aj = a / q->av + fmin(J, jerk / v) * (t > 0 ? t : 0.0);
        A = Aj < A ? Aj : A;
    }
    /* never below what the jerk can take the acceleration now (acc, before
     * the step) down to in a tick: a limit learnt late (a segment queued
     * within reach) is followed at the jerk, not in one step */
    double down = fabs(acc) - J * e->period_s;
    return down > A ? fmin(down, A0) : A;
}

/* The time scaling's limits in rate units at the curve's speed: outside a
 * stop at the largest speed the curve reaches on the current segment and the
 * next one (conv_speed), so that k' dr/dt stays within a over the ticks ahead
 * also where the curve speeds up (a REST start, entered at rate 0).  A stop
 * converts them at the curve's speed here, down to a T (not the 1 m/s floor):
 * below the floor a slow object would brake at less than a, and a stop from v
 * must end within v^2/(2 a) + v T. */
void scale_limits(const engine_t *e, double *A, double *J)
{
    double v, jerk = e->cfg.scale_jerk_m_s3;

    if (e->scale.stop_req) {
        double floor = fmin(ENGINE_SCALE_V_FLOOR_M_S, e->cfg.scale_accel_m_s2 * e->period_s);
        jerk = stop_jerk(e);
        double cspeed = out_cspeed(e);
        v = cspeed > floor ? cspeed : floor;
        /* at least the segment's own A: the capacity ahead counts it
         * (scale_remaining), and it keeps every axis within its limit; with
         * per-axis jerk limits that A alone (engine_solve.c jerk_rate_accel) */
        *A = e->cfg.scale_accel_m_s2 / scale_conv_speed(e);
        if (!e->axis_jerk)
            *A = fmax(e->cfg.scale_accel_m_s2 / v, *A);
        else /* the jerk at the fastest segment it may reach: converted at the
              * speed here, it shrank as a stop went on along a transfer
              * speeding up, and the braking, released for the larger one, came
              * to rest with its deceleration left (test_axis_share) */
            v = fmax(v, stop_jerk_speed(e, *A, jerk));
    } else {
        v = scale_jerk_speed(e);
        *A = e->cfg.scale_accel_m_s2 / scale_conv_speed(e);
        if (brakes_to_rest(e)) /* planned as a stop's (above; stop_jerk_now) */
            v = fmax(v, stop_jerk_speed(e, *A, jerk));
    }
    *J = jerk / v;
}

/* The rate the output is asked for, before the buffer's limit. */
double scale_target(const engine_t *e)
{
    if (e->scale.stop_req || e->scale.end_brake)
        return 0.0;
    double r = fmin(e->scale.override, scale_ceil_here(e));
    double w = join_may_wait(e) ? join_wait_rate(e) : INFINITY; /* a live re-anchor's wait */
    return w < r ? w : r;
}

/* 1 if the time scaling's next tick would set the output moving (tried on a
 * copy of its state): it advances and is not back at rest at the tick's end
 * (a tick that brakes back to rest within itself, or advances by less than
 * the track time's last bit, repeats for ever on a curve that cannot grow). */
int scale_moves(const engine_t *e, double R, double A, double J)
{
    ts_state_t ts = e->scale.ts;
    int lim = 0;
    double ds = ts_step(&ts, scale_target(e), R, A, J, e->period_s, NULL, &lim);
    return e->scale.s + ds > e->scale.s && !(is_exactly(ts.rate, 0.0) && is_exactly(ts.acc, 0.0));
}

/* Scaled, at rate 0 at the start of cur (s = 0).  Every transfer and every
 * trajectory is entered at rate 0 and every transfer and REST end left at
 * rate 0: there the curve rests (k' = 0) with its own k'' != 0 (the
 * smoothstep's 6 D / T_x^2, a REST end's M), and the output's acceleration
 * k'' r^2 + k' dr/dt is 0 on both sides of the handover instead of stepping
 * by k'' (TIMESCALE.md, "Handovers"). */
void scale_rest(engine_t *e)
{
    e->scale.on = 1;
    e->scale.s = 0.0;
    e->scale.ts.rate = 0.0;
    e->scale.ts.acc = 0.0;
}

/* The output stands within ENGINE_HANDOVER_TOL_M of p. */
static int near_here(const engine_t *e, const double *p)
{
    double d2 = 0;
    for (int k = 0; k < AX; k++)
        d2 += (p[k] - out_pos(e)[k]) * (p[k] - out_pos(e)[k]);
    return d2 <= ENGINE_HANDOVER_TOL_M * ENGINE_HANDOVER_TOL_M;
}

static double stop_jerk_now(const engine_t *e, double J);

/* The time scaling's move of this tick from ts (scale_step's, before a
 * transfer's creep): ts_step within R and the speed cap's room Rc, at the
 * jerk a stop may use now, and, speeding up more, within the acceleration
 * the segments ahead leave too (accel_ahead; a braking keeps the A here).
 * Returns the advance; *lim as ts_step's. */
static double scale_move(const engine_t *e, ts_state_t *ts, double target, double R, double Rc,
                         double A, double J, int *lim)
{
    ts_state_t free_ts = *ts;
    double ds = ts_step_jerk(ts, target, fmin(R, Rc), A, stop_jerk_now(e, J), J, e->period_s, NULL,
                             lim);
    if (ts->acc > 0 && ts->acc >= free_ts.acc) {
        double Aup = accel_ahead(e, A, J, free_ts.acc);
        if (ts->acc > Aup) {
            *ts = free_ts;
            *lim = 0;
            ds = ts_step(ts, target, fmin(R, Rc), Aup, J, e->period_s, NULL, lim);
        }
    }
    return ds;
}

/* At rest (rate 0) within the dead band of the end of a transfer or of a
 * trajectory's REST end (asked to move, the next tick could not: no move of
 * one tick would leave room to stop, ts_step's creep included): the curve is
 * as good as there.  A closed trajectory whose end is not at rest finishes
 * where it stands (finish_here, as its end braking does) (its speed
 * vanishes at the end, the position within k'' d^2 / 2 of it, d the track
 * time left): hand over from its end. */
static void rest_handover(engine_t *e)
{
    double A, J, target = scale_target(e), end[AX];
    ts_state_t probe = e->scale.ts;
    int lim = 0;

    if (!(target > 0))
        return; /* at rest by the override */
    scale_limits(e, &A, &J);
    /* the move the next tick makes (scale_move, as scale_step: the speed
     * cap's room and the acceleration the segments ahead leave included;
     * probed without them, a move from rest that the capped segments ahead
     * allowed no acceleration for was taken as coming, and the output stood
     * short of a closed trajectory's end for good: fuzz_engine) */
    (void)scale_move(e, &probe, target, scale_remaining(e, e->scale.s),
                     scale_ceil_room(e, e->scale.s, A, J), A, J, &lim);
    if (probe.rate > 0)
        return; /* the next tick moves on (its advance from rest alone may be a
                 * rounding residue of 1e-22: not a move) */
    if (e->out.mode == OUT_XFER) {
        fdiff_eval(&e->out.cur.seg, 1.0, end, NULL, NULL);
        if (near_here(e, end))
            play_xfer_end(e);
        return;
    }
    if (e->out.mode != OUT_STREAM || !e->scale.avail_closed)
        return; /* an underrun: resumes when waypoints come */
    const qent_t *h = NULL;
    for (size_t i = 0; i < e->queue.len && !h; i++) {
        const qent_t *q = queue_at(e, i);
        if (q->traj != e->out.traj)
            break;
        if (q->kind == QE_END)
            h = q;
    }
    for (int k = 0; k < AX; k++)
        end[k] = h ? h->seg.c[k][0] : NAN;
    if (!e->scale.avail_rest || !near_here(e, end)) {
        /* an end not at rest (as end_brake would), or one that the braking
         * cannot reach (the curve ahead too fast to stop on from any move):
         * finish where the output stands, never a jump */
        play_finish_here(e);
        return;
    }
    while (q_head(e)->kind == QE_SEG)
        queue_pop(e);
    play_rest_at_end(e, q_head(e));
}

static void scaled_advance(engine_t *e, double s1, double target, int lim);

/* issue 32: while the per-axis limits hold the rate, how far the output
 * trails the newest waypoint of the trajectory it streams beyond its D
 * (only while that trajectory is still being received: a closed input's
 * newest waypoint stands still); past max_lag_s it is told once per
 * trajectory (engine_axis_lag_over). */
static void axis_lag(engine_t *e)
{
    if (e->axis_lag_track != e->out.track) { /* a new trajectory: its own lag */
        e->axis_lag_track = e->out.track;
        e->axis_lag_told = 0;
    }
    if (!e->in.open || e->out.traj != e->solve.traj || !e->solve.nodes || !e->delay.noted)
        return;
    double lag = nt(e, e->solve.nodes - 1) - e->out.t - e->delay.d.delay_s;
    e->st.axis_lag_s = lag > 0 ? lag : 0.0;
    if (e->cfg.max_lag_s > 0 && lag > e->cfg.max_lag_s && !e->axis_lag_told) {
        e->axis_lag_told = e->axis_lag_over = 1;
        e->st.axis_lag_stops++;
    }
}

/* issue 32: at rest before a segment of its trajectory that the per-axis
 * limits cannot follow at any rate the output leaves rest at (ceiling 0,
 * seg_ceiling: the track more than 1 / ENGINE_CEIL_MIN times faster on an
 * axis than its limit), or on one: the owner is told once per trajectory to
 * stop the object there, as past max_lag_s (engine_axis_lag_over), and it
 * is counted (axis_beyond).  Told or not, the output stands (the ceiling
 * holds it at rest), never past an axis's limit. */
static void axis_beyond(engine_t *e)
{
    /* (a feed hold, or no segment beyond the axes queued: nothing to look
     * for; at rest under a hold every tick looked through every capped
     * segment queued: bench_engine --hold) */
    if (e->out.mode != OUT_STREAM || !(e->scale.override > 0))
        return;
    int held = !(e->out.cur.ceil > 0);
    for (size_t i = 0; e->queue.beyond && !held && i < e->queue.slow_len; i++) {
        const qent_t *q = &e->queue.ent[e->queue.slow[(e->queue.slow_head + i) % e->queue.cap]];
        if (q->traj != e->out.traj)
            break;
        held = e->scale.override > 0 && !(q->ceil > 0);
    }
    if (!held)
        return;
    if (e->axis_lag_track != e->out.track) { /* a new trajectory: told anew */
        e->axis_lag_track = e->out.track;
        e->axis_lag_told = 0;
    }
    if (!e->axis_lag_told) {
        e->axis_lag_told = e->axis_lag_over = 1;
        e->st.axis_beyond++;
    }
}

/*
 * With per-axis jerk limits a braking to rest (brakes_to_rest: a stop, a
 * feed hold, the braking for the curve's end) converts its jerk at the
 * fastest segment it may reach (scale_limits, stop_jerk_speed), and every
 * tick of it is planned at that J.  This tick may use the jerk of the
 * segments it moves on, the current one and the next where the tick may
 * reach it: a clear asked during a ramp whose acceleration the converted
 * jerk takes back 50 times slower (a segment of 45 m/s queued ahead of one of
 * 0.9 m/s) was still speeding up when it entered segments whose ceiling it
 * was 10 times above (fuzz_engine).
 */
static double stop_jerk_now(const engine_t *e, double J)
{
    if (!brakes_to_rest(e) || e->out.mode != OUT_STREAM)
        return J;
    double v = scale_jerk_speed(e);
    const qent_t *q = seg_ahead(e, 0, 1);
    if (q && q->seg.t0_s - e->out.t <= 2.0 * TS_RATE_MAX * e->period_s)
        v = fmax(v, q->vmax); /* the tick may reach the next one */
    return fmax(J, e->cfg.scale_jerk_m_s3 / v);
}

/* Whether a kind of limit holds the rate this tick (was: it held it the
 * tick before): from where it first holds it (at the ceiling of a segment
 * it caps, capped, or braking for a capped one ahead, braking and some
 * segment it slows queued) until the rate is back at 1 (not a ramp that
 * has not reached its ceiling yet: that is the start's, in D). */
static int limits_hold(const engine_t *e, int was, int capped, uint64_t slowed, int braking)
{
    if (e->out.mode != OUT_STREAM || !(e->scale.ts.rate < 0.999))
        return 0;
    if ((capped && e->scale.ts.rate >= 0.999 * e->out.cur.ceil) || (braking && slowed))
        return 1;
    return was;
}

/* One tick off the unit grid: the time scaling chooses the advance, within
 * R (scale_remaining) and Rc (scale_ceil_room, which the caller has worked
 * out for this state already: with per-axis limits it scans the capped
 * segments ahead). */
void scale_step(engine_t *e, double target, double R, double Rc, double A, double J)
{
    int lim = 0;
    double s = out_s(e);
    double r0 = e->scale.ts.rate;
    ts_state_t free_ts = e->scale.ts; /* issue 26: held back only if the move differs */
    double ds = scale_move(e, &e->scale.ts, target, R, Rc, A, J, &lim);
    if (e->out.mode == OUT_XFER && !(ds > 0) && at_rest(e) && target > 0)
        ds = ts_creep(&e->scale.ts, fmin(R, Rc), A, J, e->period_s); /* its end, short of it */
    if (lim && !(ds < ts_step(&free_ts, target, INFINITY, A, J, e->period_s, NULL, NULL)))
        lim = 0; /* the curve ahead is short of a stop from the target, but the
                  * move is the one without it (a ramp from rest): no underrun */

    /* issue 32: time lost to the per-axis limits (and, where they do not
     * hold it, to the object's own speed and acceleration limits: the
     * output fell behind its input on jittery stamps with nothing counted) */
    e->axis_episode = limits_hold(e, e->axis_episode, e->out.cur.ceil_axis, e->st.axis_slowed,
                                  lim && Rc < R);
    e->own_episode = !e->axis_episode && limits_hold(e, e->own_episode, e->out.cur.ceil_own,
                                                     e->st.limits_slowed, lim && Rc < R);
    if (e->axis_episode) {
        e->st.axis_lost_s += (1.0 - e->scale.ts.rate) * e->period_s;
        axis_lag(e);
    }
    if (e->own_episode)
        e->st.limits_lost_s += (1.0 - e->scale.ts.rate) * e->period_s;
    /* the rate this tick starts from, if a stop within it keeps to A */
    e->scale.stop_dv = r0 <= A * e->period_s ? r0 : -1.0;
    /* held back by the speed cap ahead, not by the curve running short */
    scaled_advance(e, s + ds, target, lim && !(Rc < R));
    e->scale.stop_dv = -1.0;
}

/* Move the scaled output to track time s1 (relative to origin_t), through
 * the queued segments, and update the states that depend on it. */
static void scaled_advance(engine_t *e, double s1, double target, int lim)
{
    e->scale.on = 1;
    e->out.n++;
    while (s1 >= e->out.cur_t1) {
        if (e->out.mode == OUT_XFER) {
            /* a transfer ends at rest, braked to rate 0 (scale_remaining()) */
            s1 = e->out.cur_t1;
            e->scale.ts.rate = e->scale.ts.acc = 0.0;
            if (e->scale.stop_req)
                break; /* stop on its end */
            play_xfer_end(e);
            if (e->out.mode != OUT_STREAM)
                return;
            s1 = 0.0;
            lim = 0; /* the transfer's own end held this tick back (its creep
                      * onto the start, ts_step), not the trajectory's curve:
                      * no underrun of the trajectory entered at rest */
            continue;
        }
        qent_t *h = q_head(e);
        if (h && h->traj == e->out.traj && h->kind == QE_END) {
            play_rest_at_end(e, h);
            return;
        }
        if (!h || h->traj != e->out.traj) {
            /* cannot happen while scale_remaining() is right: see unit_step.
             * Landing on the end from a rate a tick at A brings to 0 (a creep
             * up to the end of the solved curve at 10 Hz: 7.8 mm/s) is a stop
             * within the limits, not a hard one */
            s1 = e->out.cur_t1;
            if (e->scale.ts.rate > 0 && !(e->scale.stop_dv >= 0))
                e->st.hard_stops++;
            e->scale.ts.rate = e->scale.ts.acc = 0.0;
            break;
        }
        play_take_segment(e);
    }
    e->scale.s = s1;
    scale_eval(e);
    e->out.t = e->out.origin_t + s1;

    if (lim && !e->scale.stop_req && !e->scale.avail_closed && e->out.mode == OUT_STREAM) {
        int why = e->out.underrun ? 0 : engine_delay_reserve_short(e);
        if (why) {
            /* issue 26: the data came on time, the object is faster than
             * the speed D's stop reserve was sized for, or fixes were lost
             * within the lookahead: slowed for it (told on each tick: data
             * that turns late makes it an underrun).  Lost fixes (2) of a
             * sender whose timing varies: D learns an interval, as after an
             * underrun, so that holes that come that often are held, not
             * slowed for each time; a regular sender's (engine_input_regular:
             * its holes are fixes lost) are slowed for and their lag won
             * back, D kept (the 24 h run, 1 % lost, ends with its starting
             * lag) */
            if (!e->out.reserve_slow) {
                e->st.reserve_slowed++;
                if (why == 2 && !engine_input_regular(e))
                    play_slack_learn(e);
            }
            e->out.reserve_slow = 1;
        } else {
            if (!e->out.underrun)
                play_count_underrun(e);
            e->out.underrun = 1;
        }
    } else if (!lim && e->scale.ts.rate >= target) {
        e->out.underrun = 0;
        e->out.reserve_slow = 0;
    }
    if (e->out.underrun)
        e->st.underrun_ticks++;

    if (at_rest(e)) {
        if (e->scale.stop_req) {
            play_stop_at_rest(e);
        } else if (e->scale.end_brake) {
            play_finish_here(e);
        } else {
            axis_beyond(e);
            rest_handover(e);
        }
        return;
    }
    if (!e->clk.on && is_exactly(e->scale.ts.rate, 1.0) && is_exactly(e->scale.ts.acc, 0.0) &&
        is_exactly(target, 1.0)) {
        /* back on a grid of whole periods, shifted by the time lost */
        e->scale.s_off = e->scale.s - tick_time(e, e->out.n);
        e->out.seg_n0 = e->out.n;
        play_seed_cur(e, e->out.n);
        e->scale.on = 0;
        engine_delay_restate(e); /* a fixed start_slack: D where it now trails */
    }
}

/* The rate a clocked trajectory's time scaling is asked for at s (relative):
 * the clock's rate plus ENGINE_CLOCK_GAIN times the lag left after this tick
 * if it ran at that rate, the lag's part bounded by catchup above and by rest
 * below (CLOCK.md); 0 in a stop or at the curve's end. */
static double clocked_target(const engine_t *e, double s)
{
    double rho = e->clk.rate, target = 0.0;
    if (!e->scale.stop_req && !e->scale.end_brake) {
        double lead = ENGINE_CLOCK_GAIN * (play_rel(e) - s - rho * e->period_s);
        if (lead > e->clk.catchup)
            lead = e->clk.catchup;
        target = rho + lead;
        if (target < 0)
            target = 0;
        if (e->scale.override < 1.0)
            target *= e->scale.override;
        target = fmin(target, scale_ceil_here(e));
    }
    return target;
}

/*
 * One tick of a clocked trajectory (CLOCK.md): locked on the play time while
 * it advances by one tick and the curve ahead is long enough to stop in;
 * else the time scaling with the target rate + GAIN * lag, the lag's part
 * bounded by catchup above (a bounded catch-up) and by rest below.
 */
void scale_clocked_step(engine_t *e, double R, double A, double J)
{
    double s = out_s(e), p = play_rel(e), rho = e->clk.rate;
    double T = e->period_s;
    int free_run = !e->scale.stop_req && !e->scale.end_brake && e->scale.override >= 1.0;

    double Rc = scale_ceil_room(e, s, A, J), Rm = fmin(R, Rc);
    if (e->clk.locked && free_run && fabs(p - s - rho * T) <= ENGINE_CLOCK_LOCK_S && p > s &&
        rho <= scale_ceil_here(e) && (isinf(Rm) || ts_stop_dist(rho, 0.0, A, J) < Rm - rho * T)) {
        e->scale.ts.rate = rho;
        e->scale.ts.acc = 0.0;
        e->out.n++;
        scaled_advance(e, p, rho, 0);
        if (e->out.mode == OUT_STREAM)
            e->out.t = play_abs(e);
        return;
    }
    e->clk.locked = 0;
    scale_step(e, clocked_target(e, s), R, Rc, A, J);
    if (e->out.mode == OUT_STREAM && free_run && fabs(p - e->scale.s) <= ENGINE_CLOCK_LOCK_S &&
        fabs(e->scale.ts.rate - rho) <= ENGINE_CLOCK_LOCK_S * ENGINE_CLOCK_GAIN + 1e-9)
        e->clk.locked = 1;
}
