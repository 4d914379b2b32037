/*
 * test_axis_share.c - the time scaling's acceleration limit per segment
 * (issue 32 item 3, engine_solve.c accel_speed, TIMESCALE.md "Per-axis
 * limits"): where the curve's own acceleration leaves an axis more than the
 * scaling's fixed share, the rate brakes and speeds up with what is left, and
 * still every axis keeps its limits from every state.
 *
 * The track: a rectangle 40 m x 20 m with corners of 2 m radius at 4 m/s
 * (tests/helpers/topp.py's, tests/bench/bench_axis.py), waypoints every
 * 0.1 s, sent in real time, with the per-axis limits 3,3 m/s and 1,1 m/s^2
 * (3 m/s on the straights: the rate 0.75; each corner at under a third of
 * it).  Random events at random ticks, mostly while the output brakes into or
 * speeds out of a corner with the straight's A: stop, clear, feed override,
 * the sender pausing (the waypoints it skips are lost: the track resumes
 * after a gap, a new trajectory reached by a transfer) or stalling (what it
 * holds back comes late, after the trajectory was closed by its silence,
 * silence.h: a REST end, then a transfer), the track's end.
 *
 * Reference: the limits themselves, on the finite differences of the
 * streamed positions (velocity over one tick, acceleration over two, and
 * with a per-axis jerk limit the jerk over three), every tick, with no
 * exemption; no hard stop (the output never runs past the
 * curve solved); FINISHED and at rest in the end.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine.h"

#define PERIOD_NS 10000000LL
#define VLIM 3.0
#define ALIM 1.0
/* the limits, to what the rate's landing on its ceiling overshoots (3.00008
 * m/s on a 3 m/s axis: as before the per-segment A) */
#define TOL 1e-4
/* per-axis jerk limits (m/s^3), and their tolerance on third differences:
 * 0.5 is the low one where a stop along a transfer came to rest with its
 * deceleration unreleased (0.58 m/s^3 in one tick: the stop's jerk was
 * converted at the curve's speed here, which grows along a transfer) */
static const double JLIMS[] = {2.0, 0.5};
#define JTOL 1e-3

/* The rectangle's point d metres along its perimeter (cyclic). */
static void rect_at(double d, double *x, double *y)
{
    const double w = 40.0, h = 20.0, r = 2.0, pi = acos(-1.0);
    const double run[2] = {w - 2 * r, h - 2 * r}, arc = 0.5 * pi * r;
    double len = 2 * (run[0] + run[1]) + 4 * arc, px = r, py = 0.0, ang = 0.0;
    d = fmod(d, len);
    for (int side = 0; side < 4; side++) {
        double s = run[side % 2];
        if (d <= s) {
            *x = px + d * cos(ang);
            *y = py + d * sin(ang);
            return;
        }
        px += s * cos(ang);
        py += s * sin(ang);
        d -= s;
        double cx = px - r * sin(ang), cy = py + r * cos(ang);
        if (d <= arc) {
            double a = ang + d / r;
            *x = cx + r * sin(a);
            *y = cy - r * cos(a);
            return;
        }
        ang += 0.5 * pi;
        px = cx + r * sin(ang);
        py = cy - r * cos(ang);
        d -= arc;
    }
    *x = px;
    *y = py;
}

typedef struct {
    double v, a;    /* worst |v_k| / VLIM, |a_k| / ALIM by finite differences */
    double j;       /* worst |j_k| / the jerk limit (third differences), if one is set */
    unsigned stops; /* events made */
} worst_t;

/* One run: n waypoints (the sender pausing at random), events at random
 * ticks; every tick's finite differences against the limits. */
