/*
 * test_clock.c - one clock for every object (issue 16 item 2): the drift
 * estimate and play-out clock (lib/engine/playout.h) and the clocked engine
 * (engine_set_clock, lib/engine/CLOCK.md), driven with simulated time only:
 * no clock is read, a 24-hour run takes seconds.
 *
 * References: the simulation's own parameters (the sender's clock error, the
 * latency, the frames lost), not the engine's output: the drift estimate is
 * judged against the drift the simulation applies, the play-out margin
 * against the stamps the simulated sender sent, and the setpoints against
 * direct Horner evaluation of the curve (engine_curve + fdiff_eval) at their
 * own track time.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "fdiff.h"
#include "playout.h"

#define T0_S 1700000000.0 /* an epoch time: 2023-11-14 */
#define T0_NS 1700000000000000000LL

static unsigned seed = 1616;
static double ur(void)
{
    return urand(&seed);
}

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* ---- drift estimate ----------------------------------------------------- */

/* A sender at 10 Hz whose clock runs at (1 + eps) of ours, latency 20 ms +
 * a skewed jitter up to 60 ms, 1 % of frames lost: fed for `minutes`. */
static void feed(playout_drift_t *d, double eps, double minutes)
{
    for (long i = 0; i < (long)(minutes * 600); i++) {
        double stamp_rel = i * 0.1;
        double emit = stamp_rel / (1.0 + eps); /* true time since T0 */
        double j = ur();
        double lat = 0.020 + 0.060 * j * j * j;
        if (ur() < 0.01)
            continue;
        int64_t arr = T0_NS + (int64_t)llround((emit + lat) * 1e9);
        playout_drift_add(d, arr, T0_S + stamp_rel);
    }
}

/* Given a sender 100 ppm fast, 37 ppm slow or exact, when ten minutes of
 * arrivals are fed, then the estimate is within 0.5 ppm of the truth; and
 * an 800 ppm error is absorbed only up to the bound, 500 ppm. */
static void test_drift_estimate(void **state)
{
    (void)state;
    const double eps[] = {100e-6, -37e-6, 0.0, 800e-6, -800e-6};
    for (size_t i = 0; i < sizeof eps / sizeof eps[0]; i++) {
        playout_drift_t d;
        playout_drift_init(&d, 500);
        assert_false(playout_drift_eps(&d) < 0 || playout_drift_eps(&d) > 0);
        feed(&d, eps[i], 10);
        double want = fmax(-500e-6, fmin(500e-6, eps[i]));
        printf("eps %+.1f ppm: estimate %+.3f ppm\n", eps[i] * 1e6, playout_drift_eps(&d) * 1e6);
        assert_true(fabs(playout_drift_eps(&d) - want) < 0.5e-6);
    }
}

/* Given a sender whose clock is 5 s wrong for two whole windows (a step, then
 * back), when fed for half an hour, then the estimate stays within 1 ppm of
 * the truth (Theil-Sen's median ignores the two windows). */
static void test_drift_robust(void **state)
{
    (void)state;
    playout_drift_t d;
    playout_drift_init(&d, 500);
    double eps = 60e-6;
    for (long i = 0; i < 30 * 600; i++) {
        double stamp_rel = i * 0.1, emit = stamp_rel / (1.0 + eps);
        double bad = (emit > 600 && emit < 720) ? 5.0 : 0.0;
        int64_t arr = T0_NS + (int64_t)llround((emit + 0.02 + 0.01 * ur()) * 1e9);
        playout_drift_add(&d, arr, T0_S + stamp_rel + bad);
    }
    printf("with a 2-minute clock step: %+.3f ppm\n", playout_drift_eps(&d) * 1e6);
    assert_true(fabs(playout_drift_eps(&d) - eps) < 1e-6);
}

/* Given a target drift of 100 ppm, when the clock advances second by second,
 * then the applied drift moves at most PLAYOUT_SLEW_PPM_S per second, the
 * rate is 1 + the applied drift, and the offset is the integral of it. */
