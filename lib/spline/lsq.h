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
 * them.  See lib/spline/TOOLKIT.md.
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
/* trajd public API: installed as <trajd/lsq.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>

enum lsq_error {
    LSQ_OK = 0,
    LSQ_ESIZE = 1,  /* m < n_ctrl, n_ctrl < order, dim 0, or pinned with n_ctrl < 3 */
    LSQ_EORDER = 2, /* order 0 or above BSPLINE_ORDER_MAX */
    LSQ_EKNOTS = 3, /* knot vector invalid (see bspline_check) */
    LSQ_EPARAM = 4, /* a parameter not finite or outside the knot domain; chord: all points equal */
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
int lsq_fit(size_t m, size_t dim, const double *u, const double *pts, unsigned order, size_t n_ctrl,
            const double *knots, unsigned flags, double *ctrl, double *work);

/*
 * Streaming smoother: each point j is replaced by the value at t_j of the
 * least-squares cubic B-spline (order 4, `ctrl` control points on clamped
 * uniform knots over the window's time span) fitted to the `window` points
 * around it: j - (window-1-delay) .. j + delay, delay = window/2, shifted
 * inward at the ends of the track so every fit has `window` points (or all
 * of them if the track is shorter).  Timestamps are kept; only positions
 * change.  Point j is ready once point j + delay has been pushed (or at
 * finish): that is the smoother's added lookahead.
 *
 * When a window's data leave a knot span empty (a time gap), the fit is
 * retried with 4 control points (one cubic over the window), and if that
 * fails too the raw point is passed through; both are counted in
 * `fallbacks`.  A track of fewer than 4 points is passed through unchanged.
 *
 * Memory: lsq_smooth_mem_len() doubles from the caller; nothing allocated.
 */
#define LSQ_SMOOTH_DIM_MAX 3
#define LSQ_SMOOTH_WINDOW_MAX 1024

typedef struct {
    unsigned window, ctrl, delay;
    size_t dim;
    uint64_t n_in;  /* points pushed */
    uint64_t n_out; /* smoothed points popped */
    int finished;
    uint64_t fallbacks;                  /* fits refused: fewer control points or raw value used */
    double *t, *r;                       /* ring of the last `window` points */
    double *u, *pts, *knots, *cp, *work; /* fit scratch */
} lsq_smooth_t;

/* Doubles of memory for lsq_smooth_init. */
size_t lsq_smooth_mem_len(unsigned window, unsigned ctrl, size_t dim);

/* Points of lookahead the smoother adds: window/2. */
unsigned lsq_smooth_delay(unsigned window);

/*
 * Attach memory and empty.  Requires 4 <= ctrl <= window <= LSQ_SMOOTH_WINDOW_MAX
 * and 1 <= dim <= LSQ_SMOOTH_DIM_MAX.  Returns 0, -LSQ_ESIZE.
 */
int lsq_smooth_init(lsq_smooth_t *s, unsigned window, unsigned ctrl, size_t dim, double *mem);

/* Forget all points (a new track); keep the memory and settings. */
void lsq_smooth_reset(lsq_smooth_t *s);

/* Add a point (times must increase; the engine checks).  Returns 0. */
int lsq_smooth_push(lsq_smooth_t *s, double t, const double *r);

/* No more points: the remaining ones become ready. */
void lsq_smooth_finish(lsq_smooth_t *s);

/*
 * Take the next smoothed point if it is ready: returns 1 with *t and r
 * (dim values) set, or 0 if none is ready.  Points come out in order, one
 * per point pushed.
 */
int lsq_smooth_pop(lsq_smooth_t *s, double *t, double *r);

/* Points pushed and not yet popped. */
static inline uint64_t lsq_smooth_pending(const lsq_smooth_t *s)
{
    return s->n_in - s->n_out;
}

#endif
