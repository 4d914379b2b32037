/*
 * test_engine_tick.c - engine_tick's one path: the rate decision step_once
 * keeps for the ticks ahead (engine_tick.c plain_window, plain_holds)
 * against making it every tick.  Two engines with the same configuration,
 * one deciding every tick and following that decision
 * (engine_plain_check(e, 2), engine_int.h), the other keeping the decision
 * and recomputing it on every kept tick to count where it would differ
 * (engine_plain_check(e, 1)), get the same calls
 * (pushes between ticks, finish, override changes, stop, clear, halt,
 * clocks that jitter within a period, skip periods, repeat or go back) and
 * must return the same codes, the same setpoints bit for bit (NaN
 * included) and the same status (but lag_s, which a kept tick does not
 * refresh); no kept decision may be wrong, and plain streams must keep
 * most.  Several methods, periods and speeds (so the stopping-distance
 * bound of the window is met and missed), long enough to cross re-seeds
 * (FDIFF_RESEED_STEPS).  And a walk loaded ahead, with every call that
 * changes an engine made between ticks, mostly inside a kept window.
 * A third engine, as in use (no test hook), makes the kept steps inside a
 * segment in one run (plain_tick): its setpoints and status must be the
 * same too; with a stop, halt or join read between ticks from the output
 * (out_pos, out_cspeed), they fail if plain_tick leaves the output where
 * the time scaling last wrote it (on_fd not set on a window begun on a tick
 * that landed on the grid).
 * Checked to fail when the window runs 20 or 40 ticks too long, and when
 * plain_holds leaves the stop request or the override out of its key
 * (leaving out the queue length, the lag's sample or the mode is not caught:
 * the cases made here are covered by the rest of the key or the window's
 * margin).
 */
#include "test.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "engine_int.h"

/* [0] deciding every tick and following that decision (test hook 2), [1]
 * keeping the decision and checking each kept one (hook 1: kept steps the
 * long way, kept_tick), [2] as in use (no hook: kept steps made by
 * plain_tick) */
#define NENG 3
typedef struct {
    engine_t *e[NENG];
    unsigned long setpoints, compared;
} pair_t;

/* The call made on every engine of p (as E), and the same result from each. */
#define EACH_SAME(p, call)                                                                         \
    do {                                                                                           \
        int r0_ = 0;                                                                               \
        for (int i_ = 0; i_ < NENG; i_++) {                                                        \
            engine_t *E = (p)->e[i_];                                                              \
            int r_ = (call);                                                                       \
            if (i_ == 0)                                                                           \
                r0_ = r_;                                                                          \
            else                                                                                   \
                assert_int_equal(r_, r0_);                                                         \
        }                                                                                          \
    } while (0)

static void pair_new(pair_t *p, const engine_config_t *c)
{
    memset(p, 0, sizeof *p);
    for (int i = 0; i < NENG; i++) {
        int err = 0;
        p->e[i] = engine_new(c, &err);
        assert_non_null(p->e[i]);
        engine_plain_check(p->e[i], i == 0 ? 2 : i == 1 ? 1 : 0, NULL, NULL);
    }
}

/* returns the decisions kept */
static uint64_t pair_free(pair_t *p)
{
    engine_status_t s[NENG];
    uint64_t kept = 0, wrong = 0;
    memset(s, 0, sizeof s);
    for (int i = 0; i < NENG; i++) {
        engine_status(p->e[i], &s[i]);
        s[i].lag_s = 0; /* a kept tick leaves it as the last decision told it */
    }
    assert_memory_equal(&s[0], &s[1], sizeof s[0]);
    assert_memory_equal(&s[0], &s[2], sizeof s[0]);
    engine_plain_check(p->e[1], 1, &kept, &wrong);
    if (wrong)
        print_error("%llu of %llu kept decisions wrong\n", (unsigned long long)wrong,
                    (unsigned long long)kept);
    assert_int_equal(wrong, 0);
    for (int i = 0; i < NENG; i++)
        engine_free(p->e[i]);
    return kept;
}

static void pair_tick(pair_t *p, int64_t now)
{
    engine_setpoint_t sp[NENG];
    int rc[NENG];
    memset(sp, 0, sizeof sp);
    for (int i = 0; i < NENG; i++)
        rc[i] = engine_tick(p->e[i], now, &sp[i]);
    for (int i = 1; i < NENG; i++) {
        const engine_setpoint_t *a = &sp[0], *b = &sp[i];
        assert_int_equal(rc[0], rc[i]);
        if (memcmp(a, b, sizeof *a) != 0) {
            print_error("now %lld: decided t %.17g x %.17g v %.17g state %d flags %u cycle %u | "
                        "engine %d t %.17g x %.17g v %.17g state %d flags %u cycle %u\n",
                        (long long)now, a->t_s, a->pos_m[0], a->vel_m_s[0], a->state, a->flags,
                        a->cycle, i, b->t_s, b->pos_m[0], b->vel_m_s[0], b->state, b->flags,
                        b->cycle);
            fail();
        }
    }
    p->compared++;
}

