/* test_geo.c - WGS84 geodetic -> ECEF -> ENU against closed-form values.
 * (tests/oracle/test_geo.py checks the same functions against pyproj.) */
#include "test.h"

#include <math.h>

#include "geo.h"

/* ECEF coordinates are ~6.4e6 m: one ulp is ~1e-9 m, a few operations a few
 * ulps.  1e-6 m is a thousand times the rounding and a thousand times below
 * the millimetre the loader promises. */
#define TOL_M 1e-6

/* WGS84 semi-minor axis b = a(1 - f), NIMA TR8350.2 table 3.3: 6356752.3142 m. */
#define WGS84_B_M 6356752.314245179

/* Given the equator/prime meridian, the pole and 90E, when converted to ECEF,
 * then they sit on the axes at a, b and a. */
static void test_ecef_axes(void **state)
{
    (void)state;
    double p[3];
    assert_int_equal(geo_to_ecef(0, 0, 0, p), 0);
    assert_true(fabs(p[0] - GEO_WGS84_A_M) < TOL_M && fabs(p[1]) < TOL_M && fabs(p[2]) < TOL_M);
    assert_int_equal(geo_to_ecef(90, 0, 0, p), 0);
    assert_true(fabs(p[0]) < TOL_M && fabs(p[1]) < TOL_M && fabs(p[2] - WGS84_B_M) < 1e-4);
    assert_int_equal(geo_to_ecef(0, 90, 100, p), 0);
    assert_true(fabs(p[0]) < TOL_M && fabs(p[1] - GEO_WGS84_A_M - 100) < TOL_M &&
                fabs(p[2]) < TOL_M);
    assert_int_equal(geo_to_ecef(-90, 0, 0, p), 0);
    assert_true(fabs(p[2] + WGS84_B_M) < 1e-4);
}

/* Given an origin, when a point is straight above it, then ENU is (0, 0, h). */
static void test_enu_vertical(void **state)
{
    (void)state;
    geo_enu_t f;
    double enu[3];
    assert_int_equal(geo_enu_init(45.273245, 13.715185, 271.0, &f), 0);
    assert_int_equal(geo_to_enu(&f, 45.273245, 13.715185, 1271.0, enu), 0);
    assert_true(fabs(enu[0]) < TOL_M && fabs(enu[1]) < TOL_M && fabs(enu[2] - 1000.0) < TOL_M);
    assert_int_equal(geo_to_enu(&f, 45.273245, 13.715185, 271.0, enu), 0);
    assert_true(fabs(enu[0]) < TOL_M && fabs(enu[1]) < TOL_M && fabs(enu[2]) < TOL_M);
}

/* Given an origin on the equator, when a point lies on the equator dlon east,
 * then east = a sin(dlon), north = 0, up = a cos(dlon) - a (the circle of the
 * equator has radius a: an exact closed form, not our formula). */
static void test_enu_equator_circle(void **state)
{
    (void)state;
    geo_enu_t f;
    double enu[3];
    assert_int_equal(geo_enu_init(0, 10, 0, &f), 0);
    for (double dlon = -3; dlon <= 3; dlon += 0.25) {
        double r = dlon * M_PI / 180;
        assert_int_equal(geo_to_enu(&f, 0, 10 + dlon, 0, enu), 0);
        assert_true(fabs(enu[0] - GEO_WGS84_A_M * sin(r)) < TOL_M);
        assert_true(fabs(enu[1]) < TOL_M);
        assert_true(fabs(enu[2] - (GEO_WGS84_A_M * cos(r) - GEO_WGS84_A_M)) < TOL_M);
    }
}

/* Given an origin at 45N, when a point moves 0.01 deg along the meridian,
 * then east stays 0 and north is the meridian arc M*dphi = 1111.32 m
 * (M = a(1-e2)/(1-e2 sin^2 phi)^1.5 at 45.005N = 6367387.4 m; the chord in
 * the tangent plane is shorter than the arc by well under 1 cm). */
static void test_enu_meridian(void **state)
{
    (void)state;
    geo_enu_t f;
    double enu[3];
    assert_int_equal(geo_enu_init(45, 7, 0, &f), 0);
    assert_int_equal(geo_to_enu(&f, 45.01, 7, 0, enu), 0);
    assert_true(fabs(enu[0]) < TOL_M);
    assert_true(fabs(enu[1] - 1111.3188) < 0.01);
    assert_true(enu[2] < 0);
}

/* Given an origin at latitude phi, when a point lies on the same parallel
 * dlon east, then (the parallel is a circle of radius r = N cos phi about the
 * axis, N = a / sqrt(1 - e2 sin^2 phi)): east = r sin dlon,
 * north = r (1 - cos dlon) sin phi, up = -r (1 - cos dlon) cos phi.
 * The parallel bends north of the tangent plane's east axis. */
static void test_enu_parallel_circle(void **state)
{
    (void)state;
    const double f_ = 1.0 / GEO_WGS84_INV_F, e2 = f_ * (2 - f_);
    const double lats[] = {-60.5, -12.25, 33.3, 45.273245, 78.9};
    for (size_t k = 0; k < sizeof lats / sizeof lats[0]; k++) {
        double phi = lats[k] * M_PI / 180;
        double r = GEO_WGS84_A_M / sqrt(1 - e2 * sin(phi) * sin(phi)) * cos(phi);
        geo_enu_t f;
        double enu[3];
        assert_int_equal(geo_enu_init(lats[k], 13.7, 0, &f), 0);
        for (double dlon = -2; dlon <= 2; dlon += 0.5) {
            double dl = dlon * M_PI / 180;
            assert_int_equal(geo_to_enu(&f, lats[k], 13.7 + dlon, 0, enu), 0);
            assert_true(fabs(enu[0] - r * sin(dl)) < TOL_M);
            assert_true(fabs(enu[1] - r * (1 - cos(dl)) * sin(phi)) < TOL_M);
            assert_true(fabs(enu[2] + r * (1 - cos(dl)) * cos(phi)) < TOL_M);
        }
    }
}

/* Given bad input, when checked or converted, then the documented error comes
 * back and the output is untouched. */
static void test_errors(void **state)
{
    (void)state;
    double p[3] = {1, 2, 3};
    assert_int_equal(geo_to_ecef(NAN, 0, 0, p), -GEO_ENOTFINITE);
    assert_int_equal(geo_to_ecef(0, INFINITY, 0, p), -GEO_ENOTFINITE);
    assert_int_equal(geo_to_ecef(90.5, 0, 0, p), -GEO_ELAT);
    assert_int_equal(geo_to_ecef(0, 361, 0, p), -GEO_ELON);
    assert_int_equal(geo_to_ecef(0, 0, 2e6, p), -GEO_EALT);
    const double orig[3] = {1, 2, 3};
    assert_memory_equal(p, orig, sizeof p); /* untouched */
    geo_enu_t f;
    assert_int_equal(geo_enu_init(-91, 0, 0, &f), -GEO_ELAT);
    assert_string_equal(geo_strerror(-GEO_ELAT), "latitude outside [-90, 90] degrees");
    assert_string_equal(geo_strerror(0), "success");
    assert_string_equal(geo_strerror(99), "unknown geo error");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ecef_axes),           cmocka_unit_test(test_enu_vertical),
        cmocka_unit_test(test_enu_equator_circle),  cmocka_unit_test(test_enu_meridian),
        cmocka_unit_test(test_enu_parallel_circle), cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
