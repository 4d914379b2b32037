/*
 * bench_toolkit.c - ns per point of each spline-toolkit evaluator, beside the
 * GSL call where GSL has a counterpart.  Prints a table; asserts nothing
 * about speed (numbers are noisy on a shared machine).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_bspline.h>
#include <gsl/gsl_multifit.h>
#include <gsl/gsl_spline.h>

#include "test.h"
#include "bspline.h"
#include "cspline.h"
#include "lsq.h"
#include "nurbs.h"
#include "path.h"
#include "surf.h"

static volatile double sink;

static void row(const char *what, double ns, const char *gsl_what, double gsl_ns)
{
    if (gsl_what)
        printf("| %-44s | %9.1f | %-40s | %9.1f | %7.2f |\n", what, ns, gsl_what, gsl_ns,
               gsl_ns / ns);
    else
        printf("| %-44s | %9.1f | %-40s | %9s | %7s |\n", what, ns, "-", "-", "-");
}

#define NC 1000
#define NPTS 200000

int main(void)
{
    static double breaks[NC], knots[NC + 2 * BSPLINE_ORDER_MAX], ctrl[(NC + 8) * 3];
    static double out[64], N[BSPLINE_ORDER_MAX], ders[BSPLINE_ORDER_MAX * BSPLINE_ORDER_MAX];
    unsigned seed = 1, q = 4;
    size_t i, first, nc, k;
    double t0, a, b, ns, gns, lo, hi;

    printf(
        "GSL 2.7 finds the knot interval by a linear search, hence its O(n) cost at n = 1001.\n\n");
    printf("x ref = the reference's time over ours, both measured in this run (> 1: ours is "
           "faster); the reference is GSL's counterpart, or the direct evaluation a stepper "
           "replaces.\n\n");
    printf("| evaluator | ns/point | reference (same run) | ns/point | x ref |\n"
           "|---|---:|---|---:|---:|\n");

    /* ---- B-spline, order 4, 1000 breakpoints, clamped, 3-D ---- */
    breaks[0] = 0;
    for (i = 1; i < NC; i++)
        breaks[i] = breaks[i - 1] + 0.1 + urand(&seed);
    bspline_knots_clamped(breaks, NC, q, knots);
    nc = NC + q - 2;
    for (i = 0; i < nc * 3; i++)
        ctrl[i] = urand(&seed) * 100;
    bspline_t bs = {q, nc, 3, knots, ctrl};
    bspline_domain(&bs, &lo, &hi);
    gsl_bspline_workspace *w = gsl_bspline_alloc(q, NC);
    gsl_vector *gb = gsl_vector_alloc(NC), *B = gsl_vector_alloc(q);
    gsl_matrix *dB = gsl_matrix_alloc(q, 3);
    for (i = 0; i < NC; i++)
        gsl_vector_set(gb, i, breaks[i]);
    gsl_bspline_knots(gb, w);

    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        bspline_eval(&bs, lo + (hi - lo) * (i + 0.5) / NPTS, out);
        sink += out[0];
    }
    ns = (now_s() - t0) / NPTS * 1e9;
    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        size_t is, ie, c;
        double x = lo + (hi - lo) * (i + 0.5) / NPTS;
        gsl_bspline_eval_nonzero(x, B, &is, &ie, w);
        for (c = 0; c < 3; c++) {
            double s = 0;
            for (k = is; k <= ie; k++)
                s += gsl_vector_get(B, k - is) * ctrl[k * 3 + c];
            out[c] = s;
        }
        sink += out[0];
    }
    gns = (now_s() - t0) / NPTS * 1e9;
    row("bspline_eval (de Boor), cubic, 3-D, n=1001", ns, "gsl_bspline_eval_nonzero + dot", gns);

    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        bspline_basis(knots, nc, q, lo + (hi - lo) * (i + 0.5) / NPTS, &first, N);
        sink += N[1];
    }
    ns = (now_s() - t0) / NPTS * 1e9;
    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        size_t is, ie;
        gsl_bspline_eval_nonzero(lo + (hi - lo) * (i + 0.5) / NPTS, B, &is, &ie, w);
        sink += gsl_vector_get(B, 1);
    }
    gns = (now_s() - t0) / NPTS * 1e9;
    row("bspline_basis (Cox-de Boor), cubic", ns, "gsl_bspline_eval_nonzero", gns);

    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        bspline_basis_derivs(knots, nc, q, lo + (hi - lo) * (i + 0.5) / NPTS, 2, &first, ders);
        sink += ders[5];
    }
    ns = (now_s() - t0) / NPTS * 1e9;
    t0 = now_s();
    for (i = 0; i < NPTS; i++) {
        size_t is, ie;
        gsl_bspline_deriv_eval_nonzero(lo + (hi - lo) * (i + 0.5) / NPTS, 2, dB, &is, &ie, w);
        sink += gsl_matrix_get(dB, 1, 1);
    }
    gns = (now_s() - t0) / NPTS * 1e9;
    row("bspline_basis_derivs, cubic, up to 2nd", ns, "gsl_bspline_deriv_eval_nonzero", gns);

    {
        double M[16], p[12] = {0, 0, 0, 1, 2, 0, 3, 1, 1, 4, 4, 2};
        bspline_cubic_matrix(0.8, M);
        t0 = now_s();
        for (i = 0; i < NPTS; i++) {
            bspline_cubic_segment(M, p, 3, (i + 0.5) / NPTS, 0, out);
            sink += out[0];
        }
        ns = (now_s() - t0) / NPTS * 1e9;
        row("bspline_cubic_segment (tension matrix), 3-D", ns, NULL, 0);
    }

    /* ---- order 8 for scale ---- */
    {
        unsigned q8 = 8;
        size_t nc8 = NC + q8 - 2;
        bspline_knots_clamped(breaks, NC, q8, knots);
        bspline_t b8 = {q8, nc8, 3, knots, ctrl};
        t0 = now_s();
        for (i = 0; i < NPTS / 4; i++) {
            bspline_eval(&b8, lo + (hi - lo) * (i + 0.5) / (NPTS / 4), out);
            sink += out[0];
        }
        ns = (now_s() - t0) / (NPTS / 4) * 1e9;
        row("bspline_eval, order 8 (degree 7), 3-D", ns, NULL, 0);
    }

    /* ---- cubic spline through 1000 timed points, 3-D ---- */
    {
        static double t[NC], p[NC * 3], s[NC * 3], scratch[NC * 9], x[NC], y[NC];
        cspline_t cs;
        int reps = 200;
        t[0] = 0;
        for (i = 0; i < NC; i++) {
            if (i)
                t[i] = t[i - 1] + 0.05 + urand(&seed);
            for (k = 0; k < 3; k++)
                p[i * 3 + k] = urand(&seed) * 10;
            x[i] = t[i];
            y[i] = p[i * 3];
        }
        t0 = now_s();
        for (i = 0; i < (size_t)reps; i++)
            cspline_solve(NC, 3, t, p, CSPLINE_END_NATURAL, NULL, NULL, s, scratch, &cs);
        ns = (now_s() - t0) / reps / NC * 1e9;
        gsl_spline *gs = gsl_spline_alloc(gsl_interp_cspline, NC);
        gsl_interp_accel *acc = gsl_interp_accel_alloc();
        t0 = now_s();
        for (i = 0; i < (size_t)reps; i++)
            for (k = 0; k < 3; k++)
                gsl_spline_init(gs, x, y, NC);
        gns = (now_s() - t0) / reps / NC * 1e9;
        row("cspline_solve natural, 3-D, per point", ns, "gsl_spline_init cspline x3", gns);
        t0 = now_s();
        for (i = 0; i < NPTS; i++) {
            cspline_eval(&cs, t[NC - 1] * (i + 0.5) / NPTS, 0, out);
            sink += out[0];
        }
        ns = (now_s() - t0) / NPTS * 1e9;
        gsl_spline_init(gs, x, y, NC);
        t0 = now_s();
        for (i = 0; i < NPTS; i++) {
            double xx = t[NC - 1] * (i + 0.5) / NPTS;
            for (k = 0; k < 3; k++)
                sink += gsl_spline_eval(gs, xx, acc);
        }
        gns = (now_s() - t0) / NPTS * 1e9;
        row("cspline_eval, 3-D (binary search)", ns, "gsl_spline_eval x3 (accel)", gns);
        gsl_spline_free(gs);
        gsl_interp_accel_free(acc);
    }

    /* ---- NURBS circle ---- */
    {
        double kn[12], cp[18], wt[9];
        nurbs_t c;
        nurbs_unit_circle(kn, cp, wt, &c);
        t0 = now_s();
        for (i = 0; i < NPTS; i++) {
            nurbs_eval(&c, (i + 0.5) / NPTS, out);
            sink += out[0];
        }
        ns = (now_s() - t0) / NPTS * 1e9;
        t0 = now_s();
        for (i = 0; i < NPTS; i++) {
            double a2 = 2 * M_PI * (i + 0.5) / NPTS;
            sink += cos(a2) + sin(a2);
        }
        gns = (now_s() - t0) / NPTS * 1e9;
        row("nurbs_eval, seed unit circle", ns, "(libm cos + sin, for scale)", gns);
    }

    /* ---- least squares ---- */
    {
        enum { M = 2000, NCL = 60 };
        static double u[M], pts[M * 3], kn[NCL + 4], cp[NCL * 3], work[NCL * 8];
        for (i = 0; i < M; i++) {
            double s2 = 20.0 * i / M;
            pts[i * 3] = s2 * cos(s2) + urand(&seed) - 0.5;
            pts[i * 3 + 1] = s2 * sin(s2) + urand(&seed) - 0.5;
            pts[i * 3 + 2] = 0.1 * s2;
        }
        lsq_chord_params(M, 3, pts, u);
        lsq_knots(NCL, 4, 0, 1, kn);
        int reps = 50;
        t0 = now_s();
        for (i = 0; i < (size_t)reps; i++)
            lsq_fit(M, 3, u, pts, 4, NCL, kn, 0, cp, work);
        ns = (now_s() - t0) / reps / M * 1e9;
        /* GSL: design matrix from gsl_bspline_eval + gsl_multifit_linear (SVD), x3 */
        gsl_bspline_workspace *w2 = gsl_bspline_alloc(4, NCL - 2);
        gsl_bspline_knots_uniform(0, 1, w2);
        gsl_matrix *X = gsl_matrix_alloc(M, NCL), *cov = gsl_matrix_alloc(NCL, NCL);
        gsl_vector *yv = gsl_vector_alloc(M), *cv = gsl_vector_alloc(NCL),
                   *Bv = gsl_vector_alloc(NCL);
        gsl_multifit_linear_workspace *mw = gsl_multifit_linear_alloc(M, NCL);
        double chisq;
        int greps = 3;
        t0 = now_s();
        for (int r = 0; r < greps; r++) {
            for (i = 0; i < M; i++) {
                gsl_bspline_eval(u[i], Bv, w2);
                for (k = 0; k < NCL; k++)
                    gsl_matrix_set(X, i, k, gsl_vector_get(Bv, k));
            }
            for (k = 0; k < 3; k++) {
                for (i = 0; i < M; i++)
                    gsl_vector_set(yv, i, pts[i * 3 + k]);
                gsl_multifit_linear(X, yv, cv, cov, &chisq, mw);
            }
        }
        gns = (now_s() - t0) / greps / M * 1e9;
        sink += gsl_vector_get(cv, 3) - cp[9];
        row("lsq_fit 2000 pts -> 60 ctrl, cubic, 3-D, per pt", ns,
            "design matrix + gsl_multifit_linear x3", gns);
        gsl_matrix_free(X);
        gsl_matrix_free(cov);
        gsl_vector_free(yv);
        gsl_vector_free(cv);
        gsl_vector_free(Bv);
        gsl_multifit_linear_free(mw);
        gsl_bspline_free(w2);
    }

    /* ---- streaming smoother (engine method smooth), window 24, 6 control points ---- */
    {
        static double mem[4096], tt, rr[3];
        lsq_smooth_t sm;
        size_t nout = 0;
        if (lsq_smooth_mem_len(24, 6, 3) <= 4096 && lsq_smooth_init(&sm, 24, 6, 3, mem) == 0) {
            t0 = now_s();
            for (i = 0; i < 20000; i++) {
                double r3[3] = {urand(&seed), urand(&seed), 0.1 * i};
                lsq_smooth_push(&sm, (double)i, r3);
                while (lsq_smooth_pop(&sm, &tt, rr) == 1) {
                    sink += rr[0];
                    nout++;
                }
            }
            row("lsq_smooth (window 24, 6 ctrl), per waypoint", (now_s() - t0) / nout * 1e9, NULL,
                0);
        }
    }

    /* ---- surface ---- */
    {
        enum { GM = 30, GN = 40, ST = 32 };
        static double g[GM * GN * 3], cp[(GM + 2) * (GN + 2) * 3], scr[8192],
            fd[(ST + 1) * (ST + 1) * 3];
        surf_t s;
        size_t j, n = 0;
        for (i = 0; i < GM; i++)
            for (j = 0; j < GN; j++) {
                g[(i * GN + j) * 3] = i;
                g[(i * GN + j) * 3 + 1] = j;
                g[(i * GN + j) * 3 + 2] = sin(0.3 * i) * cos(0.2 * j);
            }
        surf_interpolate(GM, GN, 3, g, cp, scr, &s);
        t0 = now_s();
        for (i = 0; i + 1 < GM; i++)
            for (j = 0; j + 1 < GN; j++) {
                surf_patch_fd(&s, i, j, ST, ST, fd);
                sink += fd[7];
                n += (ST + 1) * (ST + 1);
            }
        ns = (now_s() - t0) / n * 1e9;
        t0 = now_s();
        n = 0;
        for (i = 0; i + 1 < GM; i += 3)
            for (j = 0; j + 1 < GN; j += 3)
                for (a = 0; a <= ST; a++)
                    for (b = 0; b <= ST; b++) {
                        surf_eval(&s, i + a / ST, j + b / ST, 0, out);
                        sink += out[2];
                        n++;
                    }
        gns = (now_s() - t0) / n * 1e9;
        row("surf_patch_fd (forward differences), 3-D", ns, "surf_eval (direct, 16 blends), 3-D",
            gns);
        t0 = now_s();
        for (i = 0; i < 100; i++)
            surf_interpolate(GM, GN, 3, g, cp, scr, &s);
        row("surf_interpolate 30x40 grid, per grid point", (now_s() - t0) / 100 / (GM * GN) * 1e9,
            NULL, 0);
    }

    /* ---- path ---- */
    {
        const char *prog[] = {"start 0 0 0",
                              "speed 5",
                              "step 0.1",
                              "line 100 0 0",
                              "arc 100 50 50 -90 90",
                              "circle 100 50 50 90 cw",
                              "line 0 100 0"};
        path_elem_t el[8];
        static engine_waypoint_t wp[4096];
        size_t nw = 0;
        for (i = 0; i < 7; i++)
            path_parse_line(prog[i], &el[i]);
        int reps = 200;
        t0 = now_s();
        for (i = 0; i < (size_t)reps; i++)
            path_expand(el, 7, wp, 4096, &nw);
        row("path_expand (lines + NURBS arcs), per waypoint", (now_s() - t0) / reps / nw * 1e9,
            NULL, 0);
        sink += wp[5].pos_m[0];
    }

    gsl_vector_free(gb);
    gsl_vector_free(B);
    gsl_matrix_free(dB);
    gsl_bspline_free(w);
    return sink > 1e300;
}
