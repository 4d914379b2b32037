/*
 * test_axis_join.c - the per-axis limits hold from every state (issue 32
 * item 1): the curve is continuous in velocity where fragments meet, and a
 * track far faster on an axis than its limit never takes the output past it.
 *
 * The track (items 1, 2): a zig-zag in y of +-9 m every 0.2 s (90 m/s chords, a turn at
 * every waypoint) drifting 0.5 m per waypoint in x, solved in fragments of 6
 * overlapping by 2 with natural ends (fuzz_engine's configuration 2).  The
 * second derivatives about a junction come from two fragments whose values
 * there differ by about 2 - sqrt(3) of the curvature (frag.h): before, the
 * curve stepped in velocity there by up to 140 m/s, which the per-axis
 * ceilings cannot see (they bound |k'| r, |k''| r^2 within a segment) and
 * the output stepped by that times the rate (fuzz_engine: 6.7 m/s^2 on a
 * 4 m/s^2 axis, tests/fuzz/regress/fuzz_engine/axis-accel-junction-step).
 *
 * References: the curve's own cubics evaluated at both sides of every join
 * (Horner, not the engine's stepper), and lib/safety's per-axis bounds on
 * the finite differences of the streamed positions, as the daemon runs it.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine.h"
#include "safety.h"

#define NWP 24
#define PERIOD_NS 20000000LL

static engine_waypoint_t zigzag(int i)
{
    engine_waypoint_t w;
    memset(&w, 0, sizeof w);
    w.t_s = 0.2 * (i + 1);
    w.pos_m[0] = 0.5 * i;
    w.pos_m[1] = (i & 1) ? -9.0 : 9.0;
    w.seq = (uint32_t)i + 1;
    return w;
}

static void config(engine_config_t *c, engine_method_t method, int axis_limits)
{
    engine_config_default(c);
    c->method = method;
    c->param = ENGINE_PARAM_TIME;
    c->ends = ENGINE_ENDS_NATURAL;
    c->fragment = 6;
    c->overlap = 2;
    c->start_slack = 0;
    if (method == ENGINE_METHOD_SMOOTH) {
        c->smooth_window = 8;
        c->smooth_ctrl = 4;
    }
    c->max_speed_m_s = 100;
    c->max_accel_m_s2 = 0;
    c->period_ns = PERIOD_NS;
    c->max_gap_s = 1;
    if (axis_limits) { /* fuzz_engine's: x 2 m/s, 1 m/s^2, 20 m/s^3; y 3 m/s, 4 m/s^2 */
        const double v[3] = {2, 3, 0}, a[3] = {1, 4, 0}, j[3] = {20, 0, 0};
        for (int k = 0; k < 3; k++) {
            c->axis_max_speed_m_s[k] = v[k];
            c->axis_max_accel_m_s2[k] = a[k];
            c->axis_max_jerk_m_s3[k] = j[k];
        }
    }
}

/* dk/dt of segment s's axis k at u (0 or 1). */
static double vel_at(const fdiff_seg_t *s, int k, double u)
{
    const double *c = s->c[k];
    return (c[1] + u * (2 * c[2] + 3 * u * c[3])) / s->dur_s;
}

static double pos_at(const fdiff_seg_t *s, int k, double u)
{
    const double *c = s->c[k];
    return c[0] + u * (c[1] + u * (c[2] + u * c[3]));
}

/* Given the zig-zag in fragments of 6/2, when the curve is built (every
 * method with knots at the timestamps), then at every join of two segments
 * the velocity is the same on both sides, the position too, and the curve
 * passes through every waypoint (cubic, bspline: they interpolate). */
static void test_junctions_continuous_in_velocity(void **state)
{
    (void)state;
    const engine_method_t methods[3] = {ENGINE_METHOD_CUBIC, ENGINE_METHOD_BSPLINE,
                                        ENGINE_METHOD_SMOOTH};
    const char *names[3] = {"cubic", "bspline", "smooth"};
    engine_waypoint_t wp[NWP];
    for (int i = 0; i < NWP; i++)
        wp[i] = zigzag(i);
    for (int m = 0; m < 3; m++) {
        engine_config_t c;
        fdiff_seg_t seg[4 * NWP];
        size_t n = 0;
        double worst = 0, speed = 0;
        config(&c, methods[m], 0);
        assert_int_equal(engine_curve(&c, wp, NWP, seg, 4 * NWP, &n), 0);
        assert_true(n >= NWP / 2);
        for (size_t i = 0; i + 1 < n; i++) {
            assert_true(fabs(seg[i].t0_s + seg[i].dur_s - seg[i + 1].t0_s) < 1e-12);
            for (int k = 0; k < 3; k++) {
                double v0 = vel_at(&seg[i], k, 1), v1 = vel_at(&seg[i + 1], k, 0);
                worst = fmax(worst, fabs(v1 - v0));
                speed = fmax(speed, fabs(v0));
                assert_true(fabs(pos_at(&seg[i], k, 1) - pos_at(&seg[i + 1], k, 0)) < 1e-9);
            }
        }
        print_message("%s: %zu segments, fastest %.1f m/s, largest velocity step at a join "
                      "%.3g m/s\n",
                      names[m], n, speed, worst);
        /* the track is what it says (the smoother rounds the turns off) */
        assert_true(speed > (methods[m] == ENGINE_METHOD_SMOOTH ? 20 : 90));
        assert_true(worst <= 1e-9 * speed);
        if (methods[m] == ENGINE_METHOD_SMOOTH)
            continue;                  /* a smoother does not interpolate */
        for (size_t i = 0; i < n; i++) /* each segment starts on a waypoint */
            for (int w = 0; w < NWP; w++)
                if (fabs(wp[w].t_s - seg[i].t0_s) < 1e-12)
                    for (int k = 0; k < 3; k++)
                        assert_true(fabs(pos_at(&seg[i], k, 0) - wp[w].pos_m[k]) < 1e-9);
    }
}

