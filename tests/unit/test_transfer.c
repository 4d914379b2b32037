/*
 * test_transfer.c - a transfer with the derived limits (lib/engine/transfer.h)
 * takes the object's own pace, also where its recent motion shows no
 * acceleration (a straight line at constant speed).
 *
 * The engine at its defaults, ticking at 100 Hz on a virtual clock, as
 * trajreplay and the daemon do.  Trajectory A: x 0 .. 2 m at 1 m/s, 10 Hz,
 * then FINISH; once the output rests on its end, trajectory B: x 3 .. 5 m at
 * 1 m/s, 1 m on, then FINISH.  The transfer from A's end to B's start lasts
 * max(1 s, 1.5 D / v, sqrt(6 D / a)) with v the object's 1 m/s and a at least
 * what reaches that speed within TRANSFER_REACH_S: a few seconds.  Before, the
 * implied acceleration of a straight line, a rounding residue of 1e-14 m/s^2,
 * was taken as the object's own, the duration sqrt(6 D / 1e-9) was cut to
 * max_gap_s: 60 s for 1 m (after 20 s the output had covered 0.26 m).
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine.h"
#include "transfer.h"

#define PERIOD_NS 10000000LL

static void line(engine_t *e, double x0, double t0, int n)
{
    for (int i = 0; i < n; i++) {
        engine_waypoint_t w;
        memset(&w, 0, sizeof w);
        w.t_s = t0 + 0.1 * i;
        w.pos_m[0] = x0 + 0.1 * i;
        assert_int_equal(engine_push(e, &w), 0);
    }
    assert_int_equal(engine_finish(e), 0);
}

static void test_straight_line_transfer_at_its_pace(void **state)
{
    (void)state;
    engine_config_t c;
    engine_config_default(&c);
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    engine_setpoint_t sp;
    int64_t k = 0;
    line(e, 0.0, 0.0, 21);
    for (; k < 3000; k++) { /* A plays out to its end and rests there */
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
    }
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_true(fabs(sp.pos_m[0] - 2.0) < 1e-9);
    line(e, 3.0, 10.0, 21);
    int64_t t_start = -1, t_there = -1;
    for (k++; k < 30000 && t_there < 0; k++) {
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (t_start < 0 && (sp.flags & ENGINE_SP_TRANSFER))
            t_start = k;
        if (t_start >= 0 && !(sp.flags & ENGINE_SP_TRANSFER) && fabs(sp.pos_m[0] - 3.0) < 1e-9)
            t_there = k;
    }
    print_message("1 m transfer after a straight line at 1 m/s: %.2f s\n",
                  (double)(t_there - t_start) * PERIOD_NS * 1e-9);
    assert_true(t_start >= 0 && t_there > t_start);
    /* 1.5 D / v = 1.5 s, sqrt(6 D / (v / TRANSFER_REACH_S)) = 3.5 s */
    assert_true((double)(t_there - t_start) * PERIOD_NS * 1e-9 <= 4.0);
    engine_free(e);
}

/* The duration itself: a residue of an acceleration, or none, with or
 * without a configured speed, gives the pace of that speed. */
static void test_duration_floor(void **state)
{
    (void)state;
    transfer_config_t c = {
        .speed_m_s = 0, .accel_m_s2 = 0, .max_s = 60, .vmax_m_s = 0, .period_s = 0.01};
    int capped = 1;
    double d = transfer_duration(&c, 1.0, 1.0, 1e-14, 0, &capped);
    assert_true(d <= 4.0);
    assert_int_equal(capped, 0);
    c.speed_m_s = 1.0; /* only the speed configured */
    assert_true(transfer_duration(&c, 1.0, 1.0, 1e-14, 0, NULL) <= 4.0);
    c.speed_m_s = 0; /* a slow toolpath keeps its own pace: 10 mm/s */
    d = transfer_duration(&c, 0.1, 0.01, 1e-14, 0, NULL);
    assert_true(d >= 1.5 * 0.1 / 0.01 - 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_straight_line_transfer_at_its_pace),
        cmocka_unit_test(test_duration_floor),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
