/*
 * test_safety.c - the safety monitor (lib/safety/safety.h): every bound is
 * checked against motions whose finite differences are known exactly by hand
 * (constant speed, constant acceleration), with no engine involved.
 */
#include "test.h"

#include <math.h>
#include <string.h>

#include "safety.h"

#define T_NS 10000000LL /* 100 Hz */
#define T_S 0.01

static engine_setpoint_t at(int64_t k, double x)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    sp.now_ns = k * T_NS;
    sp.pos_m[0] = x;
    sp.vel_m_s[0] = 123.0; /* the monitor must not trust what the engine says */
    sp.state = ENGINE_STATE_STREAMING;
    return sp;
}

static safety_t mk(double step, double speed, double accel)
{
    safety_t s;
    safety_limits_t l = {.max_step_m = step, .max_speed_m_s = speed, .max_accel_m_s2 = accel};
    safety_init(&s, &l);
    return s;
}

/* Given a 1 m/s motion and a 2 m/s bound, when a tick jumps 5 cm (5 m/s),
 * then that setpoint is replaced by the last one sent, flagged, counted, and
 * every later one is held until rearmed. */
static void test_speed_violation_holds_and_latches(void **state)
{
    (void)state;
    safety_t s = mk(0, 2.0, 0);
    engine_setpoint_t sp;
    for (int k = 0; k <= 10; k++) {
        sp = at(k, 0.01 * k);
        assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
        assert_memory_equal(&sp.pos_m[0], &(double){0.01 * k}, sizeof(double)); /* untouched */
        assert_false(sp.flags & ENGINE_SP_FAULT);
    }
    sp = at(11, 0.10 + 0.05);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FSPEED);
    assert_true(fabs(sp.pos_m[0] - 0.10) < 1e-15);
    assert_true(fabs(sp.vel_m_s[0]) <= 0.0 && fabs(sp.acc_m_s2[0]) <= 0.0);
    assert_true((sp.flags & (ENGINE_SP_FAULT | ENGINE_SP_HOLD)) ==
                (ENGINE_SP_FAULT | ENGINE_SP_HOLD));
    assert_true(fabs(s.last_value - 5.0) < 1e-9 && fabs(s.last_limit - 2.0) <= 0.0);
    /* latched: even a setpoint that would be fine is held */
    sp = at(12, 0.105);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FSPEED);
    assert_true(fabs(sp.pos_m[0] - 0.10) < 1e-15);
    assert_int_equal(s.by[SAFETY_FSPEED], 1);
    assert_int_equal(s.violations, 2);
    assert_int_equal(s.held, 2);
    double held[3];
    assert_int_equal(safety_held(&s, held), 0);
    assert_true(fabs(held[0] - 0.10) < 1e-15);
    /* rearmed: judged from the held position at rest */
    safety_rearm(&s);
    sp = at(13, 0.10 + 0.001); /* 0.1 m/s from rest */
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    assert_int_equal(safety_fault(&s), 0);
    /* what the last violation was stays told after the clear (the daemon logs
     * it once a second: it named "not finite" for a speed cleared meanwhile) */
    assert_int_equal(s.last_fault, SAFETY_FSPEED);
}

/* Given positions of a constant acceleration a (p = a t^2 / 2), the finite
 * differences give exactly a: a bound of a passes, a bound 1 % below fails. */
static void test_accel_exact(void **state)
{
    (void)state;
    const double a = 10.0;
    for (int pass = 0; pass < 2; pass++) {
        safety_t s = mk(0, 0, pass ? a * 0.99 : a);
        int faults = 0;
        for (int k = 0; k < 100; k++) {
            double t = k * T_S;
            engine_setpoint_t sp = at(k, 0.5 * a * t * t);
            faults += safety_check(&s, &sp) != SAFETY_OK;
        }
        assert_int_equal(faults, pass ? 98 : 0); /* ticks 2..99 once latched */
        if (pass)
            assert_int_equal(s.by[SAFETY_FACCEL], 1);
    }
}

