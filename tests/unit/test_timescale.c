/*
 * test_timescale.c - the time scaling between the curve and the output
 * (lib/engine/timescale.h, lib/engine/TIMESCALE.md), alone and in the engine.
 *
 * References: the stopping distance against a tick-by-tick simulation of the
 * braking; the engine's setpoints against direct Horner evaluation of the
 * curve (engine_curve + fdiff_eval) at the setpoint's own track time, and
 * against the chain-rule bounds on acceleration and jerk computed from the
 * curve's own derivatives (sampled densely by Horner, not by the engine).
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "fdiff.h"
#include "timescale.h"

#define PERIOD_NS 10000000LL
#define T_S 0.01
/* lib/engine/engine_int.h ENGINE_SCALE_V_FLOOR_M_S, documented in TIMESCALE.md */
#define V_FLOOR_M_S 1.0
/* Setpoint vs Horner at its own track time (as test_engine.c). */
#define TOL_HORNER_M 1e-9
/* Bounds are for the continuous profile; 2 % for the sampled maxima of the
 * curve's derivatives and the change of the limits within a tick. */
#define SLACK 1.02

static unsigned seed = 16;
static double ur(void)
{
    return urand(&seed);
}

static double norm3(const double *a)
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

/* ---- the scaling alone ------------------------------------------------- */

/* Given random states and limits, when braking tick by tick with target 0,
 * then the distance run matches ts_stop_dist within the discretisation
 * (a few ticks of the starting rate), |a| stays within A, every jerk within
 * J, and the rate ends exactly at 0; ts_rate_max inverts ts_stop_dist. */
static void test_stop_dist_matches_simulation(void **state)
{
    (void)state;
    for (int i = 0; i < 2000; i++) {
        double A = 0.05 + 5 * ur(), J = 0.5 + 50 * ur();
        double r = 2 * ur(), a = (2 * ur() - 1) * A;
        if (a < 0 && 0.5 * a * a / J >= r)
            continue; /* decelerating too hard to end at rest within J: not reachable */
        ts_state_t st = {r, a};
        double d = ts_stop_dist(r, a, A, J), run = 0, jmax = 0, amax = 0;
        int n = 0;
        while (st.rate > 0 || st.acc < 0 || st.acc > 0) {
            double j;
            run += ts_step(&st, 0.0, INFINITY, A, J, T_S, &j, NULL);
            jmax = fmax(jmax, fabs(j));
            amax = fmax(amax, fabs(st.acc));
            assert_true(++n < 1000000);
        }
        /* a few ticks at the highest rate the braking passes through */
        double rpeak = r + (a > 0 ? 0.5 * a * a / J : 0);
        if (!(fabs(run - d) <= 3 * (rpeak + A * T_S) * T_S + 1e-12))
            fail_msg("r %g a %g A %g J %g: ran %.6g, formula %.6g", r, a, A, J, run, d);
        assert_true(jmax <= J * (1 + 1e-12));
        assert_true(amax <= fmax(A, fabs(a)) * (1 + 1e-12));
        double r0 = 2 * ur();
        double back = ts_rate_max(ts_stop_dist(r0, 0, A, J), A, J);
        assert_true(fabs(back - r0) <= 1e-9 * (1 + r0));
    }
    assert_true(isinf(ts_rate_max(INFINITY, 1, 1)));
    assert_true(ts_rate_max(-1, 1, 1) <= 0);
}

/* Given a remaining distance R, when running at full target, then the
 * scaling never needs more than R to stop: it comes to rest within R plus
 * the margin the engine keeps (TS_MARGIN_TICKS of track time) and at rest
 * exactly. */
static void test_never_overruns_R(void **state)
{
    (void)state;
    for (int i = 0; i < 500; i++) {
        double A = 0.05 + 5 * ur(), J = 0.5 + 50 * ur(), R = 20 * ur();
        ts_state_t st = {ur(), 0};
        if (ts_stop_dist(st.rate, 0, A, J) > R)
            continue;
        double run = 0;
        for (int n = 0; n < 200000 && (st.rate > 0 || run < 1e-12); n++) {
            run += ts_step(&st, 1.0 + ur(), R - run, A, J, T_S, NULL, NULL);
            if (!(st.rate > 0) && n > 0)
                break;
        }
        if (!(run <= R + TS_MARGIN_TICKS * T_S))
            fail_msg("A %g J %g R %g: ran %.6g", A, J, R, run);
    }
}

/* ---- in the engine ------------------------------------------------------ */

typedef struct {
    double v, a, j; /* max |k'|, |k''|, |k'''| of the curve */
} curve_max_t;

/* The curve's own maxima, sampled densely by Horner (k''' from the cubic). */
static curve_max_t curve_max(const fdiff_seg_t *s, size_t n)
{
    curve_max_t m = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        double jj[3];
        for (int k = 0; k < 3; k++)
            jj[k] = 6 * s[i].c[k][3] / (s[i].dur_s * s[i].dur_s * s[i].dur_s);
        m.j = fmax(m.j, norm3(jj));
        for (int q = 0; q <= 100; q++) {
            double v[3], a[3];
            fdiff_eval(&s[i], q / 100.0, NULL, v, a);
            m.v = fmax(m.v, norm3(v));
            m.a = fmax(m.a, norm3(a));
        }
    }
    return m;
}

/* Chain rule (TIMESCALE.md): with rate <= rmax, |k' dr/dt| <= a_s, |k' j| <=
 * j_s and |dr/dt| <= a_s / V_FLOOR_M_S,
 *   |acc|  <= A_c rmax^2 + a_s
 *   |jerk| <= J_c rmax^3 + 3 A_c rmax a_s / V_FLOOR_M_S + j_s            */
