/*
 * cubic.h - the interpolating C2 cubic spline of seed 002 (system 5.18), in
 * second-derivative form: unknowns M(j) = k''(s) at node j, where s is the
 * spline's parameter and h(j) = s(j+1) - s(j):
 *
 *   h(j-1) M(j-1) + 2 (h(j-1) + h(j)) M(j) + h(j) M(j+1)
 *        = 6 ((R(j+1) - R(j)) / h(j) - (R(j) - R(j-1)) / h(j-1))
 *
 * Two parameterisations:
 *   ENGINE_PARAM_TIME     s = the timestamps, h(j) = T(j): knots at the
 *                         timestamps, C2 in physical time.  This is the same
 *                         curve as the interpolating non-uniform cubic
 *                         B-spline on those knots (the C2 cubic interpolant
 *                         with given end conditions is unique; test_spline.py
 *                         checks it against scipy's make_interp_spline, which
 *                         solves for B-spline coefficients).
 *   ENGINE_PARAM_UNIFORM  s = node index, h = 1, each segment mapped onto its
 *                         time interval (same curve as the Hoang B-spline
 *                         with the same end condition).
 *
 * End conditions: NATURAL (M = 0), CLAMPED (k' = v at the ends, v in m/s),
 * REST (CLAMPED with v = 0).  HELD and MULTIPLE are the paper's handling of
 * the B-spline control polygon; they have no meaning for this form and are
 * refused by engine_config_check.
 *
 * The row helpers are shared by the global solve here and by the engine's
 * fragment window.
 */
#ifndef TRAJD_CUBIC_H
#define TRAJD_CUBIC_H

#include <stddef.h>

#include "engine.h"
#include "fdiff.h"
#include "frag.h"

/* Interior row at node j: h0 = h(j-1), h1 = h(j); rm, r, rp = R(j-1..j+1). */
void cubic_row_interior(double h0, double h1, const double *rm, const double *r, const double *rp,
                        frag_row_t *row);

/* Start row at node 0; v0_s = dk/ds at the start (velocity * T(0) / h(0)). */
void cubic_row_start(engine_ends_t ends, double h0, const double *r0, const double *r1,
                     const double *v0_s, frag_row_t *row);

/* End row at the last node L; h = h(L-1); v1_s = dk/ds at the end. */
void cubic_row_end(engine_ends_t ends, double h, const double *rm, const double *rl,
                   const double *v1_s, frag_row_t *row);

/* Segment between nodes with positions r0, r1, second derivatives m0, m1
 * (per s), parameter step h, mapped onto [t0_s, t0_s + dur_s]. */
void cubic_segment(const double *r0, const double *r1, const double *m0, const double *m1, double h,
                   double t0_s, double dur_s, fdiff_seg_t *seg);

/*
 * Join seg to the segment before it: its velocity at the start becomes v0
 * (m/s), its positions at both ends and its velocity at the end are kept (the
 * cubic Hermite segment of those four).  Where fragments meet (frag.h), the
 * second derivatives of the nodes about a junction come from different
 * fragments and the rows there do not hold exactly: the curve steps in
 * velocity at those nodes, by about rho^(O/2) of the curvature scale (135 m/s
 * at overlap 2 on a track of 100 m/s chords).  Joined, it is continuous in
 * velocity (and steps in acceleration instead, by the same residual).
 * Returns 1 if seg changed, 0 if it already started at v0.
 */
int cubic_join(fdiff_seg_t *seg, const double *v0);

#endif
