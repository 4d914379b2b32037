/* hoang.c - exact-interpolating uniform cubic B-spline; see hoang.h. */
#include "hoang.h"

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