static void limits(const engine_config_t *c, curve_max_t m, double rmax, double *acc_lim,
                   double *jerk_lim)
{
    double as = c->scale_accel_m_s2, js = c->scale_jerk_m_s3;
    *acc_lim = m.a * rmax * rmax + as;
    *jerk_lim = m.j * rmax * rmax * rmax + 3 * m.a * rmax * as / V_FLOOR_M_S + js;
}

/* Helix of radius radius_m, 0.15 rad per waypoint, climbing 0.3 m per waypoint. */
static void helix_wp(engine_waypoint_t *w, int i, double dt, double radius_m)
{
    memset(w, 0, sizeof(*w));
    w->t_s = i * dt;
    w->pos_m[0] = radius_m * cos(0.15 * i);
    w->pos_m[1] = radius_m * sin(0.15 * i);
    w->pos_m[2] = 0.3 * i;
    w->seq = (uint32_t)i + 1;
}

typedef struct {
    double dv_max, da_max, horner_max;
    long moving, scaled;
} check_t;

/* Every pair of consecutive setpoints of one trajectory that are not WAITING. */
static void check_pair(check_t *ck, const engine_setpoint_t *p, const engine_setpoint_t *sp,
                       const fdiff_seg_t *segs, size_t nseg)
{
    if (sp->state == ENGINE_STATE_WAITING || p->state == ENGINE_STATE_WAITING)
        return;
    ck->dv_max = fmax(ck->dv_max, dist3(sp->vel_m_s, p->vel_m_s));
    if (getenv("TS_DEBUG") && dist3(sp->acc_m_s2, p->acc_m_s2) > ck->da_max)
        fprintf(stderr, "da %.3f at t_s %.4f state %d->%d flags %x->%x |a| %.3f->%.3f\n",
                dist3(sp->acc_m_s2, p->acc_m_s2), sp->t_s, p->state, sp->state, p->flags, sp->flags,
                norm3(p->acc_m_s2), norm3(sp->acc_m_s2));
    /* into FINISHED too: a REST end is left at rate 0, so its k'' != 0 does
     * not step the acceleration to the rest's 0 */
    ck->da_max = fmax(ck->da_max, dist3(sp->acc_m_s2, p->acc_m_s2));
    if (sp->state != ENGINE_STATE_FINISHED) {
        double q[3];
        fdiff_eval_curve(segs, nseg, &sp->t_s, 1, q, NULL, NULL);
        ck->horner_max = fmax(ck->horner_max, dist3(q, sp->pos_m));
    }
    ck->moving++;
    ck->scaled += (sp->flags & ENGINE_SP_SCALED) != 0;
}

/*
 * Property: given random stalls of the sender (it pauses for 0 .. 4 intervals at
 * random waypoints, then sends what it owes at once) and, in half of the
 * runs, random feed overrides (0 .. 2), then on every output |delta
 * velocity| per tick <= accel limit * T and |delta acceleration| per tick
 * <= jerk limit * T (limits from the chain rule on the curve's own maxima),
 * every position is the curve at the setpoint's track time, the scaling
 * never failed to brake in time (hard_stops 0), and the run finishes on the
 * last waypoint.
 */
static void test_property_random_stalls(void **state)
{
    (void)state;
    enum { N = 240 };
    static engine_waypoint_t wp[N];
    static fdiff_seg_t segs[N + 8];
    double worst_dv = 0, worst_da = 0;
    long scaled = 0, underruns = 0;

    for (int run = 0; run < 12; run++) {
        engine_config_t c;
        size_t nseg = 0;
        double dt = 0.2 + 0.3 * ur();
        int overrides = run % 2;
        engine_config_default(&c);
        c.scale_accel_m_s2 = 2 + 8 * ur();
        c.scale_jerk_m_s3 = 10 + 90 * ur();
        for (int i = 0; i < N; i++)
            helix_wp(&wp[i], i, dt, 20.0);
        assert_int_equal(engine_curve(&c, wp, N, segs, N + 8, &nseg), 0);
        curve_max_t m = curve_max(segs, nseg);
        double acc_lim, jerk_lim;
        limits(&c, m, overrides ? 2.0 : 1.0, &acc_lim, &jerk_lim);

        engine_t *e = engine_new(&c, NULL);
        assert_non_null(e);
        engine_setpoint_t sp, p;
        memset(&p, 0, sizeof p);
        check_t ck = {0};
        int next = 0;
        double lag = 0, pause_until = -1;
        for (int64_t k = 0; k < 2000000; k++) {
            double now_s = (double)k * T_S;
            while (next < N && now_s >= pause_until && wp[next].t_s + lag <= now_s) {
                assert_int_equal(engine_push(e, &wp[next]), 0);
                if (++next == N)
                    engine_finish(e);
                else if (ur() < 0.05) {
                    /* pauses within the sender's own timing (6 intervals,
                     * silence.h): a longer one ends the trajectory, which
                     * tests/unit/test_silence.c checks.  Between two
                     * arrivals: the pause, or an interval plus the lag it
                     * adds, and a tick: at most 4 + 1 intervals + T */
                    double pause = 4 * dt * ur();
                    pause_until = now_s + pause;
                    lag += pause * ur(); /* owes some, then catches up */
                }
            }
            if (overrides && k % 500 == 0)
                assert_int_equal(engine_set_override(e, 2 * ur()), 0);
            if (overrides && k % 500 == 250)
                assert_int_equal(engine_set_override(e, 1.0), 0);
            assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
            check_pair(&ck, &p, &sp, segs, nseg);
            p = sp;
            if (sp.state == ENGINE_STATE_FINISHED)
                break;
        }
        engine_status_t st;
        engine_status(e, &st);
        assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
        assert_true(dist3(sp.pos_m, wp[N - 1].pos_m) < 1e-9);
        assert_int_equal(st.hard_stops, 0);
        assert_true(ck.horner_max < TOL_HORNER_M);
        if (ck.dv_max > acc_lim * T_S * SLACK || ck.da_max > jerk_lim * T_S * SLACK)
            fail_msg("run %d: dv/T %.3f (limit %.3f), da/T %.3f (limit %.3f)", run, ck.dv_max / T_S,
                     acc_lim, ck.da_max / T_S, jerk_lim);
        worst_dv = fmax(worst_dv, ck.dv_max / T_S / acc_lim);
        worst_da = fmax(worst_da, ck.da_max / T_S / jerk_lim);
        scaled += ck.scaled;
        underruns += (long)st.underruns;
        engine_free(e);
    }
    print_message("12 runs: %ld scaled ticks, %ld underruns; worst dv/T %.2f of the "
                  "accel limit, da/T %.2f of the jerk limit\n",
                  scaled, underruns, worst_dv, worst_da);
    /* the property was exercised: the scaling acted, and underruns happened
     * (3: the sender's pauses come late, and the slack holds the lateness it
     * has measured, delay.h; 4 while it learnt an interval per underrun) */
    assert_true(scaled > 1000);
    assert_true(underruns >= 3);
}

