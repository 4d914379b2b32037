/* cspline.c - C2 interpolating cubic spline (seed 002); see cspline.h. */
#include "cspline.h"

#include <math.h>
#include <string.h>

#include "tridiag.h"

/* An evaluation parameter this far (relative to t_n - t_0) past an end is clamped. */
#define CSPLINE_DOMAIN_REL_TOL 1e-12

const char *cspline_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case CSPLINE_OK: return "success";
    case CSPLINE_ESIZE: return "cubic spline: too few points (2, periodic 3) or no coordinate";
    case CSPLINE_EPARAM: return "cubic spline: parameters not finite or not strictly increasing";
    case CSPLINE_ENOTFINITE: return "cubic spline: point or end derivative not finite";
    case CSPLINE_ENOTCLOSED:
        return "cubic spline: periodic curve whose last point is not its first";
    case CSPLINE_ESINGULAR: return "cubic spline: system could not be solved";
    case CSPLINE_EDOMAIN: return "cubic spline: parameter outside the curve or not finite";
    default: return "unknown cspline error";
    }
}

int cspline_params(size_t npts, size_t dim, const double *p, cspline_param_t param, double *t)
{
    size_t i, c;

    if (npts < 2 || dim == 0)
        return -CSPLINE_ESIZE;
    if (param == CSPLINE_PARAM_GIVEN)
        return 0;
    t[0] = 0.0;
    for (i = 1; i < npts; i++) {
        if (param == CSPLINE_PARAM_UNIFORM) {
            t[i] = (double)i;
            continue;
        }
        double d2 = 0.0;
        for (c = 0; c < dim; c++) {
            double d = p[i * dim + c] - p[(i - 1) * dim + c];
            d2 += d * d;
        }
        if (!isfinite(d2))
            return -CSPLINE_ENOTFINITE;
        t[i] = t[i - 1] + sqrt(d2);
    }
    return 0;
}

size_t cspline_scratch_len(size_t npts, size_t dim)
{
    /* a, b, c, tridiag scratch, Sherman-Morrison vector, spare; rhs */
    return 6 * npts + npts * dim;
}

/* Right-hand side 6 (p_{i+1}-p_i)/h_i - 6 (p_i-p_{i-1})/h_{i-1} for coordinate c. */
static double rhs_row(const double *p, size_t dim, size_t im, size_t i, size_t ip, double hm,
                      double h, size_t c)
{
    return 6.0 * (p[ip * dim + c] - p[i * dim + c]) / h -
           6.0 * (p[i * dim + c] - p[im * dim + c]) / hm;
}

static int check_input(size_t npts, size_t dim, const double *t, const double *p)
{
    size_t i;

    for (i = 0; i < npts * dim; i++)
        if (!isfinite(p[i]))
            return -CSPLINE_ENOTFINITE;
    for (i = 0; i < npts; i++)
        if (!isfinite(t[i]) || (i > 0 && !(t[i] > t[i - 1])))
            return -CSPLINE_EPARAM;
    return 0;
}

static int solve_open(size_t npts, size_t dim, const double *t, const double *p, cspline_end_t end,
                      const double *d0, const double *dn, double *s, double *scratch)
{
    size_t n = npts - 1, i, c;
    double *a = scratch, *b = a + npts, *cc = b + npts, *tw = cc + npts;
    double *d = tw + 3 * npts;
    int rc;

    if (end == CSPLINE_END_CLAMPED) {
        if (!d0 || !dn)
            return -CSPLINE_ENOTFINITE;
        for (c = 0; c < dim; c++)
            if (!isfinite(d0[c]) || !isfinite(dn[c]))
                return -CSPLINE_ENOTFINITE;
    }
    if (n == 1 && end == CSPLINE_END_CURVATURE) {
        /* s_0 = s_1 is then all there is: any common value interpolates.
         * Take the straight line (s = 0), the natural choice. */
        memset(s, 0, npts * dim * sizeof *s);
        return 0;
    }
    for (i = 1; i < n; i++) {
        double hm = t[i] - t[i - 1], h = t[i + 1] - t[i];
        a[i] = hm;
        b[i] = 2.0 * (hm + h);
        cc[i] = h;
        for (c = 0; c < dim; c++)
            d[i * dim + c] = rhs_row(p, dim, i - 1, i, i + 1, hm, h, c);
    }
    a[0] = 0.0;
    cc[n] = 0.0;
    switch (end) {
    case CSPLINE_END_CLAMPED: {
        double h0 = t[1] - t[0], hn = t[n] - t[n - 1];
        b[0] = 2.0 * h0;
        cc[0] = h0;
        a[n] = hn;
        b[n] = 2.0 * hn;
        for (c = 0; c < dim; c++) {
            d[c] = 6.0 * ((p[dim + c] - p[c]) / h0 - d0[c]);
            d[n * dim + c] = 6.0 * (dn[c] - (p[n * dim + c] - p[(n - 1) * dim + c]) / hn);
        }
        break;
    }
    case CSPLINE_END_CURVATURE:
        /* s_0 - s_1 = 0: the first pivot of row 1 becomes 2(h0+h1)+h0 > 0. */
        b[0] = 1.0;
        cc[0] = -1.0;
        a[n] = -1.0;
        b[n] = 1.0;
        for (c = 0; c < dim; c++)
            d[c] = d[n * dim + c] = 0.0;
        break;
    default: /* natural */
        b[0] = 1.0;
        cc[0] = 0.0;
        a[n] = 0.0;
        b[n] = 1.0;
        for (c = 0; c < dim; c++)
            d[c] = d[n * dim + c] = 0.0;
        break;
    }
    rc = tridiag_solve(npts, dim, a, b, cc, d, s, tw);
    return rc < 0 ? -CSPLINE_ESINGULAR : 0;
}

