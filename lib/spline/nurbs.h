/*
 * nurbs.h - rational B-splines (seed 004): circles, arcs and conics exactly.
 *
 *   r(t) = sum_k w_k N_k^q(t) P_k / sum_j w_j N_j^q(t)
 *
 * with the B-spline basis of lib/spline/bspline.h (same order/knot conventions) and
 * positive weights.  A quadratic rational Bezier piece (P0, P1, P2; weights
 * 1, w, 1) is an ellipse arc for w < 1, a parabola for w = 1, a hyperbola for
 * w > 1; with w = cos(phi) and P1 at the intersection of the tangents it is a
 * circular arc of angle 2 phi.  The seed's circle is four such quarter arcs.
 *
 * On a circular arc piece of half-angle phi the parameter is not
 * proportional to the angle: the point at local parameter s in [0,1] sits at
 * the angle  theta = mid + 2 atan((2s - 1) tan(phi/2))  from the piece's
 * middle (the stereographic projection is linear in s for a rational
 * quadratic circle).  nurbs_arc_param() inverts this, so a caller can sample
 * exactly at chosen angles (uniform speed) and still evaluate the NURBS.
 *
 * No allocation: caller memory throughout.
 */
#ifndef TRAJD_NURBS_H
#define TRAJD_NURBS_H
/* trajd public API: installed as <trajd/nurbs.h> (make install; pkg-config trajd). */

#include <stddef.h>

#include "bspline.h"

enum nurbs_error {
    NURBS_OK = 0,
    NURBS_EBSPLINE = 1, /* the underlying B-spline is invalid (see bspline_check) */
    NURBS_EWEIGHT = 2,  /* a weight not finite or not positive */
    NURBS_EDOMAIN = 3,  /* parameter outside the domain or not finite */
    NURBS_ESIZE = 4,    /* derivative count above 2, or dim above NURBS_DIM_MAX */
    NURBS_EARG = 5,     /* arc: radius <= 0, sweep 0 or above 2 pi, not finite */
};

/* Coordinates of one control point at most (homogeneous work on the stack). */
#define NURBS_DIM_MAX 8

/* Quarter-turn pieces an arc may use: at most 4, so a full circle has 9 poles. */
#define NURBS_ARC_PIECES_MAX 4
/* Sizes for nurbs_arc output buffers. */
#define NURBS_ARC_CTRL_MAX (2 * NURBS_ARC_PIECES_MAX + 1)
#define NURBS_ARC_KNOTS_MAX (NURBS_ARC_CTRL_MAX + 3)

const char *nurbs_strerror(int err);

typedef struct {
    unsigned order; /* q (2 for conics) */
    size_t n_ctrl;
    size_t dim;          /* 1 .. NURBS_DIM_MAX */
    const double *knots; /* n_ctrl + order */
    const double *ctrl;  /* n_ctrl * dim, Cartesian (not pre-multiplied by w) */
    const double *w;     /* n_ctrl weights > 0 */
} nurbs_t;

/* Check the B-spline part, dim and every weight.  Returns 0, -NURBS_EBSPLINE,
 * -NURBS_EWEIGHT, -NURBS_ESIZE. */
int nurbs_check(const nurbs_t *c);

/*
 * Point at t (out: dim values).  The denominator sum w_j N_j(t) is a convex
 * combination of positive weights (the basis is a partition of unity), so it
 * is at least min(w) > 0: no division by zero.
 * Returns 0, -NURBS_EDOMAIN, -NURBS_EBSPLINE (order), -NURBS_ESIZE.
 * Weights are not re-checked here (O(n)); call nurbs_check once.
 */
int nurbs_eval(const nurbs_t *c, double t, double *out);

/* Point and derivatives up to nder <= 2 (and < order): out[d*dim + k].
 * Returns as nurbs_eval. */
int nurbs_eval_derivs(const nurbs_t *c, double t, unsigned nder, double *out);

/*
 * The seed's unit circle: 9 poles (the corners and edge midpoints of the
 * square around it, last = first), weights alternating 1 and sqrt(2)/2,
 * knots (0,0,0,1/4,1/4,1/2,1/2,3/4,3/4,1,1,1), order 3.
 * knots: 12, ctrl: 18 (x,y), w: 9.  c (if not NULL) is set to view them.
 */
void nurbs_unit_circle(double *knots, double *ctrl, double *w, nurbs_t *c);

/*
 * Circular arc in the plane: centre (cx, cy), radius r_m, from angle start_rad
 * sweeping sweep_rad (positive = counter-clockwise, |sweep| <= 2 pi), as
 * ceil(|sweep| / (pi/2)) rational quadratic pieces on knots over [0, 1].
 * dim 2 (x, y) or 3 (x, y, z = cz constant); cz ignored for dim 2.
 * knots: NURBS_ARC_KNOTS_MAX, ctrl: NURBS_ARC_CTRL_MAX*dim, w: NURBS_ARC_CTRL_MAX.
 * c receives the curve (order 3, n_ctrl = 2*pieces + 1).
 * Returns 0, -NURBS_EARG.
 */
int nurbs_arc(double cx, double cy, double cz, size_t dim, double r_m, double start_rad,
              double sweep_rad, double *knots, double *ctrl, double *w, nurbs_t *c);

/*
 * Parameter t in [0, 1] of the arc built by nurbs_arc(start, sweep) at which
 * the point lies at angle start + frac*sweep (frac in [0, 1]).  Exact up to
 * rounding (closed form above, one atan/tan per call).
 */
double nurbs_arc_param(double sweep_rad, double frac);

/*
 * General conic arc: the rational quadratic Bezier (P0, P1, P2), weights
 * (1, w1, 1), knots (0,0,0,1,1,1).  w1 < 1 ellipse, = 1 parabola, > 1 hyperbola.
 * p: the three points (3*dim), copied into ctrl (3*dim); knots 6; w 3.
 * Returns 0, -NURBS_EWEIGHT (w1 <= 0 or not finite), -NURBS_ESIZE.
 */
int nurbs_conic(const double *p, size_t dim, double w1, double *knots, double *ctrl, double *w,
                nurbs_t *c);

#endif
