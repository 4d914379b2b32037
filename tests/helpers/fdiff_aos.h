/*
 * fdiff_aos.h - the previous forward-difference stepper (per-axis layout,
 * before lib/engine/fdiff.h became struct-of-arrays), kept as the reference:
 * test_fdiff checks the new one makes the same doubles bit for bit, and
 * bench_engine times the two side by side.  Header-only (static inline).
 */
#ifndef TRAJD_FDIFF_AOS_H
#define TRAJD_FDIFF_AOS_H

#include "fdiff.h"

typedef struct {
    double p[FDIFF_AXES][4]; /* position f, d1, d2, d3 */
    double v[FDIFF_AXES][3]; /* velocity f, d1, d2 */
    double a[FDIFF_AXES][2]; /* acceleration f, d1 */
} fdiff_aos_t;

static inline void fdiff_aos_seed(fdiff_aos_t *fd, const fdiff_seg_t *seg, double u0, double du)
{
    double inv_t = 1.0 / seg->dur_s, inv_t2 = inv_t * inv_t;
    double h = du, h2 = du * du, h3 = h2 * du, u = u0;
    for (int k = 0; k < FDIFF_AXES; k++) {
        double c0 = seg->c[k][0], c1 = seg->c[k][1], c2 = seg->c[k][2], c3 = seg->c[k][3];
        fd->p[k][0] = c0 + u * (c1 + u * (c2 + u * c3));
        fd->p[k][1] = c1 * h + c2 * (2 * u * h + h2) + c3 * (3 * u * u * h + 3 * u * h2 + h3);
        fd->p[k][2] = 2 * c2 * h2 + c3 * (6 * u * h2 + 6 * h3);
        fd->p[k][3] = 6 * c3 * h3;
        fd->v[k][0] = (c1 + u * (2 * c2 + u * 3 * c3)) * inv_t;
        fd->v[k][1] = (2 * c2 * h + 3 * c3 * (2 * u * h + h2)) * inv_t;
        fd->v[k][2] = 6 * c3 * h2 * inv_t;
        fd->a[k][0] = (2 * c2 + 6 * c3 * u) * inv_t2;
        fd->a[k][1] = 6 * c3 * h * inv_t2;
    }
}

static inline void fdiff_aos_step(fdiff_aos_t *fd)
{
    for (int k = 0; k < FDIFF_AXES; k++) {
        fd->p[k][0] += fd->p[k][1];
        fd->p[k][1] += fd->p[k][2];
        fd->p[k][2] += fd->p[k][3];
        fd->v[k][0] += fd->v[k][1];
        fd->v[k][1] += fd->v[k][2];
        fd->a[k][0] += fd->a[k][1];
    }
}

static inline void fdiff_aos_get(const fdiff_aos_t *fd, double *pos, double *vel, double *acc)
{
    for (int k = 0; k < FDIFF_AXES; k++) {
        pos[k] = fd->p[k][0];
        vel[k] = fd->v[k][0];
        acc[k] = fd->a[k][0];
    }
}

#endif