/*
 * Closed curve: unknowns s_0 .. s_{m-1} (m = n), s_n = s_0.  Row i couples
 * s_{i-1}, s_i, s_{i+1} cyclically.  Sherman-Morrison (as in Numerical
 * Recipes' cyclic): A = A' + u v^T with corners folded into A'; two Thomas
 * solves.  gamma = -b_0 keeps the modified diagonal b_0 - gamma = 2 b_0
 * dominant; the system is strictly diagonally dominant (2(h+h') > h + h'),
 * so 1 + v.z cannot vanish.
 */
static int solve_periodic(size_t npts, size_t dim, const double *t, const double *p, double *s,
                          double *scratch)
{
    size_t m = npts - 1, i, c;
    double *a = scratch, *b = a + npts, *cc = b + npts, *tw = cc + npts;
    double *z = tw + npts, *d = z + 2 * npts;
    double alpha, beta, gamma;
    int rc;

    for (i = 0; i < m; i++) {
        size_t im = i == 0 ? m - 1 : i - 1;
        double hm = i == 0 ? t[m] - t[m - 1] : t[i] - t[i - 1];
        double h = t[i + 1] - t[i];
        a[i] = hm;
        b[i] = 2.0 * (hm + h);
        cc[i] = h;
        for (c = 0; c < dim; c++) /* p[i+1] with i+1 = m is p[m] == p[0] */
            d[i * dim + c] = rhs_row(p, dim, im, i, i + 1, hm, h, c);
    }
    if (m == 2) {
        /* Both neighbours of each row are the other unknown: fold them. */
        double a2[2] = {0.0, a[1] + cc[1]}, c2[2] = {a[0] + cc[0], 0.0};
        rc = tridiag_solve(2, dim, a2, b, c2, d, s, tw);
        if (rc < 0)
            return -CSPLINE_ESINGULAR;
        for (c = 0; c < dim; c++)
            s[m * dim + c] = s[c];
        return 0;
    }
    alpha = cc[m - 1]; /* row m-1, column 0 */
    beta = a[0];       /* row 0, column m-1 */
    gamma = -b[0];
    b[0] -= gamma;
    b[m - 1] -= alpha * beta / gamma;
    rc = tridiag_solve(m, dim, a, b, cc, d, s, tw);
    if (rc < 0)
        return -CSPLINE_ESINGULAR;
    for (i = 0; i < m; i++)
        z[i] = 0.0;
    z[0] = gamma;
    z[m - 1] = alpha;
    rc = tridiag_solve(m, 1, a, b, cc, z, z, tw);
    if (rc < 0)
        return -CSPLINE_ESINGULAR;
    {
        double den = 1.0 + z[0] + beta * z[m - 1] / gamma;
        if (!(fabs(den) > 0.0) || !isfinite(den))
            return -CSPLINE_ESINGULAR;
        for (c = 0; c < dim; c++) {
            double f = (s[c] + beta * s[(m - 1) * dim + c] / gamma) / den;
            for (i = 0; i < m; i++)
                s[i * dim + c] -= f * z[i];
        }
    }
    for (c = 0; c < dim; c++)
        s[m * dim + c] = s[c];
    return 0;
}

