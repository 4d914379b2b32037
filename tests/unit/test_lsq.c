/* test_lsq.c - least-squares B-spline fit against GSL's gsl_multifit_linear
 * (SVD on the design matrix), the streaming smoother's bookkeeping, and the
 * engine's method smooth end to end (also run under ASan/UBSan). */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_bspline.h>
#include <gsl/gsl_multifit.h>

#include "bspline.h"
#include "engine.h"
#include "lsq.h"

/* Normal equations (Cholesky) vs SVD of N on a well-conditioned problem:
 * values ~5, condition of N^T N < 1e3: agreement ~1e-16 * 1e3 * 5. */
#define TOL_FIT 1e-11

/* Given 400 noisy samples and a cubic on 14 clamped uniform breakpoints,
 * when fitted by lsq_fit and by gsl_multifit_linear on GSL's own design
 * matrix (gsl_bspline_eval), then the coefficients agree. */
static void test_fit_matches_gsl_multifit(void **state)
{
    (void)state;
    enum { M = 400, NB = 14, Q = 4, NC = NB + Q - 2 };
    static double u[M], y[M], knots[NC + Q], ctrl[NC], work[NC * (Q + 1)];
    unsigned seed = 21;
    size_t i, k;
    double chisq;

    for (i = 0; i < M; i++) {
        u[i] = (double)i / (M - 1);
        y[i] = 3.0 * sin(7.0 * u[i]) + u[i] + (urand(&seed) - 0.5) * 0.4;
    }
    assert_true(lsq_work_len(NC, Q, 1) <= NC * (Q + 1));
    assert_int_equal(lsq_knots(NC, Q, 0.0, 1.0, knots), 0);
    assert_int_equal(lsq_fit(M, 1, u, y, Q, NC, knots, 0, ctrl, work), 0);

    gsl_bspline_workspace *w = gsl_bspline_alloc(Q, NB);
    gsl_vector *B = gsl_vector_alloc(NC), *gy = gsl_vector_alloc(M), *c = gsl_vector_alloc(NC);
    gsl_matrix *X = gsl_matrix_alloc(M, NC), *cov = gsl_matrix_alloc(NC, NC);
    gsl_multifit_linear_workspace *mw = gsl_multifit_linear_alloc(M, NC);
    gsl_bspline_knots_uniform(0.0, 1.0, w);
    for (i = 0; i < NC + Q; i++) /* the same knot vector */
        assert_true(fabs(gsl_vector_get(w->knots, i) - knots[i]) < 1e-15);
    for (i = 0; i < M; i++) {
        gsl_bspline_eval(u[i], B, w);
        for (k = 0; k < NC; k++)
            gsl_matrix_set(X, i, k, gsl_vector_get(B, k));
        gsl_vector_set(gy, i, y[i]);
    }
    assert_int_equal(gsl_multifit_linear(X, gy, c, cov, &chisq, mw), 0);
    for (k = 0; k < NC; k++)
        assert_true(fabs(ctrl[k] - gsl_vector_get(c, k)) < TOL_FIT);
    gsl_bspline_free(w);
    gsl_vector_free(B);
    gsl_vector_free(gy);
    gsl_vector_free(c);
    gsl_matrix_free(X);
    gsl_matrix_free(cov);
    gsl_multifit_linear_free(mw);
}

static void test_fit_errors(void **state)
{
    (void)state;
    double u[8] = {0, .1, .2, .3, .4, .5, .6, 1}, y[8] = {0}, knots[16], ctrl[8], work[64];
    assert_int_equal(lsq_knots(6, 4, 0, 1, knots), 0);
    assert_int_equal(lsq_fit(5, 1, u, y, 4, 6, knots, 0, ctrl, work), -LSQ_ESIZE);
    assert_int_equal(lsq_fit(8, 1, u, y, 0, 6, knots, 0, ctrl, work), -LSQ_EORDER);
    u[3] = 2.0; /* outside the knots */
    assert_int_equal(lsq_fit(8, 1, u, y, 4, 6, knots, 0, ctrl, work), -LSQ_EPARAM);
    u[3] = 0.3;
    y[2] = NAN;
    assert_int_equal(lsq_fit(8, 1, u, y, 4, 6, knots, 0, ctrl, work), -LSQ_ENOTFINITE);
    y[2] = 0;
    knots[5] = -1; /* decreasing */
    assert_int_equal(lsq_fit(8, 1, u, y, 4, 6, knots, 0, ctrl, work), -LSQ_EKNOTS);
    assert_int_equal(lsq_chord_params(3, 1, y, u), -LSQ_EPARAM); /* all equal */
    assert_int_equal(lsq_knots(6, 4, 1, 1, knots), -LSQ_EPARAM);
    assert_non_null(lsq_strerror(-LSQ_ESINGULAR));
}

