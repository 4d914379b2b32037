/* cubic.c - C2 cubic spline in second-derivative form; see cubic.h. */
#include "cubic.h"

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

int cubic_join(fdiff_seg_t *seg, const double *v0)
{
    int changed = 0;

    for (int k = 0; k < AX; k++) {
        double *c = seg->c[k], m0 = v0[k] * seg->dur_s;
        if (!(c[1] < m0 || c[1] > m0)) /* already joined (and no -Wfloat-equal) */
            continue;
        double d = c[1] + c[2] + c[3];          /* P1 - P0 */
        double m1 = c[1] + 2 * c[2] + 3 * c[3]; /* dk/du at the end */
        c[1] = m0;
        c[2] = 3 * d - 2 * m0 - m1;
        c[3] = -2 * d + m0 + m1;
        changed = 1;
    }
    return changed;
}