/*
 * Issue 16 item 1: stop now is a category-1 stop within v^2/(2a) + v T.
 * Given a straight line at v (0.05 .. 120 m/s, 10 Hz, all waypoints
 * buffered) and scale limits (a, j), when engine_stop (Modbus command 2,
 * CAN command 2, SIGTERM) or engine_clear is called at a random tick, then
 * the output comes to rest along the line within v^2/(2a) + v T of path (T
 * the period; the stop's jerk is at least a/T for this, TIMESCALE.md), not
 * sooner than v^2/(2a) (it braked at most at a, it did not jump), velocity
 * and acceleration exactly 0; every tick |delta velocity| <= a T and
 * |delta acceleration| <= max(j, a/T) T.  A waypoint pushed afterwards
 * starts a new trajectory, by a transfer.
 */
static void stop_once(double v, double a, double j, int clear, int64_t stop_at, double *worst)
{
    /* buffered beyond the start's ramp (entered at rate 0, track time about
     * v/(2a)) and the stop's end (track time v/(2a) after the call) */
    const int N = 300 + (int)(10 * (v / a + 30));
    engine_config_t c;
    engine_config_default(&c);
    c.scale_accel_m_s2 = a;
    c.scale_jerk_m_s3 = j;
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    engine_waypoint_t w;
    for (int i = 0; i < N; i++) {
        memset(&w, 0, sizeof w);
        w.t_s = 0.1 * i;
        w.pos_m[0] = v * w.t_s;
        w.pos_m[1] = 5.0;
        assert_int_equal(engine_push(e, &w), 0);
    }
    engine_setpoint_t sp, p;
    int64_t k = 0;
    /* the start is entered at rate 0 and ramps up at a: stop_at ticks after
     * the output streams at rate 1 */
    do {
        assert_int_equal(engine_tick(e, k++ * PERIOD_NS, &sp), 0);
        assert_true(k < 10000000);
    } while (sp.state != ENGINE_STATE_STREAMING || (sp.flags & ENGINE_SP_SCALED));
    stop_at += k;
    do {
        assert_int_equal(engine_tick(e, k++ * PERIOD_NS, &sp), 0);
    } while (k < stop_at);
    if (sp.state != ENGINE_STATE_STREAMING)
        fail_msg("v %g a %g j %g: state %d at tick %lld", v, a, j, sp.state, (long long)stop_at);
    double v0 = norm3(sp.vel_m_s), jstop = fmax(j, a / T_S);
    if (!(fabs(v0 - v) < 1e-6 * fmax(1, v)))
        fail_msg("v %g a %g j %g: v0 %.9g flags %x", v, a, j, v0, sp.flags);
    double start[3], path = 0, dv = 0, da = 0;
    memcpy(start, sp.pos_m, sizeof start);
    if (clear)
        engine_clear(e);
    else
        assert_int_equal(engine_stop(e), 0);
    p = sp;
    int ticks = 0;
    do {
        assert_int_equal(engine_tick(e, k++ * PERIOD_NS, &sp), 0);
        path += dist3(sp.pos_m, p.pos_m);
        dv = fmax(dv, dist3(sp.vel_m_s, p.vel_m_s));
        da = fmax(da, dist3(sp.acc_m_s2, p.acc_m_s2));
        assert_true(fabs(sp.pos_m[1] - 5.0) < 1e-9); /* on the line */
        p = sp;
        assert_true(++ticks < 100000);
    } while (!(sp.flags & ENGINE_SP_HOLD) || sp.state == ENGINE_STATE_STREAMING);
    assert_int_equal(sp.state, clear ? ENGINE_STATE_WAITING : ENGINE_STATE_FINISHED);
    double bound = v0 * v0 / (2 * a) + v0 * T_S;
    if (!(path <= bound + 1e-9) || !(path >= v0 * v0 / (2 * a) * (1 - 1e-9)))
        fail_msg("v %g a %g j %g %s at tick %lld: stopped in %.6f m, bound %.6f, v^2/2a %.6f", v, a,
                 j, clear ? "clear" : "stop", (long long)stop_at, path, bound, v0 * v0 / (2 * a));
    if (getenv("TS_DEBUG"))
        print_message("v %g a %g j %g %s: %.6g m, bound %.6g (%.4f), %d ticks\n", v, a, j,
                      clear ? "clear" : "stop", path, bound, path / bound, ticks);
    *worst = fmax(*worst, path / bound);
    worst[1] = fmax(worst[1], (path - v0 * v0 / (2 * a)) / (v0 * T_S));
    assert_true(fabs(dist3(sp.pos_m, start) - path) < 1e-6); /* straight on */
    if (dv > a * T_S * SLACK || da > jstop * T_S * SLACK)
        fail_msg("v %g a %g j %g: dv/(aT) %.3f, da/(jT) %.3f", v, a, j, dv / (a * T_S),
                 da / (jstop * T_S));
    assert_true(norm3(sp.vel_m_s) <= 0.0 && norm3(sp.acc_m_s2) <= 0.0);
    engine_status_t st;
    engine_status(e, &st);
    assert_int_equal(st.buffered, 0); /* the rest was dropped */
    /* then a new trajectory starts (by a transfer from here) */
    for (int i = 0; i < 60; i++) {
        memset(&w, 0, sizeof w);
        w.t_s = 1000 + 0.1 * i;
        w.pos_m[0] = 3 * i * 0.1;
        assert_int_equal(engine_push(e, &w), 0);
    }
    engine_finish(e);
    for (int i = 0; i < 100000 && sp.state != ENGINE_STATE_STREAMING; i++)
        assert_int_equal(engine_tick(e, k++ * PERIOD_NS, &sp), 0);
    assert_int_equal(sp.state, ENGINE_STATE_STREAMING);
    assert_true(sp.flags & ENGINE_SP_TRANSFER);
    engine_free(e);
}

