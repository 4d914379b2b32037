/* test_bspline.c - any-order B-splines against GSL's gsl_bspline, the seed's
 * properties (partition of unity, local support, Bezier case, multiple knots)
 * and the literal Cox-de Boor recursion. */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <gsl/gsl_bspline.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_vector.h>

#include "bspline.h"

/* Two independent O(q^2) recursions in double on values O(1): a few ulps
 * times q^2 (q <= 8 here) stays far below this. */
#define TOL_BASIS 1e-13
/* Derivatives carry factors (q-1)!/(q-1-k)! over knot spacings ~0.1: values
 * up to ~1e4, so the absolute tolerance is relative 1e-13 of that. */
#define TOL_DERIV_REL 1e-12
/* The curve is an affine combination of control points of size ~10. */
#define TOL_CURVE 1e-12

/* Given breakpoints 0 < ... < 1 (non-uniform), orders 1..8, when the basis
 * is computed by bspline_basis and by gsl_bspline_eval on the same clamped
 * knots, then all n_ctrl values agree at 2000 points including the ends. */
static void test_basis_matches_gsl(void **state)
{
    (void)state;
    enum { NB = 12 };
    double breaks[NB], knots[NB + 2 * BSPLINE_ORDER_MAX], N[BSPLINE_ORDER_MAX];
    unsigned seed = 3, q;
    size_t i, j, first;

    breaks[0] = 0.0;
    for (i = 1; i < NB; i++)
        breaks[i] = breaks[i - 1] + 0.02 + urand(&seed);
    for (q = 1; q <= 8; q++) {
        size_t nc = NB + q - 2;
        gsl_bspline_workspace *w = gsl_bspline_alloc(q, NB);
        gsl_vector *gb = gsl_vector_alloc(NB), *B = gsl_vector_alloc(nc);
        for (i = 0; i < NB; i++)
            gsl_vector_set(gb, i, breaks[i]);
        assert_int_equal(gsl_bspline_knots(gb, w), 0);
        assert_int_equal(bspline_knots_clamped(breaks, NB, q, knots), 0);
        for (i = 0; i < nc + q; i++) /* same knot vector */
            assert_true(fabs(gsl_vector_get(w->knots, i) - knots[i]) < 1e-15);
        for (i = 0; i <= 2000; i++) {
            double t = breaks[NB - 1] * (double)i / 2000.0, sum = 0.0;
            if (i == 2000)
                t = breaks[NB - 1];
            assert_int_equal(gsl_bspline_eval(t, B, w), 0);
            assert_int_equal(bspline_basis(knots, nc, q, t, &first, N), 0);
            for (j = 0; j < nc; j++) {
                double mine = (j >= first && j < first + q) ? N[j - first] : 0.0;
                assert_true(fabs(mine - gsl_vector_get(B, j)) < TOL_BASIS);
            }
            for (j = 0; j < q; j++)
                sum += N[j];
            assert_true(fabs(sum - 1.0) < TOL_BASIS); /* partition of unity */
        }
        gsl_vector_free(gb);
        gsl_vector_free(B);
        gsl_bspline_free(w);
    }
}

/* Given the same knots, when derivatives up to q-1 come from
 * bspline_basis_derivs and gsl_bspline_deriv_eval, then they agree. */