static void test_playout_clock_slew(void **state)
{
    (void)state;
    playout_clock_t c;
    playout_clock_init(&c);
    double rate = 0, integral = 0, prev_eps = 0;
    int64_t first = playout_clock_now(&c, T0_NS, 100e-6, &rate);
    assert_true(first == T0_NS);
    for (int s = 1; s <= 300; s++) {
        int64_t now = playout_clock_now(&c, T0_NS + (int64_t)s * 1000000000LL, 100e-6, &rate);
        double eps = rate - 1.0;
        assert_true(eps - prev_eps <= PLAYOUT_SLEW_PPM_S * 1e-6 + 1e-15);
        integral += 0.5 * (eps + prev_eps) * 1e9;
        prev_eps = eps;
        assert_true(llabs(now - (T0_NS + (int64_t)s * 1000000000LL) - (int64_t)llround(integral)) <=
                    1);
    }
    assert_true(fabs(rate - 1.0 - 100e-6) < 1e-12); /* reached after 100 s */
    /* a step back of the system clock accrues no drift and passes through */
    int64_t back = playout_clock_now(&c, T0_NS, 100e-6, &rate);
    assert_true(llabs(back - (T0_NS + (int64_t)llround(integral))) <= 1);
}

/* ---- the clocked engine ------------------------------------------------- */

#define PERIOD_NS 20000000LL /* 50 Hz output */
#define PERIOD_S 0.02
#define WP_DT 0.2 /* 5 Hz waypoints */
/* D: the curve is final (F - O/2) = 24 waypoints behind the newest (4.8 s
 * at 5 Hz), and the time scaling needs v / (2 a) = 2 s of it to stop in
 * at 20 m/s (TIMESCALE.md): with latency and lost frames, 10 s */
#define DELAY_S 10.0
#define CATCHUP 0.05

/* Object k's position at sender time u (s since T0): a 300 m circle at
 * 20 m/s, or a figure-8 at about 10 m/s. */
static void where(int k, double u, double *p)
{
    if (k == 0) {
        p[0] = 300.0 * cos(u / 15.0);
        p[1] = 300.0 * sin(u / 15.0);
        p[2] = 0;
    } else {
        p[0] = 200.0 * sin(u / 40.0);
        p[1] = 100.0 * sin(u / 20.0);
        p[2] = 5.0 * sin(u / 60.0);
    }
}

typedef struct {
    engine_t *e;
    long next;     /* next frame to emit */
    double arr_s;  /* its arrival, true seconds since T0 */
    int lost;      /* it is lost */
    double newest; /* newest stamp delivered, s since T0 */
    int on_clock;  /* its t_s was the play time in the previous tick */
    int locked;    /* it was in two ticks in a row: locked on the clock (a
                      start at rest on the play time is there for one tick) */
    engine_setpoint_t sp;
} sim_obj_t;

typedef struct {
    double eps;                 /* sender clock error */
    double loss;                /* fraction of frames lost */
    double stall_from, stall_s; /* true time of a sender stall (no frames), s */
    int line;                   /* object 0 moves on a straight line at 20 m/s */
} sim_cfg_t;

static void next_frame(sim_obj_t *o, const sim_cfg_t *c)
{
    for (;;) {
        o->next++;
        double emit = o->next * WP_DT / (1.0 + c->eps);
        double j = ur();
        o->arr_s = emit + 0.020 + 0.060 * j * j * j;
        o->lost = ur() < c->loss;
        if (!(emit >= c->stall_from && emit < c->stall_from + c->stall_s))
            return;
    }
}

static engine_t *mk(void)
{
    engine_config_t cfg;
    engine_config_default(&cfg);
    cfg.period_ns = PERIOD_NS;
    int err = 0;
    engine_t *e = engine_new(&cfg, &err);
    assert_non_null(e);
    return e;
}

/* Deliver object o's frames that arrived by true time t (s since T0). */
static void deliver(sim_obj_t *o, int k, double t, const sim_cfg_t *c, playout_drift_t *d)
{
    while (o->arr_s <= t) {
        if (!o->lost) {
            engine_waypoint_t wp = {.t_s = T0_S + o->next * WP_DT, .seq = (uint32_t)o->next + 1};
            double u = o->next * WP_DT;
            if (c->line && k == 0) {
                wp.pos_m[0] = 20.0 * u;
                wp.pos_m[1] = wp.pos_m[2] = 0;
            } else {
                where(k, u, wp.pos_m);
            }
            int64_t arr = T0_NS + (int64_t)llround(o->arr_s * 1e9);
            if (engine_push(o->e, &wp) == 0)
                playout_drift_add(d, arr, wp.t_s);
            o->newest = u;
        }
        next_frame(o, c);
    }
}

