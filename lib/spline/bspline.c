/* bspline.c - B-splines of any order on any knot vector; see bspline.h. */
#include "bspline.h"

#include <math.h>

/* Coordinates processed together by de Boor's algorithm (stack buffer). */
#define DEBOOR_DIM_CHUNK 4

const char *bspline_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case BSPLINE_OK: return "success";
    case BSPLINE_EORDER:
        return "B-spline order out of range (1..16, at most the number of control points)";
    case BSPLINE_EKNOTS: return "B-spline knots not finite, decreasing, or the domain is empty";
    case BSPLINE_ESIZE:
        return "B-spline size out of range (control points, dimension or derivative count)";
    case BSPLINE_EDOMAIN: return "B-spline parameter outside the domain or not finite";
    default: return "unknown bspline error";
    }
}

static int order_ok(size_t n_ctrl, unsigned order)
{
    return order >= 1 && order <= BSPLINE_ORDER_MAX && n_ctrl >= order;
}

int bspline_check(const bspline_t *b)
{
    size_t i, nk;

    if (b->n_ctrl == 0 || b->dim == 0)
        return -BSPLINE_ESIZE;
    if (!order_ok(b->n_ctrl, b->order))
        return -BSPLINE_EORDER;
    nk = b->n_ctrl + b->order;
    for (i = 0; i < nk; i++) {
        if (!isfinite(b->knots[i]))
            return -BSPLINE_EKNOTS;
        if (i > 0 && b->knots[i] < b->knots[i - 1])
            return -BSPLINE_EKNOTS;
    }
    if (!(b->knots[b->order - 1] < b->knots[b->n_ctrl]))
        return -BSPLINE_EKNOTS;
    return 0;
}

void bspline_domain(const bspline_t *b, double *t_min, double *t_max)
{
    *t_min = b->knots[b->order - 1];
    *t_max = b->knots[b->n_ctrl];
}

int bspline_knots_uniform(size_t n_ctrl, unsigned order, double t0, double dt, double *knots)
{
    size_t k, nk = n_ctrl + order;

    if (nk == 0)
        return -BSPLINE_ESIZE;
    if (!(dt > 0.0) || !isfinite(dt) || !isfinite(t0))
        return -BSPLINE_EKNOTS;
    for (k = 0; k < nk; k++)
        knots[k] = t0 + (double)k * dt;
    return 0;
}

int bspline_knots_open_uniform(size_t n_ctrl, unsigned order, double *knots)
{
    size_t k, n, q = order;

    if (!order_ok(n_ctrl, order))
        return -BSPLINE_EORDER;
    n = n_ctrl - 1;
    for (k = 0; k <= n + q; k++) {
        if (k < q)
            knots[k] = 0.0;
        else if (k <= n)
            knots[k] = (double)(k - q + 1);
        else
            knots[k] = (double)(n - q + 2);
    }
    return 0;
}

int bspline_knots_clamped(const double *breaks, size_t nbreak, unsigned order, double *knots)
{
    size_t i, k = 0;
    unsigned j;

    if (order < 1 || order > BSPLINE_ORDER_MAX)
        return -BSPLINE_EORDER;
    if (nbreak < 2)
        return -BSPLINE_ESIZE;
    for (i = 0; i < nbreak; i++)
        if (!isfinite(breaks[i]) || (i > 0 && !(breaks[i] > breaks[i - 1])))
            return -BSPLINE_EKNOTS;
    for (j = 1; j < order; j++)
        knots[k++] = breaks[0];
    for (i = 0; i < nbreak; i++)
        knots[k++] = breaks[i];
    for (j = 1; j < order; j++)
        knots[k++] = breaks[nbreak - 1];
    return 0;
}

/* Clamp t onto [lo, hi] if within the tolerance; -1 if outside or not finite. */
static int clamp_domain(double lo, double hi, double *t)
{
    double tol = BSPLINE_DOMAIN_REL_TOL * (hi - lo);

    if (!isfinite(*t) || *t < lo - tol || *t > hi + tol)
        return -1;
    if (*t < lo)
        *t = lo;
    if (*t > hi)
        *t = hi;
    return 0;
}

long bspline_find_span(const double *knots, size_t n_ctrl, unsigned order, double t)
{
    size_t lo, hi, n, p;

    if (!order_ok(n_ctrl, order))
        return -BSPLINE_EORDER;
    n = n_ctrl - 1;
    p = order - 1;
    if (clamp_domain(knots[p], knots[n + 1], &t) < 0)
        return -BSPLINE_EDOMAIN;
    if (t >= knots[n + 1]) {
        /* Right end: last non-empty interval.  The domain is not empty, so
         * knots[p] < knots[n+1] stops this loop at mu >= p. */
        lo = n;
        while (lo > p && !(knots[lo] < knots[n + 1]))
            lo--;
        return (long)lo;
    }
    /* Invariant: knots[lo] <= t < knots[hi]. */
    lo = p;
    hi = n + 1;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (t < knots[mid])
            hi = mid;
        else
            lo = mid;
    }
    return (long)lo;
}