static void pair_push(pair_t *p, const engine_waypoint_t *w)
{
    EACH_SAME(p, engine_push(E, w));
}

/* One random scenario: a walk of n waypoints at dt (irregular), pushed a few
 * at a time between ticks, with the calls above at random ticks. */
static uint64_t scenario_with(unsigned seed, const engine_config_t *c, double dt, double step_m,
                              int events)
{
    int64_t period_ns = c->period_ns;
    pair_t p;
    pair_new(&p, c);
    double pos[3] = {0, 0, 0}, t = 0;
    int64_t now = 0;
    uint32_t seq = 0;
    for (int round = 0; round < 400; round++) {
        int npush = (int)(urand(&seed) * 4);
        for (int i = 0; i < npush; i++) {
            engine_waypoint_t w = {.t_s = t};
            w.seq = seq++;
            for (int k = 0; k < 3; k++) {
                pos[k] += (urand(&seed) - 0.5) * step_m;
                w.pos_m[k] = pos[k];
            }
            pair_push(&p, &w);
            t += dt * (0.7 + 0.6 * urand(&seed));
        }
        int nticks = (int)(dt / ((double)period_ns * 1e-9) * (1 + urand(&seed) * 2));
        for (int i = 0; i < nticks; i++) {
            double r = urand(&seed);
            int64_t d = period_ns;
            if (events && r < 0.02)
                d = (int64_t)(period_ns * (0.5 + urand(&seed))); /* jitter within rounding */
            else if (events && r < 0.025)
                d = period_ns * (2 + (int64_t)(urand(&seed) * 5)); /* skipped periods */
            else if (events && r < 0.027)
                d = 0; /* the same time again */
            else if (events && r < 0.028)
                d = -period_ns; /* backwards: refused, last setpoint */
            now += d;
            pair_tick(&p, now);
            if (d < 0)
                now -= d;
        }
        if (events) {
            double r = urand(&seed);
            if (r < 0.05) {
                double ov = urand(&seed) * 1.5;
                EACH_SAME(&p, engine_set_override(E, ov));
            } else if (r < 0.08) {
                EACH_SAME(&p, engine_set_override(E, 1.0));
            } else if (r < 0.085) {
                EACH_SAME(&p, engine_stop(E));
            } else if (r < 0.09) {
                EACH_SAME(&p, (engine_clear(E), 0));
            } else if (r < 0.095) {
                EACH_SAME(&p, engine_finish(E));
                t += 5 * dt; /* the next waypoints open a new trajectory */
            } else if (r < 0.097) {
                double at[3] = {pos[0], pos[1] + 1.0, pos[2]};
                EACH_SAME(&p, engine_halt(E, at));
            }
        }
    }
    EACH_SAME(&p, engine_finish(E));
    for (int i = 0; i < 200000; i++) {
        now += period_ns;
        pair_tick(&p, now);
    }
    return pair_free(&p);
}

static uint64_t scenario(unsigned seed, engine_method_t m, int64_t period_ns, double dt,
                         double step_m, int events)
{
    engine_config_t c;
    engine_config_default(&c);
    c.method = m;
    c.period_ns = period_ns;
    return scenario_with(seed, &c, dt, step_m, events);
}

static void test_plain_streams(void **state)
{
    (void)state;
    uint64_t kept = 0;
    kept += scenario(1, ENGINE_METHOD_CUBIC, 1000000, 0.2, 2.0, 0);    /* 1 kHz, 5 Hz input */
    kept += scenario(2, ENGINE_METHOD_CUBIC, 10000000, 0.1, 1.0, 0);   /* 100 Hz */
    kept += scenario(3, ENGINE_METHOD_BSPLINE, 1000000, 0.1, 50.0, 0); /* quick: bound short */
    kept += scenario(4, ENGINE_METHOD_SMOOTH, 2000000, 0.25, 0.5, 0);  /* smoother */
    kept += scenario(5, ENGINE_METHOD_CUBIC, 100000, 0.25, 0.01, 0);   /* 10 kHz: re-seeds */
    assert_true(kept > 1000000); /* the plain streams keep the decision on most ticks */
}

