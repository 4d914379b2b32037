/* test_track_logs.c - the logged-track formats of the loader (issue 12):
 * NMEA 0183 and IGC written by gpsbabel (an independent converter) from the
 * GPX track in tests/data load as the same fixes as the GPX, to the
 * precision those formats hold; detection by extension and content; bad
 * lines with file:line; midnight.  Fails without gpsbabel (make check
 * installs it: DEPS_TEST). */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "geo.h"
#include "track.h"
#include "track_text.h"

#define VISNJAN_GPX "tests/data/gpxgo_visnjan.gpx"
#define VISNJAN_N 413
/* gpsbabel writes NMEA and IGC positions as degrees and thousandths of a
 * minute (ddmm.mmm): rounding is at most 0.0005' of arc, and a minute of
 * latitude is at most 1861.6 m (at the poles; 1852.2 m at 45 deg), so
 * <= 0.931 m north and <= 0.931 m * cos(lat) east. */
#define ROUND_MIN 0.0005
#define METRES_PER_MIN_MAX 1861.6
/* Altitude: NMEA writes 3 decimals (the GPX has 1), IGC whole metres. */
#define NMEA_ALT_M 0.0005
#define IGC_ALT_M 0.5
/* Comparing two ENU frames whose origins differ by <= 1 m: the frames turn
 * by <= 1.6e-7 rad, <= 3e-4 m over this 2 km track. */
#define FRAME_M 1e-3

static int parse(const char *name, const char *text, track_format_t fmt, unsigned flags, track_t *t,
                 char *err, size_t errlen)
{
    return track_load_text(name, text, strlen(text), fmt, flags, t, err, errlen);
}

/* Waypoint i of b expressed in a's ENU frame (b's origin placed in a's frame). */
static void in_frame_of(const track_t *a, const track_t *b, size_t i, double out[3])
{
    geo_enu_t fa;
    double o[3];
    assert_int_equal(geo_enu_init(a->lat0_deg, a->lon0_deg, a->alt0_m, &fa), 0);
    assert_int_equal(geo_to_enu(&fa, b->lat0_deg, b->lon0_deg, b->alt0_m, o), 0);
    for (int k = 0; k < 3; k++)
        out[k] = o[k] + b->wp[i].pos_m[k];
}

