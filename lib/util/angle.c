/* angle.c - the heading axis: unwrap, monotone cubic Hermite, wrap.  See angle.h. */
#include "angle.h"

#include <math.h>

double angle_wrap_deg(double a)
{
    if (!isfinite(a))
        return a;
    double w = fmod(a, 360.0); /* (-360, 360) */
    if (w <= -180.0)
        w += 360.0;
    else if (w > 180.0)
        w -= 360.0;
    return w;
}

void angle_unwrap_deg(double *a, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        double d = a[i] - a[i - 1];
        a[i] -= 360.0 * round(d / 360.0); /* |d| <= 180 after */
    }
}

/* Fritsch-Butland tangent at an interior sample: weighted harmonic mean of
 * the neighbouring slopes, 0 at a local extremum. */
static double tangent_mid(double h0, double h1, double d0, double d1)
{
    if (d0 * d1 <= 0.0)
        return 0.0;
    double w1 = 2.0 * h1 + h0, w2 = h1 + 2.0 * h0;
    return (w1 + w2) / (w1 / d0 + w2 / d1);
}

/* One-sided three-point tangent at an end, kept shape-preserving (scipy's
 * PchipInterpolator._edge_case). */
static int sign(double v)
{
    return (v > 0) - (v < 0);
}

static double tangent_end(double h0, double h1, double d0, double d1)
{
    double m = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
    if (sign(m) != sign(d0))
        return 0.0;
    if (sign(d0) != sign(d1) && fabs(m) > fabs(3.0 * d0))
        return 3.0 * d0;
    return m;
}

/* Tangent at sample i (n >= 2). */
static double tangent(const double *t, const double *a, size_t n, size_t i)
{
    if (n == 2)
        return (a[1] - a[0]) / (t[1] - t[0]);
    if (i == 0)
        return tangent_end(t[1] - t[0], t[2] - t[1], (a[1] - a[0]) / (t[1] - t[0]),
                           (a[2] - a[1]) / (t[2] - t[1]));
    if (i == n - 1)
        return tangent_end(t[n - 1] - t[n - 2], t[n - 2] - t[n - 3],
                           (a[n - 1] - a[n - 2]) / (t[n - 1] - t[n - 2]),
                           (a[n - 2] - a[n - 3]) / (t[n - 2] - t[n - 3]));
    return tangent_mid(t[i] - t[i - 1], t[i + 1] - t[i], (a[i] - a[i - 1]) / (t[i] - t[i - 1]),
                       (a[i + 1] - a[i]) / (t[i + 1] - t[i]));
}

double angle_pchip_eval(const double *t, const double *a, size_t n, double x, size_t *hint)
{
    if (n == 0 || isnan(x))
        return NAN;
    if (n == 1 || x <= t[0])
        return a[0];
    if (x >= t[n - 1])
        return a[n - 1];
    size_t i = *hint < n - 1 ? *hint : 0;
    if (t[i] > x)
        i = 0;
    while (t[i + 1] < x) /* t[n-1] > x: stops before n-1 */
        i++;
    *hint = i;
    double h = t[i + 1] - t[i], s = (x - t[i]) / h;
    double m0 = tangent(t, a, n, i) * h, m1 = tangent(t, a, n, i + 1) * h;
    double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * a[i] + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * a[i + 1] +
           (s3 - s2) * m1;
}