/* Given the zig-zag at irregular times (0.2 and 0.3 s in turn) with the
 * uniform parameterisation (each segment mapped onto its own interval: the
 * velocity steps by the ratio of two intervals at every knot, DESIGN.md (a)),
 * when a per-axis limit is set, then every join is continuous in velocity
 * too (without one the steps stay, as documented: up to 43 m/s here). */
static void test_uniform_joined_with_axis_limits(void **state)
{
    (void)state;
    const engine_method_t methods[2] = {ENGINE_METHOD_CUBIC, ENGINE_METHOD_BSPLINE};
    engine_waypoint_t wp[NWP];
    for (int i = 0; i < NWP; i++) {
        wp[i] = zigzag(i);
        wp[i].t_s = 0.2 + 0.25 * i - ((i & 1) ? 0.05 : 0.0); /* 0.2, 0.3, 0.2 ... s apart */
    }
    for (int m = 0; m < 2; m++)
        for (int limits = 0; limits <= 1; limits++) {
            engine_config_t c;
            fdiff_seg_t seg[4 * NWP];
            size_t n = 0;
            double worst = 0;
            config(&c, methods[m], limits);
            c.param = ENGINE_PARAM_UNIFORM;
            c.fragment = 8;
            c.overlap = 4;
            if (methods[m] == ENGINE_METHOD_BSPLINE)
                c.ends = ENGINE_ENDS_HELD;
            assert_int_equal(engine_curve(&c, wp, NWP, seg, 4 * NWP, &n), 0);
            for (size_t i = 0; i + 1 < n; i++)
                for (int k = 0; k < 3; k++)
                    worst = fmax(worst, fabs(vel_at(&seg[i + 1], k, 0) - vel_at(&seg[i], k, 1)));
            print_message("%s uniform, %s per-axis limits: largest velocity step at a join "
                          "%.3g m/s\n",
                          m ? "bspline" : "cubic", limits ? "with" : "without", worst);
            if (limits)
                assert_true(worst <= 1e-9);
            else
                assert_true(worst > 1.0); /* the documented steps: the test can tell */
        }
}

/* Stream the zig-zag with the per-axis limits, ticking every `every`
 * periods, every setpoint through lib/safety with the daemon's per-axis
 * bounds (SAFETY_AXIS_MARGIN above the limits), to FINISHED. */
static void stream(engine_method_t method, int every)
{
    engine_config_t c;
    engine_t *e;
    safety_t mon;
    safety_limits_t lim;
    engine_setpoint_t sp;
    engine_status_t st;
    int64_t now = 0;
    long ticks = 0;

    config(&c, method, 1);
    c.capacity = 256;
    e = engine_new(&c, NULL);
    assert_non_null(e);
    memset(&lim, 0, sizeof lim);
    safety_axis_limits(&lim, c.axis_max_speed_m_s, c.axis_max_accel_m_s2, c.axis_max_jerk_m_s3);
    safety_init(&mon, &lim);
    for (int i = 0; i < NWP; i++) {
        engine_waypoint_t w = zigzag(i);
        assert_int_equal(engine_push(e, &w), 0);
    }
    assert_int_equal(engine_finish(e), 0);
    do {
        now += every * PERIOD_NS;
        assert_int_equal(engine_tick(e, now, &sp), 0);
        int rc = safety_check(&mon, &sp);
        if (rc != SAFETY_OK)
            fail_msg("method %d, every %d: tick at %.2f s (t_s %.4f) refused: %s (%.3g, bound "
                     "%.3g)",
                     (int)method, every, (double)now * 1e-9, sp.t_s, safety_strerror(rc),
                     mon.last_value, mon.last_limit);
        engine_status(e, &st);
    } while (st.state != ENGINE_STATE_FINISHED && ++ticks < 2000000);
    assert_int_equal(st.state, ENGINE_STATE_FINISHED);
    print_message("method %d, every %d: FINISHED at %.1f s, %.1f s lost to the axis limits\n",
                  (int)method, every, (double)now * 1e-9, st.axis_lost_s);
    engine_free(e);
}

