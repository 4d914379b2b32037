/*
 * hoang.h - exact interpolation with a uniform cubic B-spline (Hoang Thai Ho
 * 2016, seed 003; maths notes in lib/engine/DESIGN.md).
 *
 * Control points P*(j) solve, for every interior node j,
 *
 *     P*(j-1) + 4 P*(j) + P*(j+1) = 6 R(j)
 *
 * so that the segment from node j to j+1, driven by P*(j-1..j+2) with the
 * uniform cubic B-spline matrix, starts on R(j) and ends on R(j+1).  Each
 * segment is mapped linearly onto its own time interval [t(j), t(j+1)]
 * (parameterisation (a)): C2 in u, but where consecutive intervals differ
 * the physical velocity jumps at the node by the ratio of the intervals.
 *
 * End conditions (engine_ends_t):
 *   HELD     the paper: P*(0) = R(0), P*(N-1) = R(N-1); the curve spans
 *            R(1) .. R(N-2) (the first and last segments are not emitted).
 *            Note: P*(0) = R(0) is exactly the natural condition (k''=0)
 *            written at node 0; HELD is NATURAL minus its two end segments.
 *   MULTIPLE the paper: R(0) and R(N-1) repeated twice more (N+4 nodes) with
 *            HELD ends; the segments between copies of one point are loops
 *            of zero duration and are never emitted, so the curve runs
 *            R(0) .. R(N-1).
 *   NATURAL  k''(u) = 0 at both ends: rows P*(0) = R(0), P*(N-1) = R(N-1),
 *            ghosts P*(-1) = 2P*(0) - P*(1), P*(N) = 2P*(N-1) - P*(N-2).
 *   CLAMPED  k'(u) = v * T at the ends (v in m/s, T the end interval):
 *            rows 4P*(0) + 2P*(1) = 6R(0) + 2vT, ghosts P*(-1) = P*(1) - 2vT.
 *   REST     CLAMPED with v = 0.
 *
 * The row helpers are shared by the global solve here and by the engine's
 * fragment window, so both solve the same system.
 */
#ifndef TRAJD_HOANG_H
#define TRAJD_HOANG_H

#include <stddef.h>

#include "engine.h"
#include "fdiff.h"
#include "frag.h"

/* Interior row j: 1 4 1 | 6 R(j). */
void hoang_row_interior(const double *r, frag_row_t *row);

/* True start row at node 0; v0_u = start velocity * T(0) (dk/du). */
void hoang_row_start(engine_ends_t ends, const double *r0, const double *v0_u, frag_row_t *row);

/* True end row at the last node; v1_u = end velocity * T(last interval). */
void hoang_row_end(engine_ends_t ends, const double *rl, const double *v1_u, frag_row_t *row);

/* Ghost control point before node 0 (p0 = P*(0), p1 = P*(1)). */
void hoang_ghost_start(engine_ends_t ends, const double *p0, const double *p1, const double *v0_u,
                       double *out);

/* Ghost control point after the last node (pl = P*(L), pm = P*(L-1)). */
void hoang_ghost_end(engine_ends_t ends, const double *pm, const double *pl, const double *v1_u,
                     double *out);

/* Segment from the four control points p[0..3] = P*(j-1 .. j+2). */
void hoang_segment(const double *p0, const double *p1, const double *p2, const double *p3,
                   double t0_s, double dur_s, fdiff_seg_t *seg);

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

#endif
