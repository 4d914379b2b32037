/*
 * test_core_hold.c - the feed hold of an object (daemon/core/core.h obj_hold,
 * and obj_command's override and clear, as CAN and Modbus send them): the one
 * owner of the hold a CiA 402 drive's lost heartbeat asks for, whichever
 * source (CAN, Modbus) writes the override; and the drive events daemon/can
 * raises (obj_drive_event).
 * Driven with a real engine, no clock, no sockets.
 */
#include "test.h"

#include <math.h>
#include <string.h>

#include "core.h"

#define PERIOD_NS 10000000LL /* 100 Hz */

/* A straight line along x at 1 m/s from x0, one waypoint a second. */
static void push_line(obj_t *o, double x0, uint32_t seq0)
{
    for (int i = 0; i < 20; i++) {
        engine_waypoint_t w;
        memset(&w, 0, sizeof w);
        w.t_s = i;
        w.pos_m[0] = x0 + i;
        w.seq = seq0 + (uint32_t)i;
        assert_int_equal(engine_push(o->engine, &w), 0);
    }
    assert_int_equal(engine_finish(o->engine), 0);
}

/* Tick from tick k0 for n ticks; returns the last setpoint. */
static engine_setpoint_t run(obj_t *o, int64_t k0, int n)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    for (int64_t k = k0; k < k0 + n; k++)
        assert_int_equal(engine_tick(o->engine, k * PERIOD_NS, &sp), 0);
    return sp;
}

/* The override command, as a CAN frame or a Modbus write gives it. */
static int override(obj_t *o, unsigned percent)
{
    return obj_command(o, percent ? LC_EV_OVERRIDE : LC_EV_OVERRIDE_ZERO, percent, "test");
}

/* An object with the default engine and safety monitor, given the straight
 * line from t = 0 (push_line). */
static void moving_obj(obj_t *o)
{
    engine_config_t c;
    engine_config_default(&c);
    memset(o, 0, sizeof *o);
    o->engine = engine_new(&c, NULL);
    assert_non_null(o->engine);
    safety_limits_t lim = {.tol_m = SAFETY_TOL_M_DEFAULT};
    safety_init(&o->safety, &lim);
    push_line(o, 0.0, 1);
}
/* Given an object moving at 1 m/s, when it is held (a drive's heartbeat
 * lost, obj_hold), then it comes to rest on its path; an override to move
 * again (as a Modbus override register write or a CAN override frame makes
 * it, obj_command) is refused with -ENGINE_ESTATE (Modbus: exception 03,
 * counted in mb_rejected; CAN: cmd_refused) and the object stays at rest; an
 * override 0 is taken; the clear releases the hold and the feed is back at
 * 100 %: a new track moves the object again. */
static void test_hold_refuses_override_until_clear(void **state)
{
    (void)state;
    obj_t o;
    moving_obj(&o);
    engine_setpoint_t sp = run(&o, 0, 500);
    assert_true(sp.vel_m_s[0] > 0.5);
    double x_at_hold = sp.pos_m[0];
    obj_hold(&o);
    sp = run(&o, 500, 500);
    assert_true(fabs(sp.vel_m_s[0]) < 1e-9);
    double x_held = sp.pos_m[0];
    assert_true(x_held > x_at_hold && x_held < 19.0); /* stopped on the path, short of its end */
    assert_int_equal(override(&o, 100), -ENGINE_ESTATE);
    assert_int_equal(override(&o, 1), -ENGINE_ESTATE);
    assert_int_equal(override(&o, 0), 0);
    sp = run(&o, 1000, 300);
    assert_true(fabs(sp.pos_m[0] - x_held) < 1e-9); /* still at rest */
    assert_int_equal(obj_command(&o, LC_EV_CLEAR, 0, "test"), 0);
    assert_int_equal(o.held, 0);
    sp = run(&o, 1300, 10);
    push_line(&o, sp.pos_m[0], 100);
    sp = run(&o, 1310, 500);
    assert_true(sp.pos_m[0] > x_held + 1.0); /* moving again at the feed */
    assert_int_equal(override(&o, 50), 0);
    engine_free(o.engine);
}

/* Tick through the owner (lc_tick) from tick k0 for n ticks. */
static engine_setpoint_t run_lc(obj_t *o, int64_t k0, int n)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    for (int64_t k = k0; k < k0 + n; k++)
        assert_int_equal(lc_tick(obj_lc(o), k * PERIOD_NS, NULL, &sp), 0);
    return sp;
}

