/* test_track_hostile.c - tracks a hostile or careless author writes (issue
 * 24): a .path whose `step` would expand a few lines into tens of millions
 * of waypoints is refused, counted before anything is made, at the line that
 * crosses the limit; a heading of 1e300 is a bad line, not an axis. */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "track.h"
#include "track_text.h"

static int parse(const char *name, const char *text, unsigned flags, track_t *t, char *err,
                 size_t errlen)
{
    return track_load_text(name, text, strlen(text), TRACK_FMT_AUTO, flags, t, err, errlen);
}

/* Given the 91-byte .path of the issue (step 1e-6 s and five 9.9 m lines at
 * 1 m/s: 49.5 million waypoints, 2.1 GB), then it is refused at the line
 * whose waypoints cross TRACK_PATH_WAYPOINTS_MAX (the second: 9.9 M + 9.9 M
 * > 16.8 M), and nothing is made.  The old code expanded it all. */
static void test_path_expansion_bounded(void **state)
{
    (void)state;
    const char *text = "start 0 0 0\nstep 1e-6\nline 9.9 0 0\nline 0 0 0\nline 9.9 0 0\n"
                       "line 0 0 0\nline 9.9 0 0\n";
    track_t t;
    char err[256];
    assert_int_equal(parse("p.path", text, 0, &t, err, sizeof err), -1);
    if (!strstr(err, "p.path:4: ") || !strstr(err, "more than 16777216 waypoints"))
        fail_msg("got '%s'", err);
    assert_int_equal(t.n, 0);
    /* just at the limit is still made: the start and 16 Mi - 1 steps of two
     * lines (one element makes at most 10^7) */
    char ok[128];
    snprintf(ok, sizeof ok, "start 0 0 0\nstep 1\nline 8388607 0 0\nline %lu 0 0\n",
             (unsigned long)TRACK_PATH_WAYPOINTS_MAX - 1);
    assert_int_equal(parse("q.path", ok, 0, &t, err, sizeof err), 0);
    assert_int_equal(t.n, TRACK_PATH_WAYPOINTS_MAX);
    track_free(&t);
    snprintf(ok, sizeof ok, "start 0 0 0\nstep 1\nline 8388607 0 0\nline %lu 0 0\n",
             (unsigned long)TRACK_PATH_WAYPOINTS_MAX);
    assert_int_equal(parse("q.path", ok, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "q.path:4: "));
}

/* Given a CSV whose heading column holds 1e300 on one row, then that row is
 * a bad line (refused, or skipped and counted with TRACK_SKIP_BAD), as a
 * heading no axis can turn to; 1e6 degrees (2778 turns) is still a heading. */
static void test_heading_absurd(void **state)
{
    (void)state;
    const char *text = "t,x,y,heading\n0,0,0,10\n1,1,0,1e300\n2,2,0,1e6\n3,3,0,-1e6\n";
    track_t t;
    char err[256];
    assert_int_equal(parse("h.csv", text, 0, &t, err, sizeof err), -1);
    if (!strstr(err, "h.csv:3: ") || !strstr(err, "heading"))
        fail_msg("got '%s'", err);
    assert_int_equal(parse("h.csv", text, TRACK_SKIP_BAD, &t, err, sizeof err), 0);
    assert_int_equal(t.n, 3);
    assert_int_equal(t.skipped, 1);
    assert_int_equal(t.nheading, 3);
    track_free(&t);
}

/* The track in text b (named name) is the one in text a: the same waypoints,
 * at least two. */
static void same_track(const char *name, const char *a_text, const char *b_text)
{
    char err[256];
    track_t a, b;
    if (parse(name, a_text, 0, &a, err, sizeof err) != 0)
        fail_msg("%s as written: %s", name, err);
    if (parse(name, b_text, 0, &b, err, sizeof err) != 0)
        fail_msg("%s refused: %s", name, err);
    assert_int_equal(a.n, b.n);
    assert_true(a.n >= 2);
    assert_memory_equal(a.wp, b.wp, a.n * sizeof a.wp[0]);
    track_free(&a);
    track_free(&b);
}

/* Given CSV tracks (one with a comment line) whose lines end in CR alone (classic Mac OS),
 * then they read as with LF: the same waypoints (they were one line: "no
 * waypoints"). */
static void test_cr_only_lines(void **state)
{
    (void)state;
    static const char *const lf[] = {"t,x,y,z\n0,0,0,0\n0.1,1,0,0\n0.2,2,0.5,0\n",
                                     "# a comment\nt_s,x_m,y_m\n0,1,2\n1,2,3\n"};
    for (size_t k = 0; k < sizeof lf / sizeof lf[0]; k++) {
        char cr[256];
        snprintf(cr, sizeof cr, "%s", lf[k]);
        for (char *p = cr; *p; p++)
            if (*p == '\n')
                *p = '\r';
        same_track("lf.csv", lf[k], cr);
    }
}

/* Given an NMEA 0183 log and an IGC file that start with a UTF-8 byte order
 * mark, then they read as without it (they were refused at line 1, "not an
 * NMEA 0183 sentence" / "not an IGC record"; CSV and GPX took it). */
static void test_bom_every_format(void **state)
{
    (void)state;
    static const char *const text[][2] = {
        {"a.nmea", "$GPRMC,120000.00,A,4530.0000,N,01330.0000,E,1.0,90.0,010124,,,A*60\n"
                   "$GPRMC,120001.00,A,4530.0000,N,01330.0010,E,1.0,90.0,010124,,,A*60\n"},
        {"a.igc", "AXXX001\nHFDTE010124\nB1200004530000N01330000EA0010000100\n"
                  "B1200014530000N01330010EA0010000100\n"},
    };
    for (size_t k = 0; k < 2; k++) {
        char bom[512];
        snprintf(bom, sizeof bom, "\xEF\xBB\xBF%s", text[k][1]);
        same_track(text[k][0], text[k][1], bom);
    }
}

/* Given a candump log printed without its time stamps (candump's default)
 * as an NMEA 2000 track, then the error says a candump -l log is needed,
 * once ("not a candump frame: not a candump frame" said neither). */
static void test_candump_without_stamps(void **state)
{
    (void)state;
    const char *text = "  can0  09F80103   [8]  FF FF FF FF FF FF FF FF\n";
    track_t t;
    char err[512];
    assert_int_equal(
        track_load_text("n.log", text, strlen(text), TRACK_FMT_N2K, 0, &t, err, sizeof err), -1);
    assert_non_null(strstr(err, "n.log:1: not a candump -l frame"));
    assert_non_null(strstr(err, "record it with candump -l"));
    assert_null(strstr(err, "frame: not a candump frame"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_expansion_bounded), cmocka_unit_test(test_heading_absurd),
        cmocka_unit_test(test_cr_only_lines),          cmocka_unit_test(test_bom_every_format),
        cmocka_unit_test(test_candump_without_stamps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
