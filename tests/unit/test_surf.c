/* test_surf.c - bicubic B-spline surface: exact interpolation through the
 * grid, forward differences against direct evaluation, derivatives.
 * (The oracle comparison with scipy is in test_toolkit_scipy.py.) */
#include "test.h"

#include <math.h>
#include <stdlib.h>

#include "surf.h"

#define M 7
#define N 9
#define DIM 3
/* Grid values O(10); the 1-4-1 solves are stable to a few ulps. */
#define TOL_GRID 1e-12
/* Forward differences over <= 64 steps: drift ~ steps^3 * ulp of the
 * coefficients (~1e-15 * 10) = 3e-9 in the worst case; measured far less. */
#define TOL_FD 1e-10

static double height(double x, double y)
{
    return 3.0 * sin(0.7 * x) * cos(0.4 * y) + 0.1 * x * y;
}

static void make_grid(double *g)
{
    int i, j;
    for (i = 0; i < M; i++)
        for (j = 0; j < N; j++) {
            double x = i * 1.3 + 0.1 * j, y = j * 0.9;
            g[(i * N + j) * DIM + 0] = x;
            g[(i * N + j) * DIM + 1] = y;
            g[(i * N + j) * DIM + 2] = height(x, y);
        }
}

/* Given an M x N grid, when interpolated on the (M+2) x (N+2) net, then the
 * surface passes through every grid point at (u, v) = (i, j). */
static void test_passes_through_grid(void **state)
{
    (void)state;
    static double g[M * N * DIM], ctrl[(M + 2) * (N + 2) * DIM], scratch[4096];
    double out[DIM];
    surf_t s;
    int i, j, c;

    assert_true(surf_scratch_len(M, N, DIM) <= 4096);
    make_grid(g);
    assert_int_equal(surf_interpolate(M, N, DIM, g, ctrl, scratch, &s), 0);
    for (i = 0; i < M; i++)
        for (j = 0; j < N; j++) {
            assert_int_equal(surf_eval(&s, i, j, 0, out), 0);
            for (c = 0; c < DIM; c++)
                assert_true(fabs(out[c] - g[(i * N + j) * DIM + c]) < TOL_GRID);
        }
}

/* Given a patch, when sampled by forward differences (three additions a
 * point), then every lattice point equals direct evaluation. */
static void test_forward_differences(void **state)
{
    (void)state;
    static double g[M * N * DIM], ctrl[(M + 2) * (N + 2) * DIM], scratch[4096];
    static double fd[65 * 65 * DIM];
    double out[DIM], maxerr = 0.0;
    surf_t s;
    unsigned a, b;
    size_t i, j, c;

    make_grid(g);
    assert_int_equal(surf_interpolate(M, N, DIM, g, ctrl, scratch, &s), 0);
    for (i = 0; i + 1 < M; i += 2)
        for (j = 0; j + 1 < N; j += 3) {
            assert_int_equal(surf_patch_fd(&s, i, j, 64, 48, fd), 0);
            for (a = 0; a <= 64; a++)
                for (b = 0; b <= 48; b++) {
                    assert_int_equal(surf_eval(&s, i + a / 64.0, j + b / 48.0, 0, out), 0);
                    for (c = 0; c < DIM; c++)
                        maxerr = fmax(maxerr, fabs(out[c] - fd[(a * 49 + b) * DIM + c]));
                }
        }
    print_message("surface forward differences: max |fd - direct| = %.3g\n", maxerr);
    assert_true(maxerr < TOL_FD);
    assert_int_equal(surf_patch_fd(&s, M - 1, 0, 4, 4, fd), -SURF_EDOMAIN);
    assert_int_equal(surf_patch_fd(&s, 0, 0, 0, 4, fd), -SURF_ESIZE);
}

/* Given the surface, then its u and v derivatives match central differences,
 * and the natural end condition holds: d2R/du2 = 0 on the u = 0 edge. */
static void test_derivatives_and_natural_edge(void **state)
{
    (void)state;
    static double g[M * N * DIM], ctrl[(M + 2) * (N + 2) * DIM], scratch[4096];
    double d[3 * DIM], p1[DIM], p2[DIM], p0[DIM];
    const double h = 1e-5;
    surf_t s;
    int k, c;

    make_grid(g);
    assert_int_equal(surf_interpolate(M, N, DIM, g, ctrl, scratch, &s), 0);
    for (k = 0; k < 50; k++) {
        double u = 0.3 + k * 0.11, v = 0.2 + k * 0.15;
        assert_int_equal(surf_eval(&s, u, v, 1, d), 0);
        surf_eval(&s, u + h, v, 0, p1);
        surf_eval(&s, u - h, v, 0, p2);
        for (c = 0; c < DIM; c++) /* O(h^2 R''') ~ 1e-10 * 10 */
            assert_true(fabs((p1[c] - p2[c]) / (2 * h) - d[DIM + c]) < 1e-7);
        surf_eval(&s, u, v + h, 0, p1);
        surf_eval(&s, u, v - h, 0, p2);
        for (c = 0; c < DIM; c++)
            assert_true(fabs((p1[c] - p2[c]) / (2 * h) - d[2 * DIM + c]) < 1e-7);
    }
    /* one-sided second difference at the edge: (R(2h) - 2R(h) + R(0))/h^2 -> R''(0) + O(h) */
    for (k = 0; k < 8; k++) {
        double v = k;
        const double hh = 1e-3;
        surf_eval(&s, 0, v, 0, p0);
        surf_eval(&s, hh, v, 0, p1);
        surf_eval(&s, 2 * hh, v, 0, p2);
        for (c = 0; c < DIM; c++) /* R''(0)=0; error ~ h R''' ~ 1e-3 * 10 */
            assert_true(fabs((p2[c] - 2 * p1[c] + p0[c]) / (hh * hh)) < 5e-2);
    }
    assert_int_equal(surf_eval(&s, -0.1, 0, 0, p0), -SURF_EDOMAIN);
    assert_int_equal(surf_eval(&s, 0, N, 0, p0), -SURF_EDOMAIN);
    g[5] = NAN;
    assert_int_equal(surf_interpolate(M, N, DIM, g, ctrl, scratch, &s), -SURF_ENOTFINITE);
    assert_int_equal(surf_interpolate(1, N, DIM, g, ctrl, scratch, &s), -SURF_ESIZE);
    assert_non_null(surf_strerror(-SURF_EDOMAIN));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_passes_through_grid),
        cmocka_unit_test(test_forward_differences),
        cmocka_unit_test(test_derivatives_and_natural_edge),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