/* Index of the last non-empty interval of the whole knot vector, or n_knots if none. */
static size_t last_nonempty(const double *knots, size_t n_knots)
{
    size_t k = n_knots - 1;

    while (k > 0) {
        if (knots[k - 1] < knots[k])
            return k - 1;
        k--;
    }
    return n_knots;
}

static double basis_rec(const double *knots, size_t last, size_t k, unsigned q, double t)
{
    double v = 0.0, den;

    if (q == 1) {
        if (knots[k] <= t && t < knots[k + 1])
            return 1.0;
        /* the right end belongs to the last non-empty interval */
        if (k == last && t >= knots[k + 1] && !(t > knots[k + 1]))
            return 1.0;
        return 0.0;
    }
    den = knots[k + q - 1] - knots[k];
    if (den > 0.0) /* 0/0 = 0 (seed) */
        v += (t - knots[k]) / den * basis_rec(knots, last, k, q - 1, t);
    den = knots[k + q] - knots[k + 1];
    if (den > 0.0)
        v += (knots[k + q] - t) / den * basis_rec(knots, last, k + 1, q - 1, t);
    return v;
}

double bspline_basis_one(const double *knots, size_t n_knots, size_t k, unsigned order, double t)
{
    if (order < 1 || order > BSPLINE_ORDER_MAX || k + order >= n_knots || !isfinite(t))
        return NAN;
    return basis_rec(knots, last_nonempty(knots, n_knots), k, order, t);
}

/*
 * Triangular Cox-de Boor (The NURBS Book, A2.2).  Every denominator is
 * knots[mu+r+1] - knots[mu+1-j+r] >= knots[mu+1] - knots[mu] > 0, because the
 * span mu returned by bspline_find_span is never empty: no division by zero.
 */
static void basis_at(const double *U, size_t mu, unsigned q, double t, double *N)
{
    double left[BSPLINE_ORDER_MAX], right[BSPLINE_ORDER_MAX];
    unsigned j, r;

    N[0] = 1.0;
    for (j = 1; j < q; j++) {
        double saved = 0.0;
        left[j] = t - U[mu + 1 - j];
        right[j] = U[mu + j] - t;
        for (r = 0; r < j; r++) {
            double tmp = N[r] / (right[r + 1] + left[j - r]);
            N[r] = saved + right[r + 1] * tmp;
            saved = left[j - r] * tmp;
        }
        N[j] = saved;
    }
}

int bspline_basis(const double *knots, size_t n_ctrl, unsigned order, double t, size_t *first,
                  double *N)
{
    long mu = bspline_find_span(knots, n_ctrl, order, t);
    double lo, hi;

    if (mu < 0)
        return (int)mu;
    lo = knots[order - 1];
    hi = knots[n_ctrl];
    (void)clamp_domain(lo, hi, &t);
    basis_at(knots, (size_t)mu, order, t, N);
    *first = (size_t)mu - (order - 1);
    return 0;
}

/*
 * Basis functions and derivatives (The NURBS Book, A2.3), on the stack.
 * Denominators ndu[p+1][..] are knot differences over spans that contain
 * the non-empty span mu (as in basis_at): positive.
 */
int bspline_basis_derivs(const double *knots, size_t n_ctrl, unsigned order, double t,
                         unsigned nder, size_t *first, double *ders)
{
    double ndu[BSPLINE_ORDER_MAX][BSPLINE_ORDER_MAX];
    double a[2][BSPLINE_ORDER_MAX];
    double left[BSPLINE_ORDER_MAX], right[BSPLINE_ORDER_MAX];
    const double *U = knots;
    unsigned p, j, r, k;
    long mu;

    if (order < 1 || order > BSPLINE_ORDER_MAX)
        return -BSPLINE_EORDER;
    if (nder >= order)
        return -BSPLINE_ESIZE;
    mu = bspline_find_span(knots, n_ctrl, order, t);
    if (mu < 0)
        return (int)mu;
    (void)clamp_domain(knots[order - 1], knots[n_ctrl], &t);
    p = order - 1;
    ndu[0][0] = 1.0;
    for (j = 1; j <= p; j++) {
        double saved = 0.0;
        left[j] = t - U[mu + 1 - j];
        right[j] = U[mu + j] - t;
        for (r = 0; r < j; r++) {
            double tmp;
            ndu[j][r] = right[r + 1] + left[j - r]; /* lower triangle: knot differences */
            tmp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * tmp; /* upper triangle: basis values */
            saved = left[j - r] * tmp;
        }
        ndu[j][j] = saved;
    }
    for (j = 0; j <= p; j++)
        ders[j] = ndu[j][p];
    for (r = 0; r <= p; r++) {
        unsigned s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (k = 1; k <= nder; k++) {
            double d = 0.0;
            int rk = (int)r - (int)k, pk = (int)p - (int)k, jj;
            int j1, j2;
            if (r >= k) {
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                d = a[s2][0] * ndu[rk][pk];
            }
            j1 = rk >= -1 ? 1 : -rk;
            j2 = ((int)r - 1 <= pk) ? (int)k - 1 : (int)p - (int)r;
            for (jj = j1; jj <= j2; jj++) {
                a[s2][jj] = (a[s1][jj] - a[s1][jj - 1]) / ndu[pk + 1][rk + jj];
                d += a[s2][jj] * ndu[rk + jj][pk];
            }
            if ((int)r <= pk) {
                a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k * order + r] = d;
            s1 ^= 1u;
            s2 ^= 1u;
        }
    }
    /* multiply by p!/(p-k)! */
    {
        double f = (double)p;
        for (k = 1; k <= nder; k++) {
            for (j = 0; j <= p; j++)
                ders[k * order + j] *= f;
            f *= (double)(p - k);
        }
    }
    *first = (size_t)mu - p;
    return 0;
}

