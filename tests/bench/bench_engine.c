/*
 * bench_engine.c - prints the engine's numbers (lib/engine/DESIGN.md).
 *
 *  1. ns per waypoint (engine_push: validation + incremental fragment solve +
 *     segment building) and ns per 3-axis setpoint (engine_tick) for tracks
 *     of 1e3 .. 1e6 waypoints: both should be flat in the length.
 *  2. side by side: the paper's global approach (re-solve all control points
 *     on every new waypoint, capped at 1e4 waypoints: it is O(N^2)) and GSL's
 *     gsl_spline_init on the whole track (3 axes).
 *  3. error against one global solve and lookahead for several (F, O).
 *  4. heap allocations inside push/tick after setup, counted by wrapping
 *     malloc/calloc/realloc/free (forwarded to glibc's __libc_* functions).
 *  5. the acceptance policy alone (offer + every verdict), lib/engine/accept.c
 *     against the former one kept in tests/helpers/accept_ref.h and the one
 *     before its chain search was kept across verdicts (the same verdicts,
 *     tests/helpers/accept_prev/) (alone: bench_engine --accept [REPS]).
 *  --walk PERIOD_NS: the tick table's walk ticked once, untimed, its setpoints
 *     hashed (instruction counts under callgrind, tests/bench/RESULTS.md).
 *
 * Numbers only, no assertions (timings on a shared machine are noisy).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_spline.h>

#include "test.h"
#include "accept.h"
#include "accept_prev.h"
#include "accept_ref.h"
#include "cubic.h"
#include "engine.h"
#include "fdiff.h"
#include "fdiff_aos.h"
#include "global_curve.h"
#include "hoang.h"

/* ---- allocation counter ---------------------------------------------------- */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
static int counting;
static unsigned long allocs;

void *malloc(size_t n);
void *calloc(size_t n, size_t m);
void *realloc(void *p, size_t n);
void free(void *p);

void *malloc(size_t n)
{
    if (counting)
        allocs++;
    return __libc_malloc(n);
}

void *calloc(size_t n, size_t m)
{
    if (counting)
        allocs++;
    return __libc_calloc(n, m);
}

void *realloc(void *p, size_t n)
{
    if (counting)
        allocs++;
    return __libc_realloc(p, n);
}

void free(void *p)
{
    if (counting && p)
        allocs++;
    __libc_free(p);
}

/* ---------------------------------------------------------------------------- */
static void walk_wp(engine_waypoint_t *w, long i, double dt, unsigned *seed, double *pos)
{
    for (int k = 0; k < 3; k++) {
        *seed = *seed * 1103515245u + 12345u;
        pos[k] += ((double)((*seed >> 8) % 2001) - 1000.0) * 0.001;
    }
    w->t_s = (double)i * dt;
    memcpy(w->pos_m, pos, sizeof(w->pos_m));
    w->seq = (uint32_t)i;
}

/* ns per waypoint of the fastest batch of 1000 in the last bench_stream_fo:
 * on a shared machine the batches another process did not interrupt */
static double best_batch_ns;

/* push N waypoints (batches of 1000, timed) and tick until drained (timed);
 * F, O = 0: the defaults (auto, with the acceptance policy of profile auto,
 * lib/engine/accept.h); otherwise F, O with profile none (the solver) */
static void bench_stream_fo(long n, unsigned f, unsigned o, double *ns_wp, double *ns_sp,
                            unsigned long *alloc_count)
{
    engine_config_t c;
    engine_config_default(&c);
    if (f) { /* the solver alone: no acceptance rules (profile none) */
        c.fragment = f;
        c.overlap = o;
        c.profile = ENGINE_PROFILE_NONE;
    }
    engine_t *e = engine_new(&c, NULL);
    engine_waypoint_t w = {0};
    engine_setpoint_t sp;
    double pos[3] = {0, 0, 0}, t_push = 0, t_tick = 0;
    unsigned seed = 1;
    long i = 0, ticks = 0;
    int64_t k = 0;
    const double dt = 0.1; /* 10 ticks of 10 ms per segment */

    counting = 1;
    allocs = 0;
    best_batch_ns = 1e30;
    while (i < n) {
        double t0 = now_s();
        long stop = i + 1000 < n ? i + 1000 : n;
        for (; i < stop; i++) {
            walk_wp(&w, i, dt, &seed, pos);
            engine_push(e, &w);
        }
        if (i == n)
            engine_finish(e);
        double t1 = now_s();
        t_push += t1 - t0;
        if (i < n && (t1 - t0) * 1e9 / 1000.0 < best_batch_ns)
            best_batch_ns = (t1 - t0) * 1e9 / 1000.0;
        /* tick until the output is within 100 waypoints of the input (or done) */
        for (;;) {
            engine_tick(e, k++ * c.period_ns, &sp);
            ticks++;
            if (sp.state == ENGINE_STATE_FINISHED)
                break;
            if (i < n && sp.t_s > (double)(i - 100) * dt)
                break;
        }
        t_tick += now_s() - t1;
    }
    counting = 0;
    *ns_wp = t_push * 1e9 / (double)n;
    *ns_sp = t_tick * 1e9 / (double)ticks;
    *alloc_count = allocs;
    engine_free(e);
}