int cspline_solve(size_t npts, size_t dim, const double *t, const double *p, cspline_end_t end,
                  const double *d0, const double *dn, double *s, double *scratch, cspline_t *cs)
{
    int rc;

    if (dim == 0 || npts < 2 || (end == CSPLINE_END_PERIODIC && npts < 3))
        return -CSPLINE_ESIZE;
    rc = check_input(npts, dim, t, p);
    if (rc < 0)
        return rc;
    if (end == CSPLINE_END_PERIODIC) {
        double ext = 0.0, gap = 0.0;
        size_t i, c;
        for (i = 0; i < npts * dim; i++)
            ext = fmax(ext, fabs(p[i] - p[i % dim]));
        for (c = 0; c < dim; c++)
            gap = fmax(gap, fabs(p[(npts - 1) * dim + c] - p[c]));
        if (gap > CSPLINE_CLOSED_REL_TOL * ext + 1e-300)
            return -CSPLINE_ENOTCLOSED;
        rc = solve_periodic(npts, dim, t, p, s, scratch);
    } else {
        rc = solve_open(npts, dim, t, p, end, d0, dn, s, scratch);
    }
    if (rc == 0 && cs) {
        cs->n = npts - 1;
        cs->dim = dim;
        cs->t = t;
        cs->p = p;
        cs->s = s;
        cs->periodic = end == CSPLINE_END_PERIODIC;
    }
    return rc;
}

long cspline_find(const cspline_t *cs, double *tp)
{
    const double *t = cs->t;
    double lo = t[0], hi = t[cs->n], x = *tp;
    size_t a, b;

    if (!isfinite(x))
        return -CSPLINE_EDOMAIN;
    if (cs->periodic) {
        double per = hi - lo;
        x = fmod(x - lo, per);
        if (x < 0.0)
            x += per;
        x += lo;
        if (x > hi)
            x = hi;
    } else {
        double tol = CSPLINE_DOMAIN_REL_TOL * (hi - lo);
        if (x < lo - tol || x > hi + tol)
            return -CSPLINE_EDOMAIN;
        x = x < lo ? lo : (x > hi ? hi : x);
    }
    /* Invariant t[a] <= x <= t[b]. */
    a = 0;
    b = cs->n;
    while (b - a > 1) {
        size_t mid = a + (b - a) / 2;
        if (x < t[mid])
            b = mid;
        else
            a = mid;
    }
    *tp = x;
    return (long)a;
}

int cspline_eval(const cspline_t *cs, double t, unsigned nder, double *out)
{
    long li;
    size_t i, c, dim = cs->dim;
    double h, w, h26;

    if (nder > 3)
        return -CSPLINE_ESIZE;
    li = cspline_find(cs, &t);
    if (li < 0)
        return (int)li;
    i = (size_t)li;
    h = cs->t[i + 1] - cs->t[i]; /* > 0: checked strictly increasing at solve */
    w = (t - cs->t[i]) / h;
    h26 = h * h / 6.0;
    for (c = 0; c < dim; c++) {
        double p0 = cs->p[i * dim + c], p1 = cs->p[(i + 1) * dim + c];
        double s0 = cs->s[i * dim + c], s1 = cs->s[(i + 1) * dim + c];
        double A = w * (-2.0 + w * (3.0 - w)), B = w * (w * w - 1.0);
        out[c] = (1.0 - w) * p0 + w * p1 + (A * s0 + B * s1) * h26;
        if (nder >= 1) {
            double A1 = -2.0 + w * (6.0 - 3.0 * w), B1 = 3.0 * w * w - 1.0;
            out[dim + c] = (p1 - p0) / h + (A1 * s0 + B1 * s1) * h / 6.0;
        }
        if (nder >= 2)
            out[2 * dim + c] = (1.0 - w) * s0 + w * s1;
        if (nder >= 3)
            out[3 * dim + c] = (s1 - s0) / h;
    }
    return 0;
}

void cspline_coeffs(const cspline_t *cs, size_t i, double *co)
{
    size_t c, dim = cs->dim;
    double h = cs->t[i + 1] - cs->t[i];

    for (c = 0; c < dim; c++) {
        double p0 = cs->p[i * dim + c], p1 = cs->p[(i + 1) * dim + c];
        double s0 = cs->s[i * dim + c], s1 = cs->s[(i + 1) * dim + c];
        co[c * 4 + 0] = (s1 - s0) / (6.0 * h);
        co[c * 4 + 1] = 0.5 * s0;
        co[c * 4 + 2] = (p1 - p0) / h - h * (2.0 * s0 + s1) / 6.0;
        co[c * 4 + 3] = p0;
    }
}
