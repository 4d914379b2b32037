/*
 * test_fdiff.c - forward differences against Horner; the time-knot cubic
 * against GSL's natural cubic spline; the fragment window's bookkeeping.
 */
#include "test.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_spline.h>

#include "cubic.h"
#include "engine.h"
#include "fdiff.h"
#include "fdiff_aos.h"
#include "global_curve.h"
#include "frag.h"

/* The longest segment the engine may stream: max_gap_s (60 s by default)
 * at the fastest rate (ENGINE_PERIOD_NS_MIN, 10 kHz): 600000 steps. */
#define LONGEST_STEPS (60LL * 1000000000LL / ENGINE_PERIOD_NS_MIN)

/*
 * Worst-case drift of n forward steps: every addition rounds by at most
 * eps/2 of its result, and the rounding of d1 (d2) feeds n (n^2/2) later
 * additions of f; with |d1| ~ |c|/n, |d2| ~ |c|/n^2 each term is ~ n eps |c|
 * summed: bound n * eps * (|c0| + |c1| + |c2| + |c3|) (times 2 for margin).
 * A stepper that lost its phase or seeded wrongly would be off by ~|c|/n,
 * far above it.
 */
static double drift_bound(const fdiff_seg_t *s, int k, long long n)
{
    double m = fabs(s->c[k][0]) + fabs(s->c[k][1]) + fabs(s->c[k][2]) + fabs(s->c[k][3]);
    return 2.0 * (double)n * DBL_EPSILON * m;
}

/* Given the longest segment at the fastest rate with coefficients up to
 * max_abs_m (1e7 m), when stepped 600000 times without re-seeding, then
 * position, velocity and acceleration stay within the worst-case drift bound
 * of Horner; the measured drift is printed. */
static void test_drift_longest_segment(void **state)
{
    (void)state;
    fdiff_seg_t s = {0, 60.0, {{1000, -30, 50, -20}, {-5e6, 300, -200, 100}, {1e7, 5, -3, 2}}};
    long long n = LONGEST_STEPS;
    double du = 1.0 / (double)n, worst[3] = {0}, worstv = 0, worsta = 0;
    fdiff_t fd;

    fdiff_seed(&fd, &s, 0.0, du);
    for (long long i = 0; i <= n; i++) {
        double p[3], v[3], a[3], P[3], V[3], A[3];
        if (i % 997 == 0 || i == n) { /* Horner on a sample: keeps the test fast */
            fdiff_get(&fd, p, v, a);
            fdiff_eval(&s, (double)i * du, P, V, A);
            for (int k = 0; k < 3; k++) {
                double e = fabs(p[k] - P[k]);
                if (e > worst[k])
                    worst[k] = e;
                assert_true(e <= drift_bound(&s, k, n));
                if (fabs(v[k] - V[k]) > worstv)
                    worstv = fabs(v[k] - V[k]);
                if (fabs(a[k] - A[k]) > worsta)
                    worsta = fabs(a[k] - A[k]);
            }
        }
        fdiff_step(&fd);
    }
    /* velocity and acceleration are lower-degree: (n eps |c| / dur) bounds them */
    assert_true(worstv <= 2.0 * (double)n * DBL_EPSILON * 1e7 / 60.0);
    assert_true(worsta <= 2.0 * (double)n * DBL_EPSILON * 1e7 / 3600.0);
    print_message("drift over %lld steps: pos %.2e %.2e %.2e m (|c0| 1e3, 5e6, 1e7), "
                  "vel %.2e m/s, acc %.2e m/s2; engine re-seeds every %u steps\n",
                  n, worst[0], worst[1], worst[2], worstv, worsta, FDIFF_RESEED_STEPS);
}

/* Given a seed at a fractional phase u0, then the stepper's k-th point is
 * the cubic at u0 + k du (the phase the engine carries across boundaries). */