static void test_stop_now_distance(void **state)
{
    (void)state;
    static const double speeds[] = {0.05, 0.3, 0.9, 2, 5, 11, 20, 45, 120};
    static const double aj[][2] = {{2, 20}, {5, 50}, {10, 100}, {18, 5000}, {0.5, 3}};
    double worst[2] = {0, 0}; /* d / bound, (d - v^2/2a) / (v T) */
    int n = 0;
    for (size_t i = 0; i < sizeof speeds / sizeof speeds[0]; i++)
        for (size_t m = 0; m < sizeof aj / sizeof aj[0]; m++)
            for (int clear = 0; clear < 2; clear++) {
                stop_once(speeds[i], aj[m][0], aj[m][1], clear, 300 + (int64_t)(ur() * 700), worst);
                n++;
            }
    print_message("%d stops from 0.05 .. 120 m/s: worst stop distance %.4f of v^2/(2a) + v T; "
                  "beyond v^2/(2a) at most %.3f v T\n",
                  n, worst[0], worst[1]);
}

/*
 * Given a track fully buffered, when the feed override goes 100 % -> 50 %
 * -> 200 % -> 0 % -> 100 %, then every position is the unscaled curve at
 * the setpoint's track time (the same path), track time advances by
 * override * T per tick once settled, velocity is the curve's times the
 * rate, the bounds of the property hold with rmax 2, and the run finishes
 * on the last waypoint; override outside 0..2 is refused.
 */
static void test_override_same_path(void **state)
{
    (void)state;
    enum { N = 300 };
    static engine_waypoint_t wp[N];
    static fdiff_seg_t segs[N + 8];
    size_t nseg = 0;
    engine_config_t c;
    engine_config_default(&c);
    for (int i = 0; i < N; i++)
        helix_wp(&wp[i], i, 0.5, 20.0);
    assert_int_equal(engine_curve(&c, wp, N, segs, N + 8, &nseg), 0);
    curve_max_t m = curve_max(segs, nseg);
    double acc_lim, jerk_lim;
    limits(&c, m, 2.0, &acc_lim, &jerk_lim);
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    assert_int_equal(engine_set_override(e, 2.5), -ENGINE_ERANGE);
    assert_int_equal(engine_set_override(e, -0.1), -ENGINE_ERANGE);
    assert_int_equal(engine_set_override(e, NAN), -ENGINE_ERANGE);
    for (int i = 0; i < N; i++)
        assert_int_equal(engine_push(e, &wp[i]), 0);
    engine_finish(e);
    static const struct {
        int64_t at;
        double ov;
    } plan[] = {
        {1000, 0.5},
        {3000, 2.0},
        {5000, 0.0},
        {7000, 1.0},
    };
    engine_setpoint_t sp, p;
    memset(&p, 0, sizeof p);
    check_t ck = {0};
    size_t pi = 0;
    double ov = 1.0;
    int settled_checked = 0;
    for (int64_t k = 0; k < 200000; k++) {
        if (pi < 4 && k == plan[pi].at) {
            ov = plan[pi].ov;
            assert_int_equal(engine_set_override(e, ov), 0);
            pi++;
        }
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        check_pair(&ck, &p, &sp, segs, nseg);
        if (getenv("TS_DEBUG") && pi > 0 && k == plan[pi - 1].at + 1500)
            fprintf(stderr, "k %lld state %d flags %x dt %.12f\n", (long long)k, sp.state, sp.flags,
                    sp.t_s - p.t_s);
        if (pi > 0 && k == plan[pi - 1].at + 1500 && sp.state == ENGINE_STATE_STREAMING) {
            /* settled: track time advances at the override */
            assert_true(fabs(sp.t_s - p.t_s - ov * T_S) < 1e-12);
            double cv[3];
            fdiff_eval_curve(segs, nseg, &sp.t_s, 1, NULL, cv, NULL);
            for (int a = 0; a < 3; a++)
                assert_true(fabs(sp.vel_m_s[a] - ov * cv[a]) < 1e-9);
            settled_checked++;
        }
        p = sp;
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
    }
    assert_int_equal(settled_checked, 4);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_true(dist3(sp.pos_m, wp[N - 1].pos_m) < 1e-9);
    assert_true(ck.horner_max < TOL_HORNER_M);
    print_message("override: dv/T %.3f (limit %.3f), da/T %.3f (limit %.3f)\n", ck.dv_max / T_S,
                  acc_lim, ck.da_max / T_S, jerk_lim);
    assert_true(ck.dv_max <= acc_lim * T_S * SLACK);
    assert_true(ck.da_max <= jerk_lim * T_S * SLACK);
    engine_free(e);
}

