/*
 * fuzz_engine.c - libFuzzer target: bounded random sequences of pushes (small
 * steps mostly, raw bit patterns for time and position sometimes: NaN and
 * infinities included), ticks (one or several periods, sometimes backwards),
 * finish, stop, clear and counter resets, on several configurations.
 *
 * Oracle: the safe-motion property (issue 10):
 *  - every setpoint is finite (from the first position on);
 *  - no position step beyond the speed limit: between two ticks k periods
 *    apart, |delta pos| <= k * period * max_speed_m_s + 1e-9 m (Euclidean)
 *    when the configuration has a speed limit, both ticks holding;
 *    ENGINE_SPEED_CAP times that both transferring (a join that keeps moving
 *    is one, lib/engine/join.c), CURVE_MARGIN times on the curve (see below);
 *  - lib/safety after the engine, as in the daemon: with the daemon's default
 *    bounds (the per-axis ones SAFETY_AXIS_MARGIN above the per-axis limits,
 *    issue 32) it never refuses a setpoint; with tighter ones (some inputs) what
 *    it lets out keeps them (checked here) and what it refuses is the held
 *    position; rearmed as the daemon does;
 *  - it always finishes: after engine_finish with no further input, the
 *    output reaches FINISHED (or stays WAITING when no waypoint was accepted
 *    since the last clear) within the time the accepted waypoints and their
 *    transfers can take, and rests there; FINISHED when the last command
 *    since the last accepted waypoint was a stop (engine.h: the later of stop
 *    and clear decides the state at rest, even while the output brakes).
 *
 * Fast by construction: the engine's buffer is the smallest the configuration
 * allows (lookahead + fragment + 8 waypoints; the default 4096 cost a 2 MB
 * calloc per input), at most MAX_OPS operations and MAX_PUSH waypoints per
 * input (judging and fitting waypoints is most of the engine's work: a push
 * costs about two ticks), coordinates within
 * max_abs_m = 20 m and gaps above 1 s so transfers and tracks stay short.
 */
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "safety.h"

#define MAX_OPS 128
#define MAX_PUSH 40 /* several lookaheads (engine_lookahead: 8..14 waypoints) */
/* The curve passes through the waypoints at their times, and engine_push
 * checks the mean speed between waypoints against max_speed_m_s; between them
 * the cubic may be faster (1.5 x the mean on a rest-to-rest segment).  Steps
 * on the curve are checked against CURVE_MARGIN x the limit, the daemon's
 * default safety bound (daemon/core/core.c obj_safety_limits: the engine must
 * never trip its own monitor); holds against the limit itself, transfers
 * (rest-to-rest at most the limit, engine.h; a join that keeps moving at most
 * ENGINE_SPEED_CAP times it) against ENGINE_SPEED_CAP times it. */
#ifndef CURVE_MARGIN
#define CURVE_MARGIN 2.0
#endif
#define HOLD_OR_TRANSFER (ENGINE_SP_HOLD | ENGINE_SP_TRANSFER)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static double take_double(const uint8_t **p, const uint8_t *end)
{
    double d = 0;
    if (end - *p >= (long)sizeof(d)) {
        memcpy(&d, *p, sizeof(d));
        *p += sizeof(d);
    }
    return d;
}

typedef struct {
    engine_t *e;
    engine_config_t c;
    int64_t now;
    engine_setpoint_t last;
    int have_last;          /* last holds a setpoint with a position */
    int positioned;         /* a waypoint was accepted or a position set: from the
                        next tick on, every setpoint is a position */
    safety_t mon;           /* lib/safety as the daemon runs it after the engine */
    int tight;              /* mon has bounds the engine may break (else the daemon's defaults) */
    engine_setpoint_t sent; /* the last setpoint mon let out or held */
    int have_sent;
} run_t;

/* The monitor: what it lets out keeps its bounds, checked here independently;
 * what it refuses is replaced by the last position sent; with the daemon's
 * default bounds the engine never trips it. */