/* Given random segments, seeds and steps, when stepped 20000 times by the
 * struct-of-arrays stepper and by the previous per-axis one (fdiff_aos.h),
 * then every position, velocity and acceleration is the same double. */
static void test_soa_equals_previous(void **state)
{
    (void)state;
    unsigned seed = 77;
    for (int s = 0; s < 20; s++) {
        fdiff_seg_t seg = {.t0_s = 0, .dur_s = 0.05 + 10 * urand(&seed)};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 4; j++)
                seg.c[k][j] = (urand(&seed) - 0.5) * pow(10, 7 * urand(&seed));
        double du = 1.0 / (1 + 20000 * urand(&seed)), u0 = urand(&seed) * du;
        fdiff_t fd;
        fdiff_aos_t ref;
        fdiff_seed(&fd, &seg, u0, du);
        fdiff_aos_seed(&ref, &seg, u0, du);
        for (int n = 0; n < 20000; n++) {
            double p[3], v[3], a[3], P[3], V[3], A[3];
            fdiff_get(&fd, p, v, a);
            fdiff_aos_get(&ref, P, V, A);
            if (memcmp(p, P, sizeof p) || memcmp(v, V, sizeof v) || memcmp(a, A, sizeof a)) {
                print_error("segment %d step %d differs\n", s, n);
                fail();
            }
            fdiff_step(&fd);
            fdiff_aos_step(&ref);
        }
    }
}

static void test_seed_phase(void **state)
{
    (void)state;
    fdiff_seg_t s = {2.0, 0.37, {{1, 2, -3, 4}, {0, -1, 0.5, 0.25}, {3, 0, 0, 1}}};
    fdiff_t fd;
    double u0 = 0.123456789, du = 0.01 / 0.37;

    fdiff_seed(&fd, &s, u0, du);
    for (int i = 0; i < 30; i++) {
        double p[3], v[3], a[3], P[3], V[3], A[3];
        fdiff_get(&fd, p, v, a);
        fdiff_eval(&s, u0 + i * du, P, V, A);
        for (int k = 0; k < 3; k++) {
            assert_true(fabs(p[k] - P[k]) < 1e-13);
            assert_true(fabs(v[k] - V[k]) < 1e-12);
            assert_true(fabs(a[k] - A[k]) < 1e-11);
        }
        fdiff_step(&fd);
    }
}

/* Given an irregular track, when cubic_curve (knots at the timestamps,
 * natural) and GSL's gsl_interp_cspline are evaluated, then they agree. */
static void test_cubic_vs_gsl(void **state)
{
    (void)state;
    enum { N = 80 };
    double t[N], y[3][N], r[N * 3];
    fdiff_seg_t segs[N];
    size_t nseg;
    unsigned seed = 99;

    for (int i = 0; i < N; i++) {
        seed = seed * 1103515245u + 12345u;
        /* cppcheck-suppress uninitvar ; t[i - 1] is read for i >= 1 only, set the step before */
        t[i] = i ? t[i - 1] + 0.2 + ((seed >> 8) % 1000) * 0.003 : 0.0;
        for (int k = 0; k < 3; k++) {
            seed = seed * 1103515245u + 12345u;
            y[k][i] = (i ? y[k][i - 1] : 0) + ((double)((seed >> 8) % 2001) - 1000) * 0.01;
            r[i * 3 + k] = y[k][i];
        }
    }
    assert_int_equal(
        cubic_curve(N, t, r, ENGINE_PARAM_TIME, ENGINE_ENDS_NATURAL, NULL, NULL, segs, N, &nseg),
        0);
    assert_int_equal(nseg, N - 1);
    for (int k = 0; k < 3; k++) {
        gsl_interp_accel *acc = gsl_interp_accel_alloc();
        gsl_spline *sp = gsl_spline_alloc(gsl_interp_cspline, N);
        assert_int_equal(gsl_spline_init(sp, t, y[k], N), GSL_SUCCESS);
        for (int j = 0; j <= 5000; j++) {
            double tq = t[0] + (t[N - 1] - t[0]) * j / 5000.0, p[3], v[3], a[3];
            fdiff_eval_curve(segs, nseg, &tq, 1, p, v, a);
            /* both O(1) flops per point from equally conditioned systems:
             * 1e-11 of values of order 10-100 */
            assert_true(fabs(p[k] - gsl_spline_eval(sp, tq, acc)) < 1e-11);
            assert_true(fabs(v[k] - gsl_spline_eval_deriv(sp, tq, acc)) < 1e-10);
            assert_true(fabs(a[k] - gsl_spline_eval_deriv2(sp, tq, acc)) < 1e-9);
        }
        gsl_spline_free(sp);
        gsl_interp_accel_free(acc);
    }
}