static void bench_stream(long n, double *ns_wp, double *ns_sp, unsigned long *alloc_count)
{
    bench_stream_fo(n, 0, 0, ns_wp, ns_sp, alloc_count);
}

/* ns per waypoint (push + solve) of F/O: the fastest batch of 1000 over
 * 1e5 waypoints, best of 3 */
static double bench_wp_ns(unsigned f, unsigned o)
{
    double best = 1e30, sp, wp;
    unsigned long al;
    for (int rep = 0; rep < 3; rep++) {
        bench_stream_fo(100000, f, o, &wp, &sp, &al);
        best = best_batch_ns < best ? best_batch_ns : best;
    }
    return best;
}

static void bench_global(long n, double *ns_paper, double *ns_gsl)
{
    double *r = __libc_malloc(sizeof(double) * 3 * (size_t)n);
    double *p = __libc_malloc(sizeof(double) * 3 * (size_t)n);
    double *scr = __libc_malloc(sizeof(double) * 4 * (size_t)n);
    double *t = __libc_malloc(sizeof(double) * (size_t)n);
    double *y = __libc_malloc(sizeof(double) * (size_t)n);
    double pos[3] = {0, 0, 0};
    engine_waypoint_t w;
    unsigned seed = 2;
    long i, cap = n < 10000 ? n : 10000;

    for (i = 0; i < n; i++) {
        walk_wp(&w, i, 0.1, &seed, pos);
        memcpy(r + 3 * i, w.pos_m, sizeof(w.pos_m));
        t[i] = w.t_s;
    }
    /* the paper: every new waypoint re-solves the whole system so far */
    double t0 = now_s();
    for (i = 2; i <= cap; i++)
        hoang_solve((size_t)i, r, ENGINE_ENDS_HELD, NULL, NULL, p, scr);
    *ns_paper = (now_s() - t0) * 1e9 / (double)cap;
    /* GSL: one natural cubic spline per axis on the whole track */
    t0 = now_s();
    for (int k = 0; k < 3; k++) {
        gsl_spline *sp = gsl_spline_alloc(gsl_interp_cspline, (size_t)n);
        for (i = 0; i < n; i++)
            y[i] = r[3 * i + k];
        gsl_spline_init(sp, t, y, (size_t)n);
        gsl_spline_free(sp);
    }
    *ns_gsl = (now_s() - t0) * 1e9 / (double)n;
    __libc_free(r);
    __libc_free(p);
    __libc_free(scr);
    __libc_free(t);
    __libc_free(y);
}

/* max |streamed - global| over dense samples, relative to the extent */
static double frag_error(const engine_waypoint_t *wp, size_t n, engine_method_t m,
                         engine_param_t pa, engine_ends_t en, unsigned f, unsigned o, double *abs_m)
{
    engine_config_t c;
    fdiff_seg_t *g = __libc_malloc(sizeof(fdiff_seg_t) * (n + 8));
    fdiff_seg_t *s = __libc_malloc(sizeof(fdiff_seg_t) * (n + 8));
    size_t ng = 0, ns = 0;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, ext = 0, err = 0;

    engine_config_default(&c);
    c.method = m;
    c.param = pa;
    c.ends = en;
    c.max_speed_m_s = 0;
    c.max_accel_m_s2 = 0;
    c.max_gap_s = 1e9;
    c.fragment = ENGINE_FRAGMENT_MAX; /* one fragment for n < 1024: the global solve */
    c.start_slack = 8;                /* fragment 0 uncut (frag.h) */
    c.overlap = 16;
    engine_curve(&c, wp, n, g, n + 8, &ng);
    c.fragment = f;
    c.overlap = o;
    c.start_slack = ENGINE_AUTO; /* the default */
    c.capacity = 4096;
    engine_curve(&c, wp, n, s, n + 8, &ns);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            if (wp[i].pos_m[k] < lo[k])
                lo[k] = wp[i].pos_m[k];
            if (wp[i].pos_m[k] > hi[k])
                hi[k] = wp[i].pos_m[k];
        }
    for (int k = 0; k < 3; k++)
        if (hi[k] - lo[k] > ext)
            ext = hi[k] - lo[k];
    for (size_t i = 0; i < ng && i < ns; i++)
        for (int j = 0; j <= 20; j++) {
            double a[3], b[3];
            fdiff_eval(&g[i], j / 20.0, a, NULL, NULL);
            fdiff_eval(&s[i], j / 20.0, b, NULL, NULL);
            for (int k = 0; k < 3; k++)
                if (fabs(a[k] - b[k]) > err)
                    err = fabs(a[k] - b[k]);
        }
    __libc_free(g);
    __libc_free(s);
    *abs_m = err;
    return err / ext;
}