/*
 * Hard stops unreachable (issue 10, gpxpy_cerknicko-jezero with bspline +
 * uniform had one).  With the uniform parameterisation a short interval
 * between evenly spaced waypoints is a segment many times faster than its
 * neighbours.  The limits of the scaling are in rate units at the curve's
 * speed (A = a / v), so the track time needed to brake grows with the speed
 * of the curve ahead.  Given a sender that stalls for good after waypoint
 * n (every n of a range, so that the fast segment comes to be the last one
 * solved), when the output rides the underrun up to the end of the solved
 * curve, then it comes to rest there by braking: hard_stops 0 (a hard stop
 * is a step of the velocity to 0 in one tick), velocity 0 at rest.
 */
static void test_no_hard_stop_fast_end(void **state)
{
    (void)state;
    enum { N = 100 };
    engine_waypoint_t wp[N];
    uint64_t hard = 0;
    int ran = 0;
    for (int i = 0; i < N; i++) {
        memset(&wp[i], 0, sizeof wp[i]);
        /* 2 s apart; every 7th step 40 m instead of 2 m (20x faster) */
        wp[i].t_s = 2.0 * i;
        wp[i].pos_m[0] = i == 0 ? 0 : wp[i - 1].pos_m[0] + (i % 7 == 0 ? 40.0 : 2.0);
        wp[i].pos_m[1] = 0.3 * (i % 2);
        wp[i].seq = (uint32_t)i + 1;
    }
    for (int stall = 40; stall < N; stall++) {
        engine_config_t c;
        engine_config_default(&c);
        c.method = ENGINE_METHOD_BSPLINE;
        c.param = ENGINE_PARAM_UNIFORM;
        c.max_accel_m_s2 = 0;
        engine_t *e = engine_new(&c, NULL);
        assert_non_null(e);
        engine_setpoint_t sp;
        int next = 0, rest_ticks = 0;
        for (int64_t k = 0; k < 400000 && rest_ticks < 100; k++) {
            double now_s = (double)k * T_S;
            while (next < stall && wp[next].t_s <= now_s)
                assert_int_equal(engine_push(e, &wp[next++]), 0);
            assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
            rest_ticks = next == stall && (sp.flags & ENGINE_SP_HOLD) ? rest_ticks + 1 : 0;
        }
        engine_status_t st;
        engine_status(e, &st);
        if (st.hard_stops)
            print_message("stall after waypoint %d: %llu hard stops\n", stall,
                          (unsigned long long)st.hard_stops);
        if (sp.state == ENGINE_STATE_WAITING && st.setpoints > 0 && st.underruns == 0) {
            engine_free(e); /* stalled before its lookahead was in: never moved */
            continue;
        }
        /* at rest at the end of the solved curve (UNDERRUN), or, once the
         * silence outlasted the input's timing, on its last waypoint
         * (FINISHED: the tail played out, silence.h) */
        assert_true(sp.state == ENGINE_STATE_UNDERRUN || sp.state == ENGINE_STATE_FINISHED);
        assert_true(norm3(sp.vel_m_s) <= 0.0);
        hard += st.hard_stops;
        ran++;
        engine_free(e);
    }
    print_message("%d stalls before a fast segment: %llu hard stops\n", ran,
                  (unsigned long long)hard);
    assert_true(ran >= 40);
    assert_true(hard == 0);
}

/*
 * The scaling's own jerk (issue 16 item 5).  On a straight line at constant
 * speed v (clamped ends at v: the curve's second and third derivatives are 0
 * everywhere) the acceleration is all the scaling's, k' dr/dt.  Given random
 * feed overrides (0 .. 2, every 0.5 .. 3 s), the start (entered at rate 0
 * although the curve moves there) and the end (a clamped end moving at v:
 * braked to rest before it), then on every tick |delta acceleration| <=
 * scale_jerk_m_s3 T and |delta velocity| <= scale_accel_m_s2 T (no ts_step
 * landing on its target clears the acceleration faster than the jerk allows).
 */
static void test_jerk_straight_line(void **state)
{
    (void)state;
    double worst_da = 0, worst_dv = 0;
    for (int run = 0; run < 6; run++) {
        double v = 0.5 + 30 * ur();
        engine_config_t c;
        engine_config_default(&c);
        c.ends = ENGINE_ENDS_CLAMPED;
        c.start_vel_m_s[0] = c.end_vel_m_s[0] = v;
        c.scale_accel_m_s2 = 1 + 9 * ur();
        c.scale_jerk_m_s3 = 5 + 95 * ur();
        engine_t *e = engine_new(&c, NULL);
        assert_non_null(e);
        engine_waypoint_t w;
        for (int i = 0; i < 600; i++) {
            memset(&w, 0, sizeof w);
            w.t_s = 0.1 * i;
            w.pos_m[0] = v * w.t_s;
            w.pos_m[1] = 7.0;
            assert_int_equal(engine_push(e, &w), 0);
        }
        assert_int_equal(engine_finish(e), 0);
        engine_setpoint_t sp, p;
        int have = 0;
        int64_t next_ov = 50;
        for (int64_t k = 0; k < 2000000; k++) {
            if (k == next_ov) {
                assert_int_equal(engine_set_override(e, 2 * ur()), 0);
                next_ov += 50 + (int64_t)(250 * ur());
            }
            assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
            if (have && sp.state != ENGINE_STATE_WAITING) {
                double da = dist3(sp.acc_m_s2, p.acc_m_s2), dv = dist3(sp.vel_m_s, p.vel_m_s);
                if (da > c.scale_jerk_m_s3 * T_S * (1 + 1e-9) ||
                    dv > c.scale_accel_m_s2 * T_S * (1 + 1e-9))
                    fail_msg("run %d v %g a %g j %g tick %lld t_s %.4f: da %.6g (jT %.6g), dv "
                             "%.6g (aT %.6g)",
                             run, v, c.scale_accel_m_s2, c.scale_jerk_m_s3, (long long)k, sp.t_s,
                             da, c.scale_jerk_m_s3 * T_S, dv, c.scale_accel_m_s2 * T_S);
                worst_da = fmax(worst_da, da / (c.scale_jerk_m_s3 * T_S));
                worst_dv = fmax(worst_dv, dv / (c.scale_accel_m_s2 * T_S));
                assert_true(fabs(sp.pos_m[1] - 7.0) < 1e-9); /* on the line */
            }
            p = sp;
            have = sp.state != ENGINE_STATE_WAITING;
            if (sp.state == ENGINE_STATE_FINISHED)
                break;
        }
        assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
        engine_free(e);
    }
    print_message("straight line, random overrides: worst |da| %.3f of j T, |dv| %.3f of a T\n",
                  worst_da, worst_dv);
}