/* Given the zig-zag and the per-axis limits, when it streams every tick, or
 * with 20 ticks skipped between two (fuzz_engine's finish loop), then no
 * setpoint exceeds an axis's speed or acceleration bound. */
static void test_axis_limits_across_junctions(void **state)
{
    (void)state;
    stream(ENGINE_METHOD_CUBIC, 1);
    stream(ENGINE_METHOD_CUBIC, 20);
    stream(ENGINE_METHOD_BSPLINE, 20);
}

/* Given a track along x at 1 m/s for 10 s, then at 10 m/s (a sprint), and
 * x limited to 0.05 m/s and 1 m/s^2: the slow part is 20 times faster than
 * x may go (rate 1/30 at the cubic's 1.5), the sprint 200 times, beyond the
 * lowest rate the output may stand at (ENGINE_CEIL_MIN, 1/100).  When it
 * streams, every tick through lib/safety with the daemon's per-axis bounds,
 * the owner stopping the object when told (engine_axis_lag_over, as the
 * lifecycle and trajreplay do), then it follows the slow part, stands at
 * rest before the sprint, is told once (axis_beyond 1), stops there
 * (FINISHED) and never exceeds an axis's bound.  Before: the ceilings stopped
 * at 1/100, and the monitor refused the output entering the sprint (x 10.007
 * m, 0.0552 m/s against 0.055). */
static void test_track_beyond_the_axes_stops_before(void **state)
{
    (void)state;
    engine_config_t c;
    engine_t *e;
    safety_t mon;
    safety_limits_t lim;
    engine_setpoint_t sp;
    engine_status_t st;
    int64_t now = 0;
    int told = 0;
    double x_told = NAN, v_told = NAN;

    engine_config_default(&c);
    c.period_ns = PERIOD_NS;
    c.max_speed_m_s = 20;
    c.axis_max_speed_m_s[0] = 0.05;
    c.axis_max_accel_m_s2[0] = 1;
    e = engine_new(&c, NULL);
    assert_non_null(e);
    memset(&lim, 0, sizeof lim);
    safety_axis_limits(&lim, c.axis_max_speed_m_s, c.axis_max_accel_m_s2,
                       c.axis_max_jerk_m_s3); /* x alone set */
    safety_init(&mon, &lim);
    double x = 0;
    for (int i = 0; i <= 20; i++) {
        engine_waypoint_t w;
        memset(&w, 0, sizeof w);
        w.t_s = i;
        w.pos_m[0] = x;
        w.seq = (uint32_t)i + 1;
        assert_int_equal(engine_push(e, &w), 0);
        x += i < 10 ? 1.0 : 10.0;
    }
    assert_int_equal(engine_finish(e), 0);
    for (long ticks = 0; ticks < 1000000; ticks++) {
        now += PERIOD_NS;
        assert_int_equal(engine_tick(e, now, &sp), 0);
        int rc = safety_check(&mon, &sp);
        if (rc != SAFETY_OK)
            fail_msg("tick at %.2f s (t_s %.4f, x %.4f) refused: %s (%.3g, bound %.3g)",
                     (double)now * 1e-9, sp.t_s, sp.pos_m[0], safety_strerror(rc), mon.last_value,
                     mon.last_limit);
        if (engine_axis_lag_over(e)) {
            told++;
            x_told = sp.pos_m[0];
            v_told = sp.vel_m_s[0];
            (void)engine_stop(e);
        }
        engine_status(e, &st);
        if (st.state == ENGINE_STATE_FINISHED)
            break;
    }
    print_message("told at x %.4f m (the sprint starts at 10 m), v %.3g m/s, %.1f s; FINISHED "
                  "at x %.4f\n",
                  x_told, v_told, (double)now * 1e-9, sp.pos_m[0]);
    assert_int_equal(st.state, ENGINE_STATE_FINISHED);
    assert_int_equal(told, 1);
    assert_int_equal(st.axis_beyond, 1);
    assert_true(x_told > 5.0 && x_told < 10.0); /* followed the slow part, not the sprint */
    assert_true(fabs(v_told) < 1e-12);          /* at rest when told */
    assert_true(fabs(sp.pos_m[0] - x_told) < 1e-9);
    engine_free(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_junctions_continuous_in_velocity),
        cmocka_unit_test(test_uniform_joined_with_axis_limits),
        cmocka_unit_test(test_axis_limits_across_junctions),
        cmocka_unit_test(test_track_beyond_the_axes_stops_before),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
