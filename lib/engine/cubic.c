/* cubic.c - C2 cubic spline in second-derivative form; see cubic.h. */
#include "cubic.h"

#include <stdlib.h>

#include "tridiag.h"

#define AX FRAG_AXES

static double vel_s(engine_ends_t ends, const double *v, int k)
{
    return ends == ENGINE_ENDS_CLAMPED && v ? v[k] : 0.0;
}

void cubic_row_interior(double h0, double h1, const double *rm, const double *r, const double *rp,
                        frag_row_t *row)
{
    row->a = h0;
    row->b = 2.0 * (h0 + h1);
    row->c = h1;
    for (int k = 0; k < AX; k++)
        row->d[k] = 6.0 * ((rp[k] - r[k]) / h1 - (r[k] - rm[k]) / h0);
}

void cubic_row_start(engine_ends_t ends, double h0, const double *r0, const double *r1,
                     const double *v0_s, frag_row_t *row)
{
    row->a = 0.0;
    if (ends == ENGINE_ENDS_NATURAL) {
        row->b = 1.0;
        row->c = 0.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = 0.0;
    } else {
        row->b = 2.0 * h0;
        row->c = h0;
        for (int k = 0; k < AX; k++)
            row->d[k] = 6.0 * ((r1[k] - r0[k]) / h0 - vel_s(ends, v0_s, k));
    }
}

void cubic_row_end(engine_ends_t ends, double h, const double *rm, const double *rl,
                   const double *v1_s, frag_row_t *row)
{
    row->c = 0.0;
    if (ends == ENGINE_ENDS_NATURAL) {
        row->a = 0.0;
        row->b = 1.0;
        for (int k = 0; k < AX; k++)
            row->d[k] = 0.0;
    } else {
        row->a = h;
        row->b = 2.0 * h;
        for (int k = 0; k < AX; k++)
            row->d[k] = 6.0 * (vel_s(ends, v1_s, k) - (rl[k] - rm[k]) / h);
    }
}

void cubic_segment(const double *r0, const double *r1, const double *m0, const double *m1, double h,
                   double t0_s, double dur_s, fdiff_seg_t *seg)
{
    double q = h * h / 6.0;

    seg->t0_s = t0_s;
    seg->dur_s = dur_s;
    for (int k = 0; k < AX; k++) {
        /* R0 (1-u) + R1 u + h^2/6 [M0 ((1-u)^3 - (1-u)) + M1 (u^3 - u)] */
        seg->c[k][0] = r0[k];
        seg->c[k][1] = (r1[k] - r0[k]) - q * (2.0 * m0[k] + m1[k]);
        seg->c[k][2] = 3.0 * q * m0[k];
        seg->c[k][3] = q * (m1[k] - m0[k]);
    }
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
