/* fdiff.c - forward-difference stepper; see fdiff.h. */
#include "fdiff.h"

#include <string.h>

/* Two lanes of a row (x and y). */
typedef double lane2_t __attribute__((vector_size(16)));

/*
 * The differences of the cubic c0 + c1 u + c2 u^2 + c3 u^3 at u for the step
 * h (h2 = h h, h3 = h2 h), written in closed form (exact algebra, no
 * cancellation of k(u+h) - k(u) on large values), for a pair of lanes (the
 * scalars broadcast): each lane computes, operation by operation, what
 * these expressions do for its axis,
 *     p0 = c0 + u (c1 + u (c2 + u c3))
 *     p1 = c1 h + c2 (2 u h + h2) + c3 (3 u u h + 3 u h2 + h3)
 *     p2 = 2 c2 h2 + c3 (6 u h2 + 6 h3)
 *     p3 = 6 c3 h3
 *     v0 = (c1 + u (2 c2 + u 3 c3)) inv_t           k'(u), a quadratic
 *     v1 = (2 c2 h + 3 c3 (2 u h + h2)) inv_t
 *     v2 = 6 c3 h2 inv_t
 *     a0 = (2 c2 + 6 c3 u) inv_t2                   k''(u), a line
 *     a1 = 6 c3 h inv_t2
 * each product and sum left to right, the parts common to the axes (x, y,
 * zz, u3) worked out once.
 */
static inline void seed_pair(lane2_t r[9], lane2_t c0, lane2_t c1, lane2_t c2, lane2_t c3, double u,
                             double h, double h2, double h3, double inv_t, double inv_t2)
{
    double x = 2 * u * h + h2, y = 3 * u * u * h + 3 * u * h2 + h3, zz = 6 * u * h2 + 6 * h3;
    double u3 = u * 3;
    lane2_t c2x2 = 2 * c2, c3x3 = 3 * c3, c3x6 = 6 * c3;
    r[0] = c0 + u * (c1 + u * (c2 + u * c3));
    r[1] = c1 * h + c2 * x + c3 * y;
    r[2] = c2x2 * h2 + c3 * zz;
    r[3] = c3x6 * h3;
    r[4] = (c1 + u * (c2x2 + u3 * c3)) * inv_t;
    r[5] = (c2x2 * h + c3x3 * x) * inv_t;
    r[6] = c3x6 * h2 * inv_t;
    r[7] = (c2x2 + c3x6 * u) * inv_t2;
    r[8] = c3x6 * h * inv_t2;
}

void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du)
{
    double inv_t = 1.0 / seg->dur_s, inv_t2 = inv_t * inv_t;
    double h = du, h2 = du * du, h3 = h2 * du, u = u0;
    const double(*c)[4] = seg->c;
    lane2_t r[9];
    /* where seed_pair's r[i] goes: row, and the place of x in it */
    double *at[9] = {fd->f + FDIFF_POS, fd->d1 + FDIFF_POS, fd->d2 + FDIFF_POS, fd->d3,
                     fd->f + FDIFF_VEL, fd->d1 + FDIFF_VEL, fd->d2 + FDIFF_VEL, fd->f + FDIFF_ACC,
                     fd->d1 + FDIFF_ACC};

    _Static_assert(FDIFF_AXES == 3, "x, y in one pair; z in the other");
    seed_pair(r, (lane2_t){c[0][0], c[1][0]}, (lane2_t){c[0][1], c[1][1]},
              (lane2_t){c[0][2], c[1][2]}, (lane2_t){c[0][3], c[1][3]}, u, h, h2, h3, inv_t,
              inv_t2);
#pragma GCC unroll 9
    for (int i = 0; i < 9; i++)
        memcpy(at[i], &r[i], sizeof r[i]);
    /* z in the first lane (the second's 0 unused) */
    seed_pair(r, (lane2_t){c[2][0], 0.0}, (lane2_t){c[2][1], 0.0}, (lane2_t){c[2][2], 0.0},
              (lane2_t){c[2][3], 0.0}, u, h, h2, h3, inv_t, inv_t2);
#pragma GCC unroll 9
    for (int i = 0; i < 9; i++)
        at[i][2] = r[i][0];
    fd->f[3 * FDIFF_AXES] = fd->d1[3 * FDIFF_AXES] = 0.0; /* the zeros */
}

void fdiff_get(const fdiff_t *fd, double *pos, double *vel, double *acc)
{
    for (int k = 0; k < FDIFF_AXES; k++) {
        if (pos)
            pos[k] = fd->f[FDIFF_POS + k];
        if (vel)
            vel[k] = fd->f[FDIFF_VEL + k];
        if (acc)
            acc[k] = fd->f[FDIFF_ACC + k];
    }
}

/* fdiff_eval's expressions for a pair of lanes (u and inv_t broadcast),
 * each lane operation by operation what they are for its axis. */
static inline void eval_pair(lane2_t c0, lane2_t c1, lane2_t c2, lane2_t c3, double u, double inv_t,
                             lane2_t *p, lane2_t *v, lane2_t *a)
{
    *p = c0 + u * (c1 + u * (c2 + u * c3));
    *v = (c1 + u * (2 * c2 + u * 3 * c3)) * inv_t;
    *a = (2 * c2 + 6 * c3 * u) * inv_t * inv_t;
}

void fdiff_eval(const fdiff_seg_t *seg, double u, double *pos, double *vel, double *acc)
{
    double inv_t = 1.0 / seg->dur_s;
    const double(*c)[4] = seg->c;
    lane2_t p, v, a, pz, vz, az; /* x, y; and z (its second lane unused) */

    _Static_assert(FDIFF_AXES == 3, "x, y in one pair; z in the other");
    eval_pair((lane2_t){c[0][0], c[1][0]}, (lane2_t){c[0][1], c[1][1]}, (lane2_t){c[0][2], c[1][2]},
              (lane2_t){c[0][3], c[1][3]}, u, inv_t, &p, &v, &a);
    eval_pair((lane2_t){c[2][0], 0.0}, (lane2_t){c[2][1], 0.0}, (lane2_t){c[2][2], 0.0},
              (lane2_t){c[2][3], 0.0}, u, inv_t, &pz, &vz, &az);
    if (pos) {
        memcpy(pos, &p, sizeof p);
        pos[2] = pz[0];
    }
    if (vel) {
        memcpy(vel, &v, sizeof v);
        vel[2] = vz[0];
    }
    if (acc) {
        memcpy(acc, &a, sizeof a);
        acc[2] = az[0];
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