static void test_with_events(void **state)
{
    (void)state;
    for (unsigned s = 10; s < 22; s++)
        scenario(s, (engine_method_t)(s % 3), s % 2 ? 1000000 : 10000000, 0.1 + 0.05 * (s % 4),
                 s % 5 == 0 ? 80.0 : 1.5, 1);
}

/* issue 32: with per-axis acceleration limits each segment's acceleration
 * limit is converted at its own speed (qent_t av, engine_solve.c
 * accel_speed), below the jerk's, and a segment is queued once the next one
 * is built: the decision kept on the segments the limits leave at rate 1
 * (walks of steps small enough for most of them) is still the one made. */
static void test_axis_limited(void **state)
{
    (void)state;
    uint64_t kept = 0;
    for (unsigned s = 30; s < 36; s++) {
        engine_config_t c;
        engine_config_default(&c);
        c.method = (engine_method_t)(s % 3);
        c.period_ns = s % 2 ? 1000000 : 10000000;
        c.axis_max_accel_m_s2[0] = 4.0;
        c.axis_max_accel_m_s2[1] = 8.0;
        c.axis_max_speed_m_s[2] = 20.0;
        kept += scenario_with(s, &c, 0.1 + 0.05 * (s % 4), 0.01, s >= 33);
    }
    assert_true(kept > 20000); /* (as many as without the limits: pushes close windows) */
}

/* A walk loaded before the first tick (an upload: no lag to win back, so
 * the decision is kept), then every call that changes an engine made
 * between ticks at random, most of them in the middle of a kept window;
 * returns the decisions kept. */
static uint64_t calls_mid_window(unsigned seed, int64_t period_ns)
{
    engine_config_t c;
    engine_config_default(&c);
    c.period_ns = period_ns;
    c.capacity = 4096;
    c.max_accel_m_s2 = 0; /* the walk's rate not capped (its speed cap: seg_ceiling) */
    pair_t p;
    pair_new(&p, &c);
    double pos[3] = {0, 0, 0}, t = 0;
    uint32_t seq = 0;
    int64_t now = 0;
    for (int i = 0; i < 300; i++, t += 0.1) {
        engine_waypoint_t w = {.t_s = t, .seq = seq};
        seq++;
        for (int k = 0; k < 3; k++)
            w.pos_m[k] = pos[k] += (urand(&seed) - 0.5) * 2.0;
        pair_push(&p, &w);
    }
    for (int round = 0; round < 300; round++) {
        int nticks = 20 + (int)(urand(&seed) * 400);
        for (int i = 0; i < nticks; i++)
            pair_tick(&p, now += period_ns);
        int r = (int)(urand(&seed) * 16);
        engine_rejection_t rj;
        double at[3] = {pos[0], pos[1], pos[2] + 1.0};
        switch (r) {
        case 0:
        case 1:
        case 2: /* more of the walk, ahead of time (an upload: no lag), now and then
                 * a burst or a sharp turn */
            for (int i = 0; i < 1 + (int)(urand(&seed) * 8) || t < (double)now * 1e-9 + 20;
                 i++, t += 0.1) {
                engine_waypoint_t w = {.t_s = t, .seq = seq};
                seq++;
                double step = urand(&seed) < 0.1 ? 30.0 : 2.0;
                for (int k = 0; k < 3; k++)
                    w.pos_m[k] = pos[k] += (urand(&seed) - 0.5) * step;
                pair_push(&p, &w);
            }
            break;
        case 3: { /* a feed override for a while, then back to 1 */
            double ov = urand(&seed) * 1.5;
            EACH_SAME(&p, engine_set_override(E, ov));
            for (int i = 0; i < 50; i++)
                pair_tick(&p, now += period_ns);
            EACH_SAME(&p, engine_set_override(E, 1.0));
            break;
        }
        case 4: EACH_SAME(&p, engine_stop(E)); break;
        case 5: EACH_SAME(&p, (engine_clear(E), 0)); break;
        case 6: EACH_SAME(&p, engine_halt(E, at)); break;
        case 7: EACH_SAME(&p, engine_finish(E)); break;
        case 8: EACH_SAME(&p, engine_set_catchup(E, 0.1)); break;
        case 9: EACH_SAME(&p, (engine_reset_counters(E), 0)); break;
        case 10: EACH_SAME(&p, engine_rejection_next(E, &rj)); break;
        case 11: /* the same time again, and back */
            pair_tick(&p, now);
            pair_tick(&p, now - period_ns / 3);
            break;
        default: break;
        }
        if (r == 4 || r == 5 || r == 6 || r == 7) /* a new trajectory after a while */
            t += 2.0;
    }
    EACH_SAME(&p, engine_finish(E));
    for (int i = 0; i < 100000; i++)
        pair_tick(&p, now += period_ns);
    return pair_free(&p);
}