static size_t load_figure8(engine_waypoint_t *wp, size_t max)
{
    FILE *f = fopen("tests/data/n2k_furuno_figure8_src52.csv", "r");
    char line[256];
    size_t n = 0;
    double lat0 = 0, lon0 = 0, last = -1e300;

    if (!f)
        return 0;
    if (!fgets(line, sizeof(line), f)) {
        fclose(f);
        return 0;
    }
    while (n < max && fgets(line, sizeof(line), f)) {
        double t, lat, lon;
        if (sscanf(line, "%lf,%lf,%lf", &t, &lat, &lon) != 3 || !(t > last + 1e-9))
            continue;
        if (n == 0) {
            lat0 = lat;
            lon0 = lon;
        }
        /* test-only equirectangular projection about the first point */
        wp[n].t_s = t;
        wp[n].pos_m[0] = (lon - lon0) * M_PI / 180.0 * cos(lat0 * M_PI / 180.0) * 6371008.8;
        wp[n].pos_m[1] = (lat - lat0) * M_PI / 180.0 * 6371008.8;
        wp[n].pos_m[2] = 0;
        last = t;
        n++;
    }
    fclose(f);
    return n;
}

/* ns per 3-axis setpoint (step + position, velocity, acceleration out) of
 * the struct-of-arrays stepper and of the previous per-axis one, in the same
 * run, re-seeding every FDIFF_RESEED_STEPS as the engine does. */
static void bench_stepper(void)
{
    enum { STEPS = 20000000 };
    fdiff_seg_t seg = {.t0_s = 0, .dur_s = 1.0, .c = {{1, 2, 3, 4}, {5, 6, 7, 8}, {9, 1, 2, 3}}};
    double pos[3], vel[3], acc[3], sink = 0, best_soa = 1e9, best_aos = 1e9;
    for (int rep = 0; rep < 3; rep++) { /* best of 3: the least disturbed */
        fdiff_t fd;
        fdiff_aos_t ref;
        double t0 = now_s();
        for (long n = 0; n < STEPS; n++) {
            if (n % FDIFF_RESEED_STEPS == 0)
                fdiff_seed(&fd, &seg, 0, 1e-3);
            else
                fdiff_step(&fd);
            fdiff_get(&fd, pos, vel, acc);
            sink += pos[0] + vel[1] + acc[2];
        }
        double t1 = now_s();
        for (long n = 0; n < STEPS; n++) {
            if (n % FDIFF_RESEED_STEPS == 0)
                fdiff_aos_seed(&ref, &seg, 0, 1e-3);
            else
                fdiff_aos_step(&ref);
            fdiff_aos_get(&ref, pos, vel, acc);
            sink += pos[0] + vel[1] + acc[2];
        }
        double t2 = now_s();
        if ((t1 - t0) < best_soa)
            best_soa = t1 - t0;
        if ((t2 - t1) < best_aos)
            best_aos = t2 - t1;
    }
    printf("forward-difference stepper, ns per 3-axis setpoint (p, v, a), best of 3, same run:\n"
           "| stepper | ns/setpoint | x previous |\n|---|---|---|\n"
           "| previous per-axis (tests/helpers/fdiff_aos.h) | %.2f | 1.00 |\n"
           "| struct-of-arrays (lib/engine/fdiff.h) | %.2f | %.2f |\n"
           "target <= 8 ns per setpoint (issue 13); the engine_tick figure below adds the "
           "state machine around it.  (sink %g)\n\n",
           best_aos * 1e9 / STEPS, best_soa * 1e9 / STEPS, best_aos / best_soa,
           sink > 0 ? 1.0 : 0.0);
}

/* ns per engine_tick of the fastest chunk of 10000 ticks in the last
 * bench_ticks (the chunks no other process interrupted) */
static double best_chunk_ns;
/* runs of each bench_ticks, the best taken (bench_engine --ticks REPS) */
static int tick_reps = 5;

/* An engine at period_ns with 4000 waypoints of the walk (every 0.1 s)
 * pushed and its input finished: what bench_ticks and bench_walk tick.  No
 * acceleration limit (issue 27's profile limit): the walk's white-noise
 * velocity would cap the rate of most segments (their speed cap,
 * seg_ceiling), and every tick would look through the thousands of capped
 * segments queued ahead (scale_ceil_room). */
static engine_t *walk_engine(int64_t period_ns)
{
    engine_config_t c;
    engine_config_default(&c);
    c.capacity = 8192;
    c.period_ns = period_ns;
    c.max_accel_m_s2 = 0;
    engine_t *e = engine_new(&c, NULL);
    engine_waypoint_t w = {0};
    double pos[3] = {0, 0, 0};
    unsigned seed = 5;
    for (long i = 0; i < 4000; i++) {
        walk_wp(&w, i, 0.1, &seed, pos);
        engine_push(e, &w);
    }
    engine_finish(e);
    return e;
}

/* ns per engine_tick while streaming a prefilled walk (waypoints every
 * 0.1 s), best of tick_reps. */
