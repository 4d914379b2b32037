/*
 * angle.h - a heading (yaw) axis that wraps: no 360 degree spin when it
 * crosses +-180.  Pure (no I/O, no allocation).
 *
 * The input angles are unwrapped first (each sample moved by a multiple of
 * 360 so it differs from the previous one by at most 180: the short way
 * round), interpolated as an ordinary smooth function of time, and wrapped
 * again on output.  The interpolant is the monotone piecewise cubic Hermite
 * of Fritsch and Carlson with the tangents of Fritsch and Butland (F. N.
 * Fritsch, J. Butland, "A method for constructing local monotone piecewise
 * cubic interpolants", SIAM J. Sci. Stat. Comput. 5(2), 1984), the one
 * scipy.interpolate.PchipInterpolator computes (tests/oracle/test_angle.py
 * checks it against scipy): C1, through every sample, and never
 * overshooting between two samples, so a vessel turning from 170 to -170
 * goes through 180, never round through 0.
 */
#ifndef TRAJD_ANGLE_H
#define TRAJD_ANGLE_H
/* trajd public API: installed as <trajd/angle.h> (make install; pkg-config trajd). */

#include <stddef.h>

/* a wrapped to (-180, 180] degrees (NaN stays NaN). */
double angle_wrap_deg(double a);

/* Unwrap a[0..n-1] in place: a[i] - a[i-1] in [-180, 180] for every i > 0. */
void angle_unwrap_deg(double *a, size_t n);

/*
 * The monotone cubic Hermite interpolant of (t[i], a[i]), i < n (t strictly
 * increasing), at x; held at a[0] before t[0] and at a[n-1] after t[n-1].
 * *hint (start 0) is the interval of the previous call: a clock that moves
 * forward costs O(1) per call.  NaN if n == 0 or x is NaN.
 */
double angle_pchip_eval(const double *t, const double *a, size_t n, double x, size_t *hint);

#endif