static void monitor(run_t *r, const engine_setpoint_t *sp)
{
    engine_setpoint_t out = *sp;
    int rc = safety_check(&r->mon, &out);
    if (rc == SAFETY_OK) {
        if (memcmp(out.pos_m, sp->pos_m, sizeof out.pos_m) || r->mon.fault)
            abort();
    } else {
        if (!r->tight) {
            if (getenv("FUZZ_DBG")) /* what tripped it, where */
                fprintf(stderr, "fault %d: %g against %g, state %d, flags %#x, now %lld ns\n", rc,
                        r->mon.last_value, r->mon.last_limit, (int)sp->state, (unsigned)sp->flags,
                        (long long)sp->now_ns);
            abort(); /* the engine tripped the daemon's default monitor */
        }
        if (!(out.flags & SAFETY_SP_FAULT) || !r->mon.fault)
            abort();
        if (r->have_sent && memcmp(out.pos_m, r->sent.pos_m, sizeof out.pos_m))
            abort(); /* a refused setpoint is the held position */
    }
#ifdef ENGINE_SP_NO_POSITION
    if (out.flags & ENGINE_SP_NO_POSITION)
        return;
#endif
    for (int a = 0; a < ENGINE_AXES; a++)
        if (!isfinite(out.pos_m[a]))
            abort();
    if (r->have_sent && rc == SAFETY_OK) {
        const safety_limits_t *lim = &r->mon.lim;
        double d2 = 0, dt = (double)(out.now_ns - r->sent.now_ns) * 1e-9;
        for (int a = 0; a < ENGINE_AXES; a++)
            d2 += (out.pos_m[a] - r->sent.pos_m[a]) * (out.pos_m[a] - r->sent.pos_m[a]);
        double tol = lim->tol_m + 1e-12;
        if ((lim->max_step_m > 0 && sqrt(d2) > lim->max_step_m + tol) ||
            (lim->max_speed_m_s > 0 && sqrt(d2) > lim->max_speed_m_s * dt + tol))
            abort();
    }
    r->sent = out;
    r->have_sent = 1;
}

/* Before any position exists the output is no position (ENGINE_SP_NO_POSITION,
 * NaN; before that flag existed: a documented hold at 0), not a setpoint: the
 * step bound applies from the first position on. */
static int no_position(const run_t *r, const engine_setpoint_t *sp)
{
#ifdef ENGINE_SP_NO_POSITION
    if (sp->flags & ENGINE_SP_NO_POSITION) {
        if (r->have_last || sp->state == ENGINE_STATE_STREAMING)
            abort(); /* a position, once there, is never lost; no motion without one */
        return 1;
    }
#endif
    (void)sp;
    return !r->positioned;
}

/* Tick to now + k periods and check the setpoint against the previous one. */
static void tick(run_t *r, int64_t k)
{
    engine_setpoint_t sp;
    r->now += k * r->c.period_ns;
    int rc = engine_tick(r->e, r->now, &sp);
    if (rc != 0) {
        if (getenv("FUZZ_DBG"))
            fprintf(stderr, "engine_tick: %d\n", rc);
        abort(); /* time went forward: never refused */
    }
    if (engine_axis_lag_over(r->e)) /* max_lag_s passed: the owner stops (issue 32) */
        (void)engine_stop(r->e);
    monitor(r, &sp);
    if (no_position(r, &sp))
        return;
    for (int a = 0; a < ENGINE_AXES; a++)
        if (!isfinite(sp.pos_m[a]) || !isfinite(sp.vel_m_s[a]) || !isfinite(sp.acc_m_s2[a]))
            abort();
    if (r->have_last && r->c.max_speed_m_s > 0) {
        double d2 = 0;
        for (int a = 0; a < ENGINE_AXES; a++)
            d2 += (sp.pos_m[a] - r->last.pos_m[a]) * (sp.pos_m[a] - r->last.pos_m[a]);
        /* a join that keeps moving is a transfer too (ENGINE_SP_TRANSFER), within
         * ENGINE_SPEED_CAP x the limit (lib/engine/join.c): a 20-tick step across
         * one went 5.17 m/s on a 5 m/s limit */
        int exact = (sp.flags & HOLD_OR_TRANSFER) && (r->last.flags & HOLD_OR_TRANSFER);
        int held = (sp.flags & ENGINE_SP_HOLD) && (r->last.flags & ENGINE_SP_HOLD);
        double bound = (double)k * (double)r->c.period_ns * 1e-9 * r->c.max_speed_m_s *
                           (held    ? 1
                            : exact ? ENGINE_SPEED_CAP
                                    : CURVE_MARGIN) +
                       1e-9;
        if (sqrt(d2) > bound)
            abort();
    }
    r->last = sp;
    r->have_last = 1;
}