static double bench_ticks(int64_t period_ns)
{
    double best = 1e30, sink = 0;
    best_chunk_ns = 1e30;
    for (int rep = 0; rep < tick_reps; rep++) {
        engine_t *e = walk_engine(period_ns);
        engine_setpoint_t sp;
        long n = 0;
        double t0 = now_s(), tc = t0;
        for (int64_t k = 0;; k++) {
            engine_tick(e, k * period_ns, &sp);
            sink += sp.pos_m[0];
            n++;
            if (sp.state == ENGINE_STATE_FINISHED)
                break;
            if (n % 10000 == 0) {
                double t1 = now_s();
                if ((t1 - tc) * 1e5 < best_chunk_ns)
                    best_chunk_ns = (t1 - tc) * 1e5; /* ns per tick of 10000 */
                tc = t1;
            }
        }
        double t = (now_s() - t0) * 1e9 / (double)n;
        if (t < best)
            best = t;
        engine_free(e);
    }
    return best + (sink > 0 ? 0 : 0);
}

/* bench_ticks' walk ticked once at period_ns, untimed: the ticks made and a
 * hash (FNV-1a) of every setpoint's bytes, for instruction counts of the tick
 * (valgrind --tool=callgrind --toggle-collect=engine_tick bench_engine --walk
 * 10000000) and a check that two builds give the same outputs. */
static void bench_walk(int64_t period_ns)
{
    engine_t *e = walk_engine(period_ns);
    engine_setpoint_t sp;
    uint64_t h = 1469598103934665603u;
    long n = 0;
    for (int64_t k = 0;; k++) {
        engine_tick(e, k * period_ns, &sp);
        const unsigned char *b = (const unsigned char *)&sp;
        for (size_t i = 0; i < sizeof sp; i++)
            h = (h ^ b[i]) * 1099511628211u;
        n++;
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
    }
    printf("walk at %lld ns: %ld ticks, setpoints hash %016llx\n", (long long)period_ns, n,
           (unsigned long long)h);
    engine_free(e);
}

static void bench_tick_table(void)
{
    printf("engine_tick while streaming, ns per 3-axis setpoint (p, v, a), best of %d\n\n"
           "| rate | ns/setpoint | fastest chunk of 10000 ticks |\n|---|---|---|\n",
           tick_reps);
    static const int64_t periods[] = {10000000, 1000000};
    for (int i = 0; i < 2; i++) {
        double ns = bench_ticks(periods[i]);
        printf("| %lld Hz | %.1f | %.1f |\n", (long long)(1000000000 / periods[i]), ns,
               best_chunk_ns);
    }
    printf("target <= 8 ns per setpoint at 100 Hz (issue 13)\n\n");
}

/* ns per engine_tick at rest under a feed hold (override 0), the per-axis
 * limits capping every segment of a figure-8 queued ahead (4000 waypoints,
 * x = 20 sin 0.2t, y = 10 sin 0.4t at 10 Hz; 3 m/s and 0.6, 1.2 m/s^2 per
 * axis), against a tick streaming the same track just before: at rest the
 * engine looks for a segment beyond the axes (axis_beyond, engine_scale.c). */
static void bench_hold(void)
{
    double best_rest = 1e30, best_run = 1e30, sink = 0;
    for (int rep = 0; rep < tick_reps; rep++) {
        engine_config_t c;
        engine_config_default(&c);
        c.capacity = 8192;
        c.period_ns = 10000000;
        for (int k = 0; k < 3; k++) {
            c.axis_max_speed_m_s[k] = 3.0;
            c.axis_max_accel_m_s2[k] = k == 1 ? 1.2 : 0.6;
        }
        engine_t *e = engine_new(&c, NULL);
        engine_waypoint_t w = {0};
        for (long i = 0; i < 4000; i++) {
            w.t_s = 0.1 * (double)i;
            w.pos_m[0] = 20 * sin(0.02 * (double)i);
            w.pos_m[1] = 10 * sin(0.04 * (double)i);
            w.seq = (uint32_t)i + 1;
            engine_push(e, &w);
        }
        engine_finish(e);
        engine_setpoint_t sp;
        int64_t k = 0;
        for (; k < 3000; k++) /* the start, then 10 s streaming */
            engine_tick(e, k * c.period_ns, &sp);
        double t0 = now_s();
        for (int i = 0; i < 2000; i++, k++) {
            engine_tick(e, k * c.period_ns, &sp);
            sink += sp.pos_m[0];
        }
        double run = (now_s() - t0) * 1e9 / 2000;
        engine_set_override(e, 0.0);
        for (int i = 0; i < 3000; i++, k++) /* braked to rest along the path */
            engine_tick(e, k * c.period_ns, &sp);
        t0 = now_s();
        for (int i = 0; i < 20000; i++, k++) {
            engine_tick(e, k * c.period_ns, &sp);
            sink += sp.pos_m[0];
        }
        double rest = (now_s() - t0) * 1e9 / 20000;
        if (fabs(sp.vel_m_s[0]) + fabs(sp.vel_m_s[1]) > 0)
            rest = NAN; /* not at rest: no figure */
        best_rest = fmin(best_rest, rest);
        best_run = fmin(best_run, run);
        engine_free(e);
    }
    printf("engine_tick with per-axis limits, best of %d: %.0f ns at rest under a feed hold "
           "with 4000 capped segments queued ahead, %.0f ns streaming them (%.2fx)%s\n",
           tick_reps, best_rest, best_run, best_rest / best_run, sink > 0 ? "" : " ");
}