/* Given a window and a 1-4-1 system with pinned artificial ends, then the
 * final count follows frag_final_after, values are final in order, and a
 * system shorter than a fragment equals the whole solve exactly. */
static void test_frag_bookkeeping(void **state)
{
    (void)state;
    frag_t *fw = frag_new(16, 8, 3, 64);
    frag_row_t row = {1, 4, 1, {0, 0, 0}};
    double pin[3] = {0, 0, 0};

    assert_non_null(fw);
    assert_null(frag_new(16, 7, 0, 64));
    assert_null(frag_new(16, 16, 0, 64));
    assert_null(frag_new(16, 8, 12, 64)); /* offset at most S + O/2 - 1 */
    for (uint64_t r = 0; r < 200; r++) {
        row.d[0] = 6.0 * sin(0.1 * (double)r);
        assert_int_equal(frag_push(fw, &row, pin), 0);
        assert_int_equal(fw->final_rows, frag_final_after(16, 8, 3, r));
    }
    row.c = 0;
    assert_int_equal(frag_finish(fw, &row), 0);
    assert_int_equal(fw->final_rows, 201);
    assert_int_equal(frag_push(fw, &row, pin), -TRIDIAG_ESIZE); /* closed */

    /* 10 rows < F: one fragment, true ends: equals tridiag_solve bit for bit */
    double a[10], b[10], c[10], d[30], x[30], scr[10];
    frag_reset(fw);
    for (int i = 0; i < 10; i++) {
        a[i] = i ? 1 : 0;
        b[i] = 4;
        c[i] = i < 9 ? 1 : 0;
        for (int k = 0; k < 3; k++)
            d[i * 3 + k] = cos(i + k);
        frag_row_t rw = {a[i], b[i], c[i], {d[i * 3], d[i * 3 + 1], d[i * 3 + 2]}};
        if (i < 9)
            assert_int_equal(frag_push(fw, &rw, pin), 0);
        else
            assert_int_equal(frag_finish(fw, &rw), 0);
    }
    assert_int_equal(tridiag_solve(10, 3, a, b, c, d, x, scr), 0);
    for (int i = 0; i < 10; i++)
        assert_memory_equal(frag_x(fw, (uint64_t)i), &x[i * 3], 3 * sizeof(double));
    frag_free(fw);
    frag_free(NULL);
}

/*
 * Independent reference for the window's values: each fragment's own
 * system (its rows, an artificial start row x = pin at its first row when it
 * is not fragment 0, an artificial end row x = pin at its last) solved by
 * GSL's tridiagonal solver, assembled by the rule of lib/engine/frag.h and
 * lib/engine/DESIGN.md ("Fragments"): fragment k owns the rows after junction J(k-1) up to before J(k),
 * x at each junction is the MEAN of the two fragments that share it, and at
 * the end the oldest open fragment takes the true end row and owns every row
 * to the end.  J(k) = (k+1)S - delta + O/2.
 */
