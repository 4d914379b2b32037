/* global_curve.c - the global solves of the tests; see global_curve.h. */
#include "global_curve.h"

#include <stdlib.h>

#include "tridiag.h"

#define AX FRAG_AXES

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

int cubic_curve(size_t n, const double *t_s, const double *r, engine_param_t param,
                engine_ends_t ends, const double *v0, const double *v1, fdiff_seg_t *segs,
                size_t max_seg, size_t *nseg)
{
    double *mem, *a, *b, *c, *m, *scr, v0s[AX], v1s[AX];
    frag_row_t row;
    size_t i;
    int rc = 0;

    *nseg = 0;
    if (n < 2 || max_seg + 1 < n || ends == ENGINE_ENDS_HELD || ends == ENGINE_ENDS_MULTIPLE)
        return -ENGINE_ECONFIG;
    mem = malloc(sizeof(double) * n * (4 + AX));
    if (!mem)
        return -ENGINE_ENOMEM;
    a = mem;
    b = a + n;
    c = b + n;
    scr = c + n;
    m = scr + n;
#define H(j) (param == ENGINE_PARAM_TIME ? t_s[(j) + 1] - t_s[(j)] : 1.0)
    for (int k = 0; k < AX; k++) {
        v0s[k] = (v0 ? v0[k] : 0.0) * (t_s[1] - t_s[0]) / H(0);
        v1s[k] = (v1 ? v1[k] : 0.0) * (t_s[n - 1] - t_s[n - 2]) / H(n - 2);
    }
    for (i = 0; i < n; i++) {
        if (i == 0)
            cubic_row_start(ends, H(0), r, r + AX, v0s, &row);
        else if (i == n - 1)
            cubic_row_end(ends, H(n - 2), r + (n - 2) * AX, r + (n - 1) * AX, v1s, &row);
        else
            cubic_row_interior(H(i - 1), H(i), r + (i - 1) * AX, r + i * AX, r + (i + 1) * AX,
                               &row);
        a[i] = row.a;
        b[i] = row.b;
        c[i] = row.c;
        for (int k = 0; k < AX; k++)
            m[i * AX + k] = row.d[k];
    }
    if (tridiag_solve(n, AX, a, b, c, m, m, scr) < 0) {
        rc = -ENGINE_ENUMERIC;
        goto out;
    }
    for (i = 0; i + 1 < n; i++)
        cubic_segment(r + i * AX, r + (i + 1) * AX, m + i * AX, m + (i + 1) * AX, H(i), t_s[i],
                      t_s[i + 1] - t_s[i], &segs[i]);
#undef H
    *nseg = n - 1;
out:
    free(mem);
    return rc;
}
