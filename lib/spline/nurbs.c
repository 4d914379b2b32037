/* nurbs.c - rational B-splines; see nurbs.h. */
#include "nurbs.h"

#include <math.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* A sweep above 2 pi by more than this (rounding of 2*M_PI) is refused. */
#define NURBS_SWEEP_TOL 1e-12

const char *nurbs_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case NURBS_OK: return "success";
    case NURBS_EBSPLINE: return "NURBS: invalid B-spline (order, knots or size)";
    case NURBS_EWEIGHT: return "NURBS: weight not finite or not positive";
    case NURBS_EDOMAIN: return "NURBS: parameter outside the domain or not finite";
    case NURBS_ESIZE: return "NURBS: dimension or derivative count out of range";
    case NURBS_EARG: return "NURBS arc: radius, sweep or centre out of range";
    default: return "unknown nurbs error";
    }
}

static void as_bspline(const nurbs_t *c, bspline_t *b)
{
    b->order = c->order;
    b->n_ctrl = c->n_ctrl;
    b->dim = c->dim;
    b->knots = c->knots;
    b->ctrl = c->ctrl;
}

int nurbs_check(const nurbs_t *c)
{
    bspline_t b;
    size_t i;

    if (c->dim == 0 || c->dim > NURBS_DIM_MAX)
        return -NURBS_ESIZE;
    as_bspline(c, &b);
    if (bspline_check(&b) < 0)
        return -NURBS_EBSPLINE;
    for (i = 0; i < c->n_ctrl; i++)
        if (!isfinite(c->w[i]) || !(c->w[i] > 0.0))
            return -NURBS_EWEIGHT;
    return 0;
}

int nurbs_eval_derivs(const nurbs_t *c, double t, unsigned nder, double *out)
{
    double ders[3 * BSPLINE_ORDER_MAX];
    double A[3][NURBS_DIM_MAX], W[3];
    size_t first, k, dim = c->dim;
    unsigned d, j;
    int rc;

    if (dim == 0 || dim > NURBS_DIM_MAX || nder > 2)
        return -NURBS_ESIZE;
    rc = bspline_basis_derivs(c->knots, c->n_ctrl, c->order, t, nder, &first, ders);
    if (rc == -BSPLINE_EDOMAIN)
        return -NURBS_EDOMAIN;
    if (rc == -BSPLINE_ESIZE)
        return -NURBS_ESIZE;
    if (rc < 0)
        return -NURBS_EBSPLINE;
    for (d = 0; d <= nder; d++) {
        W[d] = 0.0;
        for (k = 0; k < dim; k++)
            A[d][k] = 0.0;
        for (j = 0; j < c->order; j++) {
            double wn = ders[d * c->order + j] * c->w[first + j];
            W[d] += wn;
            for (k = 0; k < dim; k++)
                A[d][k] += wn * c->ctrl[(first + j) * dim + k];
        }
    }
    /* W[0] >= min weight > 0 (convex combination of the weights). */
    for (k = 0; k < dim; k++) {
        double r0 = A[0][k] / W[0];
        out[k] = r0;
        if (nder >= 1) {
            double r1 = (A[1][k] - W[1] * r0) / W[0];
            out[dim + k] = r1;
            if (nder >= 2)
                out[2 * dim + k] = (A[2][k] - 2.0 * W[1] * r1 - W[2] * r0) / W[0];
        }
    }
    return 0;
}

int nurbs_eval(const nurbs_t *c, double t, double *out)
{
    return nurbs_eval_derivs(c, t, 0, out);
}

