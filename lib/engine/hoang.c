/* hoang.c - exact-interpolating uniform cubic B-spline; see hoang.h. */
#include "hoang.h"

#include <stdlib.h>

#include "tridiag.h"

#define AX FRAG_AXES

static int clamped(engine_ends_t ends)
{
    return ends == ENGINE_ENDS_CLAMPED || ends == ENGINE_ENDS_REST;
}

/* velocity in u units, zero for REST or when not given */
static double vel_u(engine_ends_t ends, const double *v, int k)
{
    return ends == ENGINE_ENDS_CLAMPED && v ? v[k] : 0.0;
}

void hoang_row_interior(const double *r, frag_row_t *row)
{
    row->a = 1.0;
    row->b = 4.0;
    row->c = 1.0;
    for (int k = 0; k < AX; k++)
        row->d[k] = 6.0 * r[k];
}

void hoang_row_start(engine_ends_t ends, const double *r0, const double *v0_u, frag_row_t *row)
{
    row->a = 0.0;
    if (clamped(ends)) {
        /* P(-1) = P(1) - 2v eliminated from (P(-1) + 4P(0) + P(1))/6 = R(0) */
        row->b = 4.0;
        row->c = 2.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = 6.0 * r0[k] + 2.0 * vel_u(ends, v0_u, k);
    } else {
        row->b = 1.0;
        row->c = 0.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = r0[k];
    }
}

void hoang_row_end(engine_ends_t ends, const double *rl, const double *v1_u, frag_row_t *row)
{
    row->c = 0.0;
    if (clamped(ends)) {
        /* P(N) = P(N-2) + 2v eliminated from (P(N-2) + 4P(N-1) + P(N))/6 = R */
        row->a = 2.0;
        row->b = 4.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = 6.0 * rl[k] - 2.0 * vel_u(ends, v1_u, k);
    } else {
        row->a = 0.0;
        row->b = 1.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = rl[k];
    }
}

void hoang_ghost_start(engine_ends_t ends, const double *p0, const double *p1, const double *v0_u,
                       double *out)
{
    for (int k = 0; k < AX; k++)
        out[k] = clamped(ends) ? p1[k] - 2.0 * vel_u(ends, v0_u, k) : 2.0 * p0[k] - p1[k];
}

void hoang_ghost_end(engine_ends_t ends, const double *pm, const double *pl, const double *v1_u,
                     double *out)
{
    for (int k = 0; k < AX; k++)
        out[k] = clamped(ends) ? pm[k] + 2.0 * vel_u(ends, v1_u, k) : 2.0 * pl[k] - pm[k];
}

void hoang_segment(const double *p0, const double *p1, const double *p2, const double *p3,
                   double t0_s, double dur_s, fdiff_seg_t *seg)
{
    seg->t0_s = t0_s;
    seg->dur_s = dur_s;
    for (int k = 0; k < AX; k++) {
        /* [u^3 u^2 u 1] M [P0 P1 P2 P3]^T with M the uniform cubic B-spline basis matrix */
        seg->c[k][0] = (p0[k] + 4.0 * p1[k] + p2[k]) / 6.0;
        seg->c[k][1] = (p2[k] - p0[k]) / 2.0;
        seg->c[k][2] = (p0[k] - 2.0 * p1[k] + p2[k]) / 2.0;
        seg->c[k][3] = (-p0[k] + 3.0 * p1[k] - 3.0 * p2[k] + p3[k]) / 6.0;
    }
}

int hoang_solve(size_t n, const double *r, engine_ends_t ends, const double *v0_u,
                const double *v1_u, double *p, double *scratch)
{
    double *a = scratch, *b = scratch + n, *c = scratch + 2 * n, *s = scratch + 3 * n;
    frag_row_t row;
    size_t i;

    if (n < 2)
        return -ENGINE_ECONFIG;
    for (i = 0; i < n; i++) {
        if (i == 0)
            hoang_row_start(ends, r, v0_u, &row);
        else if (i == n - 1)
            hoang_row_end(ends, r + i * AX, v1_u, &row);
        else
            hoang_row_interior(r + i * AX, &row);
        a[i] = row.a;
        b[i] = row.b;
        c[i] = row.c;
        for (int k = 0; k < AX; k++)
            p[i * AX + k] = row.d[k];
    }
    /* p holds d; tridiag_solve allows x to alias d */
    return tridiag_solve(n, AX, a, b, c, p, p, s) < 0 ? -ENGINE_ENUMERIC : 0;
}

int hoang_curve(size_t n, const double *t_s, const double *r, engine_ends_t ends, const double *v0,
                const double *v1, fdiff_seg_t *segs, size_t max_seg, size_t *nseg)
{
    int mult = ends == ENGINE_ENDS_MULTIPLE;
    size_t m = mult ? n + 4 : n, i, j, out = 0;
    double *mem, *tt, *rr, *p, *scr, v0u[AX], v1u[AX], g0[AX], g1[AX];
    int rc;

    *nseg = 0;
    if (n < 2 || max_seg + 3 < n)
        return -ENGINE_ECONFIG;
    mem = malloc(sizeof(double) * (m + m * AX * 2 + 4 * m));
    if (!mem)
        return -ENGINE_ENOMEM;
    tt = mem;
    rr = tt + m;
    p = rr + m * AX;
    scr = p + m * AX;
    for (i = 0; i < m; i++) {
        size_t src = mult ? (i < 3 ? 0 : i >= n + 1 ? n - 1 : i - 2) : i;
        tt[i] = t_s[src];
        for (int k = 0; k < AX; k++)
            rr[i * AX + k] = r[src * AX + k];
    }
    for (int k = 0; k < AX; k++) {
        v0u[k] = (v0 ? v0[k] : 0.0) * (tt[1] - tt[0]);
        v1u[k] = (v1 ? v1[k] : 0.0) * (tt[m - 1] - tt[m - 2]);
    }
    rc = hoang_solve(m, rr, mult ? ENGINE_ENDS_HELD : ends, v0u, v1u, p, scr);
    if (rc < 0)
        goto out;
    hoang_ghost_start(ends, p, p + AX, v0u, g0);
    hoang_ghost_end(ends, p + (m - 2) * AX, p + (m - 1) * AX, v1u, g1);
    for (j = 0; j + 1 < m; j++) {
        double dur = tt[j + 1] - tt[j];
        const double *q0 = j == 0 ? g0 : p + (j - 1) * AX;
        const double *q3 = j + 2 >= m ? g1 : p + (j + 2) * AX;
        if ((ends == ENGINE_ENDS_HELD || mult) && (j == 0 || j + 2 == m))
            continue; /* held ends: the end segments are not part of the curve */
        if (!(dur > 0))
            continue; /* loop between copies of one point: never motion */
        if (out == max_seg) {
            rc = -ENGINE_ECONFIG;
            goto out;
        }
        hoang_segment(q0, p + j * AX, p + (j + 1) * AX, q3, tt[j], dur, &segs[out++]);
    }
    *nseg = out;
out:
    free(mem);
    return rc;
}