typedef struct {
    uint64_t ticks, both, skewed, aged, aged_locked, age_n;
    double age_max;
    double margin_first, margin_last; /* mean margin in hour 1 and in the last hour */
    double raw_first, raw_last;       /* the same against CLOCK_REALTIME uncorrected */
    double n_first, n_last;
    double rate_max, dv_max, da_max, lag_last, skew_last;
    double start_s, lock_s, start_lag; /* both streaming, both locked; the lag between */
    uint64_t underruns, hard_stops;
} sim_out_t;

/* Run two objects for `hours` of simulated time on one play-out clock. */
static void run(const sim_cfg_t *c, double hours, sim_out_t *out)
{
    sim_obj_t o[2];
    playout_drift_t d;
    playout_clock_t pc;
    int64_t ticks = (int64_t)llround(hours * 3600.0 / PERIOD_S);
    double prev_v = NAN, prev_a = NAN;

    memset(out, 0, sizeof *out);
    playout_drift_init(&d, PLAYOUT_MAX_PPM);
    playout_clock_init(&pc);
    for (int k = 0; k < 2; k++) {
        memset(&o[k], 0, sizeof o[k]);
        o[k].e = mk();
        o[k].next = -1;
        next_frame(&o[k], c);
    }
    for (int64_t n = 0; n < ticks; n++) {
        double t = (double)n * PERIOD_S;
        int64_t real_ns = T0_NS + n * PERIOD_NS;
        double rate = 1;
        for (int k = 0; k < 2; k++)
            deliver(&o[k], k, t, c, &d);
        int64_t now = playout_clock_now(&pc, real_ns, playout_drift_eps(&d), &rate);
        engine_clock_t clk = {now, (int64_t)(DELAY_S * 1e9), rate, CATCHUP};
        for (int k = 0; k < 2; k++) {
            assert_int_equal(engine_set_clock(o[k].e, &clk), 0);
            assert_int_equal(engine_tick(o[k].e, n * PERIOD_NS, &o[k].sp), 0);
        }
        out->ticks++;
        engine_status_t st;
        engine_status(o[0].e, &st);
        if (!(o[0].sp.flags & ENGINE_SP_NO_POSITION)) {
            double v = o[0].sp.vel_m_s[0], a = o[0].sp.acc_m_s2[0];
            out->rate_max = fmax(out->rate_max, st.rate / rate);
            /* da from the first tick (the start is entered at rate 0); dv
             * after the start: a REST start on a line at 20 m/s speeds up
             * on its own, k''(0) = 346 m/s^2 times r^2 (TIMESCALE.md's
             * bound there is A_c r^2 + a, not a) */
            if (isfinite(prev_v) && t > 60)
                out->dv_max = fmax(out->dv_max, fabs(v - prev_v));
            if (isfinite(prev_v))
                out->da_max = fmax(out->da_max, fabs(a - prev_a));
            prev_v = v;
            prev_a = a;
        }
        int on = o[0].sp.state == ENGINE_STATE_STREAMING && o[1].sp.state == ENGINE_STATE_STREAMING;
        if (!on)
            continue;
        out->both++;
        double play_t = (double)((long double)(now - (int64_t)(DELAY_S * 1e9)) * 1e-9L);
        if (out->both == 1)
            out->start_s = t;
        if (!(o[0].locked && o[1].locked)) {
            for (int k = 0; k < 2; k++) {
                int at = o[k].sp.t_s >= play_t && o[k].sp.t_s <= play_t;
                o[k].locked |= at && o[k].on_clock;
                o[k].on_clock = at;
                out->start_lag = fmax(out->start_lag, play_t - o[k].sp.t_s);
            }
            out->lock_s = t;
        }
        /* the same instant once both have locked on the clock: each start is
         * entered at rate 0 and catches up along its own curve, at its own
         * pace (CLOCK.md, "Start"), so the two differ until then */
        if (o[0].locked && o[1].locked)
            out->skewed += o[0].sp.t_s < o[1].sp.t_s || o[0].sp.t_s > o[1].sp.t_s;
        for (int k = 0; k < 2; k++) {
            double age = o[k].sp.age_s;
            out->age_n++;
            out->aged += !(age <= DELAY_S + PERIOD_S);
            out->aged_locked += !(age <= DELAY_S + PERIOD_S) && o[0].locked && o[1].locked;
            out->age_max = fmax(out->age_max, age);
        }
        /* play-out margin: newest stamp received - the play time */
        double play = (double)(now - T0_NS) * 1e-9 - DELAY_S;
        double raw = (double)(real_ns - T0_NS) * 1e-9 - DELAY_S;
        double newest = fmin(o[0].newest, o[1].newest);
        if (t < 3600) {
            out->margin_first += newest - play;
            out->raw_first += newest - raw;
            out->n_first++;
        } else if (t >= hours * 3600 - 3600) {
            out->margin_last += newest - play;
            out->raw_last += newest - raw;
            out->n_last++;
        }
        out->lag_last = o[0].sp.age_s - DELAY_S;
        out->skew_last = o[0].sp.t_s - o[1].sp.t_s;
    }
    out->margin_first /= fmax(out->n_first, 1);
    out->raw_first /= fmax(out->n_first, 1);
    out->margin_last /= fmax(out->n_last, 1);
    out->raw_last /= fmax(out->n_last, 1);
    for (int k = 0; k < 2; k++) {
        engine_status_t st;
        engine_status(o[k].e, &st);
        out->underruns += st.underruns;
        out->hard_stops += st.hard_stops;
        engine_free(o[k].e);
    }
}

