/* lsq.c - least-squares B-spline approximation; see lsq.h. */
#include "lsq.h"

#include <math.h>
#include <string.h>

#include "bspline.h"

const char *lsq_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case LSQ_OK: return "success";
    case LSQ_ESIZE: return "least squares: sizes (need data >= control points >= order; pinned: 3 control points)";
    case LSQ_EORDER: return "least squares: order out of range";
    case LSQ_EKNOTS: return "least squares: invalid knot vector";
    case LSQ_EPARAM: return "least squares: parameter not finite or outside the knots, or all points equal";
    case LSQ_ENOTFINITE: return "least squares: data point not finite";
    case LSQ_ESINGULAR: return "least squares: too few data in some knot span (normal equations singular)";
    default: return "unknown lsq error";
    }
}

size_t lsq_work_len(size_t n_ctrl, unsigned order, size_t dim)
{
    return n_ctrl * order + n_ctrl * dim;
}

int lsq_chord_params(size_t m, size_t dim, const double *pts, double *u)
{
    size_t i, c;
    double total;

    if (m < 2 || dim == 0)
        return -LSQ_ESIZE;
    u[0] = 0.0;
    for (i = 1; i < m; i++) {
        double d2 = 0.0;
        for (c = 0; c < dim; c++) {
            double d = pts[i * dim + c] - pts[(i - 1) * dim + c];
            d2 += d * d;
        }
        if (!isfinite(d2))
            return -LSQ_ENOTFINITE;
        u[i] = u[i - 1] + sqrt(d2);
    }
    total = u[m - 1];
    if (!(total > 0.0))
        return -LSQ_EPARAM;
    for (i = 1; i < m; i++)
        u[i] /= total;
    u[m - 1] = 1.0;
    return 0;
}

int lsq_knots(size_t n_ctrl, unsigned order, double u0, double u1, double *knots)
{
    size_t k;
    int rc;

    if (order < 1 || order > BSPLINE_ORDER_MAX)
        return -LSQ_EORDER;
    if (n_ctrl < order)
        return -LSQ_ESIZE;
    if (!isfinite(u0) || !isfinite(u1) || !(u1 > u0))
        return -LSQ_EPARAM;
    rc = bspline_knots_open_uniform(n_ctrl, order, knots);
    if (rc < 0)
        return -LSQ_EORDER;
    {
        double top = knots[n_ctrl + order - 1]; /* n - q + 2 >= 1 */
        for (k = 0; k < n_ctrl + order; k++)
            knots[k] = u0 + (u1 - u0) * (knots[k] / top);
        for (k = 0; k < n_ctrl + order; k++) /* exact ends despite rounding */
            if (k >= n_ctrl)
                knots[k] = u1;
    }
    return 0;
}

/*
 * In-place banded Cholesky A = U^T U on rows lo..hi of the band
 * A[i*q + d] = A(i, i+d).  Returns 0 or -LSQ_ESINGULAR when a pivot is not
 * clearly positive (relative to its diagonal entry).
 */
static int band_cholesky(double *A, unsigned q, size_t lo, size_t hi)
{
    size_t i, j, k;
    unsigned p = q - 1;

    for (i = lo; i <= hi; i++) {
        double diag = A[i * q], piv = diag;
        size_t k0 = i >= lo + p ? i - p : lo;
        for (k = k0; k < i; k++) {
            double u = A[k * q + (i - k)];
            piv -= u * u;
        }
        if (!isfinite(piv) || !(piv > LSQ_PIVOT_REL_MIN * diag) || !(diag > 0.0))
            return -LSQ_ESINGULAR;
        piv = sqrt(piv);
        A[i * q] = piv;
        for (j = i + 1; j <= hi && j <= i + p; j++) {
            double v = A[i * q + (j - i)];
            size_t kk0 = j >= lo + p ? j - p : lo;
            for (k = kk0 < k0 ? k0 : kk0; k < i; k++)
                v -= A[k * q + (i - k)] * A[k * q + (j - k)];
            A[i * q + (j - i)] = v / piv; /* piv > 0 checked above */
        }
    }
    return 0;
}

