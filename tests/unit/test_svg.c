/* test_svg.c - the SVG plot: bounded decimation, and a document that an
 * independent XML parser (expat) accepts, with the expected elements. */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <expat.h>

#include "svg.h"

/* Tick i at 10 ms; track time from the clock, plus jump_s (a gap). */
static engine_setpoint_t setpoint(uint64_t i, unsigned track, double jump_s)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    sp.now_ns = (int64_t)i * 10000000;
    sp.t_s = (double)i * 0.01 + jump_s;
    sp.pos_m[0] = cos(sp.t_s) * 100;
    sp.pos_m[1] = sin(sp.t_s) * 50;
    sp.vel_m_s[0] = -sin(sp.t_s) * 100;
    sp.vel_m_s[1] = cos(sp.t_s) * 50;
    sp.state = ENGINE_STATE_STREAMING;
    sp.track = track;
    return sp;
}

/* Given a million setpoints, when added to a plot of 100 points, then at
 * most 100 are kept and the stride is the power of two that makes it so. */
static void test_decimation_bounded(void **state)
{
    (void)state;
    svg_plot_t *p = svg_plot_new(100, 0);
    assert_non_null(p);
    for (uint64_t i = 0; i < 1000000; i++) {
        engine_setpoint_t sp = setpoint(i, 1, 0);
        assert_int_equal(svg_plot_setpoint(p, &sp), 0);
        assert_true(svg_plot_kept(p) <= 100);
    }
    /* 1e6 / 100 = 1e4 -> stride 16384 (the next power of two), 62 kept. */
    assert_int_equal(svg_plot_stride(p), 16384);
    assert_int_equal(svg_plot_kept(p), (1000000 + 16383) / 16384);
    svg_plot_free(p);
    svg_plot_free(NULL);
}

typedef struct {
    int svg, title, paths, circles, texts, legend, depth_max, depth;
    char ids[512];
    size_t curve_moves, speed_moves;
} counts_t;

static void XMLCALL on_start(void *ud, const XML_Char *name, const XML_Char **attr)
{
    counts_t *c = ud;
    if (++c->depth > c->depth_max)
        c->depth_max = c->depth;
    if (strcmp(name, "svg") == 0)
        c->svg++;
    if (strcmp(name, "title") == 0)
        c->title++;
    if (strcmp(name, "path") == 0)
        c->paths++;
    if (strcmp(name, "circle") == 0)
        c->circles++;
    if (strcmp(name, "text") == 0)
        c->texts++;
    const char *id = NULL, *d = NULL;
    for (int i = 0; attr[i]; i += 2) {
        if (strcmp(attr[i], "id") == 0)
            id = attr[i + 1];
        if (strcmp(attr[i], "d") == 0)
            d = attr[i + 1];
    }
    if (id && strlen(c->ids) + strlen(id) + 2 < sizeof c->ids) {
        strcat(c->ids, id);
        strcat(c->ids, " ");
    }
    if (id && d && strcmp(id, "curve") == 0)
        for (const char *s = d; *s; s++)
            c->curve_moves += *s == 'M';
    if (id && d && strcmp(id, "speed") == 0)
        for (const char *s = d; *s; s++)
            c->speed_moves += *s == 'M';
}

static void XMLCALL on_end(void *ud, const XML_Char *name)
{
    (void)name;
    ((counts_t *)ud)->depth--;
}

/* Given waypoints (one rejected) and setpoints over two trajectories with a
 * 300 s gap in track time and one underrun, when written, then expat parses the document and
 * finds the svg root, the title (with '&' escaped), the curve as one line,
 * the speed line broken at the gap, a dot per accepted waypoint, the
 * underrun marked and counted, the axes
 * of both panels and their labels. */
