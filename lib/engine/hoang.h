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
 * The row helpers are shared by the engine's fragment window and the global
 * solve the tests compare it with (tests/helpers/global_curve.h), so both
 * solve the same system.
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

#endif