/* Solve U^T U x = b for rows lo..hi (b, x in ctrl, stride dim, coordinate c). */
static void band_solve(const double *A, unsigned q, size_t lo, size_t hi,
                       double *x, size_t dim, size_t c)
{
    size_t i, k;
    unsigned p = q - 1;

    for (i = lo; i <= hi; i++) { /* U^T y = b */
        double v = x[i * dim + c];
        size_t k0 = i >= lo + p ? i - p : lo;
        for (k = k0; k < i; k++)
            v -= A[k * q + (i - k)] * x[k * dim + c];
        x[i * dim + c] = v / A[i * q];
    }
    for (i = hi + 1; i-- > lo;) { /* U x = y */
        double v = x[i * dim + c];
        for (k = i + 1; k <= hi && k <= i + p; k++)
            v -= A[i * q + (k - i)] * x[k * dim + c];
        x[i * dim + c] = v / A[i * q];
    }
}

int lsq_fit(size_t m, size_t dim, const double *u, const double *pts,
            unsigned order, size_t n_ctrl, const double *knots, unsigned flags,
            double *ctrl, double *work)
{
    double N[BSPLINE_ORDER_MAX];
    double *A = work;
    bspline_t chk = {order, n_ctrl, 1, knots, NULL};
    size_t i, c, first, lo, hi, j;
    unsigned a, b, q = order;
    int pin = (flags & LSQ_PIN_ENDS) != 0, rc;

    if (order < 1 || order > BSPLINE_ORDER_MAX)
        return -LSQ_EORDER;
    if (dim == 0 || n_ctrl < order || m < n_ctrl || (pin && n_ctrl < 3))
        return -LSQ_ESIZE;
    if (bspline_check(&chk) < 0)
        return -LSQ_EKNOTS;
    for (i = 0; i < m * dim; i++)
        if (!isfinite(pts[i]))
            return -LSQ_ENOTFINITE;
    memset(A, 0, n_ctrl * q * sizeof *A);
    memset(ctrl, 0, n_ctrl * dim * sizeof *ctrl);
    /* Accumulate N^T N (upper band) and N^T R (in ctrl). */
    for (i = 0; i < m; i++) {
        rc = bspline_basis(knots, n_ctrl, q, u[i], &first, N);
        if (rc < 0)
            return -LSQ_EPARAM;
        for (a = 0; a < q; a++) {
            for (b = a; b < q; b++)
                A[(first + a) * q + (b - a)] += N[a] * N[b];
            for (c = 0; c < dim; c++)
                ctrl[(first + a) * dim + c] += N[a] * pts[i * dim + c];
        }
    }
    lo = 0;
    hi = n_ctrl - 1;
    if (pin) {
        const double *r0 = pts, *r1 = pts + (m - 1) * dim;
        /* Move the pinned columns to the right-hand side: row j gets
         * -A(j,0) P_0 - A(j,n-1) P_{n-1}.  A(j,k) = A(min, max) in the band. */
        for (j = 1; j + 1 < n_ctrl; j++) {
            double a0 = j < q ? A[0 * q + j] : 0.0;
            double a1 = (n_ctrl - 1 - j) < q ? A[j * q + (n_ctrl - 1 - j)] : 0.0;
            for (c = 0; c < dim; c++)
                ctrl[j * dim + c] -= a0 * r0[c] + a1 * r1[c];
        }
        /* Entries of row n-2 reaching column n-1 are no longer part of the system. */
        lo = 1;
        hi = n_ctrl - 2;
        for (j = lo; j <= hi; j++)
            for (a = 1; a < q; a++)
                if (j + a > hi)
                    A[j * q + a] = 0.0;
        for (c = 0; c < dim; c++) {
            ctrl[c] = r0[c];
            ctrl[(n_ctrl - 1) * dim + c] = r1[c];
        }
    }
    rc = band_cholesky(A, q, lo, hi);
    if (rc < 0)
        return rc;
    for (c = 0; c < dim; c++)
        band_solve(A, q, lo, hi, ctrl, dim, c);
    return 0;
}
