/*
 * surf.h - bicubic uniform B-spline surfaces (seed 003, second half).
 *
 * Patch (i, j) is R(s, t) = S . N . P . N^T . T^T with S = [s^3 s^2 s 1],
 * T = [t^3 t^2 t 1], s, t in [0, 1], N the cubic B-spline matrix and P the
 * 4x4 control points P(i..i+3, j..j+3).
 *
 * Exact interpolation through an M x N grid R(k, l): the seed extends the
 * control net to (M+2) x (N+2) points.  Grid point (k, l) is reached at
 * patch corner (u, v) = (k, l), where the surface equals
 *   sum_{a,b in -1..1} w_a w_b P(k+1+a, l+1+b),  w = (1, 4, 1)/6.
 * The seed leaves the extra border points to "a small distance" outside;
 * we fix them by the natural end condition (zero second derivative across
 * the border: P(0) = 2 P(1) - P(2)), which turns each direction into
 *   P(1) = R(0), P(M) = R(M-1), P(k) + 4 P(k+1) + P(k+2) = 6 R(k)
 * - the Hoang system with held ends.  The surface is then the tensor
 * product of natural cubic splines with uniform knots through the grid
 * (tested against scipy's CubicSpline(bc_type='natural') along both axes).
 * One tridiagonal solve per direction, all columns at once.
 *
 * The surface's parameters are the grid indices: u in [0, M-1], v in [0, N-1].
 *
 * Forward differences (seed: "three additions per point"): along a patch
 * row the surface is a cubic in s whose four coefficients are cubics in t;
 * stepping t advances those four cubics by forward differences, and each row
 * is walked in s by forward differences.  No allocation anywhere.
 */
#ifndef TRAJD_SURF_H
#define TRAJD_SURF_H
/* trajd public API: installed as <trajd/surf.h> (make install; pkg-config trajd). */

#include <stddef.h>

enum surf_error {
    SURF_OK = 0,
    SURF_ESIZE = 1,      /* grid smaller than 2 x 2, dim 0, or step count 0 */
    SURF_ENOTFINITE = 2, /* a grid value not finite */
    SURF_ESINGULAR = 3,  /* tridiagonal solve failed (cannot happen for 1-4-1; reported anyway) */
    SURF_EDOMAIN = 4,    /* (u, v) outside the grid or not finite; patch index out of range */
};

const char *surf_strerror(int err);

typedef struct {
    size_t m, n;        /* grid rows and columns (>= 2 each) */
    size_t dim;         /* coordinates per point (3 for x, y, z) */
    const double *ctrl; /* (m+2)*(n+2)*dim control points, row-major */
} surf_t;

/* Doubles of scratch surf_interpolate needs. */
size_t surf_scratch_len(size_t m, size_t n, size_t dim);

/*
 * Control net through the grid.
 *   grid    m*n*dim values, grid[(k*n + l)*dim + c]
 *   ctrl    out: (m+2)*(n+2)*dim
 *   scratch surf_scratch_len(m, n, dim)
 *   s       out (may be NULL): the surface viewing ctrl
 * Returns 0, -SURF_ESIZE, -SURF_ENOTFINITE, -SURF_ESINGULAR.
 */
int surf_interpolate(size_t m, size_t n, size_t dim, const double *grid, double *ctrl,
                     double *scratch, surf_t *s);

/*
 * Point at (u, v) in [0, m-1] x [0, n-1]; with nder = 1 also dR/du and
 * dR/dv: out[0..dim) point, out[dim..2dim) d/du, out[2dim..3dim) d/dv.
 * Returns 0, -SURF_EDOMAIN.
 */
int surf_eval(const surf_t *s, double u, double v, unsigned nder, double *out);

/*
 * Coefficients of patch (i, j) (i < m-1, j < n-1): coordinate c is
 *   sum_{a,b} C[c*16 + a*4 + b] s^(3-a) t^(3-b).
 * Returns 0, -SURF_EDOMAIN.
 */
int surf_patch_coeffs(const surf_t *s, size_t i, size_t j, double *C);

/*
 * Sample patch (i, j) on a (nu+1) x (nv+1) lattice of equal steps including
 * its four edges, by forward differences:
 *   out[((a*(nv+1)) + b)*dim + c] = R(i + a/nu, j + b/nv)_c
 * Returns 0, -SURF_EDOMAIN, -SURF_ESIZE (nu or nv 0).
 */
int surf_patch_fd(const surf_t *s, size_t i, size_t j, unsigned nu, unsigned nv, double *out);

#endif