#define FRAG_REF_ROWS 97
static void frag_ref(unsigned f, unsigned o, unsigned delta, size_t n, const double *a,
                     const double *b, const double *c, const double *d, const double *pin,
                     double *x, double *split)
{
    unsigned s = f - o;
    double junction[3] = {0, 0, 0};

    *split = 0;
    for (size_t k = 0;; k++) {
        size_t first = k == 0 ? 0 : k * s - delta, last = k * s + f - 1 - delta;
        int to_end = last > n - 2; /* not closed by frag_push: takes the true end */
        size_t hi = to_end ? n - 1 : last, m = hi - first + 1;
        gsl_vector *dg = gsl_vector_alloc(m), *up = gsl_vector_alloc(m - 1),
                   *lo = gsl_vector_alloc(m - 1), *rhs = gsl_vector_alloc(m),
                   *sol = gsl_vector_alloc(m);
        size_t jprev = k * s - delta + o / 2, jk = (k + 1) * s - delta + o / 2;
        for (int ax = 0; ax < 3; ax++) {
            for (size_t i = 0; i < m; i++) {
                size_t r = first + i;
                int art_start = k > 0 && i == 0, art_end = !to_end && r == last;
                gsl_vector_set(dg, i, art_start || art_end ? 1.0 : b[r]);
                gsl_vector_set(rhs, i, art_start || art_end ? pin[r * 3 + ax] : d[r * 3 + ax]);
                if (i + 1 < m)
                    gsl_vector_set(up, i, art_start ? 0.0 : c[r]);
                if (i > 0)
                    gsl_vector_set(lo, i - 1, art_end ? 0.0 : a[r]);
            }
            assert_int_equal(gsl_linalg_solve_tridiag(dg, up, lo, rhs, sol), GSL_SUCCESS);
            size_t from = k == 0 ? 0 : jprev, to = to_end ? n : jk;
            for (size_t r = from; r < to; r++)
                x[r * 3 + ax] = gsl_vector_get(sol, r - first);
            if (k > 0) {
                double mine = gsl_vector_get(sol, jprev - first);
                x[jprev * 3 + ax] = 0.5 * (junction[ax] + mine);
                if (fabs(junction[ax] - mine) > *split)
                    *split = fabs(junction[ax] - mine);
            }
            if (!to_end)
                junction[ax] = gsl_vector_get(sol, jk - first);
        }
        gsl_vector_free(dg);
        gsl_vector_free(up);
        gsl_vector_free(lo);
        gsl_vector_free(rhs);
        gsl_vector_free(sol);
        if (to_end)
            break;
    }
}

/* The values of a multi-fragment window equal the reference above (GSL per
 * fragment, junctions averaged), for a few (F, O, delta) and a length that
 * ends anywhere in a fragment.  Pins far from the true solution make each
 * fragment's error at a junction large (~0.268^(O/2) of the scale, >= 1e-2
 * here), so taking one fragment's value instead of the mean, a share one row
 * off, or a pin ignored is seen; the tolerance covers only two different
 * Thomas orderings of the same system (both backward stable on this
 * diagonally dominant system: 4e-16 relative measured). */
