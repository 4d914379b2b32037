/* test_tridiag.c - Thomas solver against GSL's tridiagonal solver. */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_vector.h>

#include "tridiag.h"

#define N 200
/* Both solvers are backward stable on a diagonally dominant system of this size. */
#define TOL 1e-12

/* Given a random diagonally dominant system, when solved by tridiag_solve and
 * by gsl_linalg_solve_tridiag, then the solutions agree for every RHS. */
static void test_solve_matches_gsl(void **state)
{
    (void)state;
    static double a[N], b[N], c[N], d[N * 3], x[N * 3], scratch[N];
    unsigned seed = 7;
    int i, k;

    for (i = 0; i < N; i++) {
        a[i] = i ? urand(&seed) * 2 - 1 : 0;
        c[i] = i < N - 1 ? urand(&seed) * 2 - 1 : 0;
        b[i] = fabs(a[i]) + fabs(c[i]) + 0.5 + urand(&seed);
        for (k = 0; k < 3; k++)
            d[i * 3 + k] = urand(&seed) * 100 - 50;
    }
    assert_int_equal(tridiag_solve(N, 3, a, b, c, d, x, scratch), 0);

    gsl_vector *gd = gsl_vector_alloc(N), *ge = gsl_vector_alloc(N - 1),
               *gf = gsl_vector_alloc(N - 1), *gb = gsl_vector_alloc(N), *gx = gsl_vector_alloc(N);
    for (i = 0; i < N; i++) {
        gsl_vector_set(gd, i, b[i]);
        if (i < N - 1) {
            gsl_vector_set(ge, i, c[i]);
            gsl_vector_set(gf, i, a[i + 1]);
        }
    }
    for (k = 0; k < 3; k++) {
        for (i = 0; i < N; i++)
            gsl_vector_set(gb, i, d[i * 3 + k]);
        assert_int_equal(gsl_linalg_solve_tridiag(gd, ge, gf, gb, gx), 0);
        for (i = 0; i < N; i++)
            assert_true(fabs(gsl_vector_get(gx, i) - x[i * 3 + k]) < TOL);
    }
    gsl_vector_free(gd);
    gsl_vector_free(ge);
    gsl_vector_free(gf);
    gsl_vector_free(gb);
    gsl_vector_free(gx);
}

/* Given the 1-4-1 system, when rows are pushed one by one, then the result
 * equals the whole solve bit for bit (same operations in the same order). */
static void test_sweep_equals_whole(void **state)
{
    (void)state;
    double a[50], b[50], c[50], d[50], x1[50], x2[50], s1[50], cp[50], dp[50];
    tridiag_sweep_t sw;
    int i;

    for (i = 0; i < 50; i++) {
        a[i] = 1;
        b[i] = 4;
        c[i] = 1;
        d[i] = sin(i * 0.3) * 10;
    }
    assert_int_equal(tridiag_solve(50, 1, a, b, c, d, x1, s1), 0);
    tridiag_sweep_init(&sw, cp, dp, 50, 1);
    for (i = 0; i < 50; i++)
        assert_int_equal(tridiag_sweep_push(&sw, a[i], b[i], c[i], &d[i]), 0);
    assert_int_equal(tridiag_sweep_push(&sw, 1, 4, 1, d), -TRIDIAG_ESIZE);
    assert_int_equal(tridiag_sweep_solve(&sw, x2), 0);
    for (i = 0; i < 50; i++)
        assert_memory_equal(&x1[i], &x2[i], sizeof(double));
    /* and it satisfies the system */
    for (i = 1; i < 49; i++)
        assert_true(fabs(x1[i - 1] + 4 * x1[i] + x1[i + 1] - d[i]) < 1e-12);
}

/* Given a singular or non-finite row, then the solver refuses, never divides. */
static void test_singular(void **state)
{
    (void)state;
    double a[2] = {0, 1}, b[2] = {1, 1}, c[2] = {1, 0}, d[2] = {1, 1}, x[2], s[2];
    assert_int_equal(tridiag_solve(2, 1, a, b, c, d, x, s), -TRIDIAG_ESINGULAR);
    b[0] = NAN;
    assert_int_equal(tridiag_solve(2, 1, a, b, c, d, x, s), -TRIDIAG_ESINGULAR);
    assert_int_equal(tridiag_solve(0, 1, a, b, c, d, x, s), -TRIDIAG_ESIZE);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solve_matches_gsl),
        cmocka_unit_test(test_sweep_equals_whole),
        cmocka_unit_test(test_singular),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
