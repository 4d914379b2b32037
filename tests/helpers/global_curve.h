/*
 * global_curve.h - the engine's curves by one global solve of every waypoint
 * at once, built on the same row helpers as the engine's fragment window
 * (lib/engine/hoang.h, cubic.h): the references the tests and the benchmark
 * compare the streaming engine with (tests/oracle/test_spline.py through
 * libtrajd_test.so, test_fdiff.c, bench_engine.c).  Not in the product.
 */
#ifndef TRAJD_GLOBAL_CURVE_H
#define TRAJD_GLOBAL_CURVE_H

#include <stddef.h>

#include "cubic.h"
#include "hoang.h"

/*
 * The paper's global approach: solve every control point of N nodes at once
 * (Thomas on the whole system).  r: n x 3; p: n x 3 out (P*(0..N-1)).
 * v0_u, v1_u: end velocities in u units (CLAMPED; may be NULL otherwise).
 * scratch: 4n doubles.  Returns 0, -ENGINE_ECONFIG (n < 2), -ENGINE_ENUMERIC.
 */
int hoang_solve(size_t n, const double *r, engine_ends_t ends, const double *v0_u,
                const double *v1_u, double *p, double *scratch);

/*
 * The whole curve through N timed waypoints (t strictly increasing), with
 * the multiplicity expansion and the segments actually emitted, by one
 * global solve.  v0, v1: end velocities in m/s (CLAMPED; may be NULL).
 * segs: room for max_seg (N+3 always suffices); *nseg receives the count.
 * Allocates its work memory (not for a periodic path).
 * Returns 0, -ENGINE_ECONFIG (n < 2 or max_seg too small), -ENGINE_ENOMEM,
 * -ENGINE_ENUMERIC.
 */
int hoang_curve(size_t n, const double *t_s, const double *r, engine_ends_t ends, const double *v0,
                const double *v1, fdiff_seg_t *segs, size_t max_seg, size_t *nseg);

/*
 * The whole curve through N timed waypoints (t strictly increasing) by one
 * global solve.  v0, v1: end velocities in m/s (CLAMPED; may be NULL).
 * segs: room for N-1.  Allocates its work memory.
 * Returns 0, -ENGINE_ECONFIG (n < 2, max_seg too small, HELD or MULTIPLE),
 * -ENGINE_ENOMEM, -ENGINE_ENUMERIC.
 */
int cubic_curve(size_t n, const double *t_s, const double *r, engine_param_t param,
                engine_ends_t ends, const double *v0, const double *v1, fdiff_seg_t *segs,
                size_t max_seg, size_t *nseg);

#endif
