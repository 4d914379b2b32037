/*
 * bspline.h - B-splines of any order on any knot vector (seed 000).
 *
 * Notation follows the seed: order q (polynomial degree q-1), control points
 * p_0 .. p_n (n_ctrl = n+1 of them), knots t_0 .. t_{n+q} (n_ctrl + q values,
 * non-decreasing).  The curve r(t) = sum_k N_k^q(t) p_k is defined on
 * [t_{q-1}, t_{n+1}], the only interval where the basis sums to one.
 *
 * Basis functions are computed by the Cox-de Boor recursion (seed formula 2,
 * with 0/0 taken as 0), in its triangular form: only the q functions that
 * are non-zero at t are built.  A knot repeated m times lowers the
 * continuity there to C^{q-1-m}.
 *
 * Intervals are half-open [t_k, t_{k+1}), except that the right end of the
 * domain t_{n+1} belongs to the last non-empty interval, so the curve is
 * defined (and continuous from the left) at its end point.
 *
 * No allocation anywhere: the knots and control points belong to the caller
 * and every evaluator works on the stack (order <= BSPLINE_ORDER_MAX).
 */
#ifndef TRAJD_BSPLINE_H
#define TRAJD_BSPLINE_H
/* trajd public API: installed as <trajd/bspline.h> (make install; pkg-config trajd). */

#include <stddef.h>

enum bspline_error {
    BSPLINE_OK = 0,
    BSPLINE_EORDER = 1,  /* order 0 or above BSPLINE_ORDER_MAX, or more than n_ctrl */
    BSPLINE_EKNOTS = 2,  /* knots not finite or decreasing, or an empty domain */
    BSPLINE_ESIZE = 3,   /* n_ctrl, dim or a derivative count out of range */
    BSPLINE_EDOMAIN = 4, /* parameter outside [t_{q-1}, t_{n+1}] or not finite */
};

/* Highest order handled (degree 15): evaluation keeps q x q values on the stack. */
#define BSPLINE_ORDER_MAX 16

/*
 * A parameter this far (relative to the domain length) outside the domain is
 * clamped onto it instead of refused: a t computed as t_min + i*h can land an
 * ulp or two past t_max.
 */
#define BSPLINE_DOMAIN_REL_TOL 1e-12

/* Human-readable text for a bspline_error (positive or negated). */
const char *bspline_strerror(int err);

/* A curve: everything belongs to the caller. */
typedef struct {
    unsigned order;      /* q >= 1: degree q-1 */
    size_t n_ctrl;       /* n+1 >= q control points */
    size_t dim;          /* coordinates per control point, >= 1 */
    const double *knots; /* n_ctrl + order values, non-decreasing */
    const double *ctrl;  /* n_ctrl * dim values, row-major (ctrl[k*dim + c]) */
} bspline_t;

/*
 * Check order, sizes and the knot vector.
 * Returns 0, -BSPLINE_EORDER, -BSPLINE_ESIZE (n_ctrl or dim 0),
 * -BSPLINE_EKNOTS (a knot not finite, decreasing, or t_{q-1} == t_{n+1}).
 */
int bspline_check(const bspline_t *b);

/* Domain [t_{q-1}, t_{n+1}] of a checked curve. */
void bspline_domain(const bspline_t *b, double *t_min, double *t_max);

/*
 * Uniform knots t_k = t0_s + k*dt (n_ctrl + order of them): a periodic
 * B-spline in the seed's sense (every basis function a shift of the first).
 * Returns 0, -BSPLINE_ESIZE (no knot), -BSPLINE_EKNOTS (dt <= 0 or not finite).
 */
int bspline_knots_uniform(size_t n_ctrl, unsigned order, double t0, double dt, double *knots);

/*
 * Open uniform integer knots, the seed's generator formula (n = n_ctrl-1, q = order):
 *   t_k = 0          for 0 <= k < q
 *   t_k = k - q + 1  for q <= k <= n
 *   t_k = n - q + 2  for n < k <= n + q
 * With q = n+1 this is (0..0, 1..1): the Bezier curve of the control points.
 * Returns 0, -BSPLINE_EORDER (order 0, too high, or > n_ctrl).
 */
int bspline_knots_open_uniform(size_t n_ctrl, unsigned order, double *knots);

