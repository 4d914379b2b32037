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
 * vector: each difference is a row of FDIFF_LANES doubles (x, y, z and a zero
 * lane), struct-of-arrays, so a step is 6 vector additions of whole rows.
 * Why that is faster than the previous per-axis layout (p[3][4], v[3][3],
 * a[3][2], kept in tests/bench/bench_engine.c as the reference it is timed
 * against): there, one axis's f, d1, d2, d3 were adjacent, so the compiler
 * could only emit 18 scalar addsd, each a load-add-store with a dependency
 * on the previous difference of the same axis; here a row is 32 contiguous
 * 16-byte-aligned bytes and the same 6 statements become 12 packed addpd
 * (SSE2, 2 doubles each; 6 vaddpd with AVX), with the 3 axes in independent
 * lanes.  The additions and their order per axis are the same, so every
 * double is bit for bit what the per-axis stepper made (test_fdiff checks it
 * against the previous layout; tests/e2e/test_outputs_frozen.sh the outputs).
 */
#define FDIFF_LANES 4
typedef struct {
    _Alignas(16) double p0[FDIFF_LANES]; /* position f */
    double p1[FDIFF_LANES];              /* position d1, d2, d3 */
    double p2[FDIFF_LANES];
    double p3[FDIFF_LANES];
    double v0[FDIFF_LANES]; /* velocity f, d1, d2 (m/s) */
    double v1[FDIFF_LANES];
    double v2[FDIFF_LANES];
    double a0[FDIFF_LANES]; /* acceleration f, d1 (m/s^2) */
    double a1[FDIFF_LANES];
} fdiff_t;

/*
 * Seed fd at u0 with step du (both in units of u) for seg.
 * dur_s must be > 0 (the engine never builds a shorter segment).
 */
void fdiff_seed(fdiff_t *fd, const fdiff_seg_t *seg, double u0, double du);

/* Advance one step: 6 additions per axis, as 6 row additions. */
static inline void fdiff_step(fdiff_t *fd)
{
    /* unrolled also where it is inlined into a large function (engine_tick):
     * 12 addpd, no loop */
#pragma GCC unroll 4
    for (int k = 0; k < FDIFF_LANES; k++) {
        fd->p0[k] += fd->p1[k];
        fd->p1[k] += fd->p2[k];
        fd->p2[k] += fd->p3[k];
        fd->v0[k] += fd->v1[k];
        fd->v1[k] += fd->v2[k];
        fd->a0[k] += fd->a1[k];
    }
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