/* Given one sender for two objects whose clock is 100 ppm fast (then slow),
 * 1 % of frames lost and a latency of 20..80 ms, when 24 hours are played
 * out with D = 10 s at 50 Hz, then:
 *   - the margin of data ahead of the play time does not shrink nor grow
 *     (the drift is absorbed), while against the uncorrected system clock it
 *     would have moved by the 8.64 s the sender's clock drifts in a day;
 *   - the data age p99 is at most D + one period (here: every tick but
 *     those of the start's catch-up);
 *   - the two objects are at the same instant in every tick once both
 *     have locked on the clock (skew 0), which they do within the start's
 *     lag / CATCHUP + 15 s (each start is entered at rate 0, behind);
 *   - nothing underruns. */
static void test_24h(void **state)
{
    (void)state;
    const double eps[] = {100e-6, -100e-6};
    for (int i = 0; i < 2; i++) {
        sim_cfg_t c = {.eps = eps[i], .loss = 0.01};
        sim_out_t r;
        run(&c, 24.0, &r);
        printf("eps %+.0f ppm: ticks %llu streaming %llu skewed %llu; age > D+T: %llu of %llu "
               "(%llu locked), "
               "max %.9f s; mean margin hour 1 %.3f s, hour 24 %.3f s (uncorrected %.3f -> %.3f); "
               "underruns %llu; started at %.2f s, lag up to %.3f s, both locked %.2f s later\n",
               eps[i] * 1e6, (unsigned long long)r.ticks, (unsigned long long)r.both,
               (unsigned long long)r.skewed, (unsigned long long)r.aged,
               (unsigned long long)r.age_n, (unsigned long long)r.aged_locked, r.age_max,
               r.margin_first, r.margin_last, r.raw_first, r.raw_last,
               (unsigned long long)r.underruns, r.start_s, r.start_lag, r.lock_s - r.start_s);
        assert_true(r.both > r.ticks * 99 / 100);
        assert_true(r.skewed == 0);
        assert_true(r.lock_s - r.start_s <= r.start_lag / CATCHUP + 15.0);
        assert_true(r.aged * 100 <= r.age_n);
        assert_true(r.aged_locked == 0);
        assert_true(fabs(r.margin_last - r.margin_first) < 0.05);
        assert_true(fabs((r.raw_last - r.raw_first) - eps[i] * 23 * 3600) < 0.1);
        assert_true(r.underruns == 0);
        assert_true(r.hard_stops == 0);
    }
}

