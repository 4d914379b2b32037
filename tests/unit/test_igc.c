/* test_igc.c - IGC date header and B records (lib/format/igc.h) against the
 * example B record of the FAI IGC flight recorder specification (appendix A:
 * "B1101355206343N00006198WA0058700558") and both HFDTE forms. */
#include "test.h"

#include <math.h>

#include "igc.h"

/* Given the specification's B record, then 11:01:35, 52 deg 06.343' N,
 * 0 deg 06.198' W, a 3-D fix, 587 m pressure and 558 m GNSS altitude. */
static void test_b_example(void **state)
{
    (void)state;
    igc_fix_t f;
    assert_int_equal(igc_parse_b("B1101355206343N00006198WA0058700558", &f), 0);
    assert_int_equal(f.tod_s, 11 * 3600 + 1 * 60 + 35);
    assert_true(fabs(f.lat_deg - (52 + 6.343 / 60)) < 1e-12);
    assert_true(fabs(f.lon_deg - -(6.198 / 60)) < 1e-12);
    assert_true(f.valid_3d);
    assert_int_equal(f.pressure_alt_m, 587);
    assert_int_equal(f.gnss_alt_m, 558);
    /* extensions after column 35 are allowed; negative altitudes too */
    assert_int_equal(igc_parse_b("B1101355206343S00006198EV-0012-0003123\r", &f), 0);
    assert_true(f.lat_deg < 0 && f.lon_deg > 0);
    assert_false(f.valid_3d);
    assert_int_equal(f.pressure_alt_m, -12);
    assert_int_equal(f.gnss_alt_m, -3);
}

/* Given broken B records, then refused: short, bad hemisphere, 60 minutes,
 * hour 24, validity other than A/V. */
static void test_b_refused(void **state)
{
    (void)state;
    igc_fix_t f;
    assert_int_equal(igc_parse_b("B1101355206343N00006198WA00587", &f), -IGC_ESYNTAX);
    assert_int_equal(igc_parse_b("B1101355206343X00006198WA0058700558", &f), -IGC_ESYNTAX);
    assert_int_equal(igc_parse_b("B1101355260000N00006198WA0058700558", &f), -IGC_ERANGE);
    assert_int_equal(igc_parse_b("B2401355206343N00006198WA0058700558", &f), -IGC_ERANGE);
    assert_int_equal(igc_parse_b("B1101355206343N00006198WX0058700558", &f), -IGC_ESYNTAX);
    assert_int_equal(igc_parse_b("B1101355206343N18100000WA0058700558", &f), -IGC_ERANGE);
    assert_non_null(igc_strerror(-IGC_ERANGE));
}

/* Given both header forms, then 16 July 2001; a 30 February is refused. */
static void test_date(void **state)
{
    (void)state;
    int64_t d = 0;
    assert_int_equal(igc_parse_date("HFDTE160701", &d), 0);
    assert_int_equal(d, 11519);
    d = 0;
    assert_int_equal(igc_parse_date("HFDTEDATE:160701,01", &d), 0);
    assert_int_equal(d, 11519);
    assert_int_equal(igc_parse_date("HFDTE300201", &d), -IGC_ERANGE);
    assert_int_equal(igc_parse_date("HFDTE3002", &d), -IGC_ESYNTAX);
    assert_int_equal(igc_parse_date("HFPLTPILOT:x", &d), -IGC_ESYNTAX);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_b_example),
        cmocka_unit_test(test_b_refused),
        cmocka_unit_test(test_date),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
