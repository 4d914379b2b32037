/* test_nurbs.c - the seed-004 circle, arcs by angle, conics, derivatives. */
#include "test.h"

#include <math.h>
#include <stdlib.h>

#include "nurbs.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The requirement for the seed's circle: radius 1 within 1e-14. */
#define TOL_CIRCLE 1e-14
/* Arc points against centre + r (cos, sin) for r ~ 10: a few ulps of 10. */
#define TOL_ARC 1e-13

/* Given the seed's 9-pole quadratic NURBS, when evaluated at 10^5 parameter
 * values over [0, 1] (both ends included), then every point is at distance
 * 1 from the origin to within 1e-14, and all four quadrants are visited in
 * counter-clockwise order. */
static void test_seed_unit_circle(void **state)
{
    (void)state;
    double knots[12], ctrl[18], w[9], p[2], maxerr = 0.0, prev = -1.0;
    nurbs_t c;
    int i, wraps = 0;

    nurbs_unit_circle(knots, ctrl, w, &c);
    assert_int_equal(nurbs_check(&c), 0);
    for (i = 0; i < 100000; i++) {
        double t = i / 99999.0, ang;
        assert_int_equal(nurbs_eval(&c, t, p), 0);
        maxerr = fmax(maxerr, fabs(hypot(p[0], p[1]) - 1.0));
        ang = atan2(p[1], p[0]);
        if (ang < 0)
            ang += 2 * M_PI;
        if (ang + 1e-9 < prev)
            wraps++;
        prev = ang;
    }
    print_message("seed circle: max |radius - 1| = %.3g over 1e5 points\n", maxerr);
    assert_true(maxerr <= TOL_CIRCLE);
    assert_true(wraps <= 1); /* monotone angle; the last point is back at 0 */
    assert_int_equal(nurbs_eval(&c, 1.0, p), 0);
    assert_true(fabs(p[0] - 1.0) < 1e-15 && fabs(p[1]) < 1e-15);
}

/* Given arcs of many sweeps (both directions, up to a full turn), when
 * sampled at the parameter nurbs_arc_param gives for angle fractions, then
 * each point equals centre + r (cos a, sin a) for that angle: the arc is
 * sampled exactly at chosen angles. */
static void test_arc_at_angles(void **state)
{
    (void)state;
    const double sweeps[] = {0.3, -0.3, M_PI / 2, 2.0, -2.5, M_PI, 4.0, -5.9, 2 * M_PI, -2 * M_PI};
    double knots[NURBS_ARC_KNOTS_MAX], ctrl[NURBS_ARC_CTRL_MAX * 3], w[NURBS_ARC_CTRL_MAX], p[3];
    size_t s;
    int i;

    for (s = 0; s < sizeof sweeps / sizeof sweeps[0]; s++) {
        nurbs_t c;
        double cx = 3.0, cy = -7.0, cz = 1.5, r = 12.5, a0 = 0.7;
        assert_int_equal(nurbs_arc(cx, cy, cz, 3, r, a0, sweeps[s], knots, ctrl, w, &c), 0);
        assert_int_equal(nurbs_check(&c), 0);
        for (i = 0; i <= 1000; i++) {
            double f = i / 1000.0, a = a0 + f * sweeps[s];
            assert_int_equal(nurbs_eval(&c, nurbs_arc_param(sweeps[s], f), p), 0);
            assert_true(fabs(p[0] - (cx + r * cos(a))) < TOL_ARC);
            assert_true(fabs(p[1] - (cy + r * sin(a))) < TOL_ARC);
            assert_true(fabs(p[2] - cz) < 1e-15);
        }
    }
    assert_int_equal(nurbs_arc(0, 0, 0, 2, 0.0, 0, 1, knots, ctrl, w, NULL), -NURBS_EARG);
    assert_int_equal(nurbs_arc(0, 0, 0, 2, 1.0, 0, 7, knots, ctrl, w, NULL), -NURBS_EARG);
    assert_int_equal(nurbs_arc(0, 0, 0, 2, 1.0, 0, 0, knots, ctrl, w, NULL), -NURBS_EARG);
}

