/* test_cspline.c - the seed-002 cubic spline against GSL's gsl_interp_cspline
 * (natural) and gsl_interp_cspline_periodic, plus the end conditions'
 * defining equations checked on the result. */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_interp.h>
#include <gsl/gsl_spline.h>

#include "cspline.h"

#define NP 60
/* Values O(10) from two O(n) solvers of a diagonally dominant system. */
#define TOL_VAL 1e-11
/* First and second derivatives: divided by h >= 0.05, so 20-400x the value error. */
#define TOL_D1 1e-9
#define TOL_D2 1e-8

/* Jittery timestamps (like a logged track) and a 2-D random walk. */
static void make_track(unsigned seed, double *t, double *p, int closed)
{
    int i;
    t[0] = 0;
    p[0] = 0;
    p[1] = 0;
    for (i = 1; i < NP; i++) {
        t[i] = t[i - 1] + 0.05 + urand(&seed);
        p[2 * i] = p[2 * i - 2] + urand(&seed) * 4 - 2;
        p[2 * i + 1] = p[2 * i - 1] + urand(&seed) * 4 - 2;
    }
    if (closed) {
        p[2 * (NP - 1)] = p[0];
        p[2 * (NP - 1) + 1] = p[1];
    }
}

static void compare_with_gsl(const gsl_interp_type *type, cspline_end_t end, int closed)
{
    static double t[NP], p[NP * 2], s[NP * 2], scratch[NP * 8], x[NP], y[NP];
    double out[8];
    cspline_t cs;
    int i, c;

    make_track(42, t, p, closed);
    assert_int_equal(cspline_solve(NP, 2, t, p, end, NULL, NULL, s, scratch, &cs), 0);
    for (c = 0; c < 2; c++) {
        gsl_interp *g = gsl_interp_alloc(type, NP);
        gsl_interp_accel *acc = gsl_interp_accel_alloc();
        for (i = 0; i < NP; i++) {
            x[i] = t[i];
            y[i] = p[2 * i + c];
        }
        assert_int_equal(gsl_interp_init(g, x, y, NP), 0);
        for (i = 0; i <= 3000; i++) {
            double tt = t[0] + (t[NP - 1] - t[0]) * i / 3000.0;
            assert_int_equal(cspline_eval(&cs, tt, 2, out), 0);
            assert_true(fabs(out[c] - gsl_interp_eval(g, x, y, tt, acc)) < TOL_VAL);
            assert_true(fabs(out[2 + c] - gsl_interp_eval_deriv(g, x, y, tt, acc)) < TOL_D1);
            assert_true(fabs(out[4 + c] - gsl_interp_eval_deriv2(g, x, y, tt, acc)) < TOL_D2);
        }
        gsl_interp_accel_free(acc);
        gsl_interp_free(g);
    }
}

/* Given a jittery timed 2-D track, when solved natural, then position,
 * velocity and acceleration equal GSL's natural cubic spline. */
static void test_natural_matches_gsl(void **state)
{
    (void)state;
    compare_with_gsl(gsl_interp_cspline, CSPLINE_END_NATURAL, 0);
}

/* Given a closed timed track (last point = first), when solved periodic
 * (Sherman-Morrison), then it equals GSL's periodic cubic spline. */
static void test_periodic_matches_gsl(void **state)
{
    (void)state;
    compare_with_gsl(gsl_interp_cspline_periodic, CSPLINE_END_PERIODIC, 1);
}

/* Given each open end condition, then its defining equation holds on the
 * solution, and r' is continuous at every interior knot (the C2 claim). */