static void test_derivs_match_gsl(void **state)
{
    (void)state;
    enum { NB = 9 };
    double breaks[NB], knots[NB + 2 * BSPLINE_ORDER_MAX];
    double ders[BSPLINE_ORDER_MAX * BSPLINE_ORDER_MAX];
    unsigned seed = 11, q, d;
    size_t i, j, first;

    breaks[0] = -1.0;
    for (i = 1; i < NB; i++)
        breaks[i] = breaks[i - 1] + 0.1 + 0.5 * urand(&seed);
    for (q = 2; q <= 6; q++) {
        size_t nc = NB + q - 2;
        gsl_bspline_workspace *w = gsl_bspline_alloc(q, NB);
        gsl_vector *gb = gsl_vector_alloc(NB);
        gsl_matrix *dB = gsl_matrix_alloc(nc, q);
        for (i = 0; i < NB; i++)
            gsl_vector_set(gb, i, breaks[i]);
        gsl_bspline_knots(gb, w);
        bspline_knots_clamped(breaks, NB, q, knots);
        for (i = 0; i < 500; i++) {
            double t = breaks[0] + (breaks[NB - 1] - breaks[0]) * (i + 0.37) / 500.0;
            assert_int_equal(gsl_bspline_deriv_eval(t, q - 1, dB, w), 0);
            assert_int_equal(bspline_basis_derivs(knots, nc, q, t, q - 1, &first, ders), 0);
            for (d = 0; d < q; d++)
                for (j = 0; j < nc; j++) {
                    double mine = (j >= first && j < first + q) ? ders[d * q + j - first] : 0.0;
                    double ref = gsl_matrix_get(dB, j, d);
                    assert_true(fabs(mine - ref) <= TOL_DERIV_REL * (1.0 + fabs(ref)) * 1e3);
                }
        }
        assert_int_equal(bspline_basis_derivs(knots, nc, q, 0.0, q, &first, ders), -BSPLINE_ESIZE);
        gsl_vector_free(gb);
        gsl_matrix_free(dB);
        gsl_bspline_free(w);
    }
}

/* Given an arbitrary knot vector with repeated interior knots, when the
 * triangular basis and the seed's literal recursion are compared, then they
 * agree; and each N_k is zero outside [t_k, t_{k+q}] (local support). */
static void test_literal_recursion_and_support(void **state)
{
    (void)state;
    const double knots[] = {0, 0, 0, 1, 2, 2, 3, 4, 4, 4, 5, 6, 6, 6};
    const size_t nk = sizeof knots / sizeof knots[0];
    double N[BSPLINE_ORDER_MAX];
    unsigned q;
    size_t i, k, first;

    for (q = 1; q <= 4; q++) {
        size_t nc = nk - q;
        double lo = knots[q - 1], hi = knots[nc];
        for (i = 0; i <= 600; i++) {
            double t = lo + (hi - lo) * i / 600.0;
            assert_int_equal(bspline_basis(knots, nc, q, t, &first, N), 0);
            for (k = 0; k < nc; k++) {
                double lit = bspline_basis_one(knots, nk, k, q, t);
                double mine = (k >= first && k < first + q) ? N[k - first] : 0.0;
                assert_true(fabs(lit - mine) < TOL_BASIS);
                if (t < knots[k] || t > knots[k + q])
                    assert_true(fabs(lit) < TOL_BASIS);
            }
        }
    }
}

/* Bernstein polynomial B_i^n(t) from the binomial formula (independent of
 * any recursion). */
static double bernstein(unsigned n, unsigned i, double t)
{
    double c = 1.0;
    unsigned j;
    for (j = 1; j <= i; j++)
        c = c * (n - i + j) / j;
    return c * pow(t, i) * pow(1.0 - t, n - i);
}

/* Given n+1 control points and the seed's open uniform generator with
 * q = n+1, then the knots are (0..0, 1..1) and the curve is the Bezier curve
 * sum B_i^n(t) p_i; and the generator reproduces the seed's two examples. */