/* Given an exact sender and an object on a straight line at 20 m/s (the
 * curve's own acceleration is 0: all of it is the scaling's), when the
 * sender stalls for 20 s, then the output slows down and waits (lag), and
 * after the stall it catches up at about CATCHUP above the clock's rate
 * (within 10 %: the scaling settles on its target), with |acceleration| <=
 * scale_accel_m_s2 (5) on every tick after the start and |jerk| <=
 * scale_jerk_m_s3 (50, 30 % over at the landing on the target rate) on every
 * tick, the start's own catch-up included, until the lag is back under one
 * period (within 20 s / CATCHUP + 60 s); the other object (no line, same
 * stall) is at the same instant again once both are locked. */
static void test_catchup_after_stall(void **state)
{
    (void)state;
    sim_cfg_t c = {.eps = 0, .loss = 0, .stall_from = 600, .stall_s = 20, .line = 1};
    sim_out_t r;
    run(&c, 0.3, &r); /* 1080 s: the stall ends at 620 s */
    printf("stall 20 s: rate max %.6f, |dv| max %.6f m/s, |da| max %.6f m/s2 per tick, lag at "
           "the end %.3g s, underruns %llu, hard stops %llu\n",
           r.rate_max, r.dv_max, r.da_max, r.lag_last, (unsigned long long)r.underruns,
           (unsigned long long)r.hard_stops);
    assert_true(r.underruns > 0);
    /* the target is 1 + CATCHUP; the time scaling's jerk-limited tracking
     * settles on it (measured 1.0500, the bound itself: no overshoot) */
    assert_true(r.rate_max <= 1.0 + 1.1 * CATCHUP);
    assert_true(r.rate_max > 1.0 + 0.9 * CATCHUP); /* it did catch up at the bound */
    assert_true(r.dv_max <= 5.0 * PERIOD_S * 1.02);
    /* jerk: ts_step lands on its target rate by zeroing what is left of the
     * acceleration in one tick, measured within 1.00 j T here (the time
     * scaling's landing rule, TIMESCALE.md; not the clock's) */
    assert_true(r.da_max <= 50.0 * PERIOD_S * 1.3);
    assert_true(fabs(r.lag_last) <= PERIOD_S);
    assert_false(r.skew_last < 0 || r.skew_last > 0); /* exactly 0 */
    assert_true(r.hard_stops == 0);
}

/* Given a clocked engine, when the play time crosses the first waypoint's
 * time between two ticks, then the output starts there at rest (t_s the
 * first waypoint's time: entered at rate 0 like every start, behind the clock
 * by that sub-tick phase), catches up and locks on the clock: from then on
 * its t_s is now - D (age D) at every tick (up to the braking into the REST
 * end); and at every tick the position is the curve's at t_s (Horner on
 * engine_curve's segments). */
