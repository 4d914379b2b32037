/*
 * fuzz_lifecycle.c - libFuzzer target: the lifecycle owner (lib/engine/lifecycle.h)
 * of an object moving along a circle at 2 m/s (waypoints at 10 Hz, sent on as in
 * real time), given events of every kind chosen by the input: which event, when,
 * the override ratio, how long a stall, where a faulted drive coasts to, the
 * sender's pauses, relative or on the epoch clock.
 *
 * Oracle, on every setpoint, as tests/unit/test_lifecycle.c (LIFECYCLE.md):
 *  - no step beyond v T (v = ENGINE_SPEED_CAP x max_speed_m_s, one period T,
 *    also right after a stall);
 *  - no change of velocity (finite differences) beyond a T, a = 3
 *    max_accel_m_s2 + scale_accel_m_s2, except on the tick the monitor's fault
 *    freezes (a drive's fault or boot-up brakes the object to rest);
 *  - the first setpoint after a re-anchor at the drives is their position;
 *  - held by the monitor, held at rest after a drive's brake, or stopped, not
 *    one nanometre of motion;
 *  - the safety monitor with those limits never refuses a setpoint; with
 *    per-axis limits (some inputs; issue 32) it holds them too, the jerk's
 *    included, SAFETY_AXIS_MARGIN above, as the daemon does;
 *  - every rate decision the engine keeps for the ticks ahead (plain_window,
 *    engine_tick.c) is the one it would make on each of them
 *    (engine_plain_check, as tests/unit/test_engine_tick.c checks).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "engine_int.h" /* engine_plain_check, the test hook */
#include "lifecycle.h"
#include "safety.h"

#define PERIOD_NS 10000000LL
#define T_S 0.01
#define MAX_OPS 48
#define EPOCH_S 1700000000.0

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
    engine_t *e;
    safety_t sf;
    lifecycle_t lc;
    double vlim, alim;
    int clocked;
    int64_t now, clk_off, next_wp, pause_until;
    uint32_t seq;
    double drive[3];
    int drive_lost, anchor_pending, freeze_ok, nprev;
    double anchor[3], pv[3];
    engine_setpoint_t prev;
    lc_state_t prev_state;
} fz_t;

static void send_due(fz_t *f)
{
    for (; f->next_wp <= f->now; f->next_wp += 10 * PERIOD_NS) {
        if (f->next_wp < f->pause_until)
            continue;
        engine_waypoint_t w;
        memset(&w, 0, sizeof w);
        double t = (double)f->next_wp * 1e-9; /* the circle of test_lifecycle.c */
        w.t_s = (f->clocked ? EPOCH_S : 0.0) + t;
        w.pos_m[0] = 10.0 * cos(0.2 * t);
        w.pos_m[1] = 10.0 * sin(0.2 * t);
        w.pos_m[2] = 0.1 * t;
        w.seq = ++f->seq;
        (void)lc_push(&f->lc, &w);
    }
}

static void tick(fz_t *f)
{
    engine_setpoint_t sp;
    engine_clock_t clk = {(int64_t)(EPOCH_S * 1e9) + f->now + f->clk_off, 3000000000LL, 1.0, 0.05};
    send_due(f);
    if (lc_tick(&f->lc, f->now, f->clocked ? &clk : NULL, &sp) < 0)
        abort();
    lc_state_t st = lc_state(&f->lc);
    if (sp.flags & ENGINE_SP_NO_POSITION) {
        f->nprev = 0;
    } else if (f->anchor_pending && st != LC_HELD) {
        for (int k = 0; k < 3; k++)
            if (!(fabs(sp.pos_m[k] - f->anchor[k]) <= 1e-9))
                abort(); /* not re-anchored at the drives' position */
        f->anchor_pending = 0;
        f->nprev = 1;
    } else if (f->nprev > 0) {
        double d2 = 0, dv2 = 0, v[3];
        for (int k = 0; k < 3; k++) {
            double d = sp.pos_m[k] - f->prev.pos_m[k];
            d2 += d * d;
            v[k] = d / T_S;
            dv2 += (v[k] - f->pv[k]) * (v[k] - f->pv[k]);
        }
        int frozen_now = st == LC_HELD && f->prev_state != LC_HELD && (f->lc.hold & LC_HOLD_SAFETY);
        int at_rest = fabs(f->pv[0]) + fabs(f->pv[1]) + fabs(f->pv[2]) <= 1e-9;
        if (sqrt(d2) > f->vlim * T_S * 1.0001 + 1e-9)
            abort(); /* a step */
        if (f->nprev > 1 && !frozen_now && !f->freeze_ok &&
            sqrt(dv2) > f->alim * T_S * 1.0001 + 1e-6)
            abort(); /* a velocity step */
        if (((st == LC_HELD && f->prev_state == LC_HELD &&
              ((f->lc.hold & LC_HOLD_SAFETY) || at_rest)) ||
             (st == LC_STOPPED && f->prev_state == LC_STOPPED)) &&
            sqrt(d2) > 1e-9)
            abort(); /* moved while held or latched */
        memcpy(f->pv, v, sizeof v);
        f->nprev = 2;
    } else {
        f->nprev = 1;
        memset(f->pv, 0, sizeof f->pv);
    }
    f->freeze_ok = 0;
    if (!f->drive_lost && !(sp.flags & ENGINE_SP_NO_POSITION))
        memcpy(f->drive, sp.pos_m, sizeof f->drive);
    if (st != LC_HELD && st != LC_NO_POSITION)
        f->drive_lost = 0;
    for (int k = 0; k < SAFETY_FAULT_COUNT; k++)
        if (f->sf.by[k])
            abort(); /* the monitor had to step in */
    f->prev = sp;
    f->prev_state = st;
    f->now += PERIOD_NS;
}

