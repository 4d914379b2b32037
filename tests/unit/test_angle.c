/* test_angle.c - the heading axis (lib/util/angle.h): wrap, unwrap, and a
 * turn across +-180 that goes the short way (tests/oracle/test_angle.py
 * checks the interpolant against scipy's PchipInterpolator). */
#include "test.h"

#include <math.h>

#include "angle.h"

static void test_wrap(void **state)
{
    (void)state;
    assert_true(fabs(angle_wrap_deg(180.0) - 180.0) < 1e-12);
    assert_true(fabs(angle_wrap_deg(-180.0) - 180.0) < 1e-12);
    assert_true(fabs(angle_wrap_deg(190.0) - -170.0) < 1e-12);
    assert_true(fabs(angle_wrap_deg(-190.0) - 170.0) < 1e-12);
    assert_true(fabs(angle_wrap_deg(725.0) - 5.0) < 1e-12);
    assert_true(isnan(angle_wrap_deg(NAN)));
}

/* Given headings 170, 179, -179, -170 (a turn to starboard across south),
 * then unwrapped they rise 170, 179, 181, 190, and every interpolated value
 * stays between 170 and 190 (wrapped: never near 0), rising monotonically. */
static void test_no_spin(void **state)
{
    (void)state;
    double t[] = {0, 1, 2, 3}, a[] = {170, 179, -179, -170};
    angle_unwrap_deg(a, 4);
    assert_true(fabs(a[2] - 181.0) < 1e-12 && fabs(a[3] - 190.0) < 1e-12);
    size_t hint = 0;
    double prev = -INFINITY;
    for (int i = 0; i <= 300; i++) {
        double x = i * 0.01, u = angle_pchip_eval(t, a, 4, x, &hint);
        assert_true(u >= 170.0 && u <= 190.0);
        assert_true(u >= prev);
        prev = u;
        double w = angle_wrap_deg(u);
        assert_true(fabs(w) >= 170.0 - 1e-9);
    }
    /* held outside the samples, NaN for none */
    assert_true(fabs(angle_pchip_eval(t, a, 4, -1.0, &hint) - 170.0) < 1e-12);
    assert_true(fabs(angle_pchip_eval(t, a, 4, 9.0, &hint) - 190.0) < 1e-12);
    assert_true(isnan(angle_pchip_eval(t, a, 0, 1.0, &hint)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_wrap), cmocka_unit_test(test_no_spin)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
