/*
 * test_cfgload.c - a configuration read on the reload's worker
 * (daemon/core/cfgload.h): its eventfd becomes readable once it is done, a
 * good file comes back checked against the running one, a bad one with its
 * file:line, a reload that would move an object's id refused; a drop during
 * the parse of a 300 000-row track returns (the parse cancelled) and frees
 * what was built; the old configuration is freed on a thread.  Valgrind-clean.
 */
#include "test.h"

#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg.h"
#include "cfgload.h"

static char dir[] = "/tmp/trajd-test-cfgload-XXXXXX";

static void write_track(const char *name, int rows)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("t,x,y,z\n", f);
    for (int i = 0; i < rows; i++)
        fprintf(f, "%.2f,%.2f,0,1\n", i * 0.01, i * 0.01);
    fclose(f);
}

static void write_conf(const char *name, int id, const char *track)
{
    char text[512];
    snprintf(text, sizeof text,
             "[daemon]\nrate_hz = 100\n[object.a]\nid = %d\ninput = replay\nreplay.track = %s\n"
             "output = csv\ncsv.path = out.csv\n",
             id, track);
    test_write_file(dir, name, text);
}

/* Start loading name (checked against running), wait for the eventfd, take it. */
static int load(const char *name, const cfg_t *running, cfg_t **out, char *err, size_t errlen)
{
    char path[256];
    int e = 0;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    cfgload_t *l = cfgload_start(path, running, &e);
    assert_non_null(l);
    struct pollfd p = {cfgload_fd(l), POLLIN, 0};
    assert_int_equal(poll(&p, 1, 30000), 1);
    return cfgload_finish(l, out, err, errlen);
}

static void test_good_bad_and_refused(void **state)
{
    (void)state;
    char err[1024];
    cfg_t *run = NULL, *nc = NULL;
    write_track("a.csv", 100);
    write_conf("good.conf", 0, "a.csv");
    assert_int_equal(load("good.conf", NULL, &run, err, sizeof err), 0);
    assert_non_null(run);
    assert_int_equal(run->nobj, 1);

    test_write_file(dir, "bad.conf", "[daemon]\nrate_hz = fast\n");
    assert_true(load("bad.conf", run, &nc, err, sizeof err) < 0);
    assert_null(nc);
    assert_non_null(strstr(err, "bad.conf:2"));

    write_conf("moved.conf", 1, "a.csv"); /* a reload never moves an id */
    assert_true(load("moved.conf", run, &nc, err, sizeof err) < 0);
    assert_null(nc);
    assert_non_null(strstr(err, "a reload never moves"));

    assert_int_equal(load("good.conf", run, &nc, err, sizeof err), 0);
    assert_non_null(nc);
    cfgload_retire(run); /* freed on its thread */
    cfgload_retire(nc);  /* joins the first */
    cfgload_retire_join();
}

static void test_drop_cancels_the_parse(void **state)
{
    (void)state;
    char path[256];
    int e = 0;
    write_track("long.csv", 300000);
    write_conf("long.conf", 0, "long.csv");
    snprintf(path, sizeof path, "%s/long.conf", dir);
    cfgload_t *l = cfgload_start(path, NULL, &e);
    assert_non_null(l);
    cfgload_drop(l);                          /* at once: the parse gives up within 65536 rows */
    assert_int_equal(cfgload_cancelled(), 0); /* a later load runs */
    char err[1024];
    cfg_t *c = NULL;
    assert_int_equal(load("long.conf", NULL, &c, err, sizeof err), 0);
    cfg_free(c);
}

static int setup(void **state)
{
    (void)state;
    return mkdtemp(dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_bad_and_refused),
        cmocka_unit_test(test_drop_cancels_the_parse),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