static void event(fz_t *f, lc_event_t ev, uint8_t arg)
{
    lc_state_t st = lc_state(&f->lc);
    lc_arg_t a = {arg / 127.5, NULL, f->drive};
    switch (ev) {
    case LC_EV_WAYPOINT: f->pause_until = 0; return;
    case LC_EV_GAP:
    case LC_EV_UNDERRUN: f->pause_until = f->now + (int64_t)(arg % 64) * 100000000LL; break;
    case LC_EV_STALL: f->now += (int64_t)(2 + arg) * PERIOD_NS; return;
    case LC_EV_CLOCK_STEP:
        if (f->clocked) {
            f->clk_off += ((int64_t)arg - 128) * 40000000LL;
            return;
        }
        break;
    default: break;
    }
    int rc = lc_event(&f->lc, ev, &a);
    if ((ev == LC_EV_DRIVE_LOST || ev == LC_EV_DRIVE_BOOTUP) && lc_state(&f->lc) == LC_HELD) {
        f->drive_lost = 1;
        f->anchor_pending = 0;
        f->drive[arg % 3] += (arg - 128) * 0.004; /* it coasted on */
    }
    if (ev == LC_EV_SAFETY) /* the monitor's own hold; a drive's brakes (issue 23) */
        f->freeze_ok = 1;
    if ((ev == LC_EV_DRIVE_ENABLED || ev == LC_EV_FIRST_POSITION) && rc == 0 &&
        ((st == LC_HELD && f->lc.have_reported) ||
         (st == LC_NO_POSITION && (f->drive_lost || !f->lc.have_sent)))) {
        f->anchor_pending = 1;
        memcpy(f->anchor, f->drive, sizeof f->anchor);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fz_t f;
    engine_config_t c;
    if (size < 1)
        return 0;
    engine_config_default(&c);
    c.period_ns = PERIOD_NS;
    c.capacity = 256;
    c.max_speed_m_s = 5.0;
    c.max_accel_m_s2 = 2.0;
    c.transfer_speed_m_s = 3.0;
    c.transfer_accel_m_s2 = 1.0;
    c.scale_accel_m_s2 = 2.0;
    c.scale_jerk_m_s3 = 20.0;
    c.max_gap_s = 2.0;
    if (data[0] & 2) { /* issue 32: per-axis limits, the jerk's too, which the monitor holds */
        for (int k = 0; k < 2; k++) {
            c.axis_max_speed_m_s[k] = 3.0;
            c.axis_max_accel_m_s2[k] = 1.0;
            c.axis_max_jerk_m_s3[k] = 2.0;
        }
    }
    memset(&f, 0, sizeof f);
    f.e = engine_new(&c, NULL);
    if (!f.e)
        abort();
    f.vlim = ENGINE_SPEED_CAP * c.max_speed_m_s;
    f.alim = 3.0 * c.max_accel_m_s2 + c.scale_accel_m_s2;
    safety_limits_t lim = {.max_speed_m_s = f.vlim * 1.0001,
                           .max_accel_m_s2 = f.alim * 1.0001,
                           .tol_m = SAFETY_TOL_M_DEFAULT};
    safety_axis_limits(&lim, c.axis_max_speed_m_s, c.axis_max_accel_m_s2, c.axis_max_jerk_m_s3);
    safety_init(&f.sf, &lim);
    engine_plain_check(f.e, 1, NULL, NULL); /* each kept decision made again */
    if (lc_init(&f.lc, f.e, &f.sf, PERIOD_NS, 0) < 0)
        abort();
    f.clocked = data[0] & 1;
    f.now = 1000 * PERIOD_NS;
    f.next_wp = f.now;
    for (int i = 0; i < 400; i++) /* moving */
        tick(&f);
    for (size_t i = 1, ops = 0; i + 2 < size && ops < MAX_OPS; i += 3, ops++) {
        event(&f, (lc_event_t)(data[i] % LC_EV_COUNT), data[i + 1]);
        for (int k = 0; k < 4 + data[i + 2]; k++)
            tick(&f);
    }
    uint64_t wrong = 0;
    engine_plain_check(f.e, 1, NULL, &wrong);
    if (wrong)
        abort(); /* a kept decision that a tick would not have made */
    lc_free(&f.lc);
    engine_free(f.e);
    return 0;
}