/* Given a constant acceleration a sampled with skipped ticks (intervals of
 * 1 and 3 periods mixed), then it is judged as a, not more: the velocities
 * of two intervals belong to their middles, (dt1 + dt2)/2 apart (the old
 * monitor divided by dt2 alone and saw 2 a after a skip: a false trip of
 * the default bound under load); and 1.01 a over the same ticks trips. */
static void test_accel_across_skipped_ticks(void **state)
{
    (void)state;
    const double a = 10.0;
    static const int steps[] = {1, 1, 3, 1, 1, 3, 3, 1, 2, 1, 3, 1};
    for (int pass = 0; pass < 2; pass++) {
        safety_t s = mk(0, 0, pass ? a / 1.01 : a * (1 + 1e-9));
        int faults = 0;
        int64_t k = 0;
        for (int i = 0; i < 40; i++) {
            double t = (double)k * T_S;
            engine_setpoint_t sp = at(k, 0.5 * a * t * t);
            faults += safety_check(&s, &sp) != SAFETY_OK;
            k += steps[i % 12];
        }
        if (pass)
            assert_int_equal(s.by[SAFETY_FACCEL], 1);
        else
            assert_int_equal(faults, 0);
    }
}

/* Given ticks skipped (dt = 3 periods), then speed is judged over the time
 * that passed; the absolute step bound is not. */
static void test_skipped_ticks_and_step(void **state)
{
    (void)state;
    safety_t s = mk(0, 1.5, 0);
    engine_setpoint_t sp = at(0, 0);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(3, 0.03); /* 1 m/s over 30 ms */
    sp.flags |= ENGINE_SP_SKIPPED;
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    safety_t s2 = mk(0.02, 0, 0);
    sp = at(0, 0);
    assert_int_equal(safety_check(&s2, &sp), SAFETY_OK);
    sp = at(3, 0.03);
    assert_int_equal(safety_check(&s2, &sp), SAFETY_FSTEP);
    /* Euclidean: 0.012 in x and 0.016 in y is a 0.02 step */
    safety_t s3 = mk(0.02, 0, 0);
    sp = at(0, 0);
    assert_int_equal(safety_check(&s3, &sp), SAFETY_OK);
    sp = at(1, 0.012);
    sp.pos_m[1] = 0.016;
    assert_int_equal(safety_check(&s3, &sp), SAFETY_OK);
    sp = at(2, 0.012 + 0.0121);
    sp.pos_m[1] = 0.016 + 0.016;
    assert_int_equal(safety_check(&s3, &sp), SAFETY_FSTEP);
}

/* No position before the first: passed through; NaN, a lost position or a
 * tick time that does not advance afterwards: faults. */
static void test_positions_and_time(void **state)
{
    (void)state;
    safety_t s = mk(0, 1.0, 0);
    engine_setpoint_t sp = at(0, NAN);
    sp.flags = ENGINE_SP_NO_POSITION | ENGINE_SP_HOLD;
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    assert_true(isnan(sp.pos_m[0]));
    assert_int_equal(s.checked, 0);
    /* NaN without the flag before anything was sent: refused, sent as no position */
    sp = at(1, NAN);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FNOTFINITE);
    assert_true(sp.flags & ENGINE_SP_NO_POSITION);
    sp = at(2, 5.0);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK); /* the first position is taken */
    sp = at(3, NAN);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FNOTFINITE);
    assert_true(fabs(sp.pos_m[0] - 5.0) <= 0.0);
    safety_rearm(&s);
    sp = at(4, NAN);
    sp.flags = ENGINE_SP_NO_POSITION;
    assert_int_equal(safety_check(&s, &sp), SAFETY_FNOTFINITE);
    assert_false(sp.flags & ENGINE_SP_NO_POSITION);
    assert_true(fabs(sp.pos_m[0] - 5.0) <= 0.0);
    safety_rearm(&s);
    sp = at(4, 5.0); /* same tick time as the hold sent at 4 */
    assert_int_equal(safety_check(&s, &sp), SAFETY_FTIME);
    assert_string_equal(safety_strerror(SAFETY_FTIME), "tick time did not advance");
}

