/* test_rejlog.c - the daemon's rejection log (daemon/core/rejlog.h) against
 * the real engine: each refused waypoint is named by the source it was
 * offered from, the lines are rate-limited per flush with a per-reason
 * count of the rest, and nothing the engine refused goes uncounted. */
#include "test.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine.h"
#include "rejlog.h"

#define MAX_LINES 32

typedef struct {
    char line[MAX_LINES][REJLOG_LINE_MAX];
    unsigned n;
} lines_t;

static void collect(void *ctx, const char *line)
{
    lines_t *l = ctx;
    assert_true(l->n < MAX_LINES);
    snprintf(l->line[l->n++], REJLOG_LINE_MAX, "%s", line);
}

/* Waypoint i of a circle of radius 50 m walked at 2 m/s, sampled at 5 Hz. */
static engine_waypoint_t circle(unsigned i)
{
    engine_waypoint_t wp;
    memset(&wp, 0, sizeof wp);
    wp.t_s = 0.2 * i;
    wp.pos_m[0] = 50 * cos(2 * wp.t_s / 50);
    wp.pos_m[1] = 50 * sin(2 * wp.t_s / 50);
    wp.seq = i + 1;
    return wp;
}

static engine_t *new_engine(void)
{
    engine_config_t cfg;
    engine_config_default(&cfg);
    engine_t *e = engine_new(&cfg, NULL);
    assert_non_null(e);
    return e;
}

/* Offer wp from "track.csv:(seq + 1)" (a header line first), as the replay
 * transport does, and read the verdicts. */
static void offer(rejlog_t *l, engine_t *e, const engine_waypoint_t *wp)
{
    char src[64];
    snprintf(src, sizeof src, "track.csv:%" PRIu32, wp->seq + 1);
    rejlog_offered(l, wp, src);
    (void)engine_push(e, wp);
    rejlog_drain(l, e);
}

/* Given a clean track with one fix 500 m off at row 51 (line 52), when it is
 * replayed and finished, then exactly that fix is logged, by its source
 * line, with the reason the engine counted. */
static void test_spike_named_by_its_line(void **state)
{
    (void)state;
    engine_t *e = new_engine();
    rejlog_t l;
    rejlog_init(&l);
    for (unsigned i = 0; i < 200; i++) {
        engine_waypoint_t wp = circle(i);
        if (i == 50)
            wp.pos_m[0] += 500;
        offer(&l, e, &wp);
    }
    engine_finish(e);
    rejlog_drain(&l, e);
    lines_t out = {.n = 0};
    assert_int_equal(rejlog_flush(&l, "boat", collect, &out), 1);
    engine_status_t st;
    engine_status(e, &st);
    assert_int_equal(st.rejected, 1);
    int reason = 0;
    for (int r = 1; r < ENGINE_ERROR_COUNT; r++)
        if (st.rejected_by[r])
            reason = r;
    char want[128];
    snprintf(want, sizeof want, "object 'boat': track.csv:52: rejected (%s) seq 51 t=10.000 s",
             engine_reason_name(reason));
    assert_non_null(strstr(out.line[0], want));
    /* flushed: nothing twice */
    out.n = 0;
    assert_int_equal(rejlog_flush(&l, "boat", collect, &out), 0);
    engine_free(e);
}

/* Given 12 waypoints refused at once (NaN time) within one flush, then the
 * first REJLOG_LINES are logged one line each and the other 7 are summed up
 * by reason in one line; the next flush starts afresh. */
static void test_rate_limited(void **state)
{
    (void)state;
    engine_t *e = new_engine();
    rejlog_t l;
    rejlog_init(&l);
    for (unsigned i = 0; i < 12; i++) {
        engine_waypoint_t wp = circle(i);
        wp.t_s = NAN;
        offer(&l, e, &wp);
    }
    lines_t out = {.n = 0};
    assert_int_equal(rejlog_flush(&l, "boat", collect, &out), REJLOG_LINES + 1);
    for (unsigned i = 0; i < REJLOG_LINES; i++) {
        char want[64];
        snprintf(want, sizeof want, "track.csv:%u: rejected (not_finite)", i + 2);
        assert_non_null(strstr(out.line[i], want));
    }
    char more[96];
    snprintf(more, sizeof more,
             "object 'boat': %d more rejected waypoints not shown (not_finite %d)",
             12 - REJLOG_LINES, 12 - REJLOG_LINES);
    assert_string_equal(out.line[REJLOG_LINES], more);
    engine_status_t st;
    engine_status(e, &st);
    assert_int_equal(st.rejected_by[ENGINE_ENOTFINITE], 12);
    assert_int_equal(l.seen, 12);
    out.n = 0;
    engine_waypoint_t wp = circle(0);
    wp.pos_m[2] = INFINITY;
    offer(&l, e, &wp);
    assert_int_equal(rejlog_flush(&l, "boat", collect, &out), 1);
    assert_non_null(strstr(out.line[0], "track.csv:2: rejected (not_finite)"));
    engine_free(e);
}

/* Given a waypoint pushed without its source noted (or pushed out of the
 * ring by REJLOG_RING later offers), then its refusal is still logged,
 * as from an unknown source. */