/* moving_obj, ticked through its owner (lc_tick) for 5 s: moving at 1 m/s;
 * the last setpoint. */
static engine_setpoint_t moving_through_owner(obj_t *o)
{
    moving_obj(o);
    o->lc.period_ns = PERIOD_NS;
    engine_setpoint_t sp = run_lc(o, 0, 500);
    assert_true(sp.vel_m_s[0] > 0.5);
    return sp;
}

/* Given an object moving at 1 m/s with CiA 402 drives, when a drive is lost
 * (obj_drive_event LC_EV_DRIVE_LOST, as daemon/can raises it), then the
 * object is held and brakes to rest along its path (not frozen at once); the
 * drives enabled again while it is held are not adopted (obj_drive_event
 * returns 0: the CAN side must not hand the drives the engine's targets);
 * after clear nothing is sent until the drives report, and their position
 * is adopted (returns 1), the first setpoint there. */
static void test_drive_events_through_the_owner(void **state)
{
    (void)state;
    obj_t o;
    engine_setpoint_t sp = moving_through_owner(&o);
    assert_int_equal(obj_drive_event(&o, LC_EV_DRIVE_LOST, NULL), 0);
    assert_int_equal(lc_state(&o.lc), LC_HELD);
    engine_setpoint_t b = run_lc(&o, 500, 1);
    assert_true(b.vel_m_s[0] > 0.5 * sp.vel_m_s[0]); /* braking, not frozen */
    b = run_lc(&o, 501, 500);
    assert_true(fabs(b.vel_m_s[0]) < 1e-9);
    assert_int_equal(lc_state(&o.lc), LC_HELD);
    double at[ENGINE_AXES] = {b.pos_m[0] - 0.004, 0.0, 0.0};
    assert_int_equal(obj_drive_event(&o, LC_EV_DRIVE_ENABLED, at), 0); /* not adopted */
    b = run_lc(&o, 1001, 10);
    assert_true(fabs(b.pos_m[0] - at[0]) > 1e-3); /* still held where it braked */
    (void)obj_command(&o, LC_EV_CLEAR, 0, NULL);
    b = run_lc(&o, 1011, 10);
    assert_true(b.flags & ENGINE_SP_NO_POSITION); /* the drives' position awaited afresh */
    at[0] += 0.002;
    assert_int_equal(obj_drive_event(&o, LC_EV_DRIVE_ENABLED, at), 1); /* adopted */
    b = run_lc(&o, 1021, 1);
    assert_true(fabs(b.pos_m[0] - at[0]) < 1e-12); /* re-anchored at the drives */
    /* the heartbeat: a feed hold, released by clear */
    assert_int_equal(obj_drive_event(&o, LC_EV_HEARTBEAT_LOST, NULL), 0);
    assert_int_equal(o.held, 1);
    assert_int_equal(obj_drive_event(&o, LC_EV_HEARTBEAT_BACK, NULL), 0);
    assert_int_equal(o.held, 1);
    (void)obj_command(&o, LC_EV_CLEAR, 0, NULL);
    assert_int_equal(o.held, 0);
    lc_free(&o.lc);
    engine_free(o.engine);
}

/* Given an object moving at 1 m/s, when its drives report enabled again
 * (obj_drive_event LC_EV_DRIVE_ENABLED while the engine moves: not adopted,
 * daemon/can brings it to rest first), then that is no command refused: the
 * status line's "commands refused" stays 0 (it read 13 or 29 after a reload
 * of drives with no command sent). */
static void test_drive_event_is_no_command(void **state)
{
    (void)state;
    obj_t o;
    engine_setpoint_t sp = moving_through_owner(&o);
    double at[ENGINE_AXES] = {sp.pos_m[0], 0.0, 0.0};
    assert_true(obj_drive_event(&o, LC_EV_DRIVE_ENABLED, at) <= 0); /* not adopted */
    assert_int_equal(o.lc.n.refused, 0);
    lc_free(&o.lc);
    engine_free(o.engine);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hold_refuses_override_until_clear),
        cmocka_unit_test(test_drive_events_through_the_owner),
        cmocka_unit_test(test_drive_event_is_no_command),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