static void test_document_well_formed(void **state)
{
    (void)state;
    svg_plot_t *p = svg_plot_new(0, 1);
    assert_non_null(p);
    for (int i = 0; i < 20; i++)
        assert_int_equal(svg_plot_waypoint(p, i * 10.0, i * 5.0, i != 7), 0);
    assert_int_equal(svg_plot_waypoint(p, NAN, 1, 1), 0); /* ignored */
    for (uint64_t i = 0; i < 5000; i++) {
        engine_setpoint_t sp = setpoint(i, i < 2500 ? 1 : 2, i < 2500 ? 0 : 300);
        if (i >= 1000 && i < 1010) /* one underrun of 10 ticks */
            sp.state = ENGINE_STATE_UNDERRUN;
        svg_plot_setpoint(p, &sp);
    }
    engine_setpoint_t waiting = setpoint(0, 0, 0);
    waiting.state = ENGINE_STATE_WAITING;
    waiting.pos_m[0] = 1e9; /* would ruin the scale if it were drawn */
    svg_plot_setpoint(p, &waiting);

    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    assert_int_equal(svg_plot_write(p, f, "a & b <c>"), 0);
    fclose(f);

    counts_t c;
    memset(&c, 0, sizeof c);
    XML_Parser x = XML_ParserCreate(NULL);
    XML_SetUserData(x, &c);
    XML_SetElementHandler(x, on_start, on_end);
    if (XML_Parse(x, buf, (int)len, 1) != XML_STATUS_OK)
        fail_msg("expat: %s at line %lu", XML_ErrorString(XML_GetErrorCode(x)),
                 (unsigned long)XML_GetCurrentLineNumber(x));
    XML_ParserFree(x);

    assert_int_equal(c.svg, 1);
    assert_int_equal(c.title, 1);
    assert_int_equal(c.circles, 19 + 1); /* accepted waypoints + the legend dot */
    assert_non_null(strstr(c.ids, "curve "));
    assert_non_null(strstr(c.ids, "speed "));
    assert_non_null(strstr(c.ids, "plan-axes "));
    assert_non_null(strstr(c.ids, "speed-axes "));
    assert_non_null(strstr(c.ids, "waypoints "));
    assert_non_null(strstr(c.ids, "rejected "));
    assert_non_null(strstr(c.ids, "underruns "));
    assert_non_null(strstr(c.ids, "underruns-t "));
    assert_non_null(strstr(buf, ">underrun (1)</text>"));
    assert_int_equal(c.curve_moves, 1);
    assert_int_equal(c.speed_moves, 2);
    assert_non_null(strstr(buf, "a &amp; b &lt;c&gt;"));
    assert_non_null(strstr(buf, ">east (m)</text>"));
    assert_non_null(strstr(buf, ">north (m)</text>"));
    assert_non_null(strstr(buf, ">track time t (s)</text>"));
    assert_non_null(strstr(buf, ">speed |v| (m/s)</text>"));
    assert_null(strstr(buf, "nan"));
    assert_null(strstr(buf, "inf"));
    assert_true(len < 400000);
    free(buf);
    svg_plot_free(p);
}

/* Given an empty plot or a single point, when written, then still a valid
 * document with finite numbers (degenerate ranges widened). */
static void test_degenerate(void **state)
{
    (void)state;
    for (int k = 0; k < 2; k++) {
        svg_plot_t *p = svg_plot_new(16, 0);
        if (k) {
            svg_plot_waypoint(p, 5, 5, 1);
            engine_setpoint_t sp = setpoint(0, 1, 0);
            sp.pos_m[0] = sp.pos_m[1] = 5;
            sp.vel_m_s[0] = sp.vel_m_s[1] = 0;
            svg_plot_setpoint(p, &sp);
        }
        char *buf = NULL;
        size_t len = 0;
        FILE *f = open_memstream(&buf, &len);
        assert_int_equal(svg_plot_write(p, f, NULL), 0);
        fclose(f);
        XML_Parser x = XML_ParserCreate(NULL);
        assert_int_equal(XML_Parse(x, buf, (int)len, 1), XML_STATUS_OK);
        XML_ParserFree(x);
        assert_null(strstr(buf, "nan"));
        assert_null(strstr(buf, "inf"));
        assert_non_null(strstr(buf, ">x (m)</text>"));
        free(buf);
        svg_plot_free(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decimation_bounded),
        cmocka_unit_test(test_document_well_formed),
        cmocka_unit_test(test_degenerate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
