/*
 * hermite.h - the local methods (issue 31): a C1 cubic Hermite segment
 * between two waypoints from their positions and velocities, and the
 * velocities estimated from the waypoints around each one where the source
 * sends none.  Each segment depends only on its two waypoints and their
 * velocities, so the curve is final one or two waypoints after a segment's
 * end instead of a fragment's lookahead later; it passes exactly through
 * every waypoint and its velocity is continuous (each waypoint's velocity is
 * computed once and shared by the segments on both sides), its acceleration
 * is not (C1, not C2).
 *
 * Velocity estimates, with h1, h2 the intervals before and after waypoint i
 * and d1, d2 the chord velocities over them (the derivative at t_i of the
 * parabola through three waypoints, second-order accurate):
 *   backward (HERMITE)          v_i = d2 + h2 (d2 - d1) / (h1 + h2), from
 *                               waypoints i-2, i-1, i (h1, d1 then the
 *                               interval i-2..i-1, h2, d2 the one to i);
 *   centred (HERMITE_CENTRED)   v_i = (h2 d1 + h1 d2) / (h1 + h2), from
 *                               waypoints i-1, i, i+1.
 * A trajectory's end: ENGINE_ENDS_REST 0, CLAMPED the configured velocity,
 * NATURAL the one that makes k'' = 0 there: v0 = (3 d - v1) / 2 for the
 * segment's chord velocity d and far-end velocity v1.
 *
 * Pure maths: no state, no I/O.
 */
#ifndef TRAJD_HERMITE_H
#define TRAJD_HERMITE_H

#include "fdiff.h"

/* v = derivative at the last of three waypoints (t0 < t1 < t2) */
void hermite_vel_backward(double t0, const double *p0, double t1, const double *p1, double t2,
                          const double *p2, double *v);

/* v = derivative at the middle of three waypoints */
void hermite_vel_centred(double t0, const double *p0, double t1, const double *p1, double t2,
                         const double *p2, double *v);

/* v = the chord velocity (p1 - p0) / (t1 - t0) */
void hermite_vel_chord(double t0, const double *p0, double t1, const double *p1, double *v);

/* v0 = (3 d - v1) / 2: the end velocity with zero acceleration at the end
 * whose far end has velocity v1 (d the chord velocity) */
void hermite_vel_natural(double t0, const double *p0, double t1, const double *p1, const double *v1,
                         double *v0);

/* The cubic from (t0, p0, v0) to (t0 + dur, p1, v1) in fdiff's form. */
void hermite_segment(const double *p0, const double *v0, const double *p1, const double *v1,
                     double t0, double dur, fdiff_seg_t *seg);

/* a = the second derivative of the parabola through three waypoints
 * (2 (d2 - d1) / (h1 + h2)): the acceleration estimate of the C2 methods. */
void hermite_acc_parabola(double t0, const double *p0, double t1, const double *p1, double t2,
                          const double *p2, double *a);

/*
 * The C2 methods (HERMITE_C2, HERMITE_C2_CENTRED): the curve from (t0, p0,
 * v0, a0) to (t0 + dur, p1, v1, a1) as three cubics of dur/3, each of
 * constant jerk, continuous in position, velocity and acceleration at the
 * two inner joins: the same data and continuity as the quintic Hermite,
 * carried by the cubic stepper (a cubic spline with two inner knots, the
 * only one such for the six end conditions).  In units of the piece, tau =
 * dur/3, V = v tau, A = a tau^2, J = j tau^3, the end state after three
 * pieces is affine in J1..J3; with ra = A1 - A0, rv = V1 - V0 - 3 A0, rp =
 * P1 - P0 - 3 V0 - 9/2 A0:
 *     J1 = rp - rv + ra/3,  J2 = 3 rv - 2 rp - 7/6 ra,  J3 = rp - 2 rv + 11/6 ra.
 * seg[3] receives the pieces.
 */
void hermite_c2_segments(const double *p0, const double *v0, const double *a0, const double *p1,
                         const double *v1, const double *a1, double t0, double dur,
                         fdiff_seg_t seg[3]);

#endif