/* the acceptance policy of the default configuration (profile auto) */
static void accept_cfg_default(accept_config_t *ac)
{
    engine_config_t c;
    engine_config_default(&c);
    memset(ac, 0, sizeof *ac);
    ac->max_speed_m_s = engine_config_max_speed(&c);
    ac->max_accel_m_s2 = engine_config_max_accel(&c);
    ac->max_gap_s = c.max_gap_s;
    ac->learned = 1;
    ac->stale = 1;
    ac->window = ACCEPT_WINDOW_MAX; /* start_slack auto */
    ac->confirm = c.confirm;
}

/* seconds to offer w[0..n-1] to the current policy and take every verdict;
 * *kept: waypoints taken or started */
/* rules: 0 the engine's (all), else these */
static double time_accept_rules(const engine_waypoint_t *w, long n, long *kept, unsigned rules)
{
    accept_config_t ac;
    accept_verdict_t v;
    static accept_t a;
    double t0;
    accept_cfg_default(&ac);
    ac.rules = rules;
    accept_init(&a, &ac);
    *kept = 0;
    t0 = now_s();
    for (long i = 0; i < n; i++) {
        accept_offer(&a, &w[i]);
        while (accept_decide(&a, i == n - 1, &v))
            *kept += v.kind != ACCEPT_DROP;
    }
    return now_s() - t0;
}

static double time_accept(const engine_waypoint_t *w, long n, long *kept)
{
    return time_accept_rules(w, n, kept, 0);
}

/* the same with the former policy (tests/helpers/accept_ref.h) */
static double time_accept_ref(const engine_waypoint_t *w, long n, long *kept)
{
    accept_config_t ac;
    accept_verdict_t v;
    static aref_t a;
    double t0;
    accept_cfg_default(&ac);
    aref_init(&a, &ac);
    *kept = 0;
    t0 = now_s();
    for (long i = 0; i < n; i++) {
        aref_offer(&a, &w[i]);
        while (aref_decide(&a, i == n - 1, &v))
            *kept += v.kind != ACCEPT_DROP;
    }
    return now_s() - t0;
}

/* the same with the policy before its chain search was kept across verdicts
 * (tests/helpers/accept_prev.h: the same verdicts) */
static double time_accept_prev(const engine_waypoint_t *w, long n, long *kept)
{
    accept_config_t ac;
    accept_verdict_t v;
    accept_prev_t *a;
    double t0, t;
    accept_cfg_default(&ac);
    a = accept_prev_new(&ac);
    if (!a)
        return NAN;
    *kept = 0;
    t0 = now_s();
    for (long i = 0; i < n; i++) {
        accept_prev_offer(a, &w[i]);
        while (accept_prev_decide(a, i == n - 1, &v))
            *kept += v.kind != ACCEPT_DROP;
    }
    t = now_s() - t0;
    accept_prev_free(a);
    return t;
}

/* runs of each policy over each track in bench_accept, the best taken */
static int accept_reps = 5;

/* ns per waypoint of the acceptance policy alone, former and current, best
 * of 5 interleaved: the rough walk of the streaming table (white-noise
 * velocity, so profile auto refuses about 1 in 10) and a clean circle */
static void bench_accept(void)
{
    enum { N = 100000 };
    static engine_waypoint_t walk[N], circle[N];
    const engine_waypoint_t *tracks[2] = {walk, circle};
    static const char *const names[2] = {"rough walk of the table below (0.1 s)",
                                         "circle, 5 m/s, radius 50 m (0.2 s)"};
    double pos[3] = {0, 0, 0};
    unsigned seed = 1;
    for (long i = 0; i < N; i++) {
        walk_wp(&walk[i], i, 0.1, &seed, pos);
        circle[i].t_s = 0.2 * (double)i;
        circle[i].pos_m[0] = 50.0 * cos(0.02 * (double)i);
        circle[i].pos_m[1] = 50.0 * sin(0.02 * (double)i);
        circle[i].pos_m[2] = 0;
    }
    printf("acceptance policy alone (accept_offer + accept_decide, default profile auto), ns per "
           "waypoint, %d waypoints, best of %d interleaved, same run:\n"
           "| track | kept | previous (tests/helpers/accept_ref.h) | before its chain search "
           "was kept (tests/helpers/accept_prev/) | lib/engine/accept.c | x previous | x before "
           "|\n|---|---|---|---|---|---|---|\n",
           N, accept_reps);
    for (int t = 0; t < 2; t++) {
        double best_ref = 1e30, best_prev = 1e30, best_new = 1e30;
        long kept_ref = 0, kept_prev = 0, kept_new = 0;
        for (int rep = 0; rep < accept_reps; rep++) {
            double r = time_accept_ref(tracks[t], N, &kept_ref);
            double p = time_accept_prev(tracks[t], N, &kept_prev);
            double c = time_accept(tracks[t], N, &kept_new);
            best_ref = r < best_ref ? r : best_ref;
            best_prev = p < best_prev ? p : best_prev;
            best_new = c < best_new ? c : best_new;
        }
        /* the policy before its chain search was kept had no ACCEPT_RULE_LATE:
         * the same verdicts without it (untimed) */
        long kept_nolate = 0;
        (void)time_accept_rules(tracks[t], N, &kept_nolate, ACCEPT_RULES_ALL & ~ACCEPT_RULE_LATE);
        printf("| %s | %ld%s%s | %.0f | %.0f | %.0f | %.2f | %.2f |\n", names[t], kept_new,
               kept_new == kept_ref ? "" : " (issue 27's rules: not the former's)",
               kept_nolate == kept_prev ? "" : " (NOT the same as before: a bug)",
               best_ref * 1e9 / N, best_prev * 1e9 / N, best_new * 1e9 / N, best_ref / best_new,
               best_prev / best_new);
    }
    printf("\n");
}

