/* lsq.c - least-squares B-spline approximation; see lsq.h. */
#include "lsq.h"

#include <math.h>
#include <string.h>

#include "bspline.h"

const char *lsq_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case LSQ_OK: return "success";
    case LSQ_ESIZE:
        return "least squares: sizes (need data >= control points >= order; pinned: 3 control "
               "points)";
    case LSQ_EORDER: return "least squares: order out of range";
    case LSQ_EKNOTS: return "least squares: invalid knot vector";
    case LSQ_EPARAM:
        return "least squares: parameter not finite or outside the knots, or all points equal";
    case LSQ_ENOTFINITE: return "least squares: data point not finite";
    case LSQ_ESINGULAR:
        return "least squares: too few data in some knot span (normal equations singular)";
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
static void band_solve(const double *A, unsigned q, size_t lo, size_t hi, double *x, size_t dim,
                       size_t c)
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

int lsq_fit(size_t m, size_t dim, const double *u, const double *pts, unsigned order, size_t n_ctrl,
            const double *knots, unsigned flags, double *ctrl, double *work)
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

/* ---- streaming smoother ---------------------------------------------------- */

#define SMOOTH_ORDER 4u

size_t lsq_smooth_mem_len(unsigned window, unsigned ctrl, size_t dim)
{
    return (size_t)window * (2 + 2 * dim) + (ctrl + SMOOTH_ORDER) + ctrl * dim +
           lsq_work_len(ctrl, SMOOTH_ORDER, dim);
}

unsigned lsq_smooth_delay(unsigned window)
{
    return window / 2;
}

int lsq_smooth_init(lsq_smooth_t *s, unsigned window, unsigned ctrl, size_t dim, double *mem)
{
    if (ctrl < SMOOTH_ORDER || ctrl > window || window > LSQ_SMOOTH_WINDOW_MAX || dim < 1 ||
        dim > LSQ_SMOOTH_DIM_MAX)
        return -LSQ_ESIZE;
    memset(s, 0, sizeof *s);
    s->window = window;
    s->ctrl = ctrl;
    s->delay = lsq_smooth_delay(window);
    s->dim = dim;
    s->t = mem;
    s->r = s->t + window;
    s->u = s->r + (size_t)window * dim;
    s->pts = s->u + window;
    s->knots = s->pts + (size_t)window * dim;
    s->cp = s->knots + ctrl + SMOOTH_ORDER;
    s->work = s->cp + (size_t)ctrl * dim;
    return 0;
}

void lsq_smooth_reset(lsq_smooth_t *s)
{
    s->n_in = 0;
    s->n_out = 0;
    s->finished = 0;
}

int lsq_smooth_push(lsq_smooth_t *s, double t, const double *r)
{
    size_t k = (size_t)(s->n_in % s->window);

    s->t[k] = t;
    memcpy(s->r + k * s->dim, r, s->dim * sizeof *r);
    s->n_in++;
    return 0;
}

void lsq_smooth_finish(lsq_smooth_t *s)
{
    s->finished = 1;
}

/* Fit the window [start, start+m) with nc control points and evaluate at u_j. */
static int smooth_fit(lsq_smooth_t *s, size_t m, unsigned nc, double uj, double *r)
{
    bspline_t b;
    int rc;

    if (lsq_knots(nc, SMOOTH_ORDER, 0.0, s->u[m - 1], s->knots) < 0)
        return -1;
    rc = lsq_fit(m, s->dim, s->u, s->pts, SMOOTH_ORDER, nc, s->knots, 0, s->cp, s->work);
    if (rc < 0)
        return rc;
    b.order = SMOOTH_ORDER;
    b.n_ctrl = nc;
    b.dim = s->dim;
    b.knots = s->knots;
    b.ctrl = s->cp;
    return bspline_eval(&b, uj, r) < 0 ? -1 : 0;
}

int lsq_smooth_pop(lsq_smooth_t *s, double *t, double *r)
{
    uint64_t j = s->n_out, n = s->n_in, start, before = s->window - 1 - s->delay;
    uint64_t need = j + s->delay > s->window - 1 ? j + s->delay : s->window - 1;
    size_t m, i, W = s->window, dim = s->dim;
    const double *tj_r;
    double tj;

    if (j >= n || (!s->finished && n - 1 < need))
        return 0;
    start = j >= before ? j - before : 0;
    if (s->finished && n < W)
        start = 0; /* a short track: every fit takes all of it */
    else if (s->finished && start > n - W)
        start = n - W;
    m = (size_t)((start + W < n ? start + W : n) - start);
    tj = s->t[j % W];
    tj_r = s->r + (size_t)(j % W) * dim;
    *t = tj;
    s->n_out = j + 1;
    if (m < SMOOTH_ORDER) {
        memcpy(r, tj_r, dim * sizeof *r);
        return 1;
    }
    for (i = 0; i < m; i++) {
        size_t k = (size_t)((start + i) % W);
        /* times relative to the window's first: keeps knot arithmetic exact
         * for epoch-sized timestamps */
        s->u[i] = s->t[k] - s->t[start % W];
        memcpy(s->pts + i * dim, s->r + k * dim, dim * sizeof *r);
    }
    {
        unsigned nc = s->ctrl < m ? s->ctrl : (unsigned)m;
        double uj = tj - s->t[start % W];
        if (smooth_fit(s, m, nc, uj, r) == 0)
            return 1;
        s->fallbacks++;
        if (nc > SMOOTH_ORDER && smooth_fit(s, m, SMOOTH_ORDER, uj, r) == 0)
            return 1;
    }
    memcpy(r, tj_r, dim * sizeof *r);
    return 1;
}