static void test_start_on_the_clock(void **state)
{
    (void)state;
    engine_t *e = mk();
    engine_config_t cfg;
    engine_config_default(&cfg);
    cfg.period_ns = PERIOD_NS;
    enum { N = 800 }; /* 160 s: the circle's start lags by about 3 s, won back at 5 % */
    static engine_waypoint_t wp[N];
    for (int i = 0; i < N; i++) {
        memset(&wp[i], 0, sizeof wp[i]);
        wp[i].t_s = T0_S + 0.0137 + i * WP_DT;
        where(0, i * WP_DT, wp[i].pos_m);
        wp[i].seq = (uint32_t)i + 1;
        assert_int_equal(engine_push(e, &wp[i]), 0);
    }
    assert_int_equal(engine_finish(e), 0);
    static fdiff_seg_t seg[2 * N];
    size_t nseg = 0;
    assert_int_equal(engine_curve(&cfg, wp, N, seg, 2 * N, &nseg), 0);
    int moving = 0, locked = 0;
    for (int64_t n = 0; n < 8500; n++) {
        engine_clock_t clk = {T0_NS + n * PERIOD_NS + 3000000000LL, 3000000000LL, 1.0, CATCHUP};
        engine_setpoint_t sp;
        assert_int_equal(engine_set_clock(e, &clk), 0);
        assert_int_equal(engine_tick(e, n * PERIOD_NS, &sp), 0);
        /* now - D as a double: the t_s of every output locked on the clock */
        double play = (double)((long double)(clk.now_ns - clk.delay_ns) * 1e-9L);
        int at = sp.t_s >= play && sp.t_s <= play;
        if (sp.state != ENGINE_STATE_STREAMING) {
            assert_true(moving == 0 || sp.state == ENGINE_STATE_FINISHED);
            continue;
        }
        if (moving++ == 0) { /* the start: on the first waypoint, at rest */
            assert_true(sp.t_s >= wp[0].t_s && sp.t_s <= wp[0].t_s);
            assert_false(dist3(sp.vel_m_s, (const double[3]){0, 0, 0}) > 0);
        }
        /* on the clock once locked, up to the REST end, which is left at
         * rate 0 (braking from v = where()'s speed, under 30 m/s, takes
         * v/(2a) + a/(2j) <= 3.05 s of track time at a = 5 m/s^2, j = 50
         * m/s^3; then late) */
        locked += locked || at; /* locked: on it in two ticks in a row */
        if (locked > 1 && sp.t_s < wp[N - 1].t_s - 3.1) {
            assert_true(at);
            assert_true(fabs(sp.age_s - 3.0) < 1e-6);
        }
        for (size_t i = 0; i < nseg; i++)
            if (sp.t_s >= seg[i].t0_s && sp.t_s < seg[i].t0_s + seg[i].dur_s) {
                double p[3];
                fdiff_eval(&seg[i], (sp.t_s - seg[i].t0_s) / seg[i].dur_s, p, NULL, NULL);
                for (int k = 0; k < 3; k++)
                    assert_true(fabs(p[k] - sp.pos_m[k]) < 1e-4);
            }
    }
    print_message("locked %.2f s after the start\n", (moving - locked) * PERIOD_S);
    assert_true(locked > 4000); /* it did lock, for the larger part of the track */
    assert_true(moving > 7900);
    engine_free(e);
}

/* ---- a clocked start from rest ------------------------------------------ */

#define FROM_REST_N 200     /* waypoints: 40 s */
#define FROM_REST_ALPHA 4.0 /* m/s^2 from rest up to 20 m/s (5 s), and back to rest */

/* x(u) of an object at rest at u = 0 that speeds up at FROM_REST_ALPHA to
 * 20 m/s, keeps it, and brakes at FROM_REST_ALPHA to rest at its last
 * waypoint: a curve with small k'' and k''' everywhere, its REST ends
 * included. */
static double from_rest_x(double u)
{
    double u1 = 20.0 / FROM_REST_ALPHA, end = (FROM_REST_N - 1) * WP_DT;
    double x1 = 0.5 * 20.0 * u1;
    if (u > end - u1)
        return 2 * x1 + 20.0 * (end - 2 * u1) - 0.5 * FROM_REST_ALPHA * (end - u) * (end - u);
    return u < u1 ? 0.5 * FROM_REST_ALPHA * u * u : x1 + 20.0 * (u - u1);
}

/* The curve's own maxima (TIMESCALE.md, "Bounds on every output"): |k''|
 * (linear on a segment: largest at an end) and |k'''| over its segments. */
static void curve_maxima(const fdiff_seg_t *seg, size_t nseg, double *A_c, double *J_c)
{
    *A_c = *J_c = 0;
    for (size_t i = 0; i < nseg; i++) {
        double d = seg[i].dur_s, a0 = 0, a1 = 0, j = 0;
        for (int k = 0; k < 3; k++) {
            double c2 = seg[i].c[k][2], c3 = seg[i].c[k][3];
            a0 += pow(2 * c2 / (d * d), 2);
            a1 += pow((2 * c2 + 6 * c3) / (d * d), 2);
            j += pow(6 * c3 / (d * d * d), 2);
        }
        *A_c = fmax(*A_c, sqrt(fmax(a0, a1)));
        *J_c = fmax(*J_c, sqrt(j));
    }
}