static void test_unknown_source(void **state)
{
    (void)state;
    engine_t *e = new_engine();
    rejlog_t l;
    rejlog_init(&l);
    engine_waypoint_t wp = circle(0);
    wp.t_s = NAN;
    (void)engine_push(e, &wp);
    rejlog_drain(&l, e);
    lines_t out = {.n = 0};
    assert_int_equal(rejlog_flush(&l, "x", collect, &out), 1);
    assert_non_null(strstr(out.line[0], "object 'x': unknown source: rejected (not_finite) seq 1"));
    engine_free(e);
}

/* Given two sources offering the same seq at different times (two Modbus
 * clients numbering from 1), then the refusal is named by the one whose
 * waypoint it was. */
/* Given a waypoint at x = 1e300 and t = -1e300 (refused), when its line is
 * logged, then the numbers take a bounded width: the whole line fits (it
 * ends with its closing parenthesis) and names 1e+300 (issue 24; with %.3f
 * 1e300 took 301 digits and the line was cut). */
static void test_huge_numbers_bounded(void **state)
{
    (void)state;
    engine_t *e = new_engine();
    rejlog_t l;
    rejlog_init(&l);
    engine_waypoint_t wp = circle(0);
    wp.t_s = -1e300;
    wp.pos_m[0] = 1e300;
    wp.pos_m[1] = -1e300;
    wp.pos_m[2] = 1e300;
    char src[REJLOG_SRC_LEN];
    memset(src, 'a', sizeof src - 1);
    src[sizeof src - 1] = '\0';
    rejlog_offered(&l, &wp, src);
    (void)engine_push(e, &wp);
    rejlog_drain(&l, e);
    lines_t out = {.n = 0};
    assert_int_equal(rejlog_flush(&l, "object-name-of-31-characters-xx", collect, &out), 1);
    size_t n = strlen(out.line[0]);
    assert_true(n < REJLOG_LINE_MAX - 1);
    assert_int_equal(out.line[0][n - 1], ')');
    assert_non_null(strstr(out.line[0], "t=-1e+300 s at (1e+300, -1e+300, 1e+300)"));
    engine_free(e);
}

static void test_same_seq_two_sources(void **state)
{
    (void)state;
    engine_t *e = new_engine();
    rejlog_t l;
    rejlog_init(&l);
    engine_waypoint_t a = circle(10), b = circle(10);
    b.t_s = 1.0; /* earlier than a: refused as backwards, whenever judged */
    rejlog_offered(&l, &a, "modbus 10.0.0.1:5000");
    (void)engine_push(e, &a);
    rejlog_offered(&l, &b, "modbus 10.0.0.2:6000");
    (void)engine_push(e, &b);
    engine_finish(e);
    rejlog_drain(&l, e);
    lines_t out = {.n = 0};
    assert_int_equal(rejlog_flush(&l, "boat", collect, &out), 1);
    assert_non_null(strstr(out.line[0], "modbus 10.0.0.2:6000: rejected (backwards)"));
    engine_free(e);
}

/* A replayed row's source, "PATH:LINE" (rejlog_src_file, made on every push
 * without printf), is the text the replay transport formatted with snprintf:
 * paths of every length up to and past the 160 characters kept (a longer one
 * keeps its end after "..."), line numbers of every width, and no line. */
static void test_file_source_as_printf(void **state)
{
    (void)state;
    static const uint32_t lines[] = {0, 1, 9, 10, 52, 99, 100, 12345, 999999999u, UINT32_MAX};
    char path[400], ref[REJLOG_SRC_LEN], got[REJLOG_SRC_LEN];
    unsigned seed = 7;
    for (size_t len = 0; len < 300; len++) {
        for (size_t i = 0; i < len; i++)
            path[i] = (char)('a' + (int)(urand(&seed) * 25.99));
        path[len] = 0;
        const char *tail = len > 160 ? path + len - 160 : path;
        for (size_t k = 0; k <= sizeof lines / sizeof lines[0]; k++) {
            int has = k < sizeof lines / sizeof lines[0];
            if (has)
                snprintf(ref, sizeof ref, "%s%.160s:%" PRIu32, tail != path ? "..." : "", tail,
                         lines[k]);
            else
                snprintf(ref, sizeof ref, "%s%.160s", tail != path ? "..." : "", tail);
            memset(got, 'x', sizeof got);
            size_t n = rejlog_src_file(got, path, has, has ? lines[k] : 0);
            assert_string_equal(got, ref);
            assert_int_equal(n, strlen(ref));
        }
    }
}

/* A source longer than the log keeps is cut as snprintf cut it. */
static void test_long_source_cut(void **state)
{
    (void)state;
    rejlog_t l;
    rejlog_init(&l);
    char src[300];
    memset(src, 'q', sizeof src - 1);
    src[sizeof src - 1] = 0;
    engine_waypoint_t wp = circle(0);
    rejlog_offered(&l, &wp, src);
    assert_int_equal(strlen(l.ring[0].src), REJLOG_SRC_LEN - 1);
    assert_int_equal(strspn(l.ring[0].src, "q"), REJLOG_SRC_LEN - 1);
    rejlog_offered(&l, &wp, "");
    assert_string_equal(l.ring[1].src, "unknown source");
    rejlog_offered(&l, &wp, "track.csv:7");
    assert_string_equal(l.ring[2].src, "track.csv:7");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spike_named_by_its_line),
        cmocka_unit_test(test_rate_limited),
        cmocka_unit_test(test_unknown_source),
        cmocka_unit_test(test_same_seq_two_sources),
        cmocka_unit_test(test_huge_numbers_bounded),
        cmocka_unit_test(test_file_source_as_printf),
        cmocka_unit_test(test_long_source_cut),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
