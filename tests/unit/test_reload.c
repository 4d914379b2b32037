/*
 * test_reload.c - what a reload does to a moving object, on a real core
 * (daemon/core/core.h core_open, daemon/core/reload.h) with a replay input
 * and a CSV output in a temporary directory: no clock, no sockets.  The
 * engine is stepped here, as the tick would.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg.h"
#include "core.h"
#include "reload.h"

#define PERIOD_NS 10000000LL /* 100 Hz */

static char dir[] = "/tmp/trajd-test-reload-XXXXXX";

static cfg_t *load(const char *name)
{
    char path[256], err[512];
    cfg_t *c = NULL;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (cfg_load(path, &c, err, sizeof err) < 0)
        fail_msg("%s", err);
    return c;
}

/* A line along x at 1 m/s, one waypoint a second, pushed into o's engine. */
static void push_line(obj_t *o)
{
    for (int i = 0; i < 60; i++) {
        engine_waypoint_t w;
        memset(&w, 0, sizeof w);
        w.t_s = i;
        w.pos_m[0] = i;
        w.seq = (uint32_t)i + 1;
        assert_int_equal(engine_push(o->engine, &w), 0);
    }
}

/* Step every engine of c n ticks on, as the tick does (its clock: c->now_ns). */
static void step(core_t *c, int n)
{
    for (int i = 0; i < n; i++) {
        c->now_ns += PERIOD_NS;
        for (unsigned k = 0; k < c->nobj; k++) {
            obj_t *o = &c->obj[k];
            engine_tick(o->retiring ? o->retiring : o->engine, c->now_ns, &o->sp);
        }
    }
}

static double speed(const obj_t *o)
{
    return sqrt(o->sp.vel_m_s[0] * o->sp.vel_m_s[0] + o->sp.vel_m_s[1] * o->sp.vel_m_s[1]);
}

static const char good[] = "[daemon]\nrate_hz = 100\n"
                           "[object.boat]\nid = 0\ninput = replay\nreplay.track = t.csv\n"
                           "output = csv\ncsv.path = out.csv\n";

/* A fresh directory with the track and good.conf, a loop and zeroed stats. */
static loop_t *setup(stats_t *stats)
{
    int err = 0;
    snprintf(dir, sizeof dir, "/tmp/trajd-test-reload-XXXXXX");
    assert_non_null(mkdtemp(dir));
    test_write_file(dir, "t.csv", "t,x,y,z\n0,0,0,0\n1,1,0,0\n");
    test_write_file(dir, "good.conf", good);
    loop_t *loop = loop_new(&err);
    assert_non_null(loop);
    memset(stats, 0, sizeof *stats);
    return loop;
}

/* A core on cfg whose boat (the test feeds it, not the replay) moves at 1 m/s. */
static core_t *moving_boat(loop_t *loop, const cfg_t *cfg, stats_t *stats)
{
    core_t *c = NULL;
    char why[512];
    assert_int_equal(core_open(loop, cfg, stats, NULL, &c, why, sizeof why), 0);
    obj_t *o = &c->obj[0];
    engine_clear(o->engine);
    push_line(o);
    step(c, 500);
    assert_true(speed(o) > 0.9);
    return c;
}