typedef struct {
    double dv_b, da_b;            /* the bounds per tick */
    double dv, da, dv_fd, da_fd;  /* worst ratios to them */
    double p, v[3], a[3], vf, af; /* the previous tick's */
    double rate_max, lag_max, t_start, t_lock;
} from_rest_t;

/* Judge tick n's setpoint against the previous one's: its vel/acc, and the
 * finite differences of its positions (x only: the track is on x). */
static void from_rest_judge(from_rest_t *w, int64_t n, const engine_setpoint_t *sp)
{
    double v_fd = (sp->pos_m[0] - w->p) / PERIOD_S, a_fd = (v_fd - w->vf) / PERIOD_S;
    if (n >= 3) { /* the finite differences reach back to tick 0 */
        w->dv = fmax(w->dv, dist3(sp->vel_m_s, w->v) / w->dv_b);
        w->da = fmax(w->da, dist3(sp->acc_m_s2, w->a) / w->da_b);
        w->dv_fd = fmax(w->dv_fd, fabs(v_fd - w->vf) / w->dv_b);
        w->da_fd = fmax(w->da_fd, fabs(a_fd - w->af) / w->da_b);
    }
    w->p = sp->pos_m[0];
    memcpy(w->v, sp->vel_m_s, sizeof w->v);
    memcpy(w->a, sp->acc_m_s2, sizeof w->a);
    w->vf = v_fd;
    w->af = a_fd;
}

/* The track's waypoints, pushed into e, and its curve's bounds per tick. */
static void from_rest_track(engine_t *e, const engine_config_t *cfg, engine_waypoint_t *wp,
                            from_rest_t *w)
{
    static fdiff_seg_t seg[2 * FROM_REST_N];
    size_t nseg = 0;
    double A_c, J_c, r = 1.0 + 2 * CATCHUP, a = cfg->scale_accel_m_s2;

    for (int i = 0; i < FROM_REST_N; i++) {
        memset(&wp[i], 0, sizeof wp[i]);
        wp[i].t_s = T0_S + 0.0137 + i * WP_DT; /* crossed 6.3 ms before a tick */
        wp[i].pos_m[0] = from_rest_x(i * WP_DT);
        wp[i].seq = (uint32_t)i + 1;
        assert_int_equal(engine_push(e, &wp[i]), 0);
    }
    assert_int_equal(engine_finish(e), 0);
    assert_int_equal(engine_curve(cfg, wp, FROM_REST_N, seg, 2 * FROM_REST_N, &nseg), 0);
    curve_maxima(seg, nseg, &A_c, &J_c);
    w->dv_b = (A_c * r * r + a) * PERIOD_S;
    w->da_b = (J_c * r * r * r + 3 * A_c * r * a / 1.0 + cfg->scale_jerk_m_s3) * PERIOD_S;
    print_message("a %g j %g: A_c %.3f m/s2, J_c %.3f m/s3: |dv| <= %.4f m/s, |da| <= %.4f m/s2 "
                  "per tick\n",
                  a, cfg->scale_jerk_m_s3, A_c, J_c, w->dv_b, w->da_b);
}

/* One clocked run of the from-rest track with scaling limits a, j; every
 * tick from the first (holding at the start point) to FINISHED is judged. */