static void test_open_uniform_bezier(void **state)
{
    (void)state;
    double knots[32], ctrl[8 * 2], out[2];
    const double ex1[] = {0, 0, 1, 2, 3, 3};       /* q = 2, n = 3 */
    const double ex2[] = {0, 0, 0, 0, 1, 2, 2, 2}; /* q = 4, n = 4 */
    unsigned seed = 5, n, i;
    size_t k;

    assert_int_equal(bspline_knots_open_uniform(4, 2, knots), 0);
    for (k = 0; k < 6; k++)
        assert_true(fabs(knots[k] - ex1[k]) < 1e-15);
    assert_int_equal(bspline_knots_open_uniform(5, 4, knots), 0);
    for (k = 0; k < 8; k++)
        assert_true(fabs(knots[k] - ex2[k]) < 1e-15);
    assert_int_equal(bspline_knots_open_uniform(3, 4, knots), -BSPLINE_EORDER);

    for (n = 1; n <= 7; n++) {
        bspline_t b = {n + 1, n + 1, 2, knots, ctrl};
        assert_int_equal(bspline_knots_open_uniform(n + 1, n + 1, knots), 0);
        for (k = 0; k < 2 * (n + 1); k++)
            assert_true(fabs(knots[k] - (k <= n ? 0.0 : 1.0)) < 1e-15);
        for (k = 0; k < 2 * (n + 1); k++)
            ctrl[k] = urand(&seed) * 20 - 10;
        assert_int_equal(bspline_check(&b), 0);
        for (k = 0; k <= 200; k++) {
            double t = k / 200.0, ref[2] = {0, 0};
            for (i = 0; i <= n; i++) {
                ref[0] += bernstein(n, i, t) * ctrl[2 * i];
                ref[1] += bernstein(n, i, t) * ctrl[2 * i + 1];
            }
            assert_int_equal(bspline_eval(&b, t, out), 0);
            assert_true(fabs(out[0] - ref[0]) < TOL_CURVE);
            assert_true(fabs(out[1] - ref[1]) < TOL_CURVE);
        }
    }
}

/* Given random curves of orders 1..8 on a non-uniform knot vector, when the
 * point comes from de Boor (bspline_eval) and from basis x control points
 * (bspline_eval_derivs with nder 0, i.e. GSL-checked basis), they agree. */
static void test_de_boor_equals_basis_sum(void **state)
{
    (void)state;
    double knots[64], ctrl[40 * 5], a[5], bb[5];
    unsigned seed = 9, q;
    size_t k, nc = 20, i;

    for (q = 1; q <= 8; q++) {
        bspline_t b = {q, nc, 5, knots, ctrl};
        knots[0] = 0;
        for (k = 1; k < nc + q; k++)
            knots[k] = knots[k - 1] + (urand(&seed) < 0.2 ? 0.0 : urand(&seed));
        for (k = 0; k < nc * 5; k++)
            ctrl[k] = urand(&seed) * 20 - 10;
        if (bspline_check(&b) < 0)
            continue;
        double lo, hi;
        bspline_domain(&b, &lo, &hi);
        for (i = 0; i <= 300; i++) {
            double t = lo + (hi - lo) * i / 300.0;
            assert_int_equal(bspline_eval(&b, t, a), 0);
            assert_int_equal(bspline_eval_derivs(&b, t, 0, bb), 0);
            for (k = 0; k < 5; k++)
                assert_true(fabs(a[k] - bb[k]) < TOL_CURVE);
        }
        assert_int_equal(bspline_eval(&b, hi + (hi - lo) * 1e-6, a), -BSPLINE_EDOMAIN);
        assert_int_equal(bspline_eval(&b, NAN, a), -BSPLINE_EDOMAIN);
    }
}

/* Given a cubic with a knot of multiplicity m at t = 2, then the curve's
 * derivative of order 3-m jumps there (continuity C^{2-m}) while lower
 * derivatives are continuous: multiple knots lower continuity by one each. */
static void test_multiple_knots_lower_continuity(void **state)
{
    (void)state;
    double ctrl[12] = {0, 3, -1, 4, 2, -2, 5, 1, 0, 2, 6, -3};
    double left[4], right[4];
    const double eps = 1e-7;
    unsigned m;

    for (m = 1; m <= 3; m++) {
        double knots[20];
        size_t k = 0, i, nc;
        for (i = 0; i < 4; i++)
            knots[k++] = 0;
        knots[k++] = 1;
        for (i = 0; i < m; i++)
            knots[k++] = 2;
        knots[k++] = 3;
        for (i = 0; i < 4; i++)
            knots[k++] = 4;
        nc = k - 4;
        bspline_t b = {4, nc, 1, knots, ctrl};
        assert_int_equal(bspline_check(&b), 0);
        assert_int_equal(bspline_eval_derivs(&b, 2 - eps, 3, left), 0);
        assert_int_equal(bspline_eval_derivs(&b, 2 + eps, 3, right), 0);
        for (i = 0; i <= 3; i++) {
            double jump = fabs(left[i] - right[i]);
            if (i < 3 - m + 1) /* continuous: C^(3-m) ... jump ~ eps * next derivative */
                assert_true(jump < 1e-4);
            else if (i == 3 - m + 1)
                assert_true(jump > 1e-2); /* generic control points: a real jump */
        }
    }
}