/* Bounds that are not positive finite numbers are "not checked". */
static void test_bad_limits_off(void **state)
{
    (void)state;
    safety_t s = mk(-1, NAN, INFINITY);
    assert_true(s.lim.max_step_m <= 0 && s.lim.max_speed_m_s <= 0 && s.lim.max_accel_m_s2 <= 0);
    assert_true(fabs(s.lim.tol_m - SAFETY_TOL_M_DEFAULT) <= 0.0);
    engine_setpoint_t sp = at(0, 0);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(1, 1e6);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
}

/* Given a box x in [-1, 2] m (y, z free), when the output walks x = 0, 1, 2,
 * 2.5, then 2 m is sent (on the bound), 2.5 m is not: the output holds at 2,
 * flagged, with the box as the fault; a first position outside the box is
 * sent as "no position" (issue 24: a CiA 402 target is held, never clipped). */
static void test_box(void **state)
{
    (void)state;
    safety_limits_t l = {
        .box = 1, .box_min_m = {-1, -INFINITY, -INFINITY}, .box_max_m = {2, INFINITY, INFINITY}};
    safety_t s;
    safety_init(&s, &l);
    engine_setpoint_t sp = at(0, 0);
    sp.pos_m[1] = 1e9;
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(1, 1);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(2, 2);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(3, 2.5);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FBOX);
    assert_true(fabs(sp.pos_m[0] - 2.0) <= 0.0);
    assert_true(sp.flags & ENGINE_SP_FAULT);
    assert_true(fabs(s.last_value - 2.5) <= 0.0 && fabs(s.last_limit - 2.0) <= 0.0);
    assert_string_equal(safety_strerror(SAFETY_FBOX),
                        "position outside position_min_m .. position_max_m");
    safety_init(&s, &l);
    sp = at(0, -1.5);
    assert_int_equal(safety_check(&s, &sp), SAFETY_FBOX);
    assert_true((sp.flags & ENGINE_SP_NO_POSITION) && isnan(sp.pos_m[0]));
}

/* Given finite positions, when the engine's velocity or acceleration of a
 * setpoint is NaN or infinite, then it is held and flagged like a NaN
 * position: no output row carries an unflagged NaN (issue 24). */
static void test_nonfinite_velocity(void **state)
{
    (void)state;
    safety_t s = mk(0, 0, 0);
    engine_setpoint_t sp = at(0, 0);
    assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    sp = at(1, 0.01);
    sp.vel_m_s[1] = NAN;
    assert_int_equal(safety_check(&s, &sp), SAFETY_FNOTFINITE);
    assert_true(sp.flags & ENGINE_SP_FAULT);
    safety_t u = mk(0, 0, 0);
    sp = at(0, 0);
    assert_int_equal(safety_check(&u, &sp), SAFETY_OK);
    sp = at(1, 0.01);
    sp.acc_m_s2[2] = INFINITY;
    assert_int_equal(safety_check(&u, &sp), SAFETY_FNOTFINITE);
}

/* Given per-axis bounds of 1 m/s and 1 m/s^2 on y only (issue 32) and no
 * Euclidean one, when the motion runs 1.5 m/s along x, then y stays
 * unchecked and it passes; when y then moves 1.2 cm in a tick (1.2 m/s), the
 * axis's speed bound holds it; and a y velocity changing by 2 cm/s per tick
 * (2 m/s^2) breaks the acceleration bound. */
static void test_axis_bounds(void **state)
{
    (void)state;
    safety_t s;
    safety_limits_t l = {.axis_speed_m_s = {0, 1.0, 0}, .axis_accel_m_s2 = {0, 1.0, 0}};
    engine_setpoint_t sp;
    safety_init(&s, &l);
    for (int k = 0; k <= 5; k++) {
        sp = at(k, 0.015 * k);
        assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    }
    sp = at(6, 0.015 * 6);
    sp.pos_m[1] = 0.012;
    assert_int_equal(safety_check(&s, &sp), SAFETY_FAXIS);
    assert_true(fabs(s.last_value - 1.2) < 1e-9 && fabs(s.last_limit - 1.0) <= 0.0);
    safety_init(&s, &l);
    double y = 0, v = 0;
    int f = SAFETY_OK, k;
    for (k = 0; k < 20 && f == SAFETY_OK; k++) {
        sp = at(k, 0.0);
        sp.pos_m[1] = y;
        f = safety_check(&s, &sp);
        v += 0.02; /* m/s per tick: 2 m/s^2 */
        y += v * T_S;
    }
    assert_int_equal(f, SAFETY_FAXIS);
    assert_true(fabs(s.last_value - 2.0) < 1e-6 && fabs(s.last_limit - 1.0) <= 0.0);
    assert_string_equal(safety_strerror(SAFETY_FAXIS),
                        "one axis's speed, acceleration or jerk above its per-axis bound");
}