/* --accept-walk: lib's policy alone, once over the rough walk of
 * bench_accept, untimed (for callgrind): the kept count and a hash of every
 * verdict (kind, reason, gap, stop, shift, stamp, seq, position) */
static void bench_accept_walk(void)
{
    enum { N = 100000 };
    static engine_waypoint_t walk[N];
    double pos[3] = {0, 0, 0};
    unsigned seed = 1;
    accept_config_t ac;
    accept_verdict_t v;
    static accept_t a;
    long kept = 0;
    uint64_t h = 1469598103934665603ull;

    for (long i = 0; i < N; i++)
        walk_wp(&walk[i], i, 0.1, &seed, pos);
    accept_cfg_default(&ac);
    accept_init(&a, &ac);
    for (long i = 0; i < N; i++) {
        accept_offer(&a, &walk[i]);
        while (accept_decide(&a, i == N - 1, &v)) {
            double f[6] = {v.shift_s,     v.wp.t_s,      v.wp.pos_m[0],
                           v.wp.pos_m[1], v.wp.pos_m[2], (double)v.wp.seq};
            int k[4] = {v.kind, v.reason, v.gap, v.stop};
            const unsigned char *b = (const unsigned char *)f;
            kept += v.kind != ACCEPT_DROP;
            for (size_t j = 0; j < sizeof f; j++)
                h = (h ^ b[j]) * 1099511628211ull;
            b = (const unsigned char *)k;
            for (size_t j = 0; j < sizeof k; j++)
                h = (h ^ b[j]) * 1099511628211ull;
        }
    }
    printf("rough walk: kept %ld, verdicts hash %016llx\n", kept, (unsigned long long)h);
}

/* The F/O table: error of the streamed curve against one global solve, lookahead and (timed)
 * ns per waypoint.  The errors are deterministic (seeded walks, the bundled figure-8): with
 * --errors, bench_engine prints this table alone, untimed (nan ns), in about a second;
 * tests/e2e/test_doc_counts.py checks lib/engine/DESIGN.md's error columns against it. */