/* Given the tension matrix, then its blending functions sum to 1 for every
 * t and tension (affine invariance), u = 1 gives the uniform
 * B-spline matrix of bspline.h, and the u = 1
 * segment equals the general evaluator on uniform knots. */
static void test_tension_matrix(void **state)
{
    (void)state;
    const double M1[16] = {-1, 3, -3, 1, 3, -6, 3, 0, -3, 0, 3, 0, 1, 4, 1, 0};
    double M[16], knots[10], ctrl[4 * 2] = {0, 0, 1, 3, 4, 2, 6, 5};
    double ones[4] = {1, 1, 1, 1}, out[8], ref[2];
    int i, k;
    bspline_t b = {4, 4, 2, knots, ctrl};

    bspline_cubic_matrix(1.0, M);
    for (i = 0; i < 16; i++)
        assert_true(fabs(M[i] - M1[i] / 6.0) < 1e-16);
    for (k = 0; k <= 10; k++) {
        double u = 0.2 * k;
        bspline_cubic_matrix(u, M);
        for (i = 0; i <= 20; i++) {
            double t = i / 20.0;
            bspline_cubic_segment(M, ones, 1, t, 0, out);
            assert_true(fabs(out[0] - 1.0) < 1e-14);
        }
    }
    bspline_knots_uniform(4, 4, 0.0, 1.0, knots);
    bspline_cubic_matrix(1.0, M);
    for (i = 0; i <= 20; i++) {
        double t = i / 20.0;
        bspline_cubic_segment(M, ctrl, 2, t, 2, out);
        assert_int_equal(bspline_eval(&b, 3.0 + t, ref), 0);
        assert_true(fabs(out[0] - ref[0]) < TOL_CURVE);
        assert_true(fabs(out[1] - ref[1]) < TOL_CURVE);
        /* derivative by finite difference of the general evaluator */
        double d2[6];
        assert_int_equal(bspline_eval_derivs(&b, 3.0 + t, 2, d2), 0);
        assert_true(fabs(out[2] - d2[2]) < TOL_CURVE && fabs(out[5] - d2[5]) < TOL_CURVE);
    }
}

static void test_errors(void **state)
{
    (void)state;
    double knots[8] = {0, 1, 2, 1, 4, 5, 6, 7}, ctrl[4] = {0}, out[1];
    bspline_t b = {4, 4, 1, knots, ctrl};
    assert_int_equal(bspline_check(&b), -BSPLINE_EKNOTS);
    b.order = 5;
    assert_int_equal(bspline_check(&b), -BSPLINE_EORDER);
    b.order = 0;
    assert_int_equal(bspline_eval(&b, 0.5, out), -BSPLINE_EORDER);
    b.order = 2;
    b.dim = 0;
    assert_int_equal(bspline_check(&b), -BSPLINE_ESIZE);
    assert_int_equal(bspline_knots_uniform(3, 2, 0, 0, knots), -BSPLINE_EKNOTS);
    assert_non_null(bspline_strerror(-BSPLINE_EDOMAIN));
    assert_true(isnan(bspline_basis_one(knots, 8, 6, 4, 0.5)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_basis_matches_gsl),
        cmocka_unit_test(test_derivs_match_gsl),
        cmocka_unit_test(test_literal_recursion_and_support),
        cmocka_unit_test(test_open_uniform_bezier),
        cmocka_unit_test(test_de_boor_equals_basis_sum),
        cmocka_unit_test(test_multiple_knots_lower_continuity),
        cmocka_unit_test(test_tension_matrix),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