#define TOL_FRAG_REL 1e-12
static void test_frag_values_vs_gsl(void **state)
{
    (void)state;
    static const unsigned cfgs[][3] = {{8, 4, 2}, {16, 8, 3}, {12, 2, 0}, {10, 6, 3}};
    double a[FRAG_REF_ROWS], b[FRAG_REF_ROWS], c[FRAG_REF_ROWS], d[FRAG_REF_ROWS * 3],
        pin[FRAG_REF_ROWS * 3], want[FRAG_REF_ROWS * 3], worst_rel = 0, least_split = INFINITY;

    for (size_t ci = 0; ci < sizeof cfgs / sizeof cfgs[0]; ci++)
        for (size_t n = 40; n <= FRAG_REF_ROWS; n += 19) {
            unsigned f = cfgs[ci][0], o = cfgs[ci][1], delta = cfgs[ci][2];
            frag_t *fw = frag_new(f, o, delta, 128);
            double scale = 0, maxerr = 0, split = 0;
            assert_non_null(fw);
            for (size_t r = 0; r < n; r++) {
                /* a time-knot cubic's rows: h, 2(h0+h1), h1 with uneven h */
                double h0 = 1.0 + 0.5 * sin(0.7 * (double)r),
                       h1 = 1.0 + 0.5 * sin(0.7 * (double)(r + 1));
                a[r] = r ? h0 : 0.0;
                b[r] = 2.0 * (h0 + h1);
                c[r] = r + 1 < n ? h1 : 0.0;
                for (int k = 0; k < 3; k++) {
                    d[r * 3 + k] = 6.0 * cos(0.3 * (double)r + k) + (double)k;
                    pin[r * 3 + k] = 0.25 * (double)k - 2.0; /* deliberately wrong */
                }
                frag_row_t row = {a[r], b[r], c[r], {d[r * 3], d[r * 3 + 1], d[r * 3 + 2]}};
                if (r + 1 < n)
                    assert_int_equal(frag_push(fw, &row, &pin[r * 3]), 0);
                else
                    assert_int_equal(frag_finish(fw, &row), 0);
            }
            assert_int_equal(fw->final_rows, n);
            frag_ref(f, o, delta, n, a, b, c, d, pin, want, &split);
            for (size_t i = 0; i < n * 3; i++)
                if (fabs(want[i]) > scale)
                    scale = fabs(want[i]);
            for (size_t r = 0; r < n; r++)
                for (int k = 0; k < 3; k++) {
                    double e = fabs(frag_x(fw, r)[k] - want[r * 3 + k]);
                    if (e > maxerr)
                        maxerr = e;
                }
            /* the test has teeth: two fragments disagree at some junction by
             * far more than the tolerance, so their mean is not either one */
            assert_true(split > 1e6 * TOL_FRAG_REL * scale);
            if (maxerr > TOL_FRAG_REL * scale)
                fail_msg("F=%u O=%u delta=%u n=%zu: frag_x off the per-fragment reference by "
                         "%.3g (scale %.3g)",
                         f, o, delta, n, maxerr, scale);
            worst_rel = fmax(worst_rel, maxerr / scale);
            least_split = fmin(least_split, split / scale);
            frag_free(fw);
        }
    print_message("window vs per-fragment GSL: worst %.1e relative; fragments split at a "
                  "junction by >= %.1e relative\n",
                  worst_rel, least_split);
}

/* Given a curve with a gap (two trajectories: fdiff.h allows gaps), when it
 * is evaluated exactly at the second segment's start, then that segment is
 * used (t is in [t0, t0 + dur]), not the first one's end across the gap;
 * and at each segment's start/end the constant term / the sum of terms. */
static void test_eval_curve_at_segment_start(void **state)
{
    (void)state;
    fdiff_seg_t s[2] = {{0.0, 1.0, {{1, 0, 0, 0}, {2, 0, 0, 0}, {3, 0, 0, 0}}},
                        {2.0, 1.0, {{5, 1, 0, 0}, {6, 0, 1, 0}, {7, 0, 0, 1}}}};
    const double t[4] = {0.0, 1.0, 2.0, 3.0};
    double p[12];
    fdiff_eval_curve(s, 2, t, 4, p, NULL, NULL);
    const double want[12] = {1, 2, 3, 1, 2, 3, 5, 6, 7, 6, 7, 8};
    for (int i = 0; i < 12; i++)
        assert_true(fabs(p[i] - want[i]) <= 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_drift_longest_segment),
        cmocka_unit_test(test_soa_equals_previous),
        cmocka_unit_test(test_seed_phase),
        cmocka_unit_test(test_cubic_vs_gsl),
        cmocka_unit_test(test_frag_bookkeeping),
        cmocka_unit_test(test_frag_values_vs_gsl),
        cmocka_unit_test(test_eval_curve_at_segment_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
