/* fdiff.c - forward-difference stepper; see fdiff.h. */
#include "fdiff.h"

#include <stddef.h>
#include <string.h>

/* Two lanes of a row (x and y). */
typedef double lane2_t __attribute__((vector_size(16)));

/* The differences of the cubic c0 + c1 u + c2 u^2 + c3 u^3 at u for the step
 * h (h2 = h h, h3 = h2 h), written in closed form (exact algebra, no
 * cancellation of k(u+h) - k(u) on large values), for one axis (T double)
 * or two (T lane2_t, the scalars broadcast): every lane computes what the
 * scalar expressions compute, operation by operation. */
#define SEED_ROWS(T, r, c0, c1, c2, c3)                                                            \
    do {                                                                                           \
        r[0] = c0 + u * (c1 + u * (c2 + u * c3));                                                  \
        r[1] = c1 * h + c2 * (2 * u * h + h2) + c3 * (3 * u * u * h + 3 * u * h2 + h3);            \
        r[2] = 2 * c2 * h2 + c3 * (6 * u * h2 + 6 * h3);                                           \
        r[3] = 6 * c3 * h3;                                                                        \
        /* k'(u) = c1 + 2 c2 u + 3 c3 u^2, a quadratic */                                          \
        r[4] = (c1 + u * (2 * c2 + u * 3 * c3)) * inv_t;                                           \
        r[5] = (2 * c2 * h + 3 * c3 * (2 * u * h + h2)) * inv_t;                                   \
        r[6] = 6 * c3 * h2 * inv_t;                                                                \
        /* k''(u) = 2 c2 + 6 c3 u, a line */                                                       \
        r[7] = (2 * c2 + 6 * c3 * u) * inv_t2;                                                     \
        r[8] = 6 * c3 * h * inv_t2;                                                                \
    } while (0)

void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du)
{
    double inv_t = 1.0 / seg->dur_s, inv_t2 = inv_t * inv_t;
    double h = du, h2 = du * du, h3 = h2 * du, u = u0;
    const double(*c)[4] = seg->c;
    lane2_t xy[9];
    double z[9];
    double *rows[9] = {fd->p0, fd->p1, fd->p2, fd->p3, fd->v0, fd->v1, fd->v2, fd->a0, fd->a1};

    _Static_assert(FDIFF_AXES == 3 && FDIFF_LANES == 4, "x, y in one pair; z, 0 in the other");
    SEED_ROWS(lane2_t, xy, ((lane2_t){c[0][0], c[1][0]}), ((lane2_t){c[0][1], c[1][1]}),
              ((lane2_t){c[0][2], c[1][2]}), ((lane2_t){c[0][3], c[1][3]}));
    SEED_ROWS(double, z, c[2][0], c[2][1], c[2][2], c[2][3]);
#pragma GCC unroll 9
    for (int i = 0; i < 9; i++) {
        lane2_t zw = {z[i], 0.0}; /* the zero lane stays zero */
        memcpy(rows[i], &xy[i], sizeof xy[i]);
        memcpy(rows[i] + 2, &zw, sizeof zw);
    }
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