static void test_calls_mid_window(void **state)
{
    (void)state;
    uint64_t kept = 0;
    for (unsigned s = 30; s < 36; s++)
        kept += calls_mid_window(s, s % 2 ? 1000000 : 10000000);
    assert_true(kept > 5000); /* most of the time the output waits between trajectories */
}

/* issue 32: re-anchors joined moving (join.c): a line at 5 m/s, a waypoint
 * every dt, with jumps aside every 200 waypoints that the speed limit makes
 * the acceptance re-anchor on (at 1 Hz the old curve's last interval is
 * longer than a stop: the window would run past where the join is due),
 * loaded ahead or pushed as it comes; the window kept must end where a join
 * may be due (join_ticks_left), and the joins must be made.  ovr_s > 0: the
 * feed override switched between 1 and 0.5 every ovr_s seconds (a join
 * under it is played at 0.5, and no window is kept while it is not 1; the
 * switches fall mid-window and mid-join).  Returns the decisions kept. */
static uint64_t reanchors(int ahead, int64_t period_ns, double dt, double aside, double ovr_s)
{
    engine_config_t c;
    engine_config_default(&c);
    c.period_ns = period_ns;
    c.profile = ENGINE_PROFILE_NONE;
    c.max_speed_m_s = 5.2;
    c.max_accel_m_s2 = 0;
    pair_t p;
    pair_new(&p, &c);
    int n = 1000, k = 0;
    double span_s = (n + 40) * dt;
    int64_t now = 0;
    if (ovr_s > 0)
        span_s *= 1.6; /* half the time at half the speed */
    int64_t ovr_ticks = (int64_t)(ovr_s * 1e9) / period_ns;
    int was = 0, under = 0;
    for (int64_t tick = 0; tick < (int64_t)(span_s * 1e9) / period_ns; tick++, now += period_ns) {
        while (k < n && (ahead || k * dt <= (double)now * 1e-9)) {
            engine_waypoint_t w = {.t_s = k * dt, .seq = (uint32_t)k};
            w.pos_m[0] = 5.0 * dt * k;
            w.pos_m[1] = aside * (k / 200);
            pair_push(&p, &w);
            if (++k == n)
                EACH_SAME(&p, engine_finish(E));
        }
        if (ovr_ticks > 0 && tick % ovr_ticks == 0) {
            double r = (tick / ovr_ticks) % 2 ? 0.5 : 1.0;
            EACH_SAME(&p, engine_set_override(E, r));
        }
        pair_tick(&p, now);
        int on = p.e[1]->out.mode == OUT_STREAM && p.e[1]->out.cur.join;
        if (on && !was && p.e[1]->scale.override < 1.0)
            under++; /* a join begun under the override */
        was = on;
    }
    engine_status_t st;
    engine_status(p.e[1], &st);
    assert_int_equal(st.reanchors, 4);
    assert_int_equal(st.transfers_moving, 4);
    if (ovr_s > 0)
        assert_true(under > 0);
    return pair_free(&p);
}

static void test_reanchors_joined(void **state)
{
    (void)state;
    uint64_t kept = 0;
    for (int ahead = 0; ahead < 2; ahead++) {
        kept += reanchors(ahead, 10000000, 0.1, 1.5, 0);
        kept += reanchors(ahead, 1000000, 0.1, 1.5, 0);
        kept += reanchors(ahead, 10000000, 1.0, 15.0, 0);
        kept += reanchors(ahead, 10000000, 0.1, 1.5, 3.7); /* under an override (join.c) */
        kept += reanchors(ahead, 10000000, 1.0, 15.0, 37.0);
    }
    assert_true(kept > 100000);
}

/* A stop (or a halt, or a clear) asked for a few ticks after the output
 * landed on the unit grid from the time scaling (the ramp of a start, or
 * back from an override), in the window that began on that tick and before
 * the segment ends: the stop's braking reads the output as it stands
 * (out_cspeed, out_pos), which the kept steps must have left in the
 * stepper.  Segments of 1 s, so that the window runs long inside one. */