/* Close c, free the n configurations and the loop, remove the directory. */
static void teardown(core_t *c, loop_t *loop, cfg_t **cfgs, int n)
{
    char cmd[128];
    core_close(c);
    for (int i = 0; i < n; i++)
        cfg_free(cfgs[i]);
    loop_free(loop);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

/* Given boat moving at 1 m/s, when a reload's CSV output cannot open, then
 * core_open fails with the reason and the running core keeps boat's engine,
 * untouched: the next setpoint continues the last one (no step, same
 * trajectory).  When a good config follows, boat is carried over: the new
 * core has the same engine.  When a config removes it, it brakes to rest
 * along its path (reload_brake_removed) before anything else. */
static void test_reload_keeps_the_running_engine(void **state)
{
    (void)state;
    stats_t stats;
    loop_t *loop = setup(&stats);
    char bad[sizeof good + 64];
    snprintf(bad, sizeof bad, "%s", good);
    memcpy(strstr(bad, "out.csv"), "no/dir/x", 8); /* csv.path = no/dir/x (a missing directory) */
    test_write_file(dir, "bad.conf", bad);
    test_write_file(dir, "gone.conf",
                    "[daemon]\nrate_hz = 100\n[object.ship]\nid = 1\ninput = replay\n"
                    "replay.track = t.csv\noutput = csv\ncsv.path = out.csv\n");
    cfg_t *cfgs[4] = {load("good.conf"), load("bad.conf"), load("good.conf"), load("gone.conf")};
    cfg_t *c2 = cfgs[1], *c3 = cfgs[2], *c4 = cfgs[3];
    core_t *c = moving_boat(loop, cfgs[0], &stats), *nc = NULL;
    char why[512];
    obj_t *o = &c->obj[0];
    engine_t *e = o->engine;
    engine_setpoint_t before = o->sp;

    /* the failed reload */
    assert_true(core_open(loop, c2, &stats, &c, &nc, why, sizeof why) < 0);
    assert_non_null(strstr(why, "no/dir/x"));
    assert_null(nc);
    assert_non_null(c); /* the old core runs on */
    o = &c->obj[0];
    assert_ptr_equal(o->engine, e);
    assert_null(o->retiring);
    step(c, 1);
    /* one period on at the line's 1 m/s (5 %: the curve's entry from rest) */
    assert_true(fabs(o->sp.pos_m[0] - before.pos_m[0]) <= 1.05 * PERIOD_NS * 1e-9);
    assert_true(o->sp.pos_m[0] > before.pos_m[0]);
    assert_int_equal(o->sp.track, before.track);
    assert_true(speed(o) > 0.9);

    /* a good reload: carried over */
    assert_int_equal(core_open(loop, c3, &stats, &c, &nc, why, sizeof why), 0);
    assert_null(c);
    c = nc;
    o = &c->obj[0];
    assert_ptr_equal(o->engine, e);
    assert_int_equal(o->carried, 1);
    step(c, 1);
    assert_true(speed(o) > 0.9);

    /* removed: brakes to rest along x, its speed never rising */
    assert_int_equal(reload_brake_removed(c, c4), 1);
    assert_int_equal(o->stopping, OBJ_STOPPING_REMOVED);
    assert_int_equal(reload_removed_at_rest(c, c4), 0);
    double v = speed(o), y0 = o->sp.pos_m[1];
    for (int i = 0; i < 1000 && !reload_removed_at_rest(c, c4); i++) {
        step(c, 1);
        assert_true(speed(o) <= v + 1e-9);
        assert_true(fabs(o->sp.pos_m[1] - y0) < 1e-9); /* on its path */
        v = speed(o);
    }
    assert_int_equal(reload_removed_at_rest(c, c4), 1);
    assert_true(speed(o) < 1e-12);
    assert_int_equal(reload_brake_removed(c, c4), 0); /* at rest: nothing more to brake */

    teardown(c, loop, cfgs, 4);
}

/* Given boat paused by its operator (feed override 0) at rest on its path,
 * when a reload changes its settings (a new engine, started where the old
 * one stands), then the pause goes with the object: the new engine's
 * override is 0, and with waypoints pushed it does not set off (a transfer
 * to them, with no command): the override stays the operator's until they
 * change it, as the holds and the latch do (lib/engine/LIFECYCLE.md "reload
 * new").  The operator's 50 % carries over the same way. */
static void test_reload_keeps_the_override(void **state)
{
    (void)state;
    stats_t stats;
    loop_t *loop = setup(&stats);
    char changed[sizeof good + 64];
    snprintf(changed, sizeof changed, "%sscale_jerk_m_s3 = 40\n", good);
    test_write_file(dir, "changed.conf", changed);
    cfg_t *cfgs[3] = {load("good.conf"), load("changed.conf"), load("good.conf")};
    core_t *c = moving_boat(loop, cfgs[0], &stats), *nc = NULL;
    char why[512];
    obj_t *o = &c->obj[0];
    assert_int_equal(obj_command(o, LC_EV_OVERRIDE_ZERO, 0, NULL), 0);
    step(c, 300);
    assert_true(speed(o) < 1e-12);
    double x = o->sp.pos_m[0];

    /* the changed reload: a new engine where boat stands, the pause with it */
    assert_int_equal(core_open(loop, cfgs[1], &stats, &c, &nc, why, sizeof why), 0);
    assert_null(c);
    c = nc;
    o = &c->obj[0];
    assert_int_equal(o->carried, 0);
    engine_status(o->engine, &o->status);
    assert_true(!(fabs(o->status.override) > 0));
    push_line(o); /* its track again, from x = 0: a transfer back, if it moved */
    for (int i = 0; i < 300; i++) {
        step(c, 1);
        assert_true(!(speed(o) > 0));
        assert_true(!(fabs(o->sp.pos_m[0] - x) > 0));
    }

    /* the operator's 50 %, the object moving again (the transfer back), through
     * another changed reload (back to good.conf): the old engine brakes, the new
     * one has 50 % */
    assert_int_equal(obj_command(o, LC_EV_OVERRIDE, 50, NULL), 0);
    step(c, 300);
    assert_true(speed(o) > 0.1);
    assert_int_equal(core_open(loop, cfgs[2], &stats, &c, &nc, why, sizeof why), 0);
    c = nc;
    o = &c->obj[0];
    engine_status(o->engine, &o->status);
    assert_true(!(fabs(o->status.override - 0.5) > 0));
    teardown(c, loop, cfgs, 3);
}

/* Given boat moving, when a reload removes it (it brakes to rest along its
 * path, then goes) and a later one adds it back (same name, same settings),
 * then the new boat starts where the old one came to rest, and reaches its
 * track by a transfer: no setpoint steps to the track's first waypoint (the
 * position a fresh object takes), 49 m away in the probe that found it. */
static void test_readded_object_starts_where_it_went(void **state)
{
    (void)state;
    stats_t stats;
    loop_t *loop = setup(&stats);
    test_write_file(dir, "gone.conf",
                    "[daemon]\nrate_hz = 100\n[object.ship]\nid = 1\ninput = replay\n"
                    "replay.track = t.csv\noutput = csv\ncsv.path = out2.csv\n");
    cfg_t *cfgs[3] = {load("good.conf"), load("gone.conf"), load("good.conf")};
    cfg_t *c2 = cfgs[1], *c3 = cfgs[2];
    core_t *c = moving_boat(loop, cfgs[0], &stats), *nc = NULL;
    char why[512];
    obj_t *o = &c->obj[0];

    assert_int_equal(reload_brake_removed(c, c2), 1);
    for (int i = 0; i < 1000 && !reload_removed_at_rest(c, c2); i++)
        step(c, 1);
    assert_int_equal(reload_removed_at_rest(c, c2), 1);
    double rest[3];
    memcpy(rest, o->sp.pos_m, sizeof rest);
    assert_true(rest[0] > 4.0);
    assert_int_equal(core_open(loop, c2, &stats, &c, &nc, why, sizeof why), 0);
    c = nc;
    step(c, 10);

    /* boat again */
    assert_int_equal(core_open(loop, c3, &stats, &c, &nc, why, sizeof why), 0);
    c = nc;
    o = core_obj_find(c, "boat");
    assert_non_null(o);
    push_line(o);
    double prev[3], xmin = rest[0];
    memcpy(prev, rest, sizeof prev);
    for (int i = 0; i < 3000; i++) {
        step(c, 1);
        if (o->sp.flags & ENGINE_SP_NO_POSITION)
            fail_msg("tick %d: no position (the old one forgotten)", i);
        double d = 0;
        for (int k = 0; k < 3; k++)
            d += (o->sp.pos_m[k] - prev[k]) * (o->sp.pos_m[k] - prev[k]);
        if (sqrt(d) > 1.05 * PERIOD_NS * 1e-9 * 2.0) /* above the transfer's top speed */
            fail_msg("tick %d: a step of %.3f m from (%.3f, %.3f)", i, sqrt(d), prev[0], prev[1]);
        memcpy(prev, o->sp.pos_m, sizeof prev);
        xmin = fmin(xmin, o->sp.pos_m[0]);
    }
    assert_true(xmin < 0.5); /* the transfer back to the line's start did come */

    teardown(c, loop, cfgs, 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reload_keeps_the_running_engine),
        cmocka_unit_test(test_reload_keeps_the_override),
        cmocka_unit_test(test_readded_object_starts_where_it_went),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