/* Given a ramp that built the rate's acceleration up under the limits of a
 * slow part of the curve (a = 5 m/s^2, j = 50 m/s^3 converted at the 1 m/s
 * floor: dr/dt = 4.86 /s at rate 0.55), when the output enters a faster
 * segment (the same limits converted at 15.5 m/s: A = 0.32 /s, J = 3.2 /s^2),
 * then the rate still lands on its target 1 and overshoots it by at most the
 * acceleration it carries times A/J = a/j (the time the jerk takes to bring
 * it within A again), never beyond TS_RATE_MAX.  The jerk stays within J
 * times the ratio of that acceleration to A.  (With J alone it took 1.4 s to
 * bring 4.86 down and the rate rose to 2.5: tests/fuzz/regress/fuzz_engine/
 * cubic-speed-beyond-safety-bound, where the output then moved at 24.6 m/s.) */
static void test_limits_shrink_no_overshoot(void **state)
{
    (void)state;
    const double A = 5.0 / 15.5, J = 50.0 / 15.5, T = 0.02, a0 = 4.86;
    ts_state_t st = {.rate = 0.55, .acc = a0};
    double rmax = 0, j;
    for (int i = 0; i < 1000; i++) {
        double acc = st.acc;
        (void)ts_step(&st, 1.0, INFINITY, A, J, T, &j, NULL);
        rmax = fmax(rmax, st.rate);
        assert_true(fabs(j) <= J * fmax(1.0, fabs(acc) / A) * (1 + 1e-12));
    }
    printf("limits shrink: rate at most %.4f (bound %.4f), then %.6f\n", rmax, 1.0 + a0 * A / J,
           st.rate);
    assert_true(rmax <= 1.0 + a0 * A / J);
    assert_true(rmax <= TS_RATE_MAX);
    assert_true(fabs(st.rate - 1.0) <= 0.0 && fabs(st.acc) <= 0.0); /* landed exactly */
}

/* Given the state fuzz_engine's transfer came to rest in at 10 Hz (the
 * limits converted at its speed: A 0.0042, J 0.126 per s^2, s^3 of rate;
 * 1.21e-4 s of track time left to its end, the end 1.3 um away), when the
 * output is asked on at rate 1, then ts_step alone stands still for good
 * (the room is within the dead band) and ts_creep moves on, until the
 * output is on the end (a transfer's end takes it at rest: scaled_advance;
 * it arrives at a rate within the dead band) or within a thousandth of the
 * room it had (the gap to the end, k'' d^2 / 2, a millionth). */
static void test_creep_onto_the_end(void **state)
{
    (void)state;
    const double A = 0.0042, J = 0.126, T = 0.1, R0 = 1.21e-4;
    ts_state_t st = {0};
    double left = R0;
    int ticks = 0;

    assert_true(ts_step(&st, 1.0, left, A, J, T, NULL, NULL) <= 0.0);
    assert_true(st.rate <= 0.0 && fabs(st.acc) <= 0.0);
    while (left > 1e-3 * R0 && ticks < 1000) {
        double ds = ts_step(&st, 1.0, left, A, J, T, NULL, NULL);
        if (!(ds > 0) && !(st.rate > 0))
            ds = ts_creep(&st, left, A, J, T);
        ticks++;
        assert_true(ds >= 0);
        if (ds >= left) { /* on the end */
            assert_true(st.rate <= ts_dead_band(J, T));
            left = 0;
            break;
        }
        left -= ds;
    }
    print_message("creep: %.3g of %.3g s of track time left after %d ticks\n", left, R0, ticks);
    assert_true(left <= 1e-3 * R0);
}

/* A stop asked during a ramp (rate 0.36 rising by 0.31 a second), planned at
 * the jerk of a fast segment ahead (0.11 per s^3 of rate) while the output is
 * still on a slow one that allows 5: ts_step_jerk takes this tick's jerk from
 * the segment it is on (the ramp's acceleration down by 5 T in a tick, where
 * ts_step at the planned jerk takes 0.11 T), plans every later tick at the
 * planned jerk, and the braking ends exactly at rest with no acceleration
 * left once the ticks have only the planned jerk (fuzz_engine's
 * clear-above-ceiling-then-transfer, engine_scale.c stop_jerk_now). */
