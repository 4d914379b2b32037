/* test_track.c - the track loader: CSV and GPX, comments, errors with line
 * numbers, skipping bad lines, GPX == CSV on the same real track, ISO 8601
 * against libc's timegm and the epoch column recorded in the data. */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "geo.h"
#include "track.h"
#include "track_text.h"

#define VISNJAN_CSV "tests/data/gpxgo_visnjan.csv"
#define VISNJAN_GPX "tests/data/gpxgo_visnjan.gpx"
#define VISNJAN_N 413 /* tests/data/ATTRIBUTION.md */

static int parse(const char *name, const char *text, track_format_t fmt, unsigned flags, track_t *t,
                 char *err, size_t errlen)
{
    return track_load_text(name, text, strlen(text), fmt, flags, t, err, errlen);
}

/* Given the same real track as CSV and as GPX, when both are loaded, then
 * they give the same waypoints bit for bit (same decimal text -> same double;
 * GPX times are ISO 8601 relative to the first point, CSV times are seconds). */
static void test_visnjan_gpx_equals_csv(void **state)
{
    (void)state;
    track_t a, b;
    char err[256];
    assert_int_equal(track_load_opts(VISNJAN_CSV, TRACK_FMT_AUTO, 0, &a, err, sizeof err), 0);
    assert_int_equal(track_load_opts(VISNJAN_GPX, TRACK_FMT_AUTO, 0, &b, err, sizeof err), 0);
    assert_int_equal(a.n, VISNJAN_N);
    assert_int_equal(b.n, VISNJAN_N);
    assert_int_equal(a.format, TRACK_FMT_LATLON);
    assert_int_equal(b.format, TRACK_FMT_GPX);
    assert_int_equal(b.segments, 1);
    assert_true(a.geographic && b.geographic);
    for (size_t i = 0; i < a.n; i++) {
        assert_memory_equal(&a.wp[i].t_s, &b.wp[i].t_s, sizeof(double));
        assert_memory_equal(a.wp[i].pos_m, b.wp[i].pos_m, sizeof a.wp[i].pos_m);
        assert_int_equal(a.wp[i].seq, i + 1);
        assert_int_equal(b.wp[i].seq, i + 1);
    }
    /* Origin = first point, at (0,0,0); CSV data start on line 2. */
    assert_true(fabs(a.wp[0].pos_m[0]) + fabs(a.wp[0].pos_m[1]) + fabs(a.wp[0].pos_m[2]) < 1e-9);
    assert_int_equal(a.line[0], 2);
    assert_int_equal(a.line[VISNJAN_N - 1], VISNJAN_N + 1);
    assert_int_equal(b.line[0], 14); /* <trkpt> of the first point */
    /* Last point: 17:19:42 - 16:48:52 = 1850 s. */
    assert_true(fabs(b.wp[VISNJAN_N - 1].t_s - 1850.0) < 1e-9);
    track_free(&a);
    track_free(&b);
    track_free(&b); /* twice: safe */
}

/* Given a CSV with comments, blank lines, CRLF, extra and reordered columns
 * and a nan z, when loaded, then only the data rows come out, in order. */