static void run(unsigned seed, engine_method_t method, int events, double jlim, worst_t *wo)
{
    engine_config_t c;
    engine_config_default(&c);
    c.method = method;
    c.period_ns = PERIOD_NS;
    c.max_speed_m_s = 10;
    c.max_accel_m_s2 = 0;
    c.max_gap_s = 1;
    c.capacity = 4096;
    for (int k = 0; k < 2; k++) {
        c.axis_max_speed_m_s[k] = VLIM;
        c.axis_max_accel_m_s2[k] = ALIM;
        c.axis_max_jerk_m_s3[k] = jlim;
    }
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);

    const int n = 1200; /* 120 s of track: most of two laps */
    const double T = (double)PERIOD_NS * 1e-9;
    double p[4][3] = {{0}}, t_prev[4] = {0};
    int have = 0, k = 0, pause_to = -1;
    int64_t now = 0, stall_to = 0;
    engine_setpoint_t sp;
    engine_status_t st;
    for (long tick = 0; tick < 2000000; tick++) {
        now += PERIOD_NS;
        while (k < n && 0.1 * k <= (double)now * 1e-9 && now >= stall_to) {
            if (k >= pause_to) {
                engine_waypoint_t w;
                memset(&w, 0, sizeof w);
                w.t_s = 0.1 * k;
                rect_at(0.4 * k, &w.pos_m[0], &w.pos_m[1]);
                w.seq = (uint32_t)k + 1;
                (void)engine_push(e, &w);
            }
            if (++k == n)
                assert_int_equal(engine_finish(e), 0);
        }
        if (events && urand(&seed) < 0.0015) { /* every 7 s or so */
            double r = urand(&seed);
            if (r < 0.25) {
                (void)engine_stop(e);
            } else if (r < 0.4) {
                engine_clear(e);
            } else if (r < 0.7) {
                assert_int_equal(engine_set_override(e, r < 0.55 ? 0.5 : 1.6), 0);
            } else if (r < 0.8) {
                assert_int_equal(engine_set_override(e, 1.0), 0);
            } else if (r < 0.9 && pause_to < k) {
                pause_to = k + 5 + (int)(urand(&seed) * 60); /* up to 6.5 s: lost */
            } else if (stall_to < now) { /* up to 40 s, then sent late: a silent end */
                stall_to = now + (int64_t)((5 + 35 * urand(&seed)) * 1e9);
            }
            wo->stops++;
        }
        assert_int_equal(engine_tick(e, now, &sp), 0);
        /* the last three positions a tick apart (a refused or skipped tick
         * does not happen here: every tick is one period) */
        for (int i = 0; i < 3; i++) {
            memcpy(p[i], p[i + 1], sizeof p[i]);
            t_prev[i] = t_prev[i + 1];
        }
        memcpy(p[3], sp.pos_m, sizeof p[3]);
        t_prev[3] = (double)now * 1e-9;
        if (sp.state == ENGINE_STATE_WAITING) {
            have = 0;
            continue;
        }
        if (++have >= 2)
            for (int a = 0; a < 2; a++) {
                double v = fabs(p[3][a] - p[2][a]) / T;
                if (v > VLIM * (1 + TOL))
                    fail_msg("seed %u method %d: |v_%c| %.6f m/s at %.2f s (t_s %.3f, state %d, "
                             "flags %#x), limit %g",
                             seed, (int)method, "xy"[a], v, t_prev[3], sp.t_s, (int)sp.state,
                             (unsigned)sp.flags, VLIM);
                wo->v = fmax(wo->v, v / VLIM);
            }
        if (have >= 3)
            for (int a = 0; a < 2; a++) {
                double acc = (p[3][a] - 2 * p[2][a] + p[1][a]) / (T * T);
                if (fabs(acc) > ALIM * (1 + TOL))
                    fail_msg("seed %u method %d: |a_%c| %.6f m/s^2 at %.2f s (t_s %.3f), "
                             "limit %g",
                             seed, (int)method, "xy"[a], fabs(acc), t_prev[3], sp.t_s, ALIM);
                wo->a = fmax(wo->a, fabs(acc) / ALIM);
            }
        if (jlim > 0 && have >= 4)
            for (int a = 0; a < 2; a++) {
                double jk = (p[3][a] - 3 * p[2][a] + 3 * p[1][a] - p[0][a]) / (T * T * T);
                if (fabs(jk) > jlim * (1 + JTOL))
                    fail_msg("seed %u method %d: |j_%c| %.4f m/s^3 at %.2f s (t_s %.3f, state "
                             "%d, flags %#x), limit %g",
                             seed, (int)method, "xy"[a], fabs(jk), t_prev[3], sp.t_s, (int)sp.state,
                             (unsigned)sp.flags, jlim);
                wo->j = fmax(wo->j, fabs(jk) / jlim);
            }
        engine_status(e, &st);
        if (k == n && st.state == ENGINE_STATE_FINISHED)
            break;
    }
    engine_status(e, &st);
    assert_int_equal(st.state, ENGINE_STATE_FINISHED);
    assert_int_equal(st.hard_stops, 0);
    for (int a = 0; a < 3; a++)
        assert_true(!(fabs(sp.vel_m_s[a]) > 0.0));
    engine_free(e);
}

/* Given the rectangle and its limits, when it streams in real time with and
 * without random stops, clears, overrides and pauses of the sender, then on
 * every tick |v_k| <= 3 m/s and |a_k| <= 1 m/s^2 by finite differences, no
 * hard stop, and it finishes at rest. */
static void test_rectangle_from_every_state(void **state)
{
    (void)state;
    static const engine_method_t methods[] = {ENGINE_METHOD_CUBIC, ENGINE_METHOD_HERMITE,
                                              ENGINE_METHOD_HERMITE_C2};
    worst_t wo;
    memset(&wo, 0, sizeof wo);
    for (unsigned s = 1; s <= 12; s++)
        run(s, methods[s % 3], s > 3, 0.0, &wo);
    print_message("%u events; worst |v| %.6f, |a| %.6f of the limits\n", wo.stops, wo.v, wo.a);
    assert_true(wo.v <= 1 + TOL);
    assert_true(wo.a <= 1 + TOL);
    assert_true(wo.a > 0.999); /* the braking on the straights reaches the limit */
}

/* Given the rectangle, its limits and a per-axis jerk limit (each of
 * JLIMS), on the C2 curves (cubic, local C2 Hermite), when it streams in real
 * time with random stops, clears, overrides and pauses, then on every tick
 * |j_k| <= the limit by third differences too (from every state: a stop, the
 * brake of a clear, a transfer, a handover), besides the speed and
 * acceleration. */
static void test_rectangle_jerk_from_every_state(void **state)
{
    (void)state;
    static const engine_method_t methods[] = {ENGINE_METHOD_CUBIC, ENGINE_METHOD_HERMITE_C2};
    for (size_t i = 0; i < sizeof JLIMS / sizeof JLIMS[0]; i++) {
        worst_t wo;
        memset(&wo, 0, sizeof wo);
        for (unsigned s = 1; s <= 8; s++)
            run(s, methods[s % 2], s > 2, JLIMS[i], &wo);
        print_message("jerk limit %g: %u events; worst |v| %.6f, |a| %.6f, |j| %.6f of the "
                      "limits\n",
                      JLIMS[i], wo.stops, wo.v, wo.a, wo.j);
        assert_true(wo.j <= 1 + JTOL);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rectangle_from_every_state),
        cmocka_unit_test(test_rectangle_jerk_from_every_state),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
