/* test_path.c - path text -> waypoints: lines, exact arcs, circles, timing. */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "path.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Points on a circle of radius ~20 m at coordinates ~50 m: a few ulps. */
#define TOL_POS 1e-12

static size_t parse_all(const char *const *lines, size_t n, path_elem_t *el)
{
    size_t i;
    for (i = 0; i < n; i++)
        assert_int_equal(path_parse_line(lines[i], &el[i]), 0);
    return n;
}

/* Given start, a line, a quarter arc (joined by a line) and a full circle,
 * when expanded at speed 2 m/s with 0.5 s steps, then: arc points lie on
 * their circle at equal angle steps (cos/sin of the intended angle),
 * consecutive times are <= step apart and increase, and the speed along each
 * element is exactly 2 m/s (arc length / time). */
static void test_line_arc_circle(void **state)
{
    (void)state;
    const char *const prog[] = {
        "# a test path",
        "start 0 0 1.5",
        "speed 2",
        "step 0.5",
        "line 30 0 1.5",
        "arc 30 20 20 -90 0   # quarter turn ccw from (30,0) to (50,20)",
        "circle 30 20 20 0 cw",
        "wait 3",
    };
    path_elem_t el[16];
    static engine_waypoint_t wp[1024];
    size_t n = parse_all(prog, sizeof prog / sizeof prog[0], el), nw, i, need;
    double arc_len = 20 * M_PI / 2, circ = 2 * M_PI * 20;

    assert_int_equal(path_expand(el, n, NULL, 0, &need), 0);
    assert_int_equal(path_expand(el, n, wp, 1024, &nw), 0);
    assert_int_equal(need, nw);
    /* counts: line 30 m at 1 m per step -> 30; quarter arc 31.4 m -> 32 steps;
     * circle 125.7 m -> 126 steps; start + wait -> 2 */
    assert_int_equal(nw, 1 + 30 + 32 + 126 + 1);
    for (i = 1; i < nw; i++) {
        double dt = wp[i].t_s - wp[i - 1].t_s;
        assert_true(dt > 0 && dt <= 0.5 + 1e-12 + (i == nw - 1 ? 2.5 : 0));
        assert_int_equal(wp[i].seq, i + 1);
        assert_true(fabs(wp[i].pos_m[2] - 1.5) < 1e-15);
    }
    /* quarter arc: waypoints 31..62, angle -90 + 90 k/32 */
    for (i = 31; i <= 62; i++) {
        double a = (-90.0 + 90.0 * (double)(i - 30) / 32.0) * M_PI / 180.0;
        assert_true(fabs(wp[i].pos_m[0] - (30 + 20 * cos(a))) < TOL_POS);
        assert_true(fabs(wp[i].pos_m[1] - (20 + 20 * sin(a))) < TOL_POS);
    }
    assert_true(fabs(wp[62].t_s - wp[30].t_s - arc_len / 2.0) < 1e-12);
    /* circle, clockwise from angle 0 */
    for (i = 63; i <= 188; i++) {
        double a = -2 * M_PI * (double)(i - 62) / 126.0;
        assert_true(fabs(wp[i].pos_m[0] - (30 + 20 * cos(a))) < TOL_POS);
        assert_true(fabs(wp[i].pos_m[1] - (20 + 20 * sin(a))) < TOL_POS);
    }
    assert_true(fabs(wp[188].t_s - wp[62].t_s - circ / 2.0) < 1e-11);
    assert_true(fabs(wp[189].t_s - wp[188].t_s - 3.0) < 1e-12);
    assert_memory_equal(wp[189].pos_m, wp[188].pos_m, sizeof wp[0].pos_m);
    /* capacity too small */
    assert_int_equal(path_expand(el, n, wp, 10, &nw), -PATH_EFULL);
    assert_int_equal(nw, need);
}

/* Given an arc whose start is not the current point, then a joining line is
 * inserted and the arc starts exactly at centre + r (cos a0, sin a0). */
static void test_arc_join(void **state)
{
    (void)state;
    const char *const prog[] = {"start 0 0 0", "arc 10 0 5 180 360"};
    path_elem_t el[2];
    engine_waypoint_t wp[64];
    size_t nw, i;

    parse_all(prog, 2, el);
    assert_int_equal(path_expand(el, 2, wp, 64, &nw), 0);
    /* 5 m line in 5 steps (speed 1, step 1), then 5 pi m arc in 16 steps */
    assert_int_equal(nw, 1 + 5 + 16);
    assert_true(fabs(wp[5].pos_m[0] - 5.0) < 1e-15 && fabs(wp[5].pos_m[1]) < 1e-15);
    for (i = 6; i < nw; i++)
        assert_true(fabs(hypot(wp[i].pos_m[0] - 10, wp[i].pos_m[1]) - 5) < TOL_POS);
    assert_true(fabs(wp[nw - 1].pos_m[0] - 15) < TOL_POS);
}