static void test_csv_xyz_comments(void **state)
{
    (void)state;
    const char *text = "# a comment before the header\r\n"
                       "\r\n"
                       "label, z_m ,t,x,y\r\n"
                       "a,3,0.5,1,2\r\n"
                       "   # indented comment\n"
                       "\n"
                       "b,nan,1.5,4,5\n"
                       "c,,2.5,-1e3,6.25"; /* no final newline, empty z */
    track_t t;
    char err[256];
    assert_int_equal(parse("mem.csv", text, TRACK_FMT_AUTO, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.format, TRACK_FMT_XYZ);
    assert_false(t.geographic);
    assert_int_equal(t.n, 3);
    const double want[3][4] = {{0.5, 1, 2, 3}, {1.5, 4, 5, 0}, {2.5, -1000, 6.25, 0}};
    const uint32_t lines[3] = {4, 7, 8};
    for (int i = 0; i < 3; i++) {
        assert_true(fabs(t.wp[i].t_s - want[i][0]) < 1e-15);
        for (int k = 0; k < 3; k++)
            assert_true(fabs(t.wp[i].pos_m[k] - want[i][k + 1]) < 1e-12);
        assert_int_equal(t.line[i], lines[i]);
    }
    track_free(&t);
}

/* Given headers t,x,y (no z) and t,lat,lon (no alt), then z = 0 / up = 0. */
static void test_csv_optional_columns(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("m", "t,x,y\n0,1,2\n1,3,4\n", TRACK_FMT_AUTO, 0, &t, err, sizeof err),
                     0);
    assert_int_equal(t.n, 2);
    assert_true(fabs(t.wp[1].pos_m[2]) < 1e-300);
    track_free(&t);
    assert_int_equal(
        parse("m", "t,lat,lon\n0,45,13\n1,45.001,13.001\n", TRACK_FMT_AUTO, 0, &t, err, sizeof err),
        0);
    assert_int_equal(t.format, TRACK_FMT_LATLON);
    assert_int_equal(t.n, 2);
    assert_true(fabs(t.wp[1].pos_m[2]) < 1e-300); /* no altitude: up = 0 exactly */
    assert_true(t.wp[1].pos_m[0] > 70 && t.wp[1].pos_m[1] > 100);
    assert_true(fabs(t.alt0_m) < 1e-300);
    track_free(&t);
}

/* Given a CSV without a header, when the format is named, then columns are
 * positional; when it is not, then a clear error on line 1. */
static void test_csv_positional(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("p.csv", "0,1,2,3\n1,2,3,4\n", TRACK_FMT_XYZ, 0, &t, err, sizeof err),
                     0);
    assert_int_equal(t.n, 2);
    assert_true(fabs(t.wp[1].pos_m[2] - 4) < 1e-15);
    track_free(&t);
    assert_int_equal(parse("p.csv", "0,1,2,3\n", TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "p.csv:1: no header line"));
    assert_null(t.wp);
    /* by position, every row has as many fields as the first (issue 11) */
    assert_int_equal(parse("p.csv", "0,1,2,3\n1,2,3\n", TRACK_FMT_XYZ, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "p.csv:2: 3 fields, the first row has 4 (field missing)"));
    assert_int_equal(parse("p.csv", "0,1,2,3,4\n", TRACK_FMT_XYZ, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "p.csv:1: 5 fields: by position a row is t,x,y[,z]"));
}

/* Given the first point of visnjan, when loaded as latlon, then the second
 * point's ENU equals lib/util/geo's conversion about the first (the loader wires
 * origin and altitude right; geo itself is checked against pyproj). */
static void test_csv_latlon_origin(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("v",
                           "t_s,lat_deg,lon_deg,alt_m\n"
                           "0,45.273245,13.715185,271\n"
                           "15,45.273178,13.715221,258\n",
                           TRACK_FMT_LATLON, 0, &t, err, sizeof err),
                     0);
    geo_enu_t f;
    double enu[3];
    assert_int_equal(geo_enu_init(45.273245, 13.715185, 271, &f), 0);
    assert_int_equal(geo_to_enu(&f, 45.273178, 13.715221, 258, enu), 0);
    assert_memory_equal(t.wp[1].pos_m, enu, sizeof enu);
    assert_true(fabs(t.lat0_deg - 45.273245) < 1e-12 && fabs(t.alt0_m - 271) < 1e-12);
    track_free(&t);
}

struct bad_case {
    const char *text;
    const char *want; /* substring of the message, with the line number */
};

