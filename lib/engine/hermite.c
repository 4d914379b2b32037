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