static void test_end_conditions_hold(void **state)
{
    (void)state;
    static double t[NP], p[NP * 2], s[NP * 2], scratch[NP * 8];
    double d0[2] = {1.5, -0.5}, dn[2] = {-2.0, 3.0}, l[6], r[6];
    const double eps = 1e-9;
    cspline_t cs;
    int i, e, c;

    make_track(7, t, p, 0);
    for (e = CSPLINE_END_NATURAL; e <= CSPLINE_END_CLAMPED; e++) {
        assert_int_equal(cspline_solve(NP, 2, t, p, (cspline_end_t)e, d0, dn, s, scratch, &cs), 0);
        for (i = 1; i < NP - 1; i++) {
            assert_int_equal(cspline_eval(&cs, t[i] - eps, 2, l), 0);
            assert_int_equal(cspline_eval(&cs, t[i] + eps, 2, r), 0);
            for (c = 0; c < 6; c++) /* jump ~ eps * next derivative (<= 1e3) */
                assert_true(fabs(l[c] - r[c]) < 1e-5);
            assert_int_equal(cspline_eval(&cs, t[i], 0, l), 0);
            assert_true(fabs(l[0] - p[2 * i]) < 1e-13 && fabs(l[1] - p[2 * i + 1]) < 1e-13);
        }
        assert_int_equal(cspline_eval(&cs, t[0], 2, l), 0);
        assert_int_equal(cspline_eval(&cs, t[NP - 1], 2, r), 0);
        for (c = 0; c < 2; c++) {
            if (e == CSPLINE_END_NATURAL) {
                assert_true(fabs(l[4 + c]) < 1e-12 && fabs(r[4 + c]) < 1e-12);
            } else if (e == CSPLINE_END_CURVATURE) {
                assert_true(fabs(s[c] - s[2 + c]) < 1e-12);
                assert_true(fabs(s[2 * (NP - 1) + c] - s[2 * (NP - 2) + c]) < 1e-12);
            } else {
                assert_true(fabs(l[2 + c] - d0[c]) < 1e-11);
                assert_true(fabs(r[2 + c] - dn[c]) < 1e-11);
            }
        }
    }
}

/* Given cspline_coeffs, then the local cubic equals cspline_eval. */
static void test_coeffs(void **state)
{
    (void)state;
    static double t[NP], p[NP * 2], s[NP * 2], scratch[NP * 8];
    double co[8], out[2];
    cspline_t cs;
    int i, k, c;

    make_track(3, t, p, 0);
    assert_int_equal(cspline_solve(NP, 2, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs),
                     0);
    for (i = 0; i < NP - 1; i++) {
        cspline_coeffs(&cs, (size_t)i, co);
        for (k = 0; k <= 10; k++) {
            double tau = (t[i + 1] - t[i]) * k / 10.0;
            assert_int_equal(cspline_eval(&cs, t[i] + tau, 0, out), 0);
            for (c = 0; c < 2; c++) {
                const double *q = co + 4 * c;
                assert_true(fabs(((q[0] * tau + q[1]) * tau + q[2]) * tau + q[3] - out[c]) < 1e-11);
            }
        }
    }
}

static void test_errors(void **state)
{
    (void)state;
    double t[4] = {0, 1, 1, 2}, p[4] = {0, 1, 2, 0}, s[4], scratch[64], out[1];
    cspline_t cs;
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs),
                     -CSPLINE_EPARAM);
    t[2] = 1.5;
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_PERIODIC, NULL, NULL, s, scratch, &cs),
                     0);
    p[3] = 0.5;
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_PERIODIC, NULL, NULL, s, scratch, &cs),
                     -CSPLINE_ENOTCLOSED);
    assert_int_equal(cspline_solve(1, 1, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs),
                     -CSPLINE_ESIZE);
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_CLAMPED, NULL, NULL, s, scratch, &cs),
                     -CSPLINE_ENOTFINITE);
    p[1] = NAN;
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs),
                     -CSPLINE_ENOTFINITE);
    p[1] = 1;
    assert_int_equal(cspline_solve(4, 1, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs),
                     0);
    assert_int_equal(cspline_eval(&cs, 2.5, 0, out), -CSPLINE_EDOMAIN);
    assert_int_equal(cspline_eval(&cs, NAN, 0, out), -CSPLINE_EDOMAIN);
    assert_non_null(cspline_strerror(-CSPLINE_ESINGULAR));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_natural_matches_gsl),
        cmocka_unit_test(test_periodic_matches_gsl),
        cmocka_unit_test(test_end_conditions_hold),
        cmocka_unit_test(test_coeffs),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