static void fo_table(int timed)
{
    /* the former default 32/16 first: the reference of the x 32/16 column;
     * then what accuracy/max_lookahead pick: the default 28/24 (3e-7, 18),
     * 16/12 (1e-3, 12), 24/20 (1e-5, 16), 39/34 (1e-9, 24) */
    static const unsigned fo[][2] = {{32, 16}, {8, 4},   {16, 8},  {24, 12}, {32, 8},  {48, 24},
                                     {64, 32}, {32, 30}, {16, 12}, {24, 20}, {28, 24}, {39, 34}};
    engine_config_t c;

    engine_config_default(&c);
    enum { NW = 1000 };
    static engine_waypoint_t walk[NW], reg[NW], fig8[2000];
    double pos[3] = {0, 0, 0}, rpos[3] = {0, 0, 0};
    unsigned seed = 3, rseed = 4;
    for (long i = 0; i < NW; i++) {
        walk_wp(&walk[i], i, 1.0, &seed, pos);
        walk[i].t_s += 0.5 * sin((double)i);    /* irregular: 0.0 .. 2.0 s steps */
        walk_wp(&reg[i], i, 1.0, &rseed, rpos); /* regular: 1 s steps */
    }
    size_t n8 = load_figure8(fig8, 1000); /* fragment 0 of F=1024 covers 1000: global */
    printf("\nerror of the streamed curve against one global solve (max over dense samples)\n");
    printf("random walk: 1000 waypoints, irregular (0 .. 2 s steps) or regular times; figure8: "
           "first %zu fixes of n2k_furuno_figure8_src52 (5 Hz)\n\n",
           n8);
    printf("lookahead with start_slack auto at its least (1 waypoint: regular input); "
           "ns/waypoint: push + solve with profile none (no acceptance rules: the solver's "
           "cost), the fastest batch of 1000 of 1e5 waypoints, best of 3, "
           "x 32/16 = the former "
           "default's over this one's, same run\n\n");
    printf("| F | O | lookahead (waypoints) | latency at 1 Hz / 5 Hz | walk (b) rel. extent | "
           "walk (a) rel. extent | regular walk (b) rel. extent | figure8 (b) metres | rho^(O/2) | "
           "ns/waypoint | x 32/16 |\n");
    printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    double ref_ns = 1;
    for (size_t i = 0; i < sizeof(fo) / sizeof(fo[0]); i++) {
        double ab, aa, a8, ar, wns = timed ? bench_wp_ns(fo[i][0], fo[i][1]) : NAN;
        if (i == 0)
            ref_ns = wns;
        c.fragment = fo[i][0];
        c.overlap = fo[i][1];
        unsigned la = engine_lookahead(&c);
        double eb = frag_error(walk, NW, ENGINE_METHOD_CUBIC, ENGINE_PARAM_TIME, ENGINE_ENDS_REST,
                               fo[i][0], fo[i][1], &ab);
        double ea = frag_error(walk, NW, ENGINE_METHOD_BSPLINE, ENGINE_PARAM_UNIFORM,
                               ENGINE_ENDS_NATURAL, fo[i][0], fo[i][1], &aa);
        double e8 = n8 ? (frag_error(fig8, n8, ENGINE_METHOD_CUBIC, ENGINE_PARAM_TIME,
                                     ENGINE_ENDS_REST, fo[i][0], fo[i][1], &a8),
                          a8)
                       : NAN;
        double er = frag_error(reg, NW, ENGINE_METHOD_CUBIC, ENGINE_PARAM_TIME, ENGINE_ENDS_REST,
                               fo[i][0], fo[i][1], &ar);
        printf(
            "| %u | %u | %u | %u s / %.1f s | %.1e | %.1e | %.1e | %.1e | %.1e | %.0f | %.2f |\n",
            fo[i][0], fo[i][1], la, la, la / 5.0, eb, ea, er, e8, pow(2 - sqrt(3), fo[i][1] / 2.0),
            wns, ref_ns / wns);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The tick on which 1 024 engines (defaults, 100 Hz) start at once, each fed
 * the same 5 Hz figure-8 (x = 50 sin 0.1t, y = 25 sin 0.2t) as it comes, against
 * their median tick over the 2 s streaming after it: a start simulates the
 * ramp from rest that its D is stated with (delay_run.c ramp_lag).  Best of
 * REPS runs (wall time: a preempted tick only adds). */
#define START_OBJECTS 1024
#define START_TICKS 600
static void bench_start(void)
{
    static engine_t *e[START_OBJECTS];
    double best_start = 1e30, best_steady = 1e30;
    for (int rep = 0; rep < tick_reps; rep++) {
        engine_config_t c;
        engine_config_default(&c);
        c.period_ns = 10000000;
        for (int i = 0; i < START_OBJECTS; i++)
            e[i] = engine_new(&c, NULL);
        double dt[START_TICKS];
        int64_t next = 0;
        uint32_t seq = 0;
        for (int n = 0; n < START_TICKS; n++) {
            int64_t now = n * c.period_ns;
            for (; next <= now; next += 200000000) {
                engine_waypoint_t w = {0};
                w.t_s = (double)next * 1e-9;
                w.pos_m[0] = 50 * sin(0.1 * w.t_s);
                w.pos_m[1] = 25 * sin(0.2 * w.t_s);
                w.seq = ++seq;
                for (int i = 0; i < START_OBJECTS; i++)
                    engine_push(e[i], &w);
            }
            double t0 = now_s();
            for (int i = 0; i < START_OBJECTS; i++) {
                engine_setpoint_t sp;
                engine_tick(e[i], now, &sp);
            }
            dt[n] = now_s() - t0;
        }
        int at = 0;
        for (int n = 1; n < START_TICKS; n++)
            at = dt[n] > dt[at] ? n : at;
        int len = START_TICKS - at - 1 < 200 ? START_TICKS - at - 1 : 200;
        if (len > 0) {
            qsort(dt + at + 1, (size_t)len, sizeof dt[0], cmp_double);
            best_steady = fmin(best_steady, dt[at + 1 + len / 2]);
        }
        best_start = fmin(best_start, dt[at]);
        for (int i = 0; i < START_OBJECTS; i++)
            engine_free(e[i]);
    }
    printf("%d engines starting on one tick at 100 Hz, best of %d: the start tick %.0f us (%.1f us "
           "per object), the median streaming tick after it %.0f us (%.0fx)\n",
           START_OBJECTS, tick_reps, best_start * 1e6, best_start * 1e6 / START_OBJECTS,
           best_steady * 1e6, best_start / best_steady);
}

/* --many N: N engines of the walk (300 waypoints each, their own seeds),
 * ticked in turn at 100 Hz with engine_status after each tick as trajd's
 * tick does, 1 000 ticks: ns per object per tick, with and without
 * engine_prefetch of the engine two ahead, interleaved, best of 3; beside it
 * one engine alone (its state stays in the cache): how much of a tick of many
 * objects is waiting for memory. */
static double many_run(engine_t **e, int n, int pf)
{
    engine_setpoint_t sp;
    engine_status_t st;
    double sink = 0, t0 = now_s();
    for (int64_t k = 0; k < 1000; k++)
        for (int i = 0; i < n; i++) {
            if (pf && i + 2 < n)
                engine_prefetch(e[i + 2]);
            engine_tick(e[i], k * 10000000, &sp);
            engine_status(e[i], &st);
            sink += sp.pos_m[0] + st.free;
        }
    return (now_s() - t0) * 1e9 / (1000.0 * n) + (sink > 1e300 ? 1 : 0);
}

static void bench_many(int n)
{
    engine_t **e = calloc((size_t)n, sizeof *e);
    double best[3] = {1e30, 1e30, 1e30};
    for (int rep = 0; rep < 3; rep++) {
        for (int i = 0; i < n; i++) {
            engine_config_t c;
            engine_config_default(&c);
            c.period_ns = 10000000;
            c.max_accel_m_s2 = 0;
            e[i] = engine_new(&c, NULL);
            engine_waypoint_t w = {0};
            double pos[3] = {0, 0, 0};
            unsigned seed = 5 + (unsigned)i;
            for (long j = 0; j < 300; j++) {
                walk_wp(&w, j, 0.1, &seed, pos);
                engine_push(e[i], &w);
            }
            engine_finish(e[i]);
        }
        double one = many_run(e, 1, 0), no = many_run(e + 1, n - 1, 0),
               pf = many_run(e + 1, n - 1, 1);
        best[0] = fmin(best[0], one), best[1] = fmin(best[1], no), best[2] = fmin(best[2], pf);
        for (int i = 0; i < n; i++)
            engine_free(e[i]);
    }
    printf("engine_tick + engine_status, 100 Hz, ns per object per tick, best of 3: one engine "
           "alone %.1f; %d engines in turn %.1f; with engine_prefetch two ahead %.1f\n",
           best[0], n - 1, best[1], best[2]);
    free(e);
}

int main(int argc, char **argv)
{
    if (argc > 2 && strcmp(argv[1], "--many") == 0) {
        bench_many(atoi(argv[2]) > 1 ? atoi(argv[2]) : 2);
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--start") == 0) {
        if (argc > 2)
            tick_reps = atoi(argv[2]) > 0 ? atoi(argv[2]) : 1;
        bench_start(); /* 1 024 engines starting on one tick (REPS runs, default 5) */
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--errors") == 0) {
        fo_table(0);
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--accept") == 0) {
        if (argc > 2)
            accept_reps = atoi(argv[2]) > 0 ? atoi(argv[2]) : 1;
        bench_accept(); /* the acceptance policy alone, the first table (REPS, default 5) */
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--accept-walk") == 0) {
        bench_accept_walk(); /* lib's policy once over the rough walk, untimed */
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--hold") == 0) {
        if (argc > 2)
            tick_reps = atoi(argv[2]) > 0 ? atoi(argv[2]) : 1;
        bench_hold(); /* the tick at rest under a feed hold (REPS runs, default 5) */
        return 0;
    }
    if (argc > 2 && strcmp(argv[1], "--walk") == 0) {
        bench_walk(atoll(argv[2])); /* one walk untimed, its setpoints hashed */
        return 0;
    }
    if (argc > 1 && strcmp(argv[1], "--ticks") == 0) {
        if (argc > 2)
            tick_reps = atoi(argv[2]) > 0 ? atoi(argv[2]) : 1;
        bench_tick_table(); /* the tick table alone (REPS runs each, default 5) */
        return 0;
    }
    bench_accept();
    bench_stepper();
    bench_tick_table();
    bench_hold();
    bench_start();
    bench_many(1025);
    static const long lengths[] = {1000, 10000, 100000, 1000000};
    engine_config_t c, r;

    engine_config_default(&c);
    engine_config_resolve(&c, &r);
    printf("engine defaults: method cubic, param time, ends rest, accuracy %g, max_lookahead %u: "
           "F=%u O=%u, lookahead %u, period %lld ns\n\n",
           c.accuracy, c.max_lookahead, r.fragment, r.overlap, engine_lookahead(&c),
           (long long)c.period_ns);
    printf("streaming against the global references, all measured in this run; x paper and x GSL "
           "= their ns per waypoint over ours (> 1: the stream is cheaper)\n\n");
    printf("| waypoints | ns/waypoint (push+solve) | ns/setpoint (3 axes) | heap allocs in "
           "push/tick | "
           "paper global re-solve ns/waypoint | x paper | GSL cspline init ns/waypoint | x GSL "
           "|\n");
    printf("|---|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < sizeof(lengths) / sizeof(lengths[0]); i++) {
        double wp_ns, sp_ns, paper_ns, gsl_ns;
        unsigned long al;
        bench_stream(lengths[i], &wp_ns, &sp_ns, &al);
        bench_global(lengths[i], &paper_ns, &gsl_ns);
        printf("| %ld | %.0f | %.1f | %lu | %.0f%s | %.1f | %.0f | %.2f |\n", lengths[i], wp_ns,
               sp_ns, al, paper_ns, lengths[i] > 10000 ? " (first 1e4 only)" : "", paper_ns / wp_ns,
               gsl_ns, gsl_ns / wp_ns);
    }
    fo_table(1);
    return 0;
}