/* Given malformed CSV, when loaded, then -1 and "name:line: what". */
static void test_csv_errors(void **state)
{
    (void)state;
    const struct bad_case cases[] = {
        {"t,x,y\n0,1,2\n1,abc,3\n", "bad.csv:3: x 'abc' is not a finite number"},
        {"t,x,y\n0,1,2\n\n# c\n1,2\n", "bad.csv:5: 2 fields, the header has 3 (field missing)"},
        /* issue 11: a missing z is not z = 0, an extra field is not ignored */
        {"t,x,y,z\n0,1,2,3\n1,2,3\n", "bad.csv:3: 3 fields, the header has 4 (field missing)"},
        {"t,x,y\n0,1,2\n1,2,3,4\n", "bad.csv:3: 4 fields, the header has 3 (extra field)"},
        {"t,x,y,z\n0,1,2,3,\n", "bad.csv:2: 5 fields, the header has 4 (extra field)"},
        {"t,x,y\n0,1,2\nnan,2,3\n", "bad.csv:3: time 'nan' is not a finite number"},
        {"t,x,y\n0,1,2\n1,inf,3\n", "bad.csv:3: x 'inf' is not a finite number"},
        {"t,x,y\n0,1,2 3\n", "bad.csv:2: y '2 3' is not a finite number"},
        {"t,lat,lon\n0,91,2\n", "bad.csv:2: latitude outside [-90, 90] degrees"},
        {"t,lat,lon,alt\n0,45,2,abc\n", "bad.csv:2: altitude 'abc' is not a number"},
        {"a,b,c\n1,2,3\n", "bad.csv:1: header has no time column"},
        {"t,u,v\n1,2,3\n", "bad.csv:1: header names neither"},
        /* a column named twice, or both frames: one was dropped unsaid */
        {"t,x,y,x\n0,0,0,100\n", "bad.csv:1: header names one column twice: 'x' (field 2) "
                                 "and 'x' (field 4)"},
        {"t,time,x,y\n0,0,1,2\n", "bad.csv:1: header names one column twice: 't' (field 1) "
                                  "and 'time' (field 2)"},
        {"t,x,y,lat,lon\n0,0,0,45,13\n", "bad.csv:1: header names both x,y and lat,lon"},
        {"t,x,y\n", "bad.csv: no waypoints"},
        {"", "bad.csv: no waypoints (empty file)"},
        {"# only\n\n", "bad.csv: no waypoints (empty file)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        track_t t;
        char err[256];
        assert_int_equal(parse("bad.csv", cases[i].text, TRACK_FMT_AUTO, 0, &t, err, sizeof err),
                         -1);
        if (!strstr(err, cases[i].want))
            fail_msg("case %zu: got '%s', want '%s'", i, err, cases[i].want);
        assert_int_equal(t.n, 0);
    }
}

/* Given a header naming lat/lon, when format xyz is forced, then it says so. */
static void test_csv_wrong_format(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("w.csv", "t,lat,lon\n0,1,2\n", TRACK_FMT_XYZ, 0, &t, err, sizeof err),
                     -1);
    assert_non_null(strstr(err, "w.csv:1: header has no x and y columns (it has lat/lon"));
    assert_int_equal(parse("w.csv", "t,x,y\n0,1,2\n", TRACK_FMT_LATLON, 0, &t, err, sizeof err),
                     -1);
    assert_non_null(strstr(err, "w.csv:1: header has no lat and lon columns"));
    /* both frames named: the format given says which */
    assert_int_equal(
        parse("w.csv", "t,x,y,lat,lon\n0,1,2,45,13\n", TRACK_FMT_XYZ, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 1);
    track_free(&t);
}

/* Given bad lines and TRACK_SKIP_BAD, when loaded, then the good rows load,
 * the bad ones are counted, the first is named in err and every one is
 * reported with its line (an extra field is a bad line too: issue 11). */
static void test_csv_skip_bad(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    const char *text = "t,x,y\n0,1,2\n1,zz,3\n2,3\n3,4,5\n4,5,6,7,8\n";
    assert_int_equal(parse("s.csv", text, TRACK_FMT_AUTO, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 2);
    assert_int_equal(t.skipped, 3);
    assert_non_null(strstr(err, "s.csv:3:"));
    assert_int_equal(t.nreports, 3);
    assert_non_null(strstr(t.reports[0], "s.csv:3: x 'zz'"));
    assert_non_null(strstr(t.reports[1], "s.csv:4: 2 fields, the header has 3 (field missing)"));
    assert_non_null(strstr(t.reports[2], "s.csv:6: 5 fields, the header has 3 (extra field)"));
    assert_int_equal(t.line[1], 5);
    assert_int_equal(t.wp[1].seq, 2);
    track_free(&t);
    assert_int_equal(
        parse("s.csv", "t,x,y\nq,1,2\n", TRACK_FMT_AUTO, TRACK_SKIP_BAD, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "every data line was bad"));
}

/* Given rows as recorded (duplicate, backward step), then they are kept. */
static void test_rows_kept_as_recorded(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(
        parse("k", "t,x,y\n0,0,0\n1,1,1\n1,1,1\n0.5,2,2\n", TRACK_FMT_AUTO, 0, &t, err, sizeof err),
        0);
    assert_int_equal(t.n, 4);
    assert_true(t.wp[3].t_s < t.wp[2].t_s);
    track_free(&t);
}

static const char gpx_two_segs[] =
    "<?xml version=\"1.0\"?>\n"
    "<gpx version=\"1.1\" xmlns=\"http://www.topografix.com/GPX/1/1\">\n"
    "<wpt lat=\"10\" lon=\"10\"><time>2000-01-01T00:00:00Z</time></wpt>\n"
    "<rte><rtept lat=\"11\" lon=\"11\"><time>2000-01-01T00:00:00Z</time></rtept></rte>\n"
    "<trk><name>x</name>\n"
    "<trkseg>\n"
    "<trkpt lat=\"45.0\" lon=\"13.0\"><ele>100</ele><time>2020-02-29T23:59:59.5Z</time></trkpt>\n"
    "<trkpt lat=\"45.0001\" lon=\"13.0\"><time>2020-03-01T00:00:00.25Z</time>"
    "<extensions><time>1999-01-01T00:00:00Z</time><ele>5</ele></extensions></trkpt>\n"
    "</trkseg>\n"
    "<trkseg>\n"
    "<trkpt lon=\"13.0\" "
    "lat=\"45.0002\"><ele>101.5</ele><time>2020-03-01T01:00:01+01:00</time></trkpt>\n"
    "</trkseg></trk></gpx>\n";

/* Given GPX with wpt/rte, two trkseg, fractional seconds, a leap day, a
 * timezone offset, an <ele>-less point and nested extension elements, when
 * loaded, then only the trkpt come out, in order, with the right times. */
static void test_gpx_segments_times(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("mem.gpx", gpx_two_segs, TRACK_FMT_AUTO, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 3);
    assert_int_equal(t.segments, 2);
    assert_true(fabs(t.wp[0].t_s) < 1e-300);
    assert_true(fabs(t.wp[1].t_s - 0.75) < 1e-12);
    assert_true(fabs(t.wp[2].t_s - 1.5) < 1e-12);                  /* 01:00:01+01:00 = 00:00:01Z */
    assert_true(fabs(t.wp[1].pos_m[2]) < 1e-300);                  /* no <ele>: up = 0 */
    assert_true(t.wp[1].pos_m[1] > 11 && t.wp[1].pos_m[1] < 11.2); /* 0.0001 deg ~ 11.1 m */
    assert_true(t.wp[2].pos_m[2] > 1.49 && t.wp[2].pos_m[2] < 1.51);
    assert_int_equal(t.line[0], 7);
    assert_int_equal(t.line[2], 11);
    track_free(&t);
}

/* Given a GPX cut off at every possible length, when loaded, then it never
 * crashes and either fails with a message or loads a prefix of the points. */
static void test_gpx_truncated(void **state)
{
    (void)state;
    size_t len = strlen(gpx_two_segs);
    for (size_t cut = 0; cut + 1 < len; cut++) { /* len - 1: all but the final newline */
        track_t t;
        char err[256], file[128];
        int rc = track_load_text("cut.gpx", gpx_two_segs, cut, TRACK_FMT_AUTO, 0, &t, err,
                                 sizeof err);
        assert_int_equal(rc, -1); /* the root element is never closed */
        snprintf(file, sizeof file, "%s/cut.gpx", track_text_dir); /* the file loaded */
        assert_true(strncmp(err, file, strlen(file)) == 0);
        assert_true(strlen(err) > strlen(file) + 3);
    }
    track_t t;
    char err[256];
    assert_int_equal(
        track_load_text("cut.gpx", gpx_two_segs, len - 1, TRACK_FMT_AUTO, 0, &t, err, sizeof err),
        0);
    assert_int_equal(t.n, 3);
    track_free(&t);
    assert_int_equal(
        track_load_text("cut.gpx", gpx_two_segs, 300, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "XML error"));
}

/* Given GPX points with problems, when loaded, then "name:line: what". */
static void test_gpx_errors(void **state)
{
    (void)state;
    const struct bad_case cases[] = {
        {"<gpx><trk><trkseg>\n<trkpt lat=\"1\" lon=\"2\"></trkpt></trkseg></trk></gpx>",
         "e.gpx:2: trkpt without <time>"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"1\"><time>2000-01-01T00:00:00Z</time></trkpt>"
         "</trkseg></trk></gpx>",
         "e.gpx:2: trkpt without lat or lon"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"x\" lon=\"2\"><time>2000-01-01T00:00:00Z</time>"
         "</trkpt></trkseg></trk></gpx>",
         "e.gpx:2: trkpt lat 'x'"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"1\" lon=\"2\">\n<time>yesterday</time></trkpt>"
         "</trkseg></trk></gpx>",
         "e.gpx:3: <time> 'yesterday' is not an ISO 8601"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"1\" lon=\"2\">\n<ele>high</ele>"
         "<time>2000-01-01T00:00:00Z</time></trkpt></trkseg></trk></gpx>",
         "e.gpx:3: <ele> 'high' is not a number"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"95\" lon=\"2\"><time>2000-01-01T00:00:00Z</time>"
         "</trkpt></trkseg></trk></gpx>",
         "e.gpx:2: latitude outside"},
        {"<gpx><trk><trkseg>\n<trkpt lat=\"1\" lon=\"2\"><time>2000-01-01T00:00:00Z</time>"
         "</trkpt></trkseg></trk>\n<oops></gpx>",
         "e.gpx:3: XML error: mismatched tag"},
        {"<gpx></gpx>", "e.gpx: no waypoints"},
        {"not xml at all", "e.gpx:1: XML error: syntax error"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        track_t t;
        char err[256];
        assert_int_equal(parse("e.gpx", cases[i].text, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
        if (!strstr(err, cases[i].want))
            fail_msg("case %zu: got '%s', want '%s'", i, err, cases[i].want);
    }
}

/* Given a GPX with one bad point and TRACK_SKIP_BAD, then the others load. */
static void test_gpx_skip_bad(void **state)
{
    (void)state;
    const char *text = "<gpx><trk><trkseg>\n"
                       "<trkpt lat=\"1\" lon=\"2\"><time>2000-01-01T00:00:00Z</time></trkpt>\n"
                       "<trkpt lat=\"1\" lon=\"2\"><time>never</time><ele>x</ele></trkpt>\n"
                       "<trkpt lat=\"1.1\" lon=\"2\"><time>2000-01-01T00:00:09Z</time></trkpt>\n"
                       "</trkseg></trk></gpx>";
    track_t t;
    char err[256];
    assert_int_equal(parse("s.gpx", text, TRACK_FMT_GPX, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 2);
    assert_int_equal(t.skipped, 1); /* one point, two faults: counted once */
    assert_true(fabs(t.wp[1].t_s - 9) < 1e-12);
    assert_non_null(strstr(err, "s.gpx:3:"));
    track_free(&t);
}

/* Given a GPX cut off mid-point (a logger killed mid-write), then with
 * TRACK_SKIP_BAD its whole points before the cut load, the rest counted as
 * skipped with the XML error at its line (none were kept: "unclosed token",
 * exit 1, with or without skip_bad); without it, the error says what
 * skip_bad would keep. */
static void test_gpx_cut_off(void **state)
{
    (void)state;
    const char *text = "<gpx><trk><trkseg>\n"
                       "<trkpt lat=\"1\" lon=\"2\"><time>2000-01-01T00:00:00Z</time></trkpt>\n"
                       "<trkpt lat=\"1.1\" lon=\"2\"><time>2000-01-01T00:00:09Z</time></trkpt>\n"
                       "<trkpt lat=\"1.2\" lon=\"2\"><time>2000-01-01T00:00:1";
    track_t t;
    char err[256];
    assert_int_equal(parse("c.gpx", text, TRACK_FMT_GPX, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 2);
    assert_int_equal(t.skipped, 1);
    assert_true(fabs(t.wp[1].t_s - 9) < 1e-12);
    assert_non_null(strstr(err, "c.gpx:4: XML error"));
    assert_non_null(strstr(err, "the rest of the file is skipped (2 whole points kept"));
    track_free(&t);
    assert_int_equal(parse("c.gpx", text, TRACK_FMT_GPX, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "(skip_bad keeps the 2 whole points before it)"));
}

/* Given dates, when parsed, then they match libc's timegm (an independent
 * implementation of the same calendar), and the GPX times of visnjan match
 * the epoch_s column recorded in the CSV. */
static void test_iso8601(void **state)
{
    (void)state;
    int64_t s;
    double fr;
    unsigned seed = 1;
    for (int i = 0; i < 20000; i++) {
        seed = seed * 1103515245u + 12345u;
        int y = 1900 + (int)((seed >> 8) % 300);
        seed = seed * 1103515245u + 12345u;
        int mo = 1 + (int)((seed >> 8) % 12), d = 1 + (int)((seed >> 12) % 28);
        seed = seed * 1103515245u + 12345u;
        int h = (int)((seed >> 8) % 24), mi = (int)((seed >> 14) % 60),
            se = (int)((seed >> 20) % 60);
        char buf[64];
        snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02dZ", y, mo, d, h, mi, se);
        struct tm tm = {.tm_year = y - 1900,
                        .tm_mon = mo - 1,
                        .tm_mday = d,
                        .tm_hour = h,
                        .tm_min = mi,
                        .tm_sec = se};
        assert_int_equal(track_parse_iso8601(buf, &s, &fr), 0);
        assert_int_equal(s, (int64_t)timegm(&tm));
        assert_true(fr < 1e-300);
    }
    assert_int_equal(track_parse_iso8601("2014-08-22T16:48:52Z", &s, &fr), 0);
    assert_int_equal(s, 1408726132); /* epoch_s of visnjan's first row */
    assert_int_equal(track_parse_iso8601("2014-08-22T16:48:52.125", &s, &fr), 0);
    assert_true(fabs(fr - 0.125) < 1e-15);
    assert_int_equal(track_parse_iso8601("2014-08-22t18:48:52+0200", &s, &fr), 0);
    assert_int_equal(s, 1408726132);
    assert_int_equal(track_parse_iso8601("2014-08-22T14:18:52-02:30", &s, &fr), 0);
    assert_int_equal(s, 1408726132);
    /* Gregorian leap rule's 400-year case: 2000 is leap (GNU date -d and
     * Python's calendar.timegm give 951825600), 1900 is not */
    assert_int_equal(track_parse_iso8601("2000-02-29T12:00:00Z", &s, &fr), 0);
    assert_int_equal(s, 951825600);
    const char *bad[] = {"",
                         "2014-08-22",
                         "2014-13-01T00:00:00Z",
                         "2014-02-30T00:00:00Z",
                         "2019-02-29T00:00:00Z",
                         "1900-02-29T00:00:00Z",
                         "2014-08-22T25:00:00Z",
                         "2014-08-22T16:48:52.Z",
                         "2014-08-22T16:48:52Zjunk",
                         "20140822T164852Z",
                         "2014-08-22T16:48"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(track_parse_iso8601(bad[i], &s, &fr), -1);

    /* visnjan: GPX t + epoch of the first point == CSV epoch_s, every row. */
    track_t g;
    char err[256];
    assert_int_equal(track_load_opts(VISNJAN_GPX, TRACK_FMT_GPX, 0, &g, err, sizeof err), 0);
    FILE *f = fopen(VISNJAN_CSV, "r");
    assert_non_null(f);
    char line[512];
    assert_non_null(fgets(line, sizeof line, f));
    size_t i = 0;
    while (fgets(line, sizeof line, f)) {
        double t, la, lo, al, ep;
        assert_int_equal(sscanf(line, "%lf,%lf,%lf,%lf,%lf", &t, &la, &lo, &al, &ep), 5);
        assert_true(i < g.n);
        assert_true(fabs(g.wp[i].t_s + 1408726132.0 - ep) < 1e-6);
        i++;
    }
    assert_int_equal(i, g.n);
    fclose(f);
    track_free(&g);
}

/* Given garbage (random bytes, binary NULs, very long lines), when parsed in
 * every format, then no crash, and an error or a track. */
static void test_garbage(void **state)
{
    (void)state;
    static char buf[20000];
    unsigned seed = 99;
    for (int round = 0; round < 200; round++) {
        size_t len = (size_t)(round * 97) % sizeof buf;
        for (size_t i = 0; i < len; i++) {
            seed = seed * 1103515245u + 12345u;
            unsigned r = (seed >> 16) & 0xff;
            /* Mostly CSV-ish characters so the parser gets past the header. */
            buf[i] = round % 2 ? (char)r : "0123456789.,-\n#tlanxyz e"[r % 24];
        }
        if (round % 4 == 0 && len > 6)
            memcpy(buf, "t,x,y\n", 6);
        for (int fmt = TRACK_FMT_AUTO; fmt <= TRACK_FMT_GPX; fmt++) {
            track_t t;
            char err[128];
            for (unsigned flags = 0; flags <= TRACK_SKIP_BAD; flags++) {
                int rc = track_load_text("g", buf, len, (track_format_t)fmt, flags, &t, err,
                                         sizeof err);
                assert_true(rc == 0 || rc == -1);
                if (rc == 0) {
                    assert_true(t.n > 0);
                    for (size_t i = 0; i < t.n; i++)
                        assert_true(isfinite(t.wp[i].t_s) && isfinite(t.wp[i].pos_m[0]) &&
                                    isfinite(t.wp[i].pos_m[1]) && isfinite(t.wp[i].pos_m[2]));
                } else {
                    assert_true(err[0] != '\0');
                }
                track_free(&t);
            }
        }
    }
    /* A line longer than TRACK_LINE_MAX. */
    memset(buf, '1', sizeof buf);
    memcpy(buf, "t,x,y\n0,1,2\n", 12);
    track_t t;
    char err[128];
    assert_int_equal(
        track_load_text("long", buf, sizeof buf, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "long:3: line longer than"));
    /* A NUL byte inside a data line. */
    assert_int_equal(
        track_load_text("nul", "t,x,y\n0,1\0,2\n", 13, TRACK_FMT_AUTO, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "nul:2: NUL byte"));
}

/* Given a missing file, then the system's message. */
static void test_missing_file(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(track_load_opts("/nonexistent/x.csv", TRACK_FMT_AUTO, 0, &t, err, sizeof err),
                     -1);
    assert_string_equal(err, "/nonexistent/x.csv: No such file or directory");
    assert_int_equal(track_load_opts("/nonexistent/x.csv", TRACK_FMT_AUTO, 0, &t, NULL, 0), -1);
}

/* Given the real tracks, when loaded, then the row counts of ATTRIBUTION.md. */
static void test_real_tracks(void **state)
{
    (void)state;
    const struct {
        const char *path;
        size_t n;
    } tr[] = {
        {"tests/data/gpxpy_cerknicko-jezero.csv", 296},
        {"tests/data/n2k_furuno_figure8_src52.csv", 1786},
    };
    for (size_t k = 0; k < 2; k++) {
        track_t t;
        char err[256];
        assert_int_equal(track_load_opts(tr[k].path, TRACK_FMT_AUTO, 0, &t, err, sizeof err), 0);
        assert_int_equal(t.n, tr[k].n);
        assert_int_equal(t.skipped, 0);
        track_free(&t);
    }
    /* The candump log replays directly (issue 12; it once failed with "header
     * has no time column"): its 165 PGN 129025 fixes of source 43 (counted in
     * tests/oracle/test_n2k_candump.py by an independent decode). */
    track_t t;
    char err[256];
    assert_int_equal(track_load_opts("tests/data/canboat_candumpSample3.log", TRACK_FMT_AUTO, 0, &t,
                                     err, sizeof err),
                     0);
    assert_int_equal(t.format, TRACK_FMT_N2K);
    assert_int_equal(t.n, 165);
    assert_true(t.geographic);
    track_free(&t);
}

static void test_format_names(void **state)
{
    (void)state;
    track_format_t f;
    assert_int_equal(track_format_parse("gpx", &f), 0);
    assert_int_equal(f, TRACK_FMT_GPX);
    assert_int_equal(track_format_parse("latlon", &f), 0);
    assert_int_equal(f, TRACK_FMT_LATLON);
    assert_int_equal(track_format_parse("kml", &f), -1);
    assert_int_equal(track_format_parse(NULL, &f), -1);
    assert_string_equal(track_format_name(TRACK_FMT_XYZ), "xyz");
}

/* Given path programs that fail when expanded (issue 11: such errors had no
 * line number although the README promises file:line), then the message
 * names the line of the element that failed; a wait of 1e300 s is refused
 * at its line instead of silently turning the rest into duplicates. */
static void test_path_errors_have_lines(void **state)
{
    (void)state;
    const struct bad_case cases[] = {
        {"start 0 0 0\nspeed 1e-9\nline 100 0 0\n", "p.path:3: path: value out of range"},
        {"start 0 0 0\nline 1 0 0\nwait 1e300\nline 2 0 0\n", "p.path:3: path: time beyond"},
        {"# t\nstart 0 0 0 1e8\nspeed 1e12\n\nline 1 0 0\n", "p.path:5: path: time beyond"},
        {"start 0 0 0\nstart 1 0 0\n", "p.path:2: path: 'start' given twice"},
        {"line 1 0 0\n", "p.path:1: path: element before 'start'"},
        {"start 0 0 0\nspeed 0\n", "p.path:2: path: value out of range"},
        {"start 0 0 0\nstep 0\nline 1 0 0\n", "p.path:2: path: value out of range"},
        {"# s\nstart 0 0 0\nstep 1e-300\nline 100 0 0\n", "p.path:4: path: value out of range"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        track_t t;
        char err[256];
        assert_int_equal(parse("p.path", cases[i].text, TRACK_FMT_AUTO, 0, &t, err, sizeof err),
                         -1);
        if (!strstr(err, cases[i].want))
            fail_msg("case %zu: got '%s', want '%s'", i, err, cases[i].want);
        assert_int_equal(t.n, 0);
    }
}

/* Given a path, then each waypoint carries the line of the element that made it. */
static void test_path_lines(void **state)
{
    (void)state;
    track_t t;
    char err[256];
    assert_int_equal(parse("p.path", "start 0 0 0\n# c\nline 2 0 0\nwait 1\n", TRACK_FMT_AUTO, 0,
                           &t, err, sizeof err),
                     0);
    assert_int_equal(t.n, 4);
    assert_int_equal(t.line[0], 1);
    assert_int_equal(t.line[1], 3);
    assert_int_equal(t.line[2], 3);
    assert_int_equal(t.line[3], 4);
    track_free(&t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_visnjan_gpx_equals_csv),
        cmocka_unit_test(test_csv_xyz_comments),
        cmocka_unit_test(test_csv_optional_columns),
        cmocka_unit_test(test_csv_positional),
        cmocka_unit_test(test_path_errors_have_lines),
        cmocka_unit_test(test_path_lines),
        cmocka_unit_test(test_csv_latlon_origin),
        cmocka_unit_test(test_csv_errors),
        cmocka_unit_test(test_csv_wrong_format),
        cmocka_unit_test(test_csv_skip_bad),
        cmocka_unit_test(test_rows_kept_as_recorded),
        cmocka_unit_test(test_gpx_segments_times),
        cmocka_unit_test(test_gpx_truncated),
        cmocka_unit_test(test_gpx_errors),
        cmocka_unit_test(test_gpx_skip_bad),
        cmocka_unit_test(test_gpx_cut_off),
        cmocka_unit_test(test_iso8601),
        cmocka_unit_test(test_garbage),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_real_tracks),
        cmocka_unit_test(test_format_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
