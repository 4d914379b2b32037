/* surf.c - bicubic B-spline surfaces; see surf.h. */
#include "surf.h"

#include <math.h>
#include <string.h>

#include "bspline.h"
#include "tridiag.h"

/* Parameters this far (in grid units) outside the grid are clamped onto it. */
#define SURF_DOMAIN_TOL 1e-9

const char *surf_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case SURF_OK: return "success";
    case SURF_ESIZE: return "surface: grid smaller than 2 x 2, no coordinate, or no step";
    case SURF_ENOTFINITE: return "surface: grid value not finite";
    case SURF_ESINGULAR: return "surface: interpolation system could not be solved";
    case SURF_EDOMAIN: return "surface: parameter or patch outside the grid";
    default: return "unknown surf error";
    }
}

size_t surf_scratch_len(size_t m, size_t n, size_t dim)
{
    size_t k = m > n ? m : n;
    return 4 * k + (m + 2) * n * dim;
}

/*
 * Held-end Hoang system of size k for the interior control points
 * Q(1..k): Q(1) = R(0), Q(k) = R(k-1), Q(j-1) + 4 Q(j) + Q(j+1) = 6 R(j-1).
 * Fills a, b, c; the right-hand side is built by the caller.
 */
static void hoang_rows(size_t k, double *a, double *b, double *c)
{
    size_t r;
    for (r = 0; r < k; r++) {
        int end = r == 0 || r + 1 == k;
        a[r] = end ? 0.0 : 1.0;
        b[r] = end ? 1.0 : 4.0;
        c[r] = end ? 0.0 : 1.0;
    }
}

int surf_interpolate(size_t m, size_t n, size_t dim, const double *grid, double *ctrl,
                     double *scratch, surf_t *s)
{
    size_t k = m > n ? m : n, i, j, c, w = n * dim, W = (n + 2) * dim;
    double *a = scratch, *b = a + k, *cc = b + k, *tw = cc + k, *T = tw + k;
    int rc;

    if (m < 2 || n < 2 || dim == 0)
        return -SURF_ESIZE;
    for (i = 0; i < m * n * dim; i++)
        if (!isfinite(grid[i]))
            return -SURF_ENOTFINITE;
    /* Pass 1, along u: T(1..m) solves the system for every column at once
     * (right-hand side row r = 6 R(r) inside, R(r) at the ends). */
    for (i = 0; i < m; i++) {
        double f = (i == 0 || i + 1 == m) ? 1.0 : 6.0;
        for (j = 0; j < w; j++)
            T[(i + 1) * w + j] = f * grid[i * w + j];
    }
    hoang_rows(m, a, b, cc);
    rc = tridiag_solve(m, w, a, b, cc, T + w, T + w, tw);
    if (rc < 0)
        return -SURF_ESINGULAR;
    for (j = 0; j < w; j++) { /* natural ends: T(0) = 2T(1) - T(2) */
        T[j] = 2.0 * T[w + j] - T[2 * w + j];
        T[(m + 1) * w + j] = 2.0 * T[m * w + j] - T[(m - 1) * w + j];
    }
    /* Pass 2, along v, for each of the m+2 rows of T. */
    hoang_rows(n, a, b, cc);
    for (i = 0; i < m + 2; i++) {
        double *row = ctrl + i * W;
        const double *src = T + i * w;
        for (j = 0; j < n; j++) {
            double f = (j == 0 || j + 1 == n) ? 1.0 : 6.0;
            for (c = 0; c < dim; c++)
                row[(j + 1) * dim + c] = f * src[j * dim + c];
        }
        rc = tridiag_solve(n, dim, a, b, cc, row + dim, row + dim, tw);
        if (rc < 0)
            return -SURF_ESINGULAR;
        for (c = 0; c < dim; c++) {
            row[c] = 2.0 * row[dim + c] - row[2 * dim + c];
            row[(n + 1) * dim + c] = 2.0 * row[n * dim + c] - row[(n - 1) * dim + c];
        }
    }
    if (s) {
        s->m = m;
        s->n = n;
        s->dim = dim;
        s->ctrl = ctrl;
    }
    return 0;
}

/* Split a parameter into patch index and local parameter. */
static int locate(double x, size_t cells, size_t *idx, double *loc)
{
    double hi = (double)cells;
    size_t k;

    if (!isfinite(x) || x < -SURF_DOMAIN_TOL || x > hi + SURF_DOMAIN_TOL)
        return -SURF_EDOMAIN;
    x = x < 0.0 ? 0.0 : (x > hi ? hi : x);
    k = (size_t)floor(x);
    if (k >= cells)
        k = cells - 1;
    *idx = k;
    *loc = x - (double)k;
    return 0;
}