void nurbs_unit_circle(double *knots, double *ctrl, double *w, nurbs_t *c)
{
    static const double K[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
    static const double P[18] = {1, 0, 1, 1, 0, 1, -1, 1, -1, 0, -1, -1, 0, -1, 1, -1, 1, 0};
    size_t i;

    memcpy(knots, K, sizeof K);
    memcpy(ctrl, P, sizeof P);
    for (i = 0; i < 9; i++)
        w[i] = (i % 2) ? sqrt(2.0) / 2.0 : 1.0;
    if (c) {
        c->order = 3;
        c->n_ctrl = 9;
        c->dim = 2;
        c->knots = knots;
        c->ctrl = ctrl;
        c->w = w;
    }
}

static unsigned arc_pieces(double sweep)
{
    double a = fabs(sweep);
    unsigned n = (unsigned)ceil(a / (M_PI / 2.0) - 1e-12);
    return n < 1 ? 1 : (n > NURBS_ARC_PIECES_MAX ? NURBS_ARC_PIECES_MAX : n);
}

/*
 * The NURBS Book, A7.1, for a planar circle: piece k spans angles
 * [a_k, a_k + d], end poles on the circle, the middle pole at the tangents'
 * intersection, centre + r/cos(d/2) (cos(mid), sin(mid)), weight cos(d/2).
 * d <= pi/2, so cos(d/2) >= sqrt(2)/2: no division by a small number.
 */
int nurbs_arc(double cx, double cy, double cz, size_t dim, double r_m, double start_rad,
              double sweep_rad, double *knots, double *ctrl, double *w, nurbs_t *c)
{
    unsigned np, k;
    double d, half, wm;
    size_t i;

    if ((dim != 2 && dim != 3) || !isfinite(cx) || !isfinite(cy) || !isfinite(cz) ||
        !isfinite(r_m) || !(r_m > 0.0) || !isfinite(start_rad) || !isfinite(sweep_rad) ||
        !(fabs(sweep_rad) > 0.0) || fabs(sweep_rad) > 2.0 * M_PI + NURBS_SWEEP_TOL)
        return -NURBS_EARG;
    np = arc_pieces(sweep_rad);
    d = sweep_rad / np;
    half = 0.5 * d;
    wm = cos(half);
    for (k = 0; k <= 2 * np; k++) {
        double a, rr;
        if (k % 2 == 0) {
            a = start_rad + d * (k / 2);
            rr = r_m;
            w[k] = 1.0;
        } else {
            a = start_rad + d * (k / 2) + half;
            rr = r_m / wm;
            w[k] = wm;
        }
        ctrl[k * dim + 0] = cx + rr * cos(a);
        ctrl[k * dim + 1] = cy + rr * sin(a);
        if (dim == 3)
            ctrl[k * dim + 2] = cz;
    }
    /* A full circle: make the last pole bit-identical to the first. */
    if (fabs(fabs(sweep_rad) - 2.0 * M_PI) < NURBS_SWEEP_TOL)
        for (i = 0; i < dim; i++)
            ctrl[2 * np * dim + i] = ctrl[i];
    /* knots: 0,0,0, 1/np,1/np, ..., 1,1,1 */
    i = 0;
    knots[i++] = 0.0;
    knots[i++] = 0.0;
    knots[i++] = 0.0;
    for (k = 1; k < np; k++) {
        knots[i++] = (double)k / np;
        knots[i++] = (double)k / np;
    }
    knots[i++] = 1.0;
    knots[i++] = 1.0;
    knots[i++] = 1.0;
    if (c) {
        c->order = 3;
        c->n_ctrl = 2 * np + 1;
        c->dim = dim;
        c->knots = knots;
        c->ctrl = ctrl;
        c->w = w;
    }
    return 0;
}

double nurbs_arc_param(double sweep_rad, double frac)
{
    unsigned np = arc_pieces(sweep_rad), k;
    double pos, phi, th, s;

    if (!(frac > 0.0))
        return 0.0;
    if (!(frac < 1.0))
        return 1.0;
    pos = frac * np;
    k = (unsigned)floor(pos);
    if (k >= np)
        k = np - 1;
    /* angle from the piece's middle, in units of the piece's half-angle */
    phi = 0.5 * fabs(sweep_rad) / np;               /* half-angle, <= pi/4 */
    th = (pos - k - 0.5) * 2.0 * phi;               /* in [-phi, phi] */
    s = 0.5 + 0.5 * tan(0.5 * th) / tan(0.5 * phi); /* tan(phi/2) >= tan(tiny) > 0 */
    return ((double)k + s) / np;
}

int nurbs_conic(const double *p, size_t dim, double w1, double *knots, double *ctrl, double *w,
                nurbs_t *c)
{
    size_t i;

    if (dim == 0 || dim > NURBS_DIM_MAX)
        return -NURBS_ESIZE;
    if (!isfinite(w1) || !(w1 > 0.0))
        return -NURBS_EWEIGHT;
    for (i = 0; i < 3 * dim; i++)
        ctrl[i] = p[i];
    for (i = 0; i < 6; i++)
        knots[i] = i < 3 ? 0.0 : 1.0;
    w[0] = 1.0;
    w[1] = w1;
    w[2] = 1.0;
    if (c) {
        c->order = 3;
        c->n_ctrl = 3;
        c->dim = dim;
        c->knots = knots;
        c->ctrl = ctrl;
        c->w = w;
    }
    return 0;
}