static void from_rest_run(double a, double j, from_rest_t *w)
{
    engine_config_t cfg;
    engine_config_default(&cfg);
    cfg.period_ns = PERIOD_NS;
    cfg.scale_accel_m_s2 = a;
    cfg.scale_jerk_m_s3 = j;
    engine_t *e = engine_new(&cfg, NULL);
    assert_non_null(e);
    static engine_waypoint_t wp[FROM_REST_N];
    double start[3] = {0, 0, 0};
    memset(w, 0, sizeof *w);
    w->t_start = w->t_lock = NAN;
    from_rest_track(e, &cfg, wp, w);
    assert_int_equal(engine_set_position(e, start), 0);
    /* the braking into the REST end leaves the clock: at most the stop need
     * from the track's 20 m/s, v / (2 a) + a / (2 j) of track time */
    double unlock = wp[FROM_REST_N - 1].t_s - 20.0 / (2 * a) - a / (2 * j);
    engine_setpoint_t sp;
    for (int64_t n = 0; n < 200000; n++) {
        /* the play time reaches the first waypoint at tick 151 */
        engine_clock_t clk = {T0_NS + n * PERIOD_NS, 3000000000LL, 1.0, CATCHUP};
        /* now - D as a double: the t_s of every output locked on the clock */
        double play = (double)((long double)(clk.now_ns - clk.delay_ns) * 1e-9L);
        engine_status_t st;
        assert_int_equal(engine_set_clock(e, &clk), 0);
        assert_int_equal(engine_tick(e, n * PERIOD_NS, &sp), 0);
        assert_false(sp.flags & ENGINE_SP_NO_POSITION);
        from_rest_judge(w, n, &sp);
        engine_status(e, &st);
        w->rate_max = fmax(w->rate_max, st.rate);
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
        if (sp.state != ENGINE_STATE_STREAMING)
            continue;
        if (isnan(w->t_start))
            w->t_start = play;
        if (isnan(w->t_lock) && sp.t_s >= play && sp.t_s <= play)
            w->t_lock = play;
        if (isnan(w->t_lock))
            w->lag_max = fmax(w->lag_max, play - sp.t_s);
        else if (sp.t_s < unlock) /* locked from then on */
            assert_false(sp.t_s < play || sp.t_s > play);
    }
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    print_message("  worst of the bounds: |dv| %.3f, |da| %.3f; by finite differences %.3f, "
                  "%.3f; rate max %.6f; started %.4f s after the first waypoint, lag max %.4f "
                  "s, locked %.3f s after the start\n",
                  w->dv, w->da, w->dv_fd, w->da_fd, w->rate_max, w->t_start - wp[0].t_s, w->lag_max,
                  w->t_lock - w->t_start);
    engine_free(e);
}

/* Given an object at rest that speeds up at 4 m/s^2 to 20 m/s along x (REST
 * ends, the default: its curve starts at rest with k''(0) about 4 m/s^2),
 * clocked, with the default scaling limits (a = 5, j = 50) and gentle ones
 * (a = 1, j = 5), when the play time reaches its first waypoint, then on
 * every tick from the first (holding at the start point) to FINISHED, the
 * setpoints stay within TIMESCALE.md's bounds on every output, with the
 * curve's own maxima A_c, J_c (|k''|, |k'''| of engine_curve's segments)
 * and the rate r <= 1 + 2 CATCHUP (asserted):
 *   |delta velocity|     <= (A_c r^2 + a) T
 *   |delta acceleration| <= (J_c r^3 + 3 A_c r a / (1 m/s) + j) T
 * by the setpoints' vel/acc and by finite differences of their positions
 * (second difference / T, third / T^2); the output enters at rate 0, behind
 * the clock, wins the lag back and locks on it (t_s = now - D) within
 * lag / CATCHUP + 15 s (the last of the lag decays with a time constant of
 * 1 s, 11 of them from CATCHUP to 1 us) and stays locked.  Before, a clocked
 * start locked from its first tick: its acceleration stepped by k''(0) in
 * one tick. */
static void test_clocked_start_from_rest(void **state)
{
    (void)state;
    const double lim[2][2] = {{5.0, 50.0}, {1.0, 5.0}};
    from_rest_t w[2];
    for (int i = 0; i < 2; i++)
        from_rest_run(lim[i][0], lim[i][1], &w[i]);
    for (int i = 0; i < 2; i++) {
        assert_true(w[i].rate_max <= 1.0 + 2 * CATCHUP);
        assert_true(w[i].dv <= 1.0 + 1e-9);
        assert_true(w[i].dv_fd <= 1.0 + 1e-6);
        assert_true(w[i].da <= 1.0 + 1e-9);
        assert_true(w[i].da_fd <= 1.0 + 1e-6);
        assert_true(w[i].t_lock - w[i].t_start <= w[i].lag_max / CATCHUP + 15.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_drift_estimate),          cmocka_unit_test(test_drift_robust),
        cmocka_unit_test(test_playout_clock_slew),      cmocka_unit_test(test_start_on_the_clock),
        cmocka_unit_test(test_catchup_after_stall),     cmocka_unit_test(test_24h),
        cmocka_unit_test(test_clocked_start_from_rest),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