/* x = j t^3 / 6 at tick k (k0: the motion's start), on x alone. */
static engine_setpoint_t jerk_at(int64_t k, int64_t k0, double j, double x0)
{
    double t = (double)(k - k0) * T_S;
    return at(k, x0 + (k > k0 ? j * t * t * t / 6.0 : 0.0));
}

/* Given a per-axis jerk bound of 1 m/s^3 on x (issue 32: the monitor holds
 * every per-axis limit), when x moves at a constant jerk of 0.9 m/s^3 from
 * rest (also across a skipped tick), then every setpoint passes; at 1.2 m/s^3
 * the jerk bound holds it with the value 1.2; an acceleration that steps by
 * 0.5 m/s^2 at a tick (a C1 curve's at a waypoint: 25 m/s^3 by third
 * differences at 100 Hz) is held too, though within the acceleration bound;
 * after a rearm the motion restarts from rest and is judged from there. */
static void test_axis_jerk(void **state)
{
    (void)state;
    safety_t s;
    safety_limits_t l = {.axis_accel_m_s2 = {10.0, 0, 0}, .axis_jerk_m_s3 = {1.0, 0, 0}};
    engine_setpoint_t sp;
    safety_init(&s, &l);
    for (int64_t k = 0; k <= 300; k++) {
        if (k == 150)
            continue; /* a skipped tick: judged over the time that passed */
        sp = jerk_at(k, 0, 0.9, 0.0);
        assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    }
    safety_init(&s, &l);
    int f = SAFETY_OK;
    for (int64_t k = 0; k <= 300 && f == SAFETY_OK; k++) {
        sp = jerk_at(k, 0, 1.2, 0.0);
        f = safety_check(&s, &sp);
    }
    assert_int_equal(f, SAFETY_FAXIS);
    assert_true(fabs(s.last_value - 1.2) < 1e-6 && fabs(s.last_limit - 1.0) <= 0.0);

    /* an acceleration step: 0 then 0.5 m/s^2 from tick 10 on */
    safety_init(&s, &l);
    f = SAFETY_OK;
    for (int64_t k = 0; k <= 20 && f == SAFETY_OK; k++) {
        double t = (double)(k > 10 ? k - 10 : 0) * T_S;
        sp = at(k, 0.25 * t * t);
        f = safety_check(&s, &sp);
    }
    assert_int_equal(f, SAFETY_FAXIS);
    assert_true(s.last_value > 20.0 && fabs(s.last_limit - 1.0) <= 0.0);
    /* rearmed at rest on the held position: a start at 0.9 m/s^3 passes */
    double held[ENGINE_AXES];
    assert_int_equal(safety_held(&s, held), 0);
    safety_rearm(&s);
    for (int64_t k = 30; k <= 200; k++) {
        sp = jerk_at(k, 30, 0.9, held[0]);
        assert_int_equal(safety_check(&s, &sp), SAFETY_OK);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nonfinite_velocity),
        cmocka_unit_test(test_box),
        cmocka_unit_test(test_speed_violation_holds_and_latches),
        cmocka_unit_test(test_accel_exact),
        cmocka_unit_test(test_accel_across_skipped_ticks),
        cmocka_unit_test(test_skipped_ticks_and_step),
        cmocka_unit_test(test_positions_and_time),
        cmocka_unit_test(test_bad_limits_off),
        cmocka_unit_test(test_axis_bounds),
        cmocka_unit_test(test_axis_jerk),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