static void configure(engine_config_t *c, uint8_t b0, uint8_t b1)
{
    engine_config_default(c);
    switch (b0 % 7) {
    case 1:
        c->method = ENGINE_METHOD_BSPLINE;
        c->param = ENGINE_PARAM_UNIFORM;
        c->ends = ENGINE_ENDS_MULTIPLE;
        c->fragment = 8;
        c->overlap = 4;
        break;
    case 2:
        c->ends = ENGINE_ENDS_NATURAL;
        c->fragment = 6;
        c->overlap = 2;
        c->start_slack = 0;
        break;
    case 3:
        c->method = ENGINE_METHOD_BSPLINE;
        c->param = ENGINE_PARAM_UNIFORM;
        c->ends = ENGINE_ENDS_HELD;
        c->fragment = 8;
        c->overlap = 4;
        break;
    case 4:
        c->method = ENGINE_METHOD_SMOOTH;
        c->fragment = 8;
        c->overlap = 4;
        c->smooth_window = 8;
        c->smooth_ctrl = 4;
        break;
    case 5: /* the local methods (issue 31) */
        c->method = (b0 & 0x10) ? ENGINE_METHOD_HERMITE_C2 : ENGINE_METHOD_HERMITE;
        c->ends = ENGINE_ENDS_NATURAL;
        break;
    case 6:
        /* too short for any fragment: HERMITE_C2_CENTRED, or at 1 HERMITE_C2
         * with each fix kept as it arrives (issue 31, accept.h at_arrival) */
        c->max_lookahead = (b0 & 0x10) ? 1 : 3;
        break;
    default:
        c->fragment = 8 + (b0 >> 4);
        c->overlap = 2 * (1 + (b0 >> 6));
        break;
    }
    static const double speeds[4] = {100, 10, 0, 5};
    c->max_speed_m_s = speeds[b1 & 3];
    c->max_accel_m_s2 = (b1 & 4) ? 0 : 30;
    c->period_ns = (b1 & 8) ? 100000000 : 20000000;
    c->max_gap_s = 1;
    c->max_abs_m = 20;
    if (b0 & 0x08) { /* issue 32: per-axis limits (and max_lag_s) */
        const double v[3] = {2, 3, 0}, a[3] = {1, 4, 0}, j[3] = {20, 0, 0};
        /* no jerk limit on the C1 curve (engine_config_check refuses it) */
        int c1 = c->method == ENGINE_METHOD_HERMITE;
        for (int k = 0; k < 3; k++) {
            c->axis_max_speed_m_s[k] = v[k];
            c->axis_max_accel_m_s2[k] = a[k];
            c->axis_max_jerk_m_s3[k] = c1 ? 0 : j[k];
        }
        c->max_lag_s = (b1 & 0x40) ? 2 : 0;
    }
    if (b1 & 0x80) /* issue 31: delay_s picks the lookahead from the first waypoints */
        c->delay_s = (b0 & 0x20) ? 1.0 : 4.0;
    engine_config_t r; /* fragment auto (case 6): the one resolved */
    unsigned f = engine_config_resolve(c, &r) == 0 ? r.fragment : c->fragment;
    c->capacity = engine_lookahead(c) + f + 8 + ((b1 >> 4) & 7);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *p = data, *end = data + size;
    run_t r;
    engine_status_t st;
    double t = 0;
    unsigned accepted = 0, ops = 0, pushes = 0;
    int stopped = 0; /* engine_stop was the last command since the last accepted waypoint */

    if (size < 2)
        return 0;
    memset(&r, 0, sizeof r);
    configure(&r.c, p[0], p[1]);
    safety_limits_t lim = {0};
    r.tight = (p[1] & 0x80) != 0;
    if (r.tight) { /* bounds the engine may break: the monitor's own paths */
        double v = r.c.max_speed_m_s > 0 ? r.c.max_speed_m_s : 10;
        lim.max_speed_m_s = (p[0] & 0x20) ? 0.5 * v : 0;
        lim.max_step_m = (p[0] & 0x40) ? 0.02 : 0;
        lim.max_accel_m_s2 = (p[0] & 0x80) ? 20 : 0;
    } else { /* the daemon's defaults (obj_safety_limits) */
        lim.max_speed_m_s = 2.0 * r.c.max_speed_m_s;
    }
    /* the per-axis bounds as the daemon holds them (obj_safety_limits,
     * SAFETY_AXIS_MARGIN above the engine's: the finite differences of the
     * setpoints it measures by); with the defaults the engine never trips them */
    safety_axis_limits(&lim, r.c.axis_max_speed_m_s, r.c.axis_max_accel_m_s2,
                       r.c.axis_max_jerk_m_s3);
    safety_init(&r.mon, &lim);
    p += 2;
    r.e = engine_new(&r.c, NULL);
    if (!r.e)
        abort();
    while (p < end && ops++ < MAX_OPS) {
        uint8_t op = *p++;
        switch (op % 8) {
        case 0:
        case 1:
        case 2: { /* push: small steps mostly, raw doubles sometimes */
            engine_waypoint_t w = {0};
            if (pushes++ >= MAX_PUSH)
                break;
            if (op & 0x80) {
                w.t_s = take_double(&p, end);
                for (int k = 0; k < 3; k++)
                    w.pos_m[k] = take_double(&p, end);
                if (op & 0x40) { /* with the source's velocity (the local methods) */
                    w.has_vel = 1;
                    for (int k = 0; k < 3; k++)
                        w.vel_m_s[k] = take_double(&p, end);
                }
            } else {
                t += (op >> 3) * 0.02;
                w.t_s = t;
                for (int k = 0; k < 3 && p < end; k++)
                    w.pos_m[k] = 0.125 * (double)(int8_t)*p++;
            }
            if (engine_push(r.e, &w) == 0) {
                accepted++;
                stopped = 0;
                r.positioned = 1;
            }
            break;
        }
        case 3:
        case 4:
        case 5: tick(&r, (op >> 3) + 1); break;
        case 6:
            if (op & 0x40) {
                engine_clear(r.e);
                accepted = 0;
                stopped = 0;
            } else if (op & 0x20) {
                (void)engine_stop(r.e);
                accepted = 0; /* every waypoint buffered is dropped */
                stopped = 1;
            } else {
                (void)engine_finish(r.e);
            }
            break;
        default:
            if ((op & 0x80) && r.have_last) {
                engine_setpoint_t sp;
                if (engine_tick(r.e, r.now - r.c.period_ns, &sp) != -ENGINE_ESTATE)
                    abort(); /* backwards: refused */
            } else if (op & 0x40) {
                engine_reset_counters(r.e);
            } else if ((op & 0x20) && safety_fault(&r.mon)) {
                /* rearm as the daemon does: the engine stands on the held position */
                double held[ENGINE_AXES];
                engine_clear(r.e);
                accepted = 0;
                stopped = 0;
                if (safety_held(&r.mon, held) < 0 || engine_set_position(r.e, held) == 0) {
                    safety_rearm(&r.mon);
                    r.last = r.sent; /* the engine continues from what was sent */
                    r.have_last = r.have_sent;
                }
            }
            engine_status(r.e, &st);
            break;
        }
    }

    /* It always finishes.  Every accepted waypoint adds at most max_gap_s of
     * track and may start a trajectory reached by a transfer of at most
     * max(1 s, TRANSFER_GAP_CAP x max_gap_s, 1.5 * distance / speed limit)
     * (lib/engine/transfer.h, derived limits), distance at most the box's
     * diagonal.  (accepted counts the waypoints taken for judgement: the
     * engine may refuse some later, lib/engine/accept.h.) */
    (void)engine_finish(r.e);
    double diag = 2 * sqrt(3) * r.c.max_abs_m;
    double transfer = fmax(fmax(1, 60.0 * r.c.max_gap_s),
                           r.c.max_speed_m_s > 0 ? 1.5 * diag / r.c.max_speed_m_s : 0) +
                      1;
    double bound_s = (double)accepted * (r.c.max_gap_s + transfer) + transfer + 1;
    if (r.c.axis_max_speed_m_s[0] > 0) /* per-axis limits: down to the ceiling's floor */
        bound_s *= 100.0;
    int64_t step = 20, n = (int64_t)(bound_s * 1e9 / (double)r.c.period_ns) / step + 2;
    for (int64_t i = 0; i < n; i++) {
        engine_status(r.e, &st);
        if (st.state == ENGINE_STATE_FINISHED ||
            (accepted == 0 && st.state == ENGINE_STATE_WAITING))
            break;
        tick(&r, step);
    }
    engine_status(r.e, &st);
    if (!(st.state == ENGINE_STATE_FINISHED || (accepted == 0 && st.state == ENGINE_STATE_WAITING)))
        abort();
    if (stopped && st.state != ENGINE_STATE_FINISHED)
        abort();
    /* and rests there */
    engine_setpoint_t rest = r.last;
    tick(&r, 1);
    if (r.have_last)
        for (int a = 0; a < ENGINE_AXES; a++)
            if (fabs(r.last.pos_m[a] - rest.pos_m[a]) > 1e-9 || fabs(r.last.vel_m_s[a]) > 0)
                abort();
    engine_free(r.e);
    return 0;
}
