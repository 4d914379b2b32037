/* fdiff.c - forward-difference stepper; see fdiff.h. */
#include "fdiff.h"

#include <stddef.h>
#include <string.h>

void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du)
{
    double inv_t = 1.0 / seg->dur_s, inv_t2 = inv_t * inv_t;
    double h = du, h2 = du * du, h3 = h2 * du, u = u0;

    for (int k = 0; k < FDIFF_AXES; k++) {
        double c0 = seg->c[k][0], c1 = seg->c[k][1], c2 = seg->c[k][2], c3 = seg->c[k][3];
        /* Differences of the cubic written in closed form at u (exact
         * algebra, no cancellation of k(u+h) - k(u) on large values). */
        fd->p0[k] = c0 + u * (c1 + u * (c2 + u * c3));
        fd->p1[k] = c1 * h + c2 * (2 * u * h + h2) + c3 * (3 * u * u * h + 3 * u * h2 + h3);
        fd->p2[k] = 2 * c2 * h2 + c3 * (6 * u * h2 + 6 * h3);
        fd->p3[k] = 6 * c3 * h3;
        /* k'(u) = c1 + 2 c2 u + 3 c3 u^2, a quadratic */
        fd->v0[k] = (c1 + u * (2 * c2 + u * 3 * c3)) * inv_t;
        fd->v1[k] = (2 * c2 * h + 3 * c3 * (2 * u * h + h2)) * inv_t;
        fd->v2[k] = 6 * c3 * h2 * inv_t;
        /* k''(u) = 2 c2 + 6 c3 u, a line */
        fd->a0[k] = (2 * c2 + 6 * c3 * u) * inv_t2;
        fd->a1[k] = 6 * c3 * h * inv_t2;
    }
    /* the zero lane stays zero */
    for (int k = FDIFF_AXES; k < FDIFF_LANES; k++)
        fd->p0[k] = fd->p1[k] = fd->p2[k] = fd->p3[k] = fd->v0[k] = fd->v1[k] = fd->v2[k] =
            fd->a0[k] = fd->a1[k] = 0.0;
}

void fdiff_get(const fdiff_t *fd, double *pos, double *vel, double *acc)
{
    for (int k = 0; k < FDIFF_AXES; k++) {
        if (pos)
            pos[k] = fd->p0[k];
        if (vel)
            vel[k] = fd->v0[k];
        if (acc)
            acc[k] = fd->a0[k];
    }
}

void fdiff_eval(const fdiff_seg_t *seg, double u, double *pos, double *vel, double *acc)
{
    double inv_t = 1.0 / seg->dur_s;

    for (int k = 0; k < FDIFF_AXES; k++) {
        const double *c = seg->c[k];
        if (pos)
            pos[k] = c[0] + u * (c[1] + u * (c[2] + u * c[3]));
        if (vel)
            vel[k] = (c[1] + u * (2 * c[2] + u * 3 * c[3])) * inv_t;
        if (acc)
            acc[k] = (2 * c[2] + 6 * c[3] * u) * inv_t * inv_t;
    }
}

void fdiff_eval_curve(const fdiff_seg_t *segs, unsigned long nseg, const double *t_s,
                      unsigned long n, double *pos, double *vel, double *acc)
{
    unsigned long i, j = 0;

    for (i = 0; i < n; i++) {
        double t = t_s[i], u;
        if (nseg == 0)
            break;
        /* segments are sorted: binary search the last one starting <= t */
        unsigned long lo = 0, hi = nseg;
        while (hi - lo > 1) {
            unsigned long mid = (lo + hi) / 2;
            if (segs[mid].t0_s <= t)
                lo = mid;
            else
                hi = mid;
        }
        j = lo;
        u = (t - segs[j].t0_s) / segs[j].dur_s;
        if (u < 0)
            u = 0;
        if (u > 1)
            u = 1;
        fdiff_eval(&segs[j], u, pos ? pos + i * FDIFF_AXES : NULL,
                   vel ? vel + i * FDIFF_AXES : NULL, acc ? acc + i * FDIFF_AXES : NULL);
    }
}
