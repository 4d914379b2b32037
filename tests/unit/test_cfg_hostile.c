/* test_cfg_hostile.c - config files a hostile or careless author writes
 * (issue 24): each is refused at check time with "name:line: ..." naming
 * the rule, or, where it is harmless, read as meant.  Run from the
 * repository root (tests/run.sh does). */
#include "test.h"
#include "cfg_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cfg.h"
#include "engine_settings.h"

#define TRACK "tests/data/n2k_furuno_figure8_src52.csv"
#define OBJ "[object.boat]\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n"

/* Given an engine setting refused by the settings' own rules (capacity below
 * what the lookahead and fragment need, delay_s below what the settings
 * need), then the error names the key's line, not its section's (it named
 * line 1 for a key on line 7). */
static void test_engine_error_at_its_key(void **state)
{
    (void)state;
    assert_true(engine_settings_count <= CFG_ENGINE_KEYS);
    load_bad(OBJ "max_gap_s = 30\n\ncapacity = 10\n", CFG_EVALUE, 7, "capacity: must be at least");
    load_bad(OBJ "delay_s = 0.5\n", CFG_EVALUE, 5, "delay_s 0.5 s is shorter");
}

/* Given a [modbus] address that is not a numeric IPv4 or IPv6 address (out of
 * range, a name), then it is refused at its line (it passed the check, and
 * the start failed with exit 69 and no file:line); numeric ones of both
 * families are read. */
static void test_modbus_address(void **state)
{
    (void)state;
    static const char *const bad[] = {"999.1.1.1", "localhost", "1.2.3", "::g"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "[modbus]\nport = 1502\naddress = %s\n" OBJ, bad[i]);
        load_bad(text, CFG_EVALUE, 3, "not a numeric IPv4 or IPv6 address");
    }
    static const char *const good[] = {"127.0.0.1", "0.0.0.0", "::1", "::"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "[modbus]\nport = 1502\naddress = %s\n" OBJ, good[i]);
        cfg_free(load_ok(text));
    }
}

/* Given a [modbus] value out of its range or not of its kind, then the
 * error says what the key takes, as [daemon]'s do ("bad value '65536' for
 * port" gave no range, after a doubled "modbus: modbus:"). */