static void test_parse_errors(void **state)
{
    (void)state;
    path_elem_t el;
    assert_int_equal(path_parse_line("   # nothing", &el), 0);
    assert_int_equal(el.kind, PATH_NONE);
    assert_int_equal(path_parse_line("jump 1 2 3", &el), -PATH_ESYNTAX);
    assert_int_equal(path_parse_line("line 1 2", &el), -PATH_ESYNTAX);
    assert_int_equal(path_parse_line("line 1 2 x", &el), -PATH_ESYNTAX);
    assert_int_equal(path_parse_line("speed 0", &el), -PATH_ERANGE);
    assert_int_equal(path_parse_line("arc 0 0 -1 0 90", &el), -PATH_ERANGE);
    assert_int_equal(path_parse_line("arc 0 0 1 0 400", &el), -PATH_ERANGE);
    assert_int_equal(path_parse_line("circle 0 0 1 0 up", &el), -PATH_ESYNTAX);
    assert_int_equal(path_parse_line("line 1 2 3", &el), 0);
    assert_int_equal(path_expand(&el, 1, NULL, 0, NULL), -PATH_ENOSTART);
    {
        path_elem_t two[3];
        assert_int_equal(path_parse_line("start 0 0 0", &two[0]), 0);
        assert_int_equal(path_parse_line("line 5 0 0", &two[1]), 0);
        assert_int_equal(path_parse_line("start 0 0 0", &two[2]), 0);
        assert_int_equal(path_expand(two, 3, NULL, 0, NULL), -PATH_ETWICE);
    }
    assert_non_null(path_strerror(-PATH_EFULL));
}

/* Given times a consumer cannot use (issue 11: "wait 1e300" made every
 * later waypoint a duplicate in time, dropped without a word), then they are
 * refused: at parse for a start time or a wait beyond PATH_TIME_MAX_S, at
 * expansion (with the failing element's index) for a step that no longer
 * advances a double time, and el_end maps waypoints to their elements. */
static void test_time_limits(void **state)
{
    (void)state;
    path_elem_t el[4];
    size_t end[4], bad = 99, n = 0;
    assert_int_equal(path_parse_line("wait 1e300", &el[0]), -PATH_ETIME);
    assert_int_equal(path_parse_line("start 0 0 0 -1e300", &el[0]), -PATH_ETIME);
    assert_int_equal(path_parse_line("wait 1e9", &el[1]), 0);
    assert_int_equal(path_parse_line("start 0 0 0 1e9", &el[0]), 0);
    /* 1e9 + 1e9 is beyond the limit: the wait element (index 1) fails */
    assert_int_equal(path_expand_ex(el, 2, NULL, 0, &n, end, &bad), -PATH_ETIME);
    assert_int_equal(bad, 1);
    /* at t = 1e8 s a 1e-12 s move does not change the double time */
    assert_int_equal(path_parse_line("start 0 0 0 1e8", &el[0]), 0);
    assert_int_equal(path_parse_line("speed 1e12", &el[1]), 0);
    assert_int_equal(path_parse_line("line 1 0 0", &el[2]), 0);
    bad = 99;
    assert_int_equal(path_expand_ex(el, 3, NULL, 0, &n, end, &bad), -PATH_ETIME);
    assert_int_equal(bad, 2);
    /* the same at t = 0 is fine; el_end counts waypoints per element */
    assert_int_equal(path_parse_line("start 0 0 0", &el[0]), 0);
    assert_int_equal(path_parse_line("line 3 0 0", &el[2]), 0);
    assert_int_equal(path_parse_line("wait 2", &el[3]), 0);
    assert_int_equal(path_expand_ex(el, 4, NULL, 0, &n, end, &bad), 0);
    assert_int_equal(n, 3);
    assert_int_equal(end[0], 1);
    assert_int_equal(end[1], 1);
    assert_int_equal(end[2], 2);
    assert_int_equal(end[3], 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_line_arc_circle),
        cmocka_unit_test(test_arc_join),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_time_limits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
