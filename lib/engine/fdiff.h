/*
 * fdiff.h - forward-difference stepper for piecewise cubics (maths notes: lib/engine/DESIGN.md).
 *
 * Every segment the engine streams, whatever the method (Hoang B-spline,
 * second-derivative cubic spline, smoothstep transfer), is one cubic per axis
 * in a local parameter u in [0,1] spread over dur_s seconds:
 *
 *     k(u) = c[0] + c[1] u + c[2] u^2 + c[3] u^3,   u = (t - t0_s) / dur_s
 *
 * so velocity = k'(u) / dur_s and acceleration = k''(u) / dur_s^2.  The
 * stepper only ever sees these cubics.
 *
 * Stepping at a fixed du costs, per axis, three additions for position
 * (f += d1; d1 += d2; d2 += d3), two for velocity and one for acceleration.
 * Rounding drift grows with the number of steps (about n * eps * |k| for
 * position, see test_fdiff.c for the measured bound over the longest
 * segment); the engine re-seeds every FDIFF_RESEED_STEPS steps at
 * deterministic points (a multiple of FDIFF_RESEED_STEPS ticks after the
 * segment's first tick), so drift is bounded by that many steps whatever the
 * segment length.
 *
 * Pure: no allocation, no I/O.
 */
#ifndef TRAJD_FDIFF_H
#define TRAJD_FDIFF_H
/* trajd public API: installed as <trajd/fdiff.h> (make install; pkg-config trajd). */

#define FDIFF_AXES 3

/*
 * Steps between exact re-seeds in the engine.  At 1000 steps the drift of
 * the additions stays below ~1e3 * 2^-53 relative to the coordinates'
 * magnitude (measured in test_fdiff.c), while a seed (~40 flops per axis)
 * costs less than 0.1 % of the stepping.
 */
#define FDIFF_RESEED_STEPS 1000u

/* One cubic segment per axis over [t0_s, t0_s + dur_s]. */
typedef struct {
    double t0_s;             /* start time */
    double dur_s;            /* duration, > 0 */
    double c[FDIFF_AXES][4]; /* k(u) = c0 + c1 u + c2 u^2 + c3 u^3 */
} fdiff_seg_t;

/*
 * Forward-difference state for one segment and one step du, the axes as one
 * vector: a row holds one difference of position, velocity and acceleration
 * (x, y, z each), f the values themselves, d1, d2, d3 their first, second
 * and third differences (those the cubic has: velocity has no d3, nor
 * acceleration d2 or d3):
 *
 *     f  = p0 v0 a0 0      d1 = p1 v1 a1 0      d2 = p2 v2      d3 = p3
 *
 * (p0 = f[FDIFF_POS .. +2], v0 = f[FDIFF_VEL ..], a0 = f[FDIFF_ACC ..];
 * positions in m, velocities in m/s, accelerations in m/s^2).  A step is
 * f += d1, then d1 += d2 (its first six), then d2 += d3 (its first three):
 * 18 additions in 9 pairs of doubles the compiler emits as packed addpd
 * (SSE2; 16-byte-aligned rows), no lane wasted but the zero of f and d1
 * (10 doubles: whole pairs), and f is the output as a setpoint holds it
 * (pos_m, vel_m_s, acc_m_s2: nine doubles in a run).  The additions and
 * their order per axis are those of the per-axis stepper (p[3][4], v[3][3],
 * a[3][2], kept in tests/helpers/fdiff_aos.h as the reference it is checked
 * against), so every double is bit for bit what it made (test_fdiff; the
 * outputs: tests/e2e/test_outputs_frozen.sh).
 */
#define FDIFF_POS 0
#define FDIFF_VEL FDIFF_AXES
#define FDIFF_ACC (2 * FDIFF_AXES)
typedef struct {
    _Alignas(16) double f[3 * FDIFF_AXES + 1]; /* p0, v0, a0 and a zero */
    double d1[3 * FDIFF_AXES + 1];             /* p1, v1, a1 and a zero */
    double d2[2 * FDIFF_AXES];                 /* p2, v2 */
    double d3[FDIFF_AXES];                     /* p3 */
} fdiff_t;

/*
 * Seed fd at u0 with step du (both in units of u) for seg.
 * dur_s must be > 0 (the engine never builds a shorter segment).
 */
void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du);

/* Advance one step: 6 additions per axis, in 9 pairs and one more (see
 * fdiff_t). */
static inline void fdiff_step(fdiff_t *fd)
{
    /* unrolled also where it is inlined into a large function (engine_tick):
     * no loop */
#pragma GCC unroll 10
    for (int k = 0; k < 3 * FDIFF_AXES + 1; k++)
        fd->f[k] += fd->d1[k];
#pragma GCC unroll 6
    for (int k = 0; k < 2 * FDIFF_AXES; k++)
        fd->d1[k] += fd->d2[k];
#pragma GCC unroll 3
    for (int k = 0; k < FDIFF_AXES; k++)
        fd->d2[k] += fd->d3[k];
}

/* Current position, velocity and acceleration (any output may be NULL). */
void fdiff_get(const fdiff_t *fd, double *pos, double *vel, double *acc);

/*
 * Direct (Horner) evaluation of seg at u: the reference the stepper is
 * checked against, also used for exact end points.  Any output may be NULL.
 */
void fdiff_eval(const fdiff_seg_t *seg, double u, double *pos, double *vel, double *acc);

/*
 * Evaluate a sorted piecewise curve (segments in time order, possibly with
 * gaps between them) at n times by Horner; a time before the first segment
 * or in a gap takes the nearest segment end, after the last the last end.
 * For tests and tools (ctypes: segs is nseg x 14 doubles).
 * pos, vel, acc: n x FDIFF_AXES each (any may be NULL).
 */
void fdiff_eval_curve(const fdiff_seg_t *segs, unsigned long nseg, const double *t_s,
                      unsigned long n, double *pos, double *vel, double *acc);

#endif