static void test_modbus_value_ranges(void **state)
{
    (void)state;
    static const char *const cases[][2] = {
        {"port = 65536", "[modbus] port: expected a number in [0, 65535], got '65536'"},
        {"unit_id = 0", "[modbus] unit_id: expected a number in [1, 247], got '0'"},
        {"rtu_parity = X", "[modbus] rtu_parity: expected N, E or O (none, even, odd)"},
        {"word_order = XYZW", "[modbus] word_order: expected ABCD, CDAB, BADC or DCBA"},
        {"writes = maybe", "[modbus] writes: expected yes or no, got 'maybe'"},
        {"address = localhost", "[modbus] address: 'localhost' is not a numeric"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[512];
        snprintf(text, sizeof text, "[modbus]\n%s\n" OBJ, cases[i][0]);
        load_bad(text, CFG_EVALUE, 2, cases[i][1]);
        assert_null(strstr(err, "modbus: modbus"));
    }
}

/* Given a directory as the file (trajd --check-config /tmp), then it is
 * refused as one; it was read as an empty file, "no [object.NAME] section:
 * nothing to do". */
static void test_directory_as_config(void **state)
{
    (void)state;
    cfg_t *c = (cfg_t *)1;
    char e[512] = "";
    assert_int_equal(cfg_load("tests/data", &c, e, sizeof e), -CFG_EIO);
    assert_null(c);
    assert_string_equal(e, "tests/data: Is a directory");
}

/* Given a file that starts with a UTF-8 byte order mark (as some Windows
 * editors write it), then it is read as without it: the section on line 1
 * is a section (it was "line 2: key before any [section]"). */
static void test_utf8_bom(void **state)
{
    (void)state;
    cfg_t *c = load_ok("\xEF\xBB\xBF[daemon]\nrate_hz = 50\n" OBJ);
    assert_true(fabs(c->daemon.rate_hz - 50) < 1e-12);
    cfg_free(c);
    /* only at the start of the file: elsewhere it is a syntax error as before */
    load_bad("[daemon]\n\xEF\xBB\xBFrate_hz = 50\n" OBJ, CFG_EUNKNOWN, 2, NULL);
}

#define VIS "tests/data/gpxgo_visnjan.csv"

/* Given a relative path written with a leading "./" (csv.path = ./a.csv
 * beside a.csv), then messages quote it as the file's directory joined to
 * it once: "<dir>/a.csv", not "<dir>/./a.csv" ("././a.csv" for a file in
 * the working directory). */
static void test_dot_slash_paths(void **state)
{
    (void)state;
    load_bad("[object.a]\nid = 0\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
             "csv.path = trajd-test-dot-a.csv\n"
             "[object.b]\nid = 1\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
             "csv.path = .//./trajd-test-dot-a.csv\n",
             CFG_EVALUE, 7, "write the same csv.path");
    char want[sizeof cfg_string_dir + 64];
    snprintf(want, sizeof want, "%s/trajd-test-dot-a.csv", cfg_string_dir);
    assert_non_null(strstr(err, want));
    assert_null(strstr(err, "/./"));
}

/* Given outputs that name an input, or each other, by another text (issue
 * 24: compared as text, `replay.track = track.csv` with `csv.path =
 * ./track.csv` and csv.truncate passed --check-config and destroyed its own
 * input), then the file is refused at check time, naming both keys. */
static void test_paths_by_identity(void **state)
{
    (void)state;
    /* an output on the track it replays */
    load_bad("[object.a]\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
             "csv.path = tests/data/../data/gpxgo_visnjan.csv\ncsv.truncate = yes\n",
             CFG_EVALUE, 1, "[object.a] replay.track");
    assert_non_null(strstr(err, "an output would overwrite an input"));
    /* two objects on one CSV output, by two spellings (not made yet) */
    load_bad("[object.a]\nid = 0\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
             "csv.path = /tmp/trajd-test-cfg-hostile-a.csv\n"
             "[object.b]\nid = 1\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
             "csv.path = /tmp/./trajd-test-cfg-hostile-a.csv\n",
             CFG_EVALUE, 7, "two outputs would write it");
    /* a CAN log_out on a csv.path */
    load_bad("[can]\nlog_out = /tmp/trajd-test-cfg-hostile-b.csv\n"
             "[object.a]\ninput = replay\nreplay.track = " VIS "\noutput = csv, can\n"
             "csv.path = /tmp//trajd-test-cfg-hostile-b.csv\n",
             CFG_EVALUE, 3, "[can] log_out");
    /* a symbolic link to the track as the output */
    char cwd[4096], link[64];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(link, sizeof link, "/tmp/trajd-test-cfg-hostile-%d.csv", (int)getpid());
    char target[4200];
    snprintf(target, sizeof target, "%s/" VIS, cwd);
    unlink(link);
    assert_int_equal(symlink(target, link), 0);
    char text[512];
    snprintf(text, sizeof text,
             "[object.a]\ninput = replay\nreplay.track = " VIS "\noutput = csv\ncsv.path = %s\n",
             link);
    load_bad(text, CFG_EVALUE, 1, "an output would overwrite an input");
    unlink(link);
    /* two inputs on one file are fine, and so are distinct outputs */
    cfg_t *c = load_ok("[object.a]\nid = 0\ninput = replay\nreplay.track = " VIS "\noutput = csv\n"
                       "csv.path = /tmp/trajd-test-cfg-hostile-c.csv\n"
                       "[object.b]\nid = 1\ninput = replay\nreplay.track = ./" VIS "\n"
                       "output = csv\ncsv.path = /tmp/trajd-test-cfg-hostile-d.csv\n");
    cfg_free(c);
}

#define CIA                                                                                        \
    "[can]\nlog_out = /tmp/trajd-test-cfg-hostile.log\n"                                           \
    "[object.a]\ninput = replay\nreplay.track = " VIS "\noutput = can\ncan.own = no\n"             \
    "can.cia402 = yes\ncan.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0x202\n"                       \
    "can.cia402_cob_z = 0\ncan.cia402_counts_per_m = 1e7\n"

/* Given CiA 402 targets at 1e7 increments per metre (int32: +-214.748 m),
 * then a box of +-300 m is refused at its line, naming the field; +-200 m is
 * taken as given; without a box, one is derived from int32 (x and y at
 * INT32_MAX / 1e7 minus half a count, z free), so the safety monitor holds the
 * object at the edge instead of the target being clipped (issue 24: 13 886 of
 * 35 713 targets went out as INT32_MAX). */
static void test_cia402_box(void **state)
{
    (void)state;
    load_bad(CIA "position_min_m = -300,-300,0\nposition_max_m = 300,300,0\n", CFG_EVALUE, 14,
             "does not fit the CiA 402 target's int32 increments");
    cfg_t *c = load_ok(CIA "position_min_m = -200,-200,-1\nposition_max_m = 200,200,1\n");
    assert_int_equal(c->obj[0].box, 1);
    assert_true(fabs(c->obj[0].box_max_m[0] - 200) <= 0.0);
    cfg_free(c);
    c = load_ok(CIA);
    const cfg_obj_t *o = &c->obj[0];
    assert_int_equal(o->box, 2);
    double edge = (2147483647.0 - 0.5) / 1e7;
    assert_true(fabs(o->box_max_m[0] - edge) < 1e-9 && fabs(o->box_min_m[0] + edge + 1e-7) < 1e-9);
    assert_true(fabs(o->box_max_m[1] - edge) < 1e-9);
    assert_true(isinf(o->box_max_m[2]) && isinf(o->box_min_m[2]));
    cfg_free(c);
    /* the keys go together, min <= max, within max_abs_m */
    load_bad(OBJ "position_min_m = 0,0,0\n", CFG_EVALUE, 5, "without position_max_m");
    load_bad(OBJ "position_min_m = 0,0,0\nposition_max_m = 1,-1,1\n", CFG_EVALUE, 6,
             "min must not exceed max");
    load_bad(OBJ "position_min_m = 0,0,0\nposition_max_m = 1,1,2e7\n", CFG_EVALUE, 6, "max_abs_m");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cia402_box),
        cmocka_unit_test(test_utf8_bom),
        cmocka_unit_test(test_modbus_address),
        cmocka_unit_test(test_modbus_value_ranges),
        cmocka_unit_test(test_directory_as_config),
        cmocka_unit_test(test_dot_slash_paths),
        cmocka_unit_test(test_engine_error_at_its_key),
        cmocka_unit_test(test_paths_by_identity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
