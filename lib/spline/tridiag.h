/*
 * tridiag.h - Thomas algorithm for tridiagonal systems, whole or one row at a time.
 *
 * Solves  a[i]*x[i-1] + b[i]*x[i] + c[i]*x[i+1] = d[i],  i = 0 .. n-1
 * (a[0] and c[n-1] are ignored) for one or several right-hand sides.
 *
 * No pivoting: the systems trajd builds (1-4-1 of the Hoang B-spline, the
 * h/2(h+h)/h second-derivative system of the cubic spline) are strictly
 * diagonally dominant, for which Thomas is stable.  A pivot that is not
 * clearly non-zero is reported, never divided by.
 *
 * No allocation: every buffer belongs to the caller.
 */
#ifndef TRAJD_TRIDIAG_H
#define TRAJD_TRIDIAG_H

#include <stddef.h>

enum tridiag_error {
    TRIDIAG_OK = 0,
    TRIDIAG_ESIZE = 1,     /* n == 0, or a row past the capacity of a sweep */
    TRIDIAG_ESINGULAR = 2, /* a pivot was zero, tiny or not finite */
};

/* A pivot smaller than this times the row's absolute sum is treated as zero. */
#define TRIDIAG_PIVOT_REL_MIN 1e-12

/*
 * Solve the system for nrhs right-hand sides at once.
 * d and x are n x nrhs, row-major (d[i*nrhs + k]); x may alias d.
 * scratch: n doubles.
 * Returns 0, -TRIDIAG_ESIZE (n == 0 or nrhs == 0), -TRIDIAG_ESINGULAR.
 */
int tridiag_solve(size_t n, size_t nrhs, const double *a, const double *b, const double *c,
                  const double *d, double *x, double *scratch);

/*
 * Incremental forward sweep: rows are pushed as the data for them arrives
 * (e.g. one row per waypoint), and back substitution runs once the last row
 * is in.  The memory is the caller's: cp holds cap doubles, dp cap*nrhs.
 */
typedef struct {
    size_t n;    /* rows pushed so far */
    size_t cap;  /* rows that fit */
    size_t nrhs; /* right-hand sides per row */
    double *cp;  /* modified super-diagonal c'[i] */
    double *dp;  /* modified right-hand sides d'[i*nrhs + k] */
} tridiag_sweep_t;

/* Attach caller memory and empty the sweep. */
void tridiag_sweep_init(tridiag_sweep_t *s, double *cp, double *dp, size_t cap, size_t nrhs);

/* Forget the rows pushed; keep the memory. */
void tridiag_sweep_reset(tridiag_sweep_t *s);

/*
 * Eliminate one row (a is ignored for the first row).  d: nrhs values.
 * Returns 0, -TRIDIAG_ESIZE (full), -TRIDIAG_ESINGULAR.
 */
int tridiag_sweep_push(tridiag_sweep_t *s, double a, double b, double c, const double *d);

/*
 * Back substitution over the rows pushed, treating the last one's c as 0.
 * x: n*nrhs doubles, row-major.  Returns 0, -TRIDIAG_ESIZE (no row).
 */
int tridiag_sweep_solve(const tridiag_sweep_t *s, double *x);

#endif