/* Given a long stream through a small window (the ring wraps many times),
 * then one output per input, in order, with the input's timestamp; and a
 * straight line at constant speed is reproduced (a cubic fits it exactly). */
static void test_smoother_stream(void **state)
{
    (void)state;
    enum { W = 7, CT = 5, N = 5000 };
    static double mem[1024];
    lsq_smooth_t s;
    double t, r[3];
    size_t got = 0, i;

    assert_true(lsq_smooth_mem_len(W, CT, 3) <= 1024);
    assert_int_equal(lsq_smooth_init(&s, W, CT, 3, mem), 0);
    for (i = 0; i < N; i++) {
        double ti = i * 0.5 + (i % 3) * 0.1, p[3] = {2.0 * ti, -ti, 5.0};
        lsq_smooth_push(&s, ti, p);
        if (i == N - 1)
            lsq_smooth_finish(&s);
        while (lsq_smooth_pop(&s, &t, r) == 1) {
            double tj = got * 0.5 + (got % 3) * 0.1;
            assert_true(fabs(t - tj) < 1e-12);
            assert_true(fabs(r[0] - 2.0 * tj) < 1e-9 && fabs(r[1] + tj) < 1e-9 &&
                        fabs(r[2] - 5.0) < 1e-9);
            got++;
        }
        assert_true(lsq_smooth_pending(&s) <= W);
    }
    assert_int_equal(got, N);
    assert_int_equal(s.fallbacks, 0);
    assert_int_equal(lsq_smooth_init(&s, 3, 4, 3, mem), -LSQ_ESIZE);
}

/* Given the engine with method smooth on a noisy circle walked at 1 m/s,
 * when all waypoints are pushed while ticking at 100 Hz, then it streams,
 * finishes at rest, every setpoint is finite, and the setpoints stay closer
 * to the true circle than the raw fixes do. */
static void test_engine_smooth_runs(void **state)
{
    (void)state;
    engine_config_t cfg;
    engine_t *e;
    engine_setpoint_t sp;
    unsigned seed = 5;
    int err, i;
    int64_t now = 0;
    double raw_err = 0, sp_err = 0;
    long nsp = 0;

    engine_config_default(&cfg);
    cfg.method = ENGINE_METHOD_SMOOTH;
    e = engine_new(&cfg, &err);
    assert_non_null(e);
    for (i = 0; i < 400; i++) {
        double a = i / 20.0, n1 = (urand(&seed) - 0.5), n2 = (urand(&seed) - 0.5);
        engine_waypoint_t wp = {
            .t_s = i * 1.0, .pos_m = {20 * cos(a) + n1, 20 * sin(a) + n2, 0}, .seq = (uint32_t)i};
        raw_err += fabs(hypot(wp.pos_m[0], wp.pos_m[1]) - 20);
        assert_int_equal(engine_push(e, &wp), 0);
        for (int k = 0; k < 100; k++, now += cfg.period_ns) {
            assert_int_equal(engine_tick(e, now, &sp), 0);
            if (sp.state == ENGINE_STATE_STREAMING) {
                sp_err += fabs(hypot(sp.pos_m[0], sp.pos_m[1]) - 20);
                nsp++;
            }
            assert_true((isfinite(sp.pos_m[0]) || (sp.flags & ENGINE_SP_NO_POSITION)) &&
                        isfinite(sp.vel_m_s[1]) && isfinite(sp.acc_m_s2[0]));
        }
    }
    assert_int_equal(engine_finish(e), 0);
    for (i = 0; i < 100 * 200 && sp.state != ENGINE_STATE_FINISHED; i++, now += cfg.period_ns)
        assert_int_equal(engine_tick(e, now, &sp), 0);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    raw_err /= 400;
    sp_err /= nsp;
    print_message("mean |r - 20|: raw fixes %.3f m, smooth setpoints %.3f m\n", raw_err, sp_err);
    assert_true(sp_err < 0.5 * raw_err);
    engine_free(e);
    /* a bad smoothing configuration is refused */
    cfg.smooth_ctrl = cfg.smooth_window + 1;
    assert_int_equal(engine_config_check(&cfg, NULL), -ENGINE_ECONFIG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fit_matches_gsl_multifit),
        cmocka_unit_test(test_fit_errors),
        cmocka_unit_test(test_smoother_stream),
        cmocka_unit_test(test_engine_smooth_runs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
