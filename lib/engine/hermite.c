/* hermite.c - the local methods' segments and velocities (see hermite.h). */
#include "hermite.h"

void hermite_vel_chord(double t0, const double *p0, double t1, const double *p1, double *v)
{
    double h = t1 - t0;
    for (int k = 0; k < FDIFF_AXES; k++)
        v[k] = (p1[k] - p0[k]) / h;
}

void hermite_vel_backward(double t0, const double *p0, double t1, const double *p1, double t2,
                          const double *p2, double *v)
{
    double h1 = t1 - t0, h2 = t2 - t1;
    for (int k = 0; k < FDIFF_AXES; k++) {
        double d1 = (p1[k] - p0[k]) / h1, d2 = (p2[k] - p1[k]) / h2;
        v[k] = d2 + h2 * (d2 - d1) / (h1 + h2);
    }
}

void hermite_vel_centred(double t0, const double *p0, double t1, const double *p1, double t2,
                         const double *p2, double *v)
{
    double h1 = t1 - t0, h2 = t2 - t1;
    for (int k = 0; k < FDIFF_AXES; k++) {
        double d1 = (p1[k] - p0[k]) / h1, d2 = (p2[k] - p1[k]) / h2;
        v[k] = (h2 * d1 + h1 * d2) / (h1 + h2);
    }
}

void hermite_vel_natural(double t0, const double *p0, double t1, const double *p1, const double *v1,
                         double *v0)
{
    double h = t1 - t0;
    for (int k = 0; k < FDIFF_AXES; k++)
        v0[k] = (3.0 * (p1[k] - p0[k]) / h - v1[k]) / 2.0;
}

void hermite_segment(const double *p0, const double *v0, const double *p1, const double *v1,
                     double t0, double dur, fdiff_seg_t *seg)
{
    seg->t0_s = t0;
    seg->dur_s = dur;
    for (int k = 0; k < FDIFF_AXES; k++) {
        double m0 = v0[k] * dur, m1 = v1[k] * dur, d = p1[k] - p0[k];
        seg->c[k][0] = p0[k];
        seg->c[k][1] = m0;
        seg->c[k][2] = 3.0 * d - 2.0 * m0 - m1;
        seg->c[k][3] = -2.0 * d + m0 + m1;
    }
}

void hermite_acc_parabola(double t0, const double *p0, double t1, const double *p1, double t2,
                          const double *p2, double *a)
{
    double h1 = t1 - t0, h2 = t2 - t1;
    for (int k = 0; k < FDIFF_AXES; k++) {
        double d1 = (p1[k] - p0[k]) / h1, d2 = (p2[k] - p1[k]) / h2;
        a[k] = 2.0 * (d2 - d1) / (h1 + h2);
    }
}

void hermite_c2_segments(const double *p0, const double *v0, const double *a0, const double *p1,
                         const double *v1, const double *a1, double t0, double dur,
                         fdiff_seg_t seg[3])
{
    double tau = dur / 3.0;
    double P[FDIFF_AXES], V[FDIFF_AXES], A[FDIFF_AXES], J[3][FDIFF_AXES];

    for (int k = 0; k < FDIFF_AXES; k++) {
        double ra = (a1[k] - a0[k]) * tau * tau;
        double rv = (v1[k] - v0[k]) * tau - 3.0 * a0[k] * tau * tau;
        double rp = p1[k] - p0[k] - 3.0 * v0[k] * tau - 4.5 * a0[k] * tau * tau;
        J[0][k] = rp - rv + ra / 3.0;
        J[1][k] = 3.0 * rv - 2.0 * rp - 7.0 / 6.0 * ra;
        J[2][k] = rp - 2.0 * rv + 11.0 / 6.0 * ra;
        P[k] = p0[k];
        V[k] = v0[k] * tau;
        A[k] = a0[k] * tau * tau;
    }
    for (int i = 0; i < 3; i++) {
        seg[i].t0_s = t0 + i * tau;
        seg[i].dur_s = i < 2 ? tau : dur - 2.0 * tau; /* the pieces add up to dur */
        for (int k = 0; k < FDIFF_AXES; k++) {
            seg[i].c[k][0] = P[k];
            seg[i].c[k][1] = V[k];
            seg[i].c[k][2] = A[k] / 2.0;
            seg[i].c[k][3] = J[i][k] / 6.0;
            /* the state at the piece's end (u = 1) starts the next */
            P[k] += V[k] + A[k] / 2.0 + J[i][k] / 6.0;
            V[k] += A[k] + J[i][k] / 2.0;
            A[k] += J[i][k];
        }
    }
    for (int k = 0; k < FDIFF_AXES; k++) /* exact through the waypoint, not up to rounding */
        seg[2].c[k][3] = (p1[k] - seg[2].c[k][0] - seg[2].c[k][1] - seg[2].c[k][2]);
}