static void test_stop_jerk_now(void **state)
{
    (void)state;
    const double A = 0.39, J = 0.11, Jnow = 5.0, T = 0.02;
    ts_state_t slow = {.rate = 0.36, .acc = 0.31}, st = slow;
    double j;

    (void)ts_step(&slow, 0.0, INFINITY, A, J, T, &j, NULL);
    assert_true(slow.acc >= 0.31 - J * T * (1 + 1e-12));
    (void)ts_step_jerk(&st, 0.0, INFINITY, A, Jnow, J, T, &j, NULL);
    assert_true(fabs(j) <= Jnow * (1 + 1e-12));
    assert_true(st.acc <= 0.31 - 0.99 * Jnow * T);
    double rmax = st.rate;
    int i;
    for (i = 1; i < 12; i++) { /* still on the slow segment */
        (void)ts_step_jerk(&st, 0.0, INFINITY, A, Jnow, J, T, &j, NULL);
        assert_true(fabs(j) <= Jnow * (1 + 1e-12));
        rmax = fmax(rmax, st.rate);
    }
    for (; i < 100000 && (st.rate > 0 || fabs(st.acc) > 0); i++) { /* on the fast one */
        double acc = st.acc;
        (void)ts_step(&st, 0.0, INFINITY, A, J, T, &j, NULL);
        assert_true(fabs(j) <= J * fmax(1.0, fabs(acc) / A) * (1 + 1e-12));
    }
    print_message("stop at this tick's jerk: peak rate %.4f, at rest after %d ticks\n", rmax, i);
    assert_true(rmax < 0.37);
    assert_true(st.rate <= 0.0 && fabs(st.acc) <= 0.0);
}

/* TS_LIM_FREE (timescale.h): where ts_step says R lowered its target but
 * the move is the one with R infinite, it is, bit for bit.  Given random
 * states, targets, limits and rooms R (most of them short of a stop, so
 * that R lowers the target), every move flagged so equals the same call
 * with R infinite in its advance, rate and acceleration, and the flag is
 * found on ramps towards R's rate at the acceleration or the jerk limit
 * (delay_run.c ramp_lag skips the second step there). */
static void test_lim_free_is_the_free_move(void **state)
{
    (void)state;
    unsigned flagged = 0, limited = 0;
    for (int k = 0; k < 400000; k++) {
        double A = 0.05 + 5.0 * ur(), J = 0.05 + 50.0 * ur(), T = k % 3 ? 0.01 : 0.001 + 0.1 * ur();
        ts_state_t st = {.rate = k % 4 ? 1.2 * ur() : 0.0, .acc = (2.0 * ur() - 1.0) * A};
        if (k % 5 == 0)
            st.acc = 1.5 * A * ur(); /* also beyond A: this tick's jerk raised */
        double target = k % 7 ? 1.0 : 2.0 * ur();
        /* about a stop from the state after the tick, to an order of magnitude */
        double r1 = st.rate + st.acc * T + 0.5 * J * T * T, a1 = st.acc + J * T;
        double R = (ts_stop_dist(r1, a1, A, J) + r1 * T) * pow(10.0, 2.0 * ur() - 1.0);
        ts_state_t free_st = st;
        int lim = 0;
        double ds = ts_step(&st, target, R, A, J, T, NULL, &lim);
        limited += (unsigned)(lim & 1);
        if (!(lim & TS_LIM_FREE))
            continue;
        flagged++;
        assert_true(lim & 1);
        double ds_free = ts_step(&free_st, target, INFINITY, A, J, T, NULL, NULL);
        assert_memory_equal(&ds, &ds_free, sizeof ds);
        assert_memory_equal(&st.rate, &free_st.rate, sizeof st.rate);
        assert_memory_equal(&st.acc, &free_st.acc, sizeof st.acc);
    }
    print_message("R lowered the target %u times; %u of them the free move\n", limited, flagged);
    assert_true(flagged > limited / 10);
}

/* ts_step_one is ts_step(st, 1.0, R, A, J, T, NULL, limited) with the
 * terms of the limits in hand (timescale.h).  Given random states (the
 * acceleration at A, at 0, within 0 .. A and beyond +-A) and rooms R (about
 * a stop from the state after the tick, to an order of magnitude; also
 * infinite and negative), and 4 000 whole ramps from rest to rate 1 as
 * delay_run.c ramp_lag simulates them (the limits changed every 37 ticks,
 * the room growing a tick a tick after a random wait), the advance, the
 * state and *limited are ts_step's, bit for bit, and where TS_ONE_FREE
 * stands for 0 in *limited, those of ts_step with R infinite too. */
static unsigned n_one_free;
static double step_one_check(ts_state_t *st, const ts_lims_t *l, double R)
{
    ts_state_t ref = *st, free_st = *st;
    int lim = -1, lim_ref = -1;
    double ds = ts_step_one(st, l, R, &lim);
    double ds_ref = ts_step(&ref, 1.0, R, l->A, l->J, l->T, NULL, &lim_ref);
    assert_memory_equal(&ds, &ds_ref, sizeof ds);
    assert_memory_equal(&st->rate, &ref.rate, sizeof ref.rate);
    assert_memory_equal(&st->acc, &ref.acc, sizeof ref.acc);
    if (lim & TS_ONE_FREE) {
        /* also the move with R infinite */
        assert_int_equal(lim, TS_ONE_FREE);
        assert_int_equal(lim_ref, 0);
        double ds_free = ts_step(&free_st, 1.0, INFINITY, l->A, l->J, l->T, NULL, NULL);
        assert_memory_equal(&ds, &ds_free, sizeof ds);
        assert_memory_equal(&st->rate, &free_st.rate, sizeof ref.rate);
        assert_memory_equal(&st->acc, &free_st.acc, sizeof ref.acc);
        n_one_free++;
    } else {
        assert_int_equal(lim, lim_ref);
    }
    return ds;
}