static void stop_after_landing(int64_t period_ns, int after, int call, int via_override)
{
    engine_config_t c;
    engine_config_default(&c);
    c.period_ns = period_ns;
    c.max_accel_m_s2 = 0;
    pair_t p;
    pair_new(&p, &c);
    for (int i = 0; i < 60; i++) {
        engine_waypoint_t w = {.t_s = i, .seq = (uint32_t)i};
        w.pos_m[0] = 3.0 * i + 0.5 * sin(0.7 * i);
        w.pos_m[1] = 2.0 * cos(0.3 * i);
        pair_push(&p, &w);
    }
    EACH_SAME(&p, engine_finish(E));
    int64_t now = 0;
    int landed = -1, lowered = 0;
    for (int tick = 0; tick < 200000 && landed < 0; tick++) {
        int was = p.e[2]->scale.on;
        pair_tick(&p, now += period_ns);
        if (via_override && !lowered && was && !p.e[2]->scale.on) {
            /* first on the grid after the start: slow down, then back to 1 */
            EACH_SAME(&p, engine_set_override(E, 0.5));
            for (int i = 0; i < 300; i++)
                pair_tick(&p, now += period_ns);
            EACH_SAME(&p, engine_set_override(E, 1.0));
            lowered = 1;
            continue;
        }
        if ((!via_override || lowered) && was && !p.e[2]->scale.on &&
            p.e[2]->out.mode == OUT_STREAM)
            landed = tick;
    }
    assert_true(landed >= 0);
    for (int i = 0; i < after; i++)
        pair_tick(&p, now += period_ns);
    assert_true(p.e[2]->out.n < p.e[2]->out.fast_last); /* still in the window, its segment */
    double at[3] = {1.0, 2.0, 3.0};
    if (call == 0)
        EACH_SAME(&p, engine_stop(E));
    else if (call == 1)
        EACH_SAME(&p, engine_halt(E, at));
    else
        EACH_SAME(&p, (engine_clear(E), 0));
    for (int i = 0; i < 3000; i++)
        pair_tick(&p, now += period_ns);
    (void)pair_free(&p);
}

static void test_stop_after_landing(void **state)
{
    (void)state;
    for (int via = 0; via < 2; via++)
        for (int call = 0; call < 3; call++)
            for (int after = 1; after < 4; after++) {
                stop_after_landing(10000000, after, call, via);
                stop_after_landing(1000000, after, call, via);
            }
}

/* A stepper seeded with a -0.0 in f (engine_out_t f_negz): z's cubic of
 * every queued segment made of -0.0s (the same curve: z stands at 0), so
 * each seed puts -0.0 in z's position, velocity and acceleration and every
 * step keeps it there (-0.0 + -0.0).  plain_tick stores f's sums without
 * put_sp's + 0.0: such a stepper must not be its, and every setpoint's
 * zeros stay positive (checked to fail with f_negz left out of fast_bound
 * and fill_plain). */
static void test_negative_zero_seed(void **state)
{
    (void)state;
    for (int pi = 0; pi < 2; pi++) {
        int64_t period_ns = pi ? 1000000 : 10000000;
        engine_config_t c;
        engine_config_default(&c);
        c.period_ns = period_ns;
        c.capacity = 1024;
        c.max_accel_m_s2 = 0;
        engine_t *e = engine_new(&c, NULL);
        assert_non_null(e);
        for (int i = 0; i < 200; i++) {
            engine_waypoint_t w = {0};
            w.t_s = 0.1 * i;
            w.pos_m[0] = 0.5 * i;
            w.pos_m[1] = 0.2 * i + 0.01 * (i % 3);
            assert_true(engine_push(e, &w) >= 0);
        }
        assert_int_equal(engine_finish(e), 0);
        unsigned long negz = 0;
        for (size_t i = 0; i < e->queue.len; i++) {
            qent_t *q = &e->queue.ent[(e->queue.head + i) % e->queue.cap];
            if (q->kind != QE_SEG)
                continue;
            for (int k = 0; k < 4; k++) {
                assert_false(q->seg.c[2][k] < 0.0 || q->seg.c[2][k] > 0.0); /* z at 0 */
                q->seg.c[2][k] = -0.0;
            }
        }
        engine_setpoint_t sp;
        unsigned long plain = 0;
        for (int64_t k = 0; k < 100000; k++) {
            assert_int_equal(engine_tick(e, k * period_ns, &sp), 0);
            negz += e->out.f_negz != 0;
            plain += e->out.last_plain != 0;
            assert_false(signbit(sp.pos_m[2]) || signbit(sp.vel_m_s[2]) || signbit(sp.acc_m_s2[2]));
            if (sp.state == ENGINE_STATE_FINISHED)
                break;
        }
        assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
        assert_true(negz > 100 && plain > 100); /* the case is made */
        engine_free(e);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_streams),      cmocka_unit_test(test_with_events),
        cmocka_unit_test(test_calls_mid_window),   cmocka_unit_test(test_reanchors_joined),
        cmocka_unit_test(test_axis_limited),       cmocka_unit_test(test_stop_after_landing),
        cmocka_unit_test(test_negative_zero_seed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