/*
 * Clamped knots on breakpoints (as gsl_bspline_knots): breaks[0] and
 * breaks[nbreak-1] repeated `order` times, interior breakpoints once.
 * n_ctrl = nbreak + order - 2; knots receives nbreak + 2*order - 2 values.
 * Returns 0, -BSPLINE_EORDER, -BSPLINE_ESIZE (nbreak < 2),
 * -BSPLINE_EKNOTS (breakpoints not finite or not increasing).
 */
int bspline_knots_clamped(const double *breaks, size_t nbreak, unsigned order, double *knots);

/*
 * Index mu of the knot interval holding t: t_mu <= t < t_{mu+1} with
 * q-1 <= mu <= n (the right end t_{n+1} maps to the last non-empty interval).
 * The q non-zero basis functions at t are N_{mu-q+1} .. N_mu.
 * t must lie in the domain (clamped by BSPLINE_DOMAIN_REL_TOL);
 * returns mu >= 0 or -BSPLINE_EDOMAIN.  Binary search: O(log n).
 */
long bspline_find_span(const double *knots, size_t n_ctrl, unsigned order, double t);

/*
 * One basis function N_k^q(t) by the literal recursion of the seed (formula 2,
 * 0/0 = 0), for any t (0 outside its support).  Exponential in q: for tests
 * and teaching; use bspline_basis for work.  n_knots: length of knots;
 * requires k + order < n_knots.  Returns NaN on bad arguments.
 * Intervals are half-open except the last non-empty one of the knot vector,
 * consistent with bspline_find_span.
 */
double bspline_basis_one(const double *knots, size_t n_knots, size_t k, unsigned order, double t);

/*
 * The q basis functions non-zero at t: N[j] = N_{first+j}^q(t), j = 0..q-1.
 * Returns 0, -BSPLINE_EORDER, -BSPLINE_EDOMAIN.  *first = mu - q + 1.
 */
int bspline_basis(const double *knots, size_t n_ctrl, unsigned order, double t, size_t *first,
                  double *N);

/*
 * The q non-zero basis functions and their derivatives up to nder at t:
 * ders[d*order + j] = d^d/dt^d N_{first+j}^q(t), d = 0..nder (nder < order;
 * higher derivatives of a degree q-1 polynomial are 0 and are refused).
 * Returns 0, -BSPLINE_EORDER, -BSPLINE_ESIZE (nder >= order), -BSPLINE_EDOMAIN.
 */
int bspline_basis_derivs(const double *knots, size_t n_ctrl, unsigned order, double t,
                         unsigned nder, size_t *first, double *ders);

/*
 * Point r(t) by de Boor's algorithm (repeated convex combinations of the q
 * control points of the interval: no basis function is formed).
 * out: dim values.  Returns 0 or a negated bspline_error (see bspline_check,
 * and -BSPLINE_EDOMAIN).
 */
int bspline_eval(const bspline_t *b, double t, double *out);

/*
 * r(t) and its derivatives up to nder (nder < order):
 * out[d*dim + c] = d^d r_c / dt^d.  Returns as bspline_eval, and
 * -BSPLINE_ESIZE if nder >= order.
 */
int bspline_eval_derivs(const bspline_t *b, double t, unsigned nder, double *out);

/*
 * The cubic matrix with the seed's tension parameter u (u = 1: the uniform
 * cubic B-spline basis matrix M):
 *   M_u = 1/6 | -u   12-9u  9u-12  u |
 *             | 3u   12u-18 18-15u 0 |
 *             | -3u  0      3u     0 |
 *             | u    6-2u   u      0 |
 * Row r holds the coefficient of t^(3-r).  The seed prints the third entry
 * of the first row as 9-12u: a typo (it agrees with 9u-12 only at u = 1).
 * With 9-12u the four blending functions sum to (27-21u)/6 at t = 1, not 1,
 * so the curve would not be an affine combination of its control points;
 * with 9u-12 they sum to 1 for every t and u (tested).  This is the form of
 * Hearn & Baker, whose text the seed follows.  M: 16 values, row-major.
 */
void bspline_cubic_matrix(double tension, double *M);

/*
 * One segment of a uniform cubic (with tension) B-spline:
 * out = [t^3 t^2 t 1] . M . [p0 p1 p2 p3]^T, t in [0,1].
 * p: 4*dim values (the four control points in a row); out: dim values.
 * nder 1, 2 or 3 adds derivatives by t: out[d*dim + c].  No check: the
 * caller gives M from bspline_cubic_matrix and nder <= 3.
 */
void bspline_cubic_segment(const double *M, const double *p, size_t dim, double t, unsigned nder,
                           double *out);

#endif