static void test_step_one_is_ts_step(void **state)
{
    (void)state;
    ts_lims_t l;
    for (int k = 0; k < 400000; k++) {
        double A = 0.05 + 5.0 * ur(), J = 0.05 + 50.0 * ur(), T = k % 3 ? 0.01 : 0.001 + 0.1 * ur();
        ts_state_t st = {.rate = k % 4 ? 1.2 * ur() : 0.0, .acc = A * ur()};
        switch (k % 6) {
        case 0: st.acc = A; break;
        case 1: st.acc = 0.0; break;
        case 2: st.acc = (2.0 * ur() - 1.0) * 1.5 * A; break;
        default: break;
        }
        double r1 = st.rate + st.acc * T + 0.5 * J * T * T, a1 = st.acc + J * T;
        double R = (ts_stop_dist(r1, a1, A, J) + r1 * T) * pow(10.0, 2.0 * ur() - 1.0);
        if (k % 50 == 0)
            R = k % 100 ? INFINITY : -R;
        ts_lims_init(&l, A, J, T);
        (void)step_one_check(&st, &l, R);
    }
    unsigned ticks = 0, ramps_at_1 = 0;
    for (int k = 0; k < 4000; k++) {
        double T = k % 2 ? 0.01 : 0.001 + 0.05 * ur(), A = 0.0, J = 0.0;
        double R = (0.3 + 2.0 * ur()) * ts_stop_dist(1.0, 0.0, 0.5, 5.0);
        double grow = k % 4 ? 1.0 : 0.8 + 0.4 * ur();
        int wait = (int)(50.0 * ur()), n;
        ts_state_t st = {0.0, 0.0};
        for (n = 0; n < 20000; n++) {
            if (n % 37 == 0) {
                A = 0.1 + 2.0 * ur();
                J = A * (2.0 + 20.0 * ur());
                ts_lims_init(&l, A, J, T);
            }
            R += (n >= wait ? grow * T : 0.0) - step_one_check(&st, &l, R);
            if (!(st.rate < 1.0 || st.rate > 1.0) && !(st.acc < 0.0 || st.acc > 0.0))
                break;
        }
        ticks += (unsigned)n;
        ramps_at_1 += n < 20000;
    }
    print_message("%u ticks of ramps, %u of 4000 ramps at rate 1; %u moves the free one\n", ticks,
                  ramps_at_1, n_one_free);
    assert_true(ramps_at_1 > 1000);
    assert_true(n_one_free > ticks / 10);
}

/* ts_rise_holds (timescale.h): given random limits, runs of 1 to 24 ticks
 * rising at A from random rates, and rooms about the stop after the run
 * (from a third to 30 times it, each tick's a little above the least, some
 * infinite), every run it passes is, tick by tick, ts_step_one's rise at A
 * (the rate + A T, the advance r T + A T^2 / 2) with TS_LIM_FREE or
 * TS_ONE_FREE, and ts_step's move bit for bit; it passes some runs and
 * fails others. */
static void test_rise_holds_is_the_rise(void **state)
{
    (void)state;
    unsigned runs = 0, held = 0;
    for (int k = 0; k < 300000; k++) {
        double A = 0.05 + 5.0 * ur(), J = A * (1.0 + 30.0 * ur());
        double T = k % 3 ? 0.01 : 0.001 + 0.1 * ur();
        ts_lims_t l;
        ts_lims_init(&l, A, J, T);
        int n = 1 + (int)(24.0 * ur());
        double r0 = 1.1 * ur(), r_last = r0, R[25], R_min = INFINITY;
        for (int m = 1; m < n; m++)
            r_last = r_last + l.at;
        double r1 = r_last + l.at;
        double Rb = (ts_stop_dist(r1, A, A, J) + r1 * T) * pow(10.0, 2.0 * ur() - 0.5);
        for (int m = 0; m < n; m++) {
            R[m] = k % 7 == 0 && m % 2 ? INFINITY : Rb * (1.0 + 0.05 * ur());
            R_min = R[m] < R_min ? R[m] : R_min;
        }
        runs++;
        if (!ts_rise_holds(&l, R_min, r0, r_last))
            continue;
        held++;
        ts_state_t st = {r0, A};
        for (int m = 0; m < n; m++) {
            ts_state_t ref = st;
            double r = st.rate, ds_rise = r * T + l.ca, r_rise = r + l.at;
            int lim = 0, lim_ref = 0;
            double ds = ts_step_one(&st, &l, R[m], &lim);
            double ds_ref = ts_step(&ref, 1.0, R[m], A, J, T, NULL, &lim_ref);
            assert_memory_equal(&ds, &ds_rise, sizeof ds);
            assert_memory_equal(&st.rate, &r_rise, sizeof r);
            assert_memory_equal(&st.acc, &A, sizeof A);
            assert_true(lim & (TS_LIM_FREE | TS_ONE_FREE));
            assert_memory_equal(&ds, &ds_ref, sizeof ds);
            assert_memory_equal(&st.rate, &ref.rate, sizeof r);
            assert_memory_equal(&st.acc, &ref.acc, sizeof A);
            assert_int_equal(lim & ~TS_ONE_FREE, lim_ref);
        }
    }
    print_message("%u of %u runs at A held\n", held, runs);
    assert_true(held > runs / 10 && held < runs - runs / 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stop_dist_matches_simulation),
        cmocka_unit_test(test_never_overruns_R),
        cmocka_unit_test(test_property_random_stalls),
        cmocka_unit_test(test_stop_now_distance),
        cmocka_unit_test(test_override_same_path),
        cmocka_unit_test(test_no_hard_stop_fast_end),
        cmocka_unit_test(test_jerk_straight_line),
        cmocka_unit_test(test_limits_shrink_no_overshoot),
        cmocka_unit_test(test_creep_onto_the_end),
        cmocka_unit_test(test_stop_jerk_now),
        cmocka_unit_test(test_lim_free_is_the_free_move),
        cmocka_unit_test(test_step_one_is_ts_step),
        cmocka_unit_test(test_rise_holds_is_the_rise),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