/* Given the conic through P0, P1, P2 with weight w, then every point
 * satisfies the conic's implicit equation:
 *   ellipse  x^2/a^2 + y^2/b^2 = 1 (quarter: (a,0),(a,b),(0,b), w = sqrt2/2)
 *   parabola y = x^2                ((-1,1),(0,-1),(1,1), w = 1)
 *   hyperbola x^2 - y^2 = 1         ((1,0),(1,1)... see below)
 * The hyperbola arc from (1,0) to (cosh u, sinh u) has its tangents meeting
 * at P1 = (1, tanh(u/2)) and weight cosh(u/2) (> 1): a standard
 * construction independent of our code. */
static void test_conics(void **state)
{
    (void)state;
    double knots[6], ctrl[6], w[3], p[2];
    const double a = 3.0, b = 1.25, u = 1.3;
    nurbs_t c;
    int i;
    double pe[6] = {a, 0, a, b, 0, b};
    double pp[6] = {-1, 1, 0, -1, 1, 1};
    double ph[6] = {1, 0, 1, tanh(u / 2), cosh(u), sinh(u)};

    assert_int_equal(nurbs_conic(pe, 2, sqrt(2.0) / 2, knots, ctrl, w, &c), 0);
    for (i = 0; i <= 1000; i++) {
        assert_int_equal(nurbs_eval(&c, i / 1000.0, p), 0);
        assert_true(fabs(p[0] * p[0] / (a * a) + p[1] * p[1] / (b * b) - 1) < 1e-14);
    }
    assert_int_equal(nurbs_conic(pp, 2, 1.0, knots, ctrl, w, &c), 0);
    for (i = 0; i <= 1000; i++) {
        assert_int_equal(nurbs_eval(&c, i / 1000.0, p), 0);
        assert_true(fabs(p[1] - p[0] * p[0]) < 1e-14);
    }
    assert_int_equal(nurbs_conic(ph, 2, cosh(u / 2), knots, ctrl, w, &c), 0);
    for (i = 0; i <= 1000; i++) {
        assert_int_equal(nurbs_eval(&c, i / 1000.0, p), 0);
        assert_true(fabs(p[0] * p[0] - p[1] * p[1] - 1) < 1e-13);
    }
    assert_int_equal(nurbs_conic(ph, 2, 0.0, knots, ctrl, w, &c), -NURBS_EWEIGHT);
}

/* Given the unit circle, then r' is tangent (r . r' = 0) and r'' matches a
 * central finite difference of r'. */
static void test_derivatives(void **state)
{
    (void)state;
    double knots[12], ctrl[18], w[9], d[6], dp[6], dm[6];
    const double h = 1e-6;
    nurbs_t c;
    int i;

    nurbs_unit_circle(knots, ctrl, w, &c);
    for (i = 1; i < 100; i++) {
        double t = i / 100.0 + 0.003;
        assert_int_equal(nurbs_eval_derivs(&c, t, 2, d), 0);
        assert_true(fabs(d[0] * d[2] + d[1] * d[3]) < 1e-12);
        assert_int_equal(nurbs_eval_derivs(&c, t + h, 1, dp), 0);
        assert_int_equal(nurbs_eval_derivs(&c, t - h, 1, dm), 0);
        /* central difference error ~ h^2 r'''' ~ 1e-12 * 1e4 */
        assert_true(fabs((dp[2] - dm[2]) / (2 * h) - d[4]) < 1e-4);
        assert_true(fabs((dp[3] - dm[3]) / (2 * h) - d[5]) < 1e-4);
    }
    assert_int_equal(nurbs_eval_derivs(&c, 0.5, 3, d), -NURBS_ESIZE);
    assert_int_equal(nurbs_eval(&c, 1.5, d), -NURBS_EDOMAIN);
    w[3] = -1;
    assert_int_equal(nurbs_check(&c), -NURBS_EWEIGHT);
    assert_non_null(nurbs_strerror(-NURBS_EARG));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_seed_unit_circle),
        cmocka_unit_test(test_arc_at_angles),
        cmocka_unit_test(test_conics),
        cmocka_unit_test(test_derivatives),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
