/*
 * fdiff.h - forward-difference stepper for piecewise cubics (MATH.md section 4).
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
    double t0_s;                 /* start time */
    double dur_s;                /* duration, > 0 */
    double c[FDIFF_AXES][4];     /* k(u) = c0 + c1 u + c2 u^2 + c3 u^3 */
} fdiff_seg_t;

/* Forward-difference state for one segment and one step du. */
typedef struct {
    double p[FDIFF_AXES][4];     /* position f, d1, d2, d3 */
    double v[FDIFF_AXES][3];     /* velocity f, d1, d2 (m/s) */
    double a[FDIFF_AXES][2];     /* acceleration f, d1 (m/s^2) */
} fdiff_t;

/*
 * Seed fd at u0 with step du (both in units of u) for seg.
 * dur_s must be > 0 (the engine never builds a shorter segment).
 */
void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du);

/* Advance one step: 6 additions per axis. */
static inline void fdiff_step(fdiff_t *fd)
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

/* Current position, velocity and acceleration (any output may be NULL). */
void fdiff_get(const fdiff_t *fd, double *pos, double *vel, double *acc);

/*
 * Direct (Horner) evaluation of seg at u: the reference the stepper is
 * checked against, also used for exact end points.  Any output may be NULL.
 */
void fdiff_eval(const fdiff_seg_t *seg, double u, double *pos, double *vel,
                double *acc);

/*
 * Evaluate a sorted piecewise curve (segments in time order, possibly with
 * gaps between them) at n times by Horner; a time before the first segment
 * or in a gap takes the nearest segment end, after the last the last end.
 * For tests and tools (ctypes: segs is nseg x 14 doubles).
 * pos, vel, acc: n x FDIFF_AXES each (any may be NULL).
 */
void fdiff_eval_curve(const fdiff_seg_t *segs, unsigned long nseg,
                      const double *t_s, unsigned long n, double *pos,
                      double *vel, double *acc);

#endif
