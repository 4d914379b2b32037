/* test_nmea0183.c - GGA, RMC and VTG sentences (lib/format/nmea0183.h) against
 * the example sentences every NMEA 0183 primer quotes (with their published
 * checksums *47 and *6A) and gpsbabel's output for tests/data/gpxgo_visnjan.gpx. */
#include "test.h"

#include <math.h>

#include "nmea0183.h"

/* Given the classic GGA example, then 12:35:19, 48 deg 07.038' N,
 * 11 deg 31.000' E, quality 1, 545.4 m above MSL, geoid 46.9 m. */
static void test_gga_example(void **state)
{
    (void)state;
    nmea0183_fix_t f;
    assert_int_equal(
        nmea0183_parse("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47", &f), 0);
    assert_int_equal(f.kind, NMEA0183_GGA);
    assert_true(f.valid);
    assert_true(f.has_pos);
    assert_true(fabs(f.tod_s - (12 * 3600 + 35 * 60 + 19)) < 1e-9);
    assert_true(fabs(f.lat_deg - (48 + 7.038 / 60)) < 1e-12);
    assert_true(fabs(f.lon_deg - (11 + 31.0 / 60)) < 1e-12);
    assert_true(fabs(f.alt_m - 545.4) < 1e-12);
    assert_true(fabs(f.sep_m - 46.9) < 1e-12);
    assert_false(f.has_date);
}

/* Given the classic RMC example, then status A and 23 March 1994; west and
 * south hemispheres are negative. */
static void test_rmc_example(void **state)
{
    (void)state;
    nmea0183_fix_t f;
    assert_int_equal(
        nmea0183_parse("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A", &f),
        0);
    assert_int_equal(f.kind, NMEA0183_RMC);
    assert_true(f.valid);
    assert_true(f.has_date);
    assert_int_equal(f.days, 8847); /* 1994-03-23 */
    assert_true(isnan(f.alt_m));
    /* gpsbabel's sentence for the first point of visnjan: 2014-08-22 */
    assert_int_equal(
        nmea0183_parse("$GPRMC,164852.000,A,4516.395,N,01342.911,E,0.00,0.00,220814,,*06", &f), 0);
    assert_int_equal(f.days, 16304);
    assert_true(fabs(f.tod_s - 60532.0) < 1e-9);
    /* status V: no valid fix */
    assert_int_equal(
        nmea0183_parse("$GPRMC,164852.000,V,4516.395,N,01342.911,E,0.00,0.00,220814,,*11", &f), 0);
    assert_false(f.valid);
    assert_int_equal(
        nmea0183_parse("$GPGGA,000001,4807.038,S,01131.000,W,1,08,0.9,5,M,,M,,*4A", &f), 0);
    assert_true(f.lat_deg < 0 && f.lon_deg < 0);
    assert_true(isnan(f.sep_m));
}

/* Given the classic RMC example's speed and course (022.4 knots, 084.4
 * degrees true) and the classic VTG example with its published checksum *48
 * (054.7 T, 005.5 knots, 010.2 km/h), then speed in m/s (1 knot = 1852 m per
 * 3600 s) and the course; VTG's mode N is no velocity; km/h serves without
 * knots; a speed without a course is none, except a speed of 0; a course
 * beyond 360 is out of range. */
static void test_velocity(void **state)
{
    (void)state;
    nmea0183_fix_t f;
    assert_int_equal(
        nmea0183_parse("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A", &f),
        0);
    assert_true(f.has_vel);
    assert_true(fabs(f.sog_m_s - 22.4 * 1852.0 / 3600.0) < 1e-12);
    assert_true(fabs(f.cog_deg - 84.4) < 1e-12);
    assert_int_equal(nmea0183_parse("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48", &f), 0);
    assert_int_equal(f.kind, NMEA0183_VTG);
    assert_true(f.has_vel);
    assert_true(fabs(f.sog_m_s - 5.5 * 1852.0 / 3600.0) < 1e-12);
    assert_true(fabs(f.cog_deg - 54.7) < 1e-12);
    assert_int_equal(nmea0183_parse("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K,N*2A", &f), 0);
    assert_false(f.has_vel);
    assert_int_equal(nmea0183_parse("$GPVTG,054.7,T,034.4,M,,N,010.2,K,A*0B", &f), 0);
    assert_true(f.has_vel);
    assert_true(fabs(f.sog_m_s - 10.2 / 3.6) < 1e-12);
    assert_int_equal(
        nmea0183_parse("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,,230394,003.1,W*4C", &f), 0);
    assert_false(f.has_vel);
    assert_int_equal(
        nmea0183_parse("$GPRMC,123519,A,4807.038,N,01131.000,E,0.0,,230394,003.1,W*48", &f), 0);
    assert_true(f.has_vel);
    assert_true(fabs(f.sog_m_s) < 1e-300);
    assert_int_equal(
        nmea0183_parse("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,400.0,230394,003.1,W*66", &f),
        -NMEA0183_ERANGE);
}

/* Given a wrong, a missing or a malformed checksum, then refused; other
 * sentences with a good checksum are OTHER; broken fields are refused. */
static void test_refused(void **state)
{
    (void)state;
    nmea0183_fix_t f;
    assert_int_equal(
        nmea0183_parse("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*48", &f),
        -NMEA0183_ECHECKSUM);
    assert_int_equal(
        nmea0183_parse("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,", &f),
        -NMEA0183_ECHECKSUM);
    assert_int_equal(
        nmea0183_parse("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*4G", &f),
        -NMEA0183_ECHECKSUM);
    assert_int_equal(nmea0183_parse("$GPGSA,A,3,,,,,,,,,,,,,0.0,0.0,0.0*32", &f), 0);
    assert_int_equal(f.kind, NMEA0183_OTHER);
    assert_int_equal(nmea0183_parse("hello", &f), -NMEA0183_ESYNTAX);
    /* 61 minutes of latitude (checksum made right): out of range */
    assert_int_equal(
        nmea0183_parse("$GPGGA,123519,4861.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47", &f),
        -NMEA0183_ERANGE);
    /* hour 25 */
    assert_int_equal(
        nmea0183_parse("$GPGGA,253519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*43", &f),
        -NMEA0183_ERANGE);
    assert_non_null(nmea0183_strerror(-NMEA0183_ECHECKSUM));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gga_example),
        cmocka_unit_test(test_rmc_example),
        cmocka_unit_test(test_velocity),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
