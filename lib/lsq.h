/*
 * lsq.h - least-squares B-spline approximation (seed 000, last part).
 *
 * Given m data points R_i at parameters u_i and a B-spline of order q with
 * n_ctrl < m control points on a given knot vector, find the control points
 * P minimising sum_i |r(u_i) - R_i|^2.  The seed writes the answer as
 * P = (N^T N)^-1 N^T R; we never form an inverse: N^T N is symmetric,
 * positive definite when the data are spread over every basis function's
 * support (Schoenberg-Whitney), and banded with half-bandwidth q-1 (each
 * row of N has q adjacent non-zeros).  It is factored by banded Cholesky in
 * O(n q^2) and solved in O(n q) per coordinate.
 *
 * Limits: the normal equations square the condition number of N.  B-spline
 * bases are well conditioned (de Boor: the condition of the basis depends on
 * q only, not on the knots), so for q <= 6 and data covering every span this
 * loses at most a few digits; when the data leave a span nearly empty the
 * Cholesky pivot collapses and the fit is refused (-LSQ_ESINGULAR) rather
 * than returned wild.  QR on N would be the remedy, at m*q^2 cost.
 *
 * Why smoothing: a fix standing still jitters by a metre; an exact
 * interpolant must pass through every jittered fix and swings between them,
 * while a least-squares spline with fewer control points than fixes averages
 * them.  See README "Spline toolkit".
 *
 * Pinned ends (LSQ_PIN_ENDS): with clamped knots (lsq_knots) the curve
 * starts at P_0 and ends at P_{n}; pinning sets them to the first and last
 * data points and fits the rest, so consecutive fits can share their end
 * points.  With unclamped knots pinning still fixes P_0 and P_n, but the
 * curve then does not pass through the data's end points.
 *
 * No allocation: the caller provides lsq_work_len() doubles.
 */
#ifndef TRAJD_LSQ_H
#define TRAJD_LSQ_H

#include <stddef.h>

enum lsq_error {
    LSQ_OK = 0,
    LSQ_ESIZE = 1,      /* m < n_ctrl, n_ctrl < order, dim 0, or pinned with n_ctrl < 3 */
    LSQ_EORDER = 2,     /* order 0 or above BSPLINE_ORDER_MAX */
    LSQ_EKNOTS = 3,     /* knot vector invalid (see bspline_check) */
    LSQ_EPARAM = 4,     /* a parameter not finite or outside the knot domain; chord: all points equal */
    LSQ_ENOTFINITE = 5, /* a data point not finite */
    LSQ_ESINGULAR = 6,  /* N^T N not positive definite: too few data in some span */
};

/* A Cholesky pivot below this times the diagonal entry it came from is refused. */
#define LSQ_PIVOT_REL_MIN 1e-12

/* Flags for lsq_fit. */
#define LSQ_PIN_ENDS 0x1u

const char *lsq_strerror(int err);

/* Doubles of work lsq_fit needs. */
size_t lsq_work_len(size_t n_ctrl, unsigned order, size_t dim);

/*
 * Chord-length parameters normalised to [0, 1] (the seed's formula):
 * u_0 = 0, u_i = sum_{j<=i} |R_j - R_{j-1}| / total.  Repeated points get
 * equal parameters (allowed in a fit).
 * Returns 0, -LSQ_ESIZE (m < 2), -LSQ_ENOTFINITE, -LSQ_EPARAM (total 0).
 */
int lsq_chord_params(size_t m, size_t dim, const double *pts, double *u);

/*
 * Clamped knots with uniform interior spacing over [u0, u1] for n_ctrl
 * control points of this order (the seed's open uniform vector, scaled):
 * n_ctrl + order values.  Returns 0, -LSQ_EORDER, -LSQ_ESIZE, -LSQ_EPARAM (u1 <= u0).
 */
int lsq_knots(size_t n_ctrl, unsigned order, double u0, double u1, double *knots);

/*
 * Fit.
 *   m, dim, u, pts   data: m parameters (in the knot domain) and m*dim values
 *   order, n_ctrl    the spline (m >= n_ctrl >= order)
 *   knots            n_ctrl + order values
 *   flags            0 or LSQ_PIN_ENDS
 *   ctrl             out: n_ctrl*dim control points
 *   work             lsq_work_len(n_ctrl, order, dim) doubles
 * Returns 0 or a negated lsq_error.
 */
int lsq_fit(size_t m, size_t dim, const double *u, const double *pts,
            unsigned order, size_t n_ctrl, const double *knots, unsigned flags,
            double *ctrl, double *work);

#endif
