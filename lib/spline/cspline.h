/*
 * cspline.h - the C2 interpolating cubic spline of seed 002.
 *
 * Through points p_0 .. p_n (each dim coordinates) at parameters
 * t_0 < ... < t_n, the unknowns are the second derivatives s_i = r''(t_i).
 * Continuity of r' gives system (5.18), i = 1 .. n-1:
 *
 *   h_{i-1} s_{i-1} + 2 (h_{i-1} + h_i) s_i + h_i s_{i+1}
 *       = 6 (p_{i+1} - p_i) / h_i - 6 (p_i - p_{i-1}) / h_{i-1},   h_i = t_{i+1} - t_i
 *
 * (the seed writes 2 s_i (t_{i+1} - t_{i-1}), the same thing), closed by one of
 *   natural                 s_0 = s_n = 0                        (5.19)
 *   constant end curvature  s_0 = s_1, s_n = s_{n-1}             (5.20)
 *   clamped                 r'(t_0), r'(t_n) given
 *   periodic                p_n = p_0, s_n = s_0, r' continuous across t_n = t_0
 * The open systems are tridiagonal (Thomas, lib/spline/tridiag); the periodic one
 * is cyclic tridiagonal, solved by Sherman-Morrison on top of Thomas.
 *
 * On [t_i, t_{i+1}], w = (t - t_i)/h_i:
 *   r = (1-w) p_i + w p_{i+1} + ((-2w + 3w^2 - w^3) s_i + (-w + w^3) s_{i+1}) h_i^2/6
 *
 * Parameters: uniform (t_i = i), chord length (t_i = sum |p_j - p_{j-1}|),
 * or given (timestamps: the spline is then C2 in physical time).
 *
 * No allocation: the caller owns t, p, s and the scratch.
 */
#ifndef TRAJD_CSPLINE_H
#define TRAJD_CSPLINE_H
/* trajd public API: installed as <trajd/cspline.h> (make install; pkg-config trajd). */

#include <stddef.h>

enum cspline_error {
    CSPLINE_OK = 0,
    CSPLINE_ESIZE = 1,      /* too few points (2 open, 3 periodic) or dim 0 */
    CSPLINE_EPARAM = 2,     /* parameters not finite or not strictly increasing */
    CSPLINE_ENOTFINITE = 3, /* a point or end derivative not finite */
    CSPLINE_ENOTCLOSED = 4, /* periodic: last point differs from the first */
    CSPLINE_ESINGULAR = 5,  /* the system could not be solved */
    CSPLINE_EDOMAIN = 6,    /* evaluation parameter outside [t_0, t_n] or not finite */
};

const char *cspline_strerror(int err);

typedef enum {
    CSPLINE_PARAM_UNIFORM = 0, /* t_i = i */
    CSPLINE_PARAM_CHORD = 1,   /* t_i = cumulative chord length */
    CSPLINE_PARAM_GIVEN = 2,   /* caller's t (e.g. timestamps) */
} cspline_param_t;

typedef enum {
    CSPLINE_END_NATURAL = 0,
    CSPLINE_END_CURVATURE = 1, /* constant end curvature: s_0 = s_1, s_n = s_{n-1} */
    CSPLINE_END_CLAMPED = 2,
    CSPLINE_END_PERIODIC = 3,
} cspline_end_t;

/*
 * Periodic: |p_n - p_0| must be at most this times the extent of the points
 * (plus an absolute 1e-300 for an all-zero set).
 */
#define CSPLINE_CLOSED_REL_TOL 1e-12

/* A solved spline: views of caller memory. */
typedef struct {
    size_t n; /* intervals: n+1 points */
    size_t dim;
    const double *t; /* n+1 parameters */
    const double *p; /* (n+1)*dim points, row-major */
    const double *s; /* (n+1)*dim second derivatives */
    int periodic;    /* evaluation wraps t into [t_0, t_n] */
} cspline_t;

/*
 * Fill t (npts values) for param UNIFORM or CHORD (GIVEN: nothing to do,
 * returns 0).  Chord length: a repeated point gives a zero interval, which
 * cspline_solve then refuses (-CSPLINE_EPARAM).
 * Returns 0, -CSPLINE_ESIZE, -CSPLINE_ENOTFINITE.
 */
int cspline_params(size_t npts, size_t dim, const double *p, cspline_param_t param, double *t);

/* Doubles of scratch cspline_solve needs for npts points and dim coordinates. */
size_t cspline_scratch_len(size_t npts, size_t dim);

/*
 * Solve for the second derivatives.
 *   npts    points (>= 2; periodic >= 3 with p[npts-1] == p[0])
 *   t, p    parameters and points
 *   end     end condition
 *   d0, dn  first derivatives dr/dt at t_0 and t_n (dim each): CLAMPED only, else NULL ok
 *   s       out: npts*dim second derivatives
 *   scratch cspline_scratch_len(npts, dim) doubles
 * On success cs (if not NULL) is set to view t, p, s.
 * Returns 0, -CSPLINE_ESIZE, -CSPLINE_EPARAM, -CSPLINE_ENOTFINITE,
 * -CSPLINE_ENOTCLOSED, -CSPLINE_ESINGULAR.
 */
int cspline_solve(size_t npts, size_t dim, const double *t, const double *p, cspline_end_t end,
                  const double *d0, const double *dn, double *s, double *scratch, cspline_t *cs);

/*
 * Interval index i with t_i <= t <= t_{i+1} (binary search); periodic
 * splines wrap t first.  Returns i >= 0 or -CSPLINE_EDOMAIN.
 */
long cspline_find(const cspline_t *cs, double *t);

/*
 * Value and derivatives up to nder (0..3) at t:
 * out[d*dim + c].  Returns 0, -CSPLINE_EDOMAIN (open spline: t outside
 * [t_0, t_n] beyond a relative 1e-12, or not finite), -CSPLINE_ESIZE (nder > 3).
 */
int cspline_eval(const cspline_t *cs, double t, unsigned nder, double *out);

/*
 * Polynomial coefficients of interval i in the local time tau = t - t_i:
 * r_c(tau) = co[c*4+0] tau^3 + co[c*4+1] tau^2 + co[c*4+2] tau + co[c*4+3].
 * For forward-difference stepping.  i < n.
 */
void cspline_coeffs(const cspline_t *cs, size_t i, double *co);

#endif