static void compare_with_gpx(const char *path, track_format_t want, double alt_tol_m)
{
    track_t g, x;
    char err[512];
    assert_int_equal(track_load_opts(VISNJAN_GPX, TRACK_FMT_AUTO, 0, &g, err, sizeof err), 0);
    if (track_load_opts(path, TRACK_FMT_AUTO, 0, &x, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_int_equal(x.format, want);
    assert_int_equal(x.n, VISNJAN_N);
    assert_int_equal(g.n, VISNJAN_N);
    double north = ROUND_MIN * METRES_PER_MIN_MAX;
    double east = north * cos(g.lat0_deg * M_PI / 180.0);
    double worst[3] = {0, 0, 0};
    for (size_t i = 0; i < g.n; i++) {
        double p[3];
        in_frame_of(&g, &x, i, p);
        assert_true(fabs(x.wp[i].t_s - g.wp[i].t_s) < 1e-9);
        for (int k = 0; k < 3; k++)
            if (fabs(p[k] - g.wp[i].pos_m[k]) > worst[k])
                worst[k] = fabs(p[k] - g.wp[i].pos_m[k]);
    }
    print_message(
        "%s: worst |d east| %.3f m (bound %.3f), |d north| %.3f m (%.3f), |d up| %.4f m (%.4f)\n",
        path, worst[0], east + FRAME_M, worst[1], north + FRAME_M, worst[2], alt_tol_m + FRAME_M);
    assert_true(worst[0] <= east + FRAME_M);
    assert_true(worst[1] <= north + FRAME_M);
    assert_true(worst[2] <= alt_tol_m + FRAME_M);
    /* and the rounding is there: the comparison can see a difference */
    assert_true(worst[1] > 0.01);
    track_free(&g);
    track_free(&x);
}

/* Given the GPX with a 3-D fix marked on each point (gpsbabel writes GGA
 * quality 0 / RMC status V without one), when gpsbabel converts it to NMEA
 * and IGC, then each loads as the GPX's 413 fixes: same times, positions
 * within the formats' rounding. */
static void test_gpsbabel_nmea_igc(void **state)
{
    (void)state;
    /* the reference is a dependency of the tests (Makefile DEPS_TEST): a
     * missing one fails, a test that skips its reference passes on nothing */
    if (system("command -v gpsbabel > /dev/null 2>&1") != 0)
        fail_msg("gpsbabel is not installed (Debian package gpsbabel, tests/deps.sh)");
    char dir[] = "/tmp/trajd-track-logs-XXXXXX", cmd[1024], nmea[256], igc[256];
    assert_non_null(mkdtemp(dir));
    snprintf(nmea, sizeof nmea, "%s/v.nmea", dir);
    snprintf(igc, sizeof igc, "%s/v.igc", dir);
    snprintf(
        cmd, sizeof cmd,
        "sed 's|</time></trkpt>|</time><fix>3d</fix></trkpt>|' " VISNJAN_GPX " > %s/f.gpx && "
        "gpsbabel -i gpx -f %s/f.gpx -o nmea -F %s && gpsbabel -i gpx -f %s/f.gpx -o igc -F %s",
        dir, dir, nmea, dir, igc);
    assert_int_equal(system(cmd), 0);
    compare_with_gpx(nmea, TRACK_FMT_NMEA0183, NMEA_ALT_M);
    compare_with_gpx(igc, TRACK_FMT_IGC, IGC_ALT_M);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

static const char nmea_text[] =
    "$GPGSA,A,3,,,,,,,,,,,,,0.0,0.0,0.0*32\n"
    "$GPRMC,235959.000,A,4516.395,N,01342.911,E,0.00,0.00,220814,,*0B\n"
    "$GPGGA,235959.000,4516.395,N,01342.911,E,1,00,0.0,271.000,M,0.0,M,,*6D\n"
    "$GPGGA,000001.500,4516.396,N,01342.911,E,1,00,0.0,272.000,M,0.0,M,,*68\n"
    "$GPGGA,000002.000,4516.397,N,01342.911,E,0,00,0.0,272.000,M,0.0,M,,*6E\n"
    "$GPRMC,000003.000,A,4516.398,N,01342.911,E,0.00,0.00,230814,,*05\n";

/* Given NMEA sentences across midnight (no RMC between), then times run on
 * (2.5 s after the first), an invalid GGA is ignored and counted, and so is
 * an RMC alone in a log with a GGA at every time (its GGA lost: its altitude
 * unknown; kept at the datum's height, a lost GGA made a 31 m dip in a
 * walk's curve); detection by content. */
static void test_nmea_midnight_and_validity(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("log.txt", nmea_text, TRACK_FMT_AUTO, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.format, TRACK_FMT_NMEA0183);
    assert_int_equal(t.n, 2);
    assert_int_equal(t.ignored, 2);
    assert_true(fabs(t.wp[1].t_s - 2.5) < 1e-9);
    assert_int_equal(t.line[0], 3); /* the GGA's line: it gave the fix */
    track_free(&t);
}

/* Given RMC at 5 Hz and GGA at 1 Hz (a receiver that sends GGA less often by
 * design), then every RMC time is a fix: those without a GGA are kept. */
static void test_nmea_gga_at_a_lower_rate(void **state)
{
    (void)state;
    static const char text[] =
        "$GPRMC,120000.000,A,4516.395,N,01342.911,E,0.00,0.00,220814,,*09\n"
        "$GPGGA,120000.000,4516.395,N,01342.911,E,1,00,0.0,271.000,M,0.0,M,,*6F\n"
        "$GPRMC,120000.200,A,4516.396,N,01342.911,E,0.00,0.00,220814,,*08\n"
        "$GPRMC,120000.400,A,4516.397,N,01342.911,E,0.00,0.00,220814,,*0F\n"
        "$GPRMC,120000.600,A,4516.398,N,01342.911,E,0.00,0.00,220814,,*02\n"
        "$GPRMC,120000.800,A,4516.399,N,01342.911,E,0.00,0.00,220814,,*0D\n";
    track_t t;
    char err[256];
    assert_int_equal(parse("r.nmea", text, TRACK_FMT_AUTO, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.skipped, 0);
    assert_int_equal(t.n, 5);
    assert_int_equal(t.ignored, 0);
    track_free(&t);
}

/* Given an NMEA log whose every sentence has no fix (GGA quality 0, RMC
 * status V: gpsbabel's default output), then the refusal says so, with the
 * count (it said only "no waypoints"). */
static void test_nmea_no_fix_at_all(void **state)
{
    (void)state;
    static const char text[] =
        "$GPGGA,235959.000,4516.395,N,01342.911,E,0,00,0.0,271.000,M,0.0,M,,*6C\n"
        "$GPGGA,000001.500,4516.396,N,01342.911,E,0,00,0.0,272.000,M,0.0,M,,*69\n";
    track_t t;
    char err[256];
    assert_int_equal(parse("v.nmea", text, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "no waypoints: 2 records without a usable fix"));
}

/* Given a bad checksum, then an error at its line, or with TRACK_SKIP_BAD a
 * counted skip reported with file:line. */
static void test_nmea_bad_checksum(void **state)
{
    (void)state;
    track_t t;
    char err[256], text[sizeof nmea_text];
    memcpy(text, nmea_text, sizeof text);
    char *p = strstr(text, "*68");
    p[2] = '9';
    assert_int_equal(parse("x.nmea", text, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "x.nmea:4: missing or wrong checksum"));
    assert_int_equal(parse("x.nmea", text, TRACK_FMT_AUTO, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.skipped, 1);
    assert_int_equal(t.n, 1); /* (and the RMC alone, its GGA lost: test above) */
    assert_non_null(strstr(t.reports[0], "x.nmea:4:"));
    track_free(&t);
}

/* Given an IGC log crossing midnight, then times run on; a broken B record
 * is an error at its line; validity V gives no altitude. */
static void test_igc_midnight(void **state)
{
    (void)state;
    static const char igc[] = "AXXXABC\nHFDTE220814\nI013638FXA\n"
                              "B2359594516395N01342911EA0000000271\n"
                              "B0000014516396N01342911EA0000000272\n"
                              "B0000024516397N01342911EV0000000000\n";
    track_t t;
    char err[256];
    assert_int_equal(parse("f.txt", igc, TRACK_FMT_AUTO, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.format, TRACK_FMT_IGC);
    assert_int_equal(t.n, 3);
    assert_true(fabs(t.wp[1].t_s - 2.0) < 1e-12);
    assert_true(fabs(t.wp[2].t_s - 3.0) < 1e-12);
    assert_true(fabs(t.wp[1].pos_m[2] - 1.0) < 0.01);
    assert_true(fabs(t.wp[2].pos_m[2]) < 1e-12); /* no altitude: up = 0 */
    track_free(&t);
    static const char bad[] = "AXXXABC\nHFDTE220814\nB2359594516395N01342911EA00000\n";
    assert_int_equal(parse("f.igc", bad, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "f.igc:3: not an IGC B record"));
}

/* Given each format's name, then it parses back; help lines exist. */
static void test_format_table(void **state)
{
    (void)state;
    for (int k = 0; k < TRACK_FMT_COUNT; k++) {
        track_format_t f;
        assert_int_equal(track_format_parse(track_format_names[k], &f), 0);
        assert_int_equal(f, k);
        assert_string_equal(track_format_name(f), track_format_names[k]);
        assert_true(strlen(track_format_help(f)) > 10);
    }
    assert_null(track_format_names[TRACK_FMT_COUNT]);
    assert_string_equal(track_format_name(TRACK_FMT_COUNT), "unknown");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gpsbabel_nmea_igc),
        cmocka_unit_test(test_nmea_midnight_and_validity),
        cmocka_unit_test(test_nmea_bad_checksum),
        cmocka_unit_test(test_igc_midnight),
        cmocka_unit_test(test_format_table),
        cmocka_unit_test(test_nmea_gga_at_a_lower_rate),
        cmocka_unit_test(test_nmea_no_fix_at_all),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