/* Uniform cubic B-spline blending functions and their derivatives. */
static void blend(double t, double *B, double *dB)
{
    double t2 = t * t, t3 = t2 * t, mt = 1.0 - t;
    B[0] = mt * mt * mt / 6.0;
    B[1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
    B[2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
    B[3] = t3 / 6.0;
    dB[0] = -0.5 * mt * mt;
    dB[1] = 1.5 * t2 - 2.0 * t;
    dB[2] = -1.5 * t2 + t + 0.5;
    dB[3] = 0.5 * t2;
}

int surf_eval(const surf_t *s, double u, double v, unsigned nder, double *out)
{
    double Bu[4], dBu[4], Bv[4], dBv[4], su, tv;
    size_t i, j, c, dim = s->dim, W = (s->n + 2) * dim;
    int a, b;

    if (locate(u, s->m - 1, &i, &su) < 0 || locate(v, s->n - 1, &j, &tv) < 0)
        return -SURF_EDOMAIN;
    blend(su, Bu, dBu);
    blend(tv, Bv, dBv);
    for (c = 0; c < dim; c++) {
        double r = 0.0, ru = 0.0, rv = 0.0;
        for (a = 0; a < 4; a++) {
            const double *row = s->ctrl + (i + a) * W + j * dim + c;
            double x = 0.0, xv = 0.0;
            for (b = 0; b < 4; b++) {
                x += Bv[b] * row[b * dim];
                xv += dBv[b] * row[b * dim];
            }
            r += Bu[a] * x;
            ru += dBu[a] * x;
            rv += Bu[a] * xv;
        }
        out[c] = r;
        if (nder >= 1) {
            out[dim + c] = ru;
            out[2 * dim + c] = rv;
        }
    }
    return 0;
}

/* C = M . P . M^T for coordinate c of patch (i, j) (16 values). */
static void coeffs_one(const surf_t *s, size_t i, size_t j, size_t c, const double *M, double *C)
{
    double MP[16];
    size_t dim = s->dim, W = (s->n + 2) * dim;
    int a, b, r, q;

    for (a = 0; a < 4; a++)
        for (q = 0; q < 4; q++) {
            double x = 0.0;
            for (r = 0; r < 4; r++)
                x += M[a * 4 + r] * s->ctrl[(i + r) * W + (j + q) * dim + c];
            MP[a * 4 + q] = x;
        }
    for (a = 0; a < 4; a++)
        for (b = 0; b < 4; b++) {
            double x = 0.0;
            for (q = 0; q < 4; q++)
                x += MP[a * 4 + q] * M[b * 4 + q];
            C[a * 4 + b] = x;
        }
}

int surf_patch_coeffs(const surf_t *s, size_t i, size_t j, double *C)
{
    double M[16];
    size_t c;

    if (i + 1 >= s->m || j + 1 >= s->n)
        return -SURF_EDOMAIN;
    bspline_cubic_matrix(1.0, M);
    for (c = 0; c < s->dim; c++)
        coeffs_one(s, i, j, c, M, C + c * 16);
    return 0;
}

/* Forward-difference state of k(x) = a x^3 + b x^2 + c x + d at step h. */
static void fd_seed(const double *k, double h, double *st)
{
    double h2 = h * h, h3 = h2 * h;
    st[0] = k[3];
    st[1] = k[0] * h3 + k[1] * h2 + k[2] * h;
    st[2] = 6.0 * k[0] * h3 + 2.0 * k[1] * h2;
    st[3] = 6.0 * k[0] * h3;
}

static void fd_step(double *st)
{
    st[0] += st[1];
    st[1] += st[2];
    st[2] += st[3];
}

int surf_patch_fd(const surf_t *s, size_t i, size_t j, unsigned nu, unsigned nv, double *out)
{
    double M[16], C[16];
    size_t c, dim = s->dim;
    unsigned x, y;
    int a;

    if (nu == 0 || nv == 0)
        return -SURF_ESIZE;
    if (i + 1 >= s->m || j + 1 >= s->n)
        return -SURF_EDOMAIN;
    bspline_cubic_matrix(1.0, M);
    for (c = 0; c < dim; c++) {
        double vst[4][4]; /* FD state, in t, of the 4 coefficient cubics f_a(t) */
        coeffs_one(s, i, j, c, M, C);
        for (a = 0; a < 4; a++)
            fd_seed(C + a * 4, 1.0 / nv, vst[a]);
        for (y = 0; y <= nv; y++) {
            double k[4], ust[4];
            for (a = 0; a < 4; a++)
                k[a] = vst[a][0];
            fd_seed(k, 1.0 / nu, ust);
            for (x = 0; x <= nu; x++) {
                out[((size_t)x * (nv + 1) + y) * dim + c] = ust[0];
                fd_step(ust);
            }
            for (a = 0; a < 4; a++)
                fd_step(vst[a]);
        }
    }
    return 0;
}