static int curve_ok(const bspline_t *b)
{
    if (b->n_ctrl == 0 || b->dim == 0)
        return -BSPLINE_ESIZE;
    if (!order_ok(b->n_ctrl, b->order))
        return -BSPLINE_EORDER;
    return 0;
}

/*
 * de Boor: d_j = P_{mu-p+j}; for r = 1..p, j = p..r:
 *   alpha = (t - U[mu-p+j]) / (U[mu+1+j-r] - U[mu-p+j]),  d_j = (1-alpha) d_{j-1} + alpha d_j.
 * The denominator spans [U[mu-p+j], U[mu+1+j-r]] which contains the
 * non-empty [U[mu], U[mu+1]]: never zero.
 */
int bspline_eval(const bspline_t *b, double t, double *out)
{
    double d[BSPLINE_ORDER_MAX][DEBOOR_DIM_CHUNK];
    const double *U = b->knots;
    size_t c0, c, dim = b->dim;
    unsigned p, j, r;
    long mu;
    int rc = curve_ok(b);

    if (rc < 0)
        return rc;
    mu = bspline_find_span(U, b->n_ctrl, b->order, t);
    if (mu < 0)
        return (int)mu;
    (void)clamp_domain(U[b->order - 1], U[b->n_ctrl], &t);
    p = b->order - 1;
    for (c0 = 0; c0 < dim; c0 += DEBOOR_DIM_CHUNK) {
        size_t nc = dim - c0 < DEBOOR_DIM_CHUNK ? dim - c0 : DEBOOR_DIM_CHUNK;
        for (j = 0; j <= p; j++)
            for (c = 0; c < nc; c++)
                d[j][c] = b->ctrl[((size_t)mu - p + j) * dim + c0 + c];
        for (r = 1; r <= p; r++) {
            for (j = p; j >= r; j--) {
                size_t i0 = (size_t)mu - p + j;
                double alpha = (t - U[i0]) / (U[(size_t)mu + 1 + j - r] - U[i0]);
                for (c = 0; c < nc; c++)
                    d[j][c] = (1.0 - alpha) * d[j - 1][c] + alpha * d[j][c];
            }
        }
        for (c = 0; c < nc; c++)
            out[c0 + c] = d[p][c];
    }
    return 0;
}

int bspline_eval_derivs(const bspline_t *b, double t, unsigned nder, double *out)
{
    double ders[BSPLINE_ORDER_MAX * BSPLINE_ORDER_MAX];
    size_t first, c, dim = b->dim;
    unsigned k, j;
    int rc = curve_ok(b);

    if (rc < 0)
        return rc;
    rc = bspline_basis_derivs(b->knots, b->n_ctrl, b->order, t, nder, &first, ders);
    if (rc < 0)
        return rc;
    for (k = 0; k <= nder; k++)
        for (c = 0; c < dim; c++) {
            double s = 0.0;
            for (j = 0; j < b->order; j++)
                s += ders[k * b->order + j] * b->ctrl[(first + j) * dim + c];
            out[k * dim + c] = s;
        }
    return 0;
}

void bspline_cubic_matrix(double u, double *M)
{
    const double m[16] = {
        -u,
        12.0 - 9.0 * u,
        9.0 * u - 12.0,
        u,
        3.0 * u,
        12.0 * u - 18.0,
        18.0 - 15.0 * u,
        0.0,
        -3.0 * u,
        0.0,
        3.0 * u,
        0.0,
        u,
        6.0 - 2.0 * u,
        u,
        0.0,
    };
    int i;

    for (i = 0; i < 16; i++)
        M[i] = m[i] / 6.0;
}

void bspline_cubic_segment(const double *M, const double *p, size_t dim, double t, unsigned nder,
                           double *out)
{
    size_t c;
    int r, j;

    for (c = 0; c < dim; c++) {
        double co[4]; /* co[0] t^3 + co[1] t^2 + co[2] t + co[3] */
        for (r = 0; r < 4; r++) {
            co[r] = 0.0;
            for (j = 0; j < 4; j++)
                co[r] += M[r * 4 + j] * p[(size_t)j * dim + c];
        }
        out[c] = ((co[0] * t + co[1]) * t + co[2]) * t + co[3];
        if (nder >= 1)
            out[dim + c] = (3.0 * co[0] * t + 2.0 * co[1]) * t + co[2];
        if (nder >= 2)
            out[2 * dim + c] = 6.0 * co[0] * t + 2.0 * co[1];
        if (nder >= 3)
            out[3 * dim + c] = 6.0 * co[0];
    }
}
