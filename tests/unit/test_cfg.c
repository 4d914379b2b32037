/* test_cfg.c - the config parser: accepted files give the values written,
 * every kind of mistake is refused with "name:line: ..." pointing at the
 * offending line (counted by the test from the text it wrote), and the
 * documented config/trajd.conf is accepted with every documented default
 * uncommented.  Run from the repository root (tests/run.sh does). */
#include "test.h"
#include "cfg_test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "can_transport.h"
#include "cfg.h"
#include "core.h"
#include "csv_transport.h"
#include "engine_settings.h"
#include "replay_transport.h"
#include "transport.h"

#define TRACK "tests/data/n2k_furuno_figure8_src52.csv"
#define OBJ "[object.boat]\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n"

/* Given a minimal file, then defaults are filled and the object is wired. */
static void test_minimal(void **state)
{
    (void)state;
    cfg_t *c = load_ok(OBJ);
    assert_int_equal(c->nobj, 1);
    assert_string_equal(c->obj[0].name, "boat");
    assert_ptr_equal(c->obj[0].input, &replay_transport);
    assert_int_equal(c->obj[0].noutput, 1);
    assert_ptr_equal(c->obj[0].output[0], &stdout_transport);
    assert_true(c->daemon.rate_hz > 99.999 && c->daemon.rate_hz < 100.001);
    assert_int_equal(c->daemon.period_ns, 10000000);
    assert_int_equal(c->obj[0].engine.period_ns, 10000000);
    assert_int_equal(c->rt.fifo_priority, 0);
    assert_int_equal(c->rt.mlockall, 0);
    assert_int_equal(c->rt.affinity_set, 0);
    const replay_transport_obj_cfg_t *r = cfg_obj_transport(&c->obj[0], &replay_transport);
    assert_true(r->loaded);
    assert_int_equal(r->trk.n, 1786); /* rows of the file (ATTRIBUTION.md) */
    assert_true(cfg_uses(c, &stdout_transport));
    assert_false(cfg_uses(c, &csv_transport));
    cfg_free(c);
}

/* Given every core key with a non-default value, then each lands in its field. */
static void test_values(void **state)
{
    (void)state;
    cfg_t *c = load_ok("[daemon]\nrate_hz = 1000\nspeed = 2.5\nstatus_interval_s = 0\n"
                       "stop_timeout_s = 1.5\nexit_when_done = yes\nlog_level = debug\n"
                       "[realtime]\nfifo_priority = 80\nmlockall = on\ncpu_affinity = 0,2-3\n"
                       "[object.a-1]\nid = 3\ninput = replay\nreplay.track = " TRACK "\n"
                       "output = csv, stdout\ncsv.path = out.csv\nmethod = bspline\n"
                       "param = uniform\nends = clamped\nstart_vel_m_s = 1, -2,3e-1\n"
                       "fragment = 32\noverlap = 16\nmax_gap_s = 7.5\n"
                       "max_accel_m_s2 = 12.5\nstart_slack = 3\n"
                       "[object.b]\nid = 0\ninput = replay\nreplay.track = " TRACK "\n"
                       "replay.start_s = 2\noutput = stdout\n");
    assert_int_equal(c->daemon.period_ns, 1000000);
    assert_true(c->daemon.speed > 2.4999 && c->daemon.speed < 2.5001);
    assert_int_equal(c->daemon.exit_when_done, 1);
    assert_int_equal(c->rt.fifo_priority, 80);
    assert_int_equal(c->rt.mlockall, 1);
    assert_true(c->rt.affinity_set);
    assert_true(CPU_ISSET(0, &c->rt.affinity) && !CPU_ISSET(1, &c->rt.affinity) &&
                CPU_ISSET(2, &c->rt.affinity) && CPU_ISSET(3, &c->rt.affinity));
    assert_int_equal(c->nobj, 2);
    const cfg_obj_t *o = &c->obj[0];
    assert_string_equal(o->name, "a-1");
    assert_int_equal(o->id, 3);
    assert_int_equal(o->id_line, 13);
    assert_int_equal(c->obj[1].id, 0);
    assert_int_equal(o->noutput, 2);
    assert_ptr_equal(o->output[0], &csv_transport);
    assert_ptr_equal(o->output[1], &stdout_transport);
    assert_int_equal(o->engine.method, ENGINE_METHOD_BSPLINE);
    assert_int_equal(o->engine.param, ENGINE_PARAM_UNIFORM);
    assert_int_equal(o->engine.ends, ENGINE_ENDS_CLAMPED);
    assert_true(o->engine.start_vel_m_s[1] > -2.0001 && o->engine.start_vel_m_s[1] < -1.9999);
    assert_true(o->engine.start_vel_m_s[2] > 0.2999 && o->engine.start_vel_m_s[2] < 0.3001);
    assert_int_equal(o->engine.fragment, 32);
    assert_true(o->engine.max_accel_m_s2 > 12.4999 && o->engine.max_accel_m_s2 < 12.5001);
    assert_int_equal(o->engine.start_slack, 3);
    assert_int_equal(o->engine.overlap, 16);
    const csv_transport_obj_cfg_t *cs = cfg_obj_transport(o, &csv_transport);
    char want[sizeof cfg_string_dir + 256];
    cfg_string_path("out.csv", want, sizeof want); /* relative to the config's directory */
    assert_string_equal(cs->path, want);
    cfg_free(c);
}

/* Given the one-clock keys (lib/engine/CLOCK.md), then defaults are auto,
 * 10 s, 5 %, 500 ppm, a day; each key lands in its field; clock = epoch with
 * a replay speed is refused at its line, and so are values out of range. */
static void test_clock_keys(void **state)
{
    (void)state;
    cfg_t *c = load_ok(OBJ);
    assert_int_equal(c->daemon.clock, CFG_CLOCK_AUTO);
    assert_true(c->daemon.delay_s > 9.999 && c->daemon.delay_s < 10.001);
    assert_true(c->daemon.catchup > 0.0499 && c->daemon.catchup < 0.0501);
    assert_true(c->daemon.drift_max_ppm > 499.9 && c->daemon.drift_max_ppm < 500.1);
    assert_true(c->daemon.clock_window_s > 86399 && c->daemon.clock_window_s < 86401);
    cfg_free(c);
    c = load_ok("[daemon]\nclock = epoch\ndelay_s = 2.5\ncatchup = 0.1\ndrift_max_ppm = 100\n"
                "clock_window_s = 60\n" OBJ);
    assert_int_equal(c->daemon.clock, CFG_CLOCK_EPOCH);
    assert_true(c->daemon.delay_s > 2.4999 && c->daemon.delay_s < 2.5001);
    assert_true(c->daemon.catchup > 0.0999 && c->daemon.catchup < 0.1001);
    assert_true(c->daemon.drift_max_ppm > 99.99 && c->daemon.drift_max_ppm < 100.01);
    assert_true(c->daemon.clock_window_s > 59.99 && c->daemon.clock_window_s < 60.01);
    cfg_free(c);
    c = load_ok("[daemon]\nclock = relative\nspeed = 20\n" OBJ);
    assert_int_equal(c->daemon.clock, CFG_CLOCK_RELATIVE);
    cfg_free(c);
    load_bad("[daemon]\nspeed = 20\nclock = epoch\n" OBJ, CFG_EVALUE, 3, "needs speed = 1");
    load_bad("[daemon]\nclock = gps\n" OBJ, CFG_EVALUE, 2, "auto, epoch, relative");
    load_bad("[daemon]\ndelay_s = -1\n" OBJ, CFG_EVALUE, 2, "delay_s");
    load_bad("[daemon]\ncatchup = 2\n" OBJ, CFG_EVALUE, 2, "catchup");
}

/* Each mistake: refused, with the line of the mistake. */
static void test_errors(void **state)
{
    (void)state;
    load_bad("[daemon]\nrate_hz = 100\nbogus = 1\n" OBJ, CFG_EUNKNOWN, 3, "bogus: unknown key");
    load_bad("[daemon]\n[deamon]\n" OBJ, CFG_EUNKNOWN, 2, "unknown section [deamon]");
    load_bad("[daemon]\nrate_hz = fast\n" OBJ, CFG_EVALUE, 2, "rate_hz");
    load_bad("[daemon]\nrate_hz = 100x\n" OBJ, CFG_EVALUE, 2, "got '100x'");
    load_bad("[daemon]\nrate_hz = 0\n" OBJ, CFG_EVALUE, 2, "rate_hz");
    load_bad("[daemon]\nrate_hz = nan\n" OBJ, CFG_EVALUE, 2, "rate_hz");
    load_bad("[daemon]\nspeed = 1\nspeed = 2\n" OBJ, CFG_EDUP, 3, "given twice");
    load_bad(OBJ "[object.boat]\n", CFG_EDUP, 5, "section given twice");
    load_bad("rate_hz = 100\n" OBJ, CFG_ESYNTAX, 1, "before any");
    load_bad("[daemon]\nthis is not ini\n" OBJ, CFG_ESYNTAX, 2, "syntax");
    /* the first error is told where it is: an unterminated section header, not
     * the key after it (it was "line 2: rate_hz: key before any [section]") */
    load_bad("[daemon\nrate_hz = 100\n" OBJ, CFG_ESYNTAX, 1, "syntax");
    /* a control character of the file is not echoed into the log as it is */
    load_bad("[daemon]\n[object.a\001b]\n", CFG_EVALUE, 2, "[object.a?b]: object name");
    load_bad("[daemon]\nrate_hz = 100\n  speed = 2\n" OBJ, CFG_ESYNTAX, 3, "do not indent");
    load_bad("[daemon]\n\n\n" OBJ "fragment = 4.5\n", CFG_EVALUE, 8, "fragment");
    load_bad(OBJ "method = spline\n", CFG_EVALUE, 5, "bspline, cubic, smooth");
    load_bad(OBJ "max_accel_m_s2 = -2\n", CFG_EVALUE, 5, "max_accel_m_s2");
    load_bad(OBJ "start_slack = 2000\n", CFG_EVALUE, 5, "start_slack");
    load_bad(OBJ "start_vel_m_s = 1,2\n", CFG_EVALUE, 5, "three numbers");
    /* initial_position: three finite numbers within max_abs_m, wherever max_abs_m is given */
    load_bad(OBJ "initial_position = 1,2\n", CFG_EVALUE, 5, "x,y,z");
    load_bad(OBJ "initial_position = 1,2,3,4\n", CFG_EVALUE, 5, "x,y,z");
    load_bad(OBJ "initial_position = 1,nan,3\n", CFG_EVALUE, 5, "x,y,z");
    load_bad(OBJ "initial_position = 1,inf,3\n", CFG_EVALUE, 5, "x,y,z");
    load_bad(OBJ "initial_position = 0,0,2e7\n", CFG_EVALUE, 5, "max_abs_m");
    load_bad(OBJ "initial_position = 0,-500,0\nmax_abs_m = 100\n", CFG_EVALUE, 5, "|y| = 500");
    load_bad("[realtime]\nfifo_priority = 100\n" OBJ, CFG_EVALUE, 2, "[0, 99]");
    load_bad("[realtime]\ncpu_affinity = 1-\n" OBJ, CFG_EVALUE, 2, "CPU list");
    load_bad("[object.bad name]\ninput = replay\n", CFG_EVALUE, 1, "object name");
    load_bad("[object.x]\ninput = carrier-pigeon\n", CFG_EVALUE, 2, "replay");
    load_bad("[object.x]\ninput = replay\noutput = stdout, fax\n", CFG_EVALUE, 3, "fax");
    load_bad("[object.x]\ninput = replay\noutput = stdout,stdout\n", CFG_EVALUE, 3, "twice");
    load_bad("[object.x]\ninput = replay\nreplay.colour = red\n", CFG_EUNKNOWN, 3, "replay.colour");
    load_bad("[object.x]\ninput = replay\nnope.key = 1\n", CFG_EUNKNOWN, 3, "nope.key");
    /* keys for a transport the object does not use */
    load_bad(OBJ "csv.path = x.csv\n", CFG_EVALUE, 5, "does not use");
    /* csv.truncate's three values, all said */
    load_bad("[object.x]\ninput = replay\nreplay.track = " TRACK
             "\noutput = csv\ncsv.path = o.csv\ncsv.truncate = sometimes\n",
             CFG_EVALUE, 6, "expected no, yes or always, got 'sometimes'");
    /* whole-file rules: reported at the object's header line */
    load_bad("[daemon]\n", CFG_EMISSING, 0, "no [object");
    load_bad("[daemon]\n[object.x]\noutput = stdout\n", CFG_EMISSING, 2, "'input' is missing");
    load_bad("[object.x]\ninput = replay\nreplay.track = " TRACK "\n", CFG_EMISSING, 1,
             "'output' is missing");
    load_bad("[object.x]\ninput = replay\noutput = stdout\n", CFG_EMISSING, 1,
             "replay.track is missing");
    load_bad("[object.x]\ninput = replay\nreplay.track = " TRACK "\noutput = csv\n", CFG_EMISSING,
             1, "csv.path is missing");
    /* a missing track file: at the replay.track line, with the OS's reason */
    load_bad("[object.x]\ninput = replay\noutput = stdout\n\nreplay.track = /nonexistent.csv\n",
             CFG_EVALUE, 5, "nonexistent.csv");
    /* engine rule (lib/engine/engine.h: overlap even and < fragment): at the line of the key
     * the reason names (it named the object's line) */
    load_bad("[daemon]\n" OBJ "fragment = 8\noverlap = 8\n", CFG_EVALUE, 7, "engine");
    /* a line too long for inih is refused, not split */
    char big[600];
    snprintf(big, sizeof big, "[daemon]\nlog_level = %0400d\n" OBJ, 0);
    load_bad(big, CFG_ESYNTAX, 2, "longer than");
}

#define CAN_OBJ(name, id, extra)                                                                   \
    "[object." name "]\n" id "input = replay\nreplay.track = " TRACK "\noutput = can\n" extra
#define CAN_LOG "[can]\nlog_out = /dev/null\nmax_load_percent = 0\n"

/* Given two objects, then each needs its own id; a lone object is id 0. */
static void test_ids(void **state)
{
    (void)state;
    cfg_t *c = load_ok(OBJ);
    assert_int_equal(c->obj[0].id, 0);
    assert_int_equal(c->obj[0].id_line, 0);
    cfg_free(c);
    c = load_ok("[object.boat]\nid = 7\ninput = replay\nreplay.track = " TRACK
                "\noutput = stdout\n");
    assert_int_equal(c->obj[0].id, 7);
    cfg_free(c);
    /* the second object has no id: refused at its section, whatever the order */
    load_bad("[object.a]\nid = 1\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n"
             "[object.b]\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n",
             CFG_EMISSING, 6, "'id' is missing");
    load_bad("[object.a]\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n"
             "[object.b]\nid = 1\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n",
             CFG_EMISSING, 1, "'id' is missing");
    load_bad("[object.a]\nid = 1\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n"
             "[object.b]\nid = 1\ninput = replay\nreplay.track = " TRACK "\noutput = stdout\n",
             CFG_EDUP, 7, "also object 'a''s id");
    load_bad("[object.a]\nid = 1024\ninput = replay\n", CFG_EVALUE, 2, "[0, 1023]");
    load_bad("[object.a]\nid = -1\ninput = replay\n", CFG_EVALUE, 2, "[0, 1023]");
}

/* CAN: default ids come from the id (never the place in the file); ids above
 * 15 have no defaults; CiA 402 COB-IDs must be given; the drive feedback's
 * TPDO is 0x180 + node unless can.cia402_tpdo_<axis> gives another. */
static void test_can_ids(void **state)
{
    (void)state;
    cfg_t *c = load_ok(CAN_LOG CAN_OBJ("b", "id = 5\n", "") CAN_OBJ("a", "id = 2\n", ""));
    canproto_ids_t ids;
    can_obj_ids(cfg_obj_transport(&c->obj[0], &can_transport), (unsigned)c->obj[0].id, &ids);
    assert_int_equal(ids.setpoint_id, 0x6A5); /* first in the file, id 5 */
    assert_int_equal(ids.status_id, 0x6C5);
    can_obj_ids(cfg_obj_transport(&c->obj[1], &can_transport), (unsigned)c->obj[1].id, &ids);
    assert_int_equal(ids.setpoint_id, 0x6A2);
    cfg_free(c);
    load_bad(CAN_LOG CAN_OBJ("b", "id = 16\n", ""), CFG_EVALUE, 4, "no default CAN ids");
    c = load_ok(CAN_LOG CAN_OBJ("b", "id = 16\n", "can.index = 3\n"));
    cfg_free(c);
    load_bad(CAN_LOG CAN_OBJ("b", "", "can.cia402 = yes\ncan.cia402_cob_x = 0x201\n"), CFG_EVALUE,
             4, "COB-ID explicit");
    c = load_ok(CAN_LOG CAN_OBJ("b", "",
                                "can.cia402 = yes\ncan.cia402_cob_x = 0x201\n"
                                "can.cia402_cob_y = 0x202\ncan.cia402_cob_z = 0\n"));
    cfg_free(c);
    /* the feedback TPDO: 0x180 + node by default, can.cia402_tpdo_<axis> moves it */
    c = load_ok(CAN_LOG CAN_OBJ("b", "",
                                "can.cia402 = yes\ncan.cia402_feedback = yes\n"
                                "can.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0x202\n"
                                "can.cia402_cob_z = 0\ncan.cia402_tpdo_y = 0x285\n"));
    can_obj_ids(cfg_obj_transport(&c->obj[0], &can_transport), (unsigned)c->obj[0].id, &ids);
    assert_int_equal(canproto_cia402_tpdo(&ids, 0), 0x181);
    assert_int_equal(canproto_cia402_tpdo(&ids, 1), 0x285);
    assert_int_equal(canproto_cia402_tpdo(&ids, 2), 0);
    cfg_free(c);
    /* feedback is the default with can.cia402 (issue 23): 0x180 + node */
    c = load_ok(CAN_LOG CAN_OBJ("b", "",
                                "can.cia402 = yes\ncan.cia402_cob_x = 0x201\n"
                                "can.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n"));
    can_obj_ids(cfg_obj_transport(&c->obj[0], &can_transport), (unsigned)c->obj[0].id, &ids);
    assert_int_equal(ids.cia402, CANPROTO_CIA402_FEEDBACK);
    assert_int_equal(canproto_cia402_tpdo(&ids, 0), 0x181);
    cfg_free(c);
    /* the one mode (issue 25) and the former keys it replaces, read to the same ids */
    static const struct {
        const char *keys;
        canproto_cia402_mode_t mode;
    } modes[] = {
        {"can.cia402 = managed\n", CANPROTO_CIA402_MANAGED},
        {"can.cia402 = yes\ncan.cia402_enable = yes\n", CANPROTO_CIA402_MANAGED},
        {"can.cia402 = yes\ncan.cia402_feedback = no\ncan.cia402_enable = yes\n",
         CANPROTO_CIA402_MANAGED},
        {"can.cia402 = feedback\n", CANPROTO_CIA402_FEEDBACK},
        {"can.cia402 = targets\n", CANPROTO_CIA402_TARGETS},
        {"can.cia402 = yes\ncan.cia402_feedback = no\n", CANPROTO_CIA402_TARGETS},
        {"can.cia402 = off\ncan.own = yes\n", CANPROTO_CIA402_OFF},
        {"can.cia402 = no\ncan.cia402_enable = yes\n", CANPROTO_CIA402_OFF},
    };
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        char obj[512];
        snprintf(obj, sizeof obj,
                 "%scan.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\n"
                 "can.cia402_cob_z = 0\n",
                 modes[i].keys);
        char text[1024];
        snprintf(text, sizeof text, CAN_LOG CAN_OBJ("b", "initial_position = 1,2,0\n", "%s"), obj);
        c = load_ok(text);
        can_obj_ids(cfg_obj_transport(&c->obj[0], &can_transport), (unsigned)c->obj[0].id, &ids);
        assert_int_equal(ids.cia402, modes[i].mode);
        cfg_free(c);
    }
    /* a former key that contradicts the mode given is refused, in either order (it
     * overrode it: can.cia402 = targets with can.cia402_feedback = yes sent no RPDO) */
    static const struct {
        const char *keys;
        unsigned line;
    } clash[] = {
        {"can.cia402 = targets\ncan.cia402_feedback = yes\n", 10},
        {"can.cia402_feedback = yes\ncan.cia402 = targets\n", 10},
        {"can.cia402 = managed\ncan.cia402_enable = no\n", 10},
        {"can.cia402 = feedback\ncan.cia402_feedback = no\n", 10},
        {"can.cia402_enable = yes\ncan.cia402 = targets\n", 10},
    };
    for (size_t i = 0; i < sizeof clash / sizeof clash[0]; i++) {
        char obj[512], text[1024];
        snprintf(obj, sizeof obj,
                 "%scan.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n",
                 clash[i].keys);
        snprintf(text, sizeof text, CAN_LOG CAN_OBJ("b", "initial_position = 1,2,0\n", "%s"), obj);
        load_bad(text, CFG_EVALUE, clash[i].line, "contradicts");
    }
    load_bad(CAN_LOG CAN_OBJ("b", "",
                             "can.cia402 = drives\ncan.cia402_cob_x = 0x201\n"
                             "can.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n"),
             CFG_EVALUE, 8, "expected off, targets, feedback or managed");
    load_bad(CAN_LOG CAN_OBJ("b", "",
                             "can.cia402 = targets\ncan.cia402_cob_x = 0x201\n"
                             "can.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n"),
             CFG_EVALUE, 4, "needs initial_position");
    /* without feedback, where the drives stand must be given: initial_position */
    load_bad(
        CAN_LOG CAN_OBJ("b", "",
                        "can.cia402 = yes\ncan.cia402_feedback = no\n"
                        "can.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n"),
        CFG_EVALUE, 4, "needs initial_position");
    c = load_ok(CAN_LOG CAN_OBJ("b", "initial_position = 1,2,0\n",
                                "can.cia402 = yes\ncan.cia402_feedback = no\n"
                                "can.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\n"
                                "can.cia402_cob_z = 0\n"));
    cfg_free(c);
    /* trajd's heartbeat as master: node 1..127, period 10..60000 ms */
    c = load_ok("[can]\nlog_out = /dev/null\nheartbeat_node = 127\nheartbeat_ms = 50\n" CAN_OBJ(
        "b", "", ""));
    const can_cfg_t *cc = cfg_transport(c, &can_transport);
    assert_int_equal(cc->heartbeat_node, 127);
    assert_int_equal(cc->heartbeat_ms, 50);
    cfg_free(c);
    load_bad("[can]\nlog_out = /dev/null\nheartbeat_node = 128\n" CAN_OBJ("b", "", ""), CFG_EVALUE,
             3, "heartbeat_node");
}

/* Reload: reordering objects that keep their ids is accepted; a moved id, CAN
 * id or COB-ID of an object that stays is refused at its line in the new file. */
static void test_reload_check(void **state)
{
    (void)state;
    const char *cob = "can.cia402 = yes\ncan.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\n"
                      "can.cia402_cob_z = 0\n";
    char text[2048];
    snprintf(text, sizeof text, CAN_LOG CAN_OBJ("a", "id = 0\n", "%s") CAN_OBJ("b", "id = 1\n", ""),
             cob);
    cfg_t *old = load_ok(text);
    snprintf(text, sizeof text, CAN_LOG CAN_OBJ("b", "id = 1\n", "") CAN_OBJ("a", "id = 0\n", "%s"),
             cob);
    cfg_t *nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), 0);
    cfg_free(nw);
    /* an object inserted above, the others renumbered: refused at b's id line */
    snprintf(text, sizeof text,
             CAN_LOG CAN_OBJ("c", "id = 0\n", "") CAN_OBJ("a", "id = 1\n", "%s")
                 CAN_OBJ("b", "id = 2\n", ""),
             cob);
    nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), -CFG_EVALUE);
    char want[sizeof cfg_string_dir + 320];
    cfg_string_path("t.conf:10: [object.a] id: 1, running as 0", want, sizeof want);
    if (strncmp(err, want, strlen(want)) != 0)
        fail_msg("got '%s'", err);
    cfg_free(nw);
    /* same id, a COB-ID moved: refused at a's section */
    snprintf(text, sizeof text, CAN_LOG CAN_OBJ("b", "id = 1\n", "") CAN_OBJ("a", "id = 0\n", "%s"),
             "can.cia402 = yes\ncan.cia402_cob_x = 0x205\ncan.cia402_cob_y = 0\n"
             "can.cia402_cob_z = 0\n");
    nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), -CFG_EVALUE);
    if (!strstr(err, "t.conf:9: ") || !strstr(err, "COB-ID x id would move from 0x201 to 0x205"))
        fail_msg("got '%s'", err);
    cfg_free(nw);
    /* same id, can.index moves the default ids */
    snprintf(text, sizeof text,
             CAN_LOG CAN_OBJ("a", "id = 0\n", "%s") CAN_OBJ("b", "id = 1\n", "can.index = 4\n"),
             cob);
    nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), -CFG_EVALUE);
    if (!strstr(err, "t.conf:13: ") || !strstr(err, "waypoint id would move from 0x681 to 0x684"))
        fail_msg("got '%s'", err);
    cfg_free(nw);
    /* an object removed and another added with its id: not a move */
    snprintf(text, sizeof text, CAN_LOG CAN_OBJ("a", "id = 0\n", "%s") CAN_OBJ("d", "id = 1\n", ""),
             cob);
    nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), 0);
    cfg_free(nw);
    /* same ids, the running drives' set-up changed (a zero, a scale, the
     * heartbeat): refused at a's section, naming it (the drives were brought
     * up again and the old engine's braking sent in the new units: steps of
     * 0.64 m in one cycle, probe N); an engine setting alone is not */
    static const char *const drive[][2] = {
        {"can.cia402_offset_x = 5000\n", "zero (can.cia402_offset_*)"},
        {"can.cia402_counts_per_m = 12000\n", "scale (can.cia402_counts_per_m*)"},
        {"can.cia402_heartbeat_ms = 1400\n", "heartbeat (can.cia402_heartbeat_ms)"},
        {"can.cia402_invert_x = yes\n", "direction (can.cia402_invert_*)"},
    };
    for (size_t i = 0; i < sizeof drive / sizeof drive[0]; i++) {
        char keys[512];
        snprintf(keys, sizeof keys, "%s%s", cob, drive[i][0]);
        snprintf(text, sizeof text,
                 CAN_LOG CAN_OBJ("a", "id = 0\n", "%s") CAN_OBJ("b", "id = 1\n", ""), keys);
        nw = load_ok(text);
        assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), -CFG_EVALUE);
        if (!strstr(err, "[object.a]: its CiA 402 drives' ") || !strstr(err, drive[i][1]))
            fail_msg("%s: got '%s'", drive[i][0], err);
        cfg_free(nw);
    }
    snprintf(text, sizeof text,
             CAN_LOG CAN_OBJ("a", "id = 0\nmax_speed_m_s = 1.45\n", "%s")
                 CAN_OBJ("b", "id = 1\n", ""),
             cob);
    nw = load_ok(text);
    assert_int_equal(cfg_reload_check(old, nw, err, sizeof err), 0);
    cfg_free(nw);
    cfg_free(old);
}

/* Given [daemon] control_socket and control_group, then a relative path is
 * made absolute against the file's directory, empty means the default, and
 * a path a Unix socket cannot hold (107 bytes at most) is refused at its line. */
static void test_control_socket_keys(void **state)
{
    (void)state;
    cfg_t *c = load_ok("[daemon]\ncontrol_socket = run/ctl\ncontrol_group = adm\n" OBJ);
    char want[sizeof cfg_string_dir + 256];
    cfg_string_path("run/ctl", want, sizeof want); /* against the file's directory */
    assert_string_equal(c->daemon.control_socket, want);
    assert_string_equal(c->daemon.control_group, "adm");
    cfg_free(c);
    /* a user or group this system does not have is refused at its line (it passed the
     * check and failed the start, exit 77 with no file:line) */
    load_bad("[daemon]\nuser = nosuchuser-trajd\n" OBJ, CFG_EVALUE, 2,
             "no user 'nosuchuser-trajd' on this system");
    load_bad("[daemon]\ncontrol_group = nosuchgroup-trajd\n" OBJ, CFG_EVALUE, 2,
             "no group 'nosuchgroup-trajd' on this system");
    cfg_free(load_ok("[daemon]\nuser = root\ncontrol_group = root\n" OBJ));
    c = load_ok("[daemon]\ncontrol_socket =\ncontrol_group =\n" OBJ);
    assert_string_equal(c->daemon.control_socket, "");
    assert_string_equal(c->daemon.control_group, "");
    cfg_free(c);
    char text[512];
    snprintf(text, sizeof text, "[daemon]\ncontrol_socket = /%0107d\n" OBJ, 0);
    load_bad(text, CFG_EVALUE, 2, "107 bytes");
    snprintf(text, sizeof text, "[daemon]\ncontrol_socket = /%0106d\n" OBJ, 0);
    cfg_free(load_ok(text)); /* 107 bytes: the most */
}

/* Given config/trajd.conf with every documented "#key = default" uncommented,
 * then it is still accepted (each documented key exists and its documented
 * default is a valid value), and the file as shipped is accepted too. */
static void test_documented_conf(void **state)
{
    (void)state;
    FILE *f = fopen("config/trajd.conf", "r");
    assert_non_null(f);
    static char text[65536], line[512];
    size_t n = 0;
    int uncommented = 0;
    while (fgets(line, sizeof line, f)) {
        const char *l = line;
        /* "#key = value" with a key character right after '#', or "#key =" (an empty
         * default: uncommented, it must mean the default too) */
        size_t len = strlen(line);
        int empty = len >= 3 && !strcmp(line + len - 3, " =\n");
        if (line[0] == '#' && line[1] >= 'a' && line[1] <= 'z' && (strstr(line, " = ") || empty)) {
            l = line + 1;
            uncommented++;
        }
        size_t m = strlen(l);
        assert_true(n + m < sizeof text);
        memcpy(text + n, l, m);
        n += m;
    }
    text[n] = 0;
    fclose(f);
    assert_true(uncommented >= 20);
    cfg_t *c = NULL;
    int rc = cfg_load_string(text, "config/trajd.conf(uncommented)", &c, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    /* and the documented defaults are the real ones: the engine's
     * engine_config_default() and the parser's own for [daemon]/[realtime] */
    engine_config_t e;
    engine_config_default(&e);
    const engine_config_t *d = &c->obj[0].engine;
    assert_true(engine_config_same(d, &e)); /* every field: engine_settings.h's table */
    cfg_t *m = load_ok(OBJ);                /* nothing set: the parser's defaults */
    assert_memory_equal(&c->daemon.rate_hz, &m->daemon.rate_hz, sizeof(double));
    assert_memory_equal(&c->daemon.speed, &m->daemon.speed, sizeof(double));
    assert_memory_equal(&c->daemon.status_interval_s, &m->daemon.status_interval_s, sizeof(double));
    assert_memory_equal(&c->daemon.stop_timeout_s, &m->daemon.stop_timeout_s, sizeof(double));
    assert_int_equal(c->daemon.log_level, m->daemon.log_level);
    assert_int_equal(c->rt.fifo_priority, m->rt.fifo_priority);
    assert_int_equal(c->rt.mlockall, m->rt.mlockall);
    cfg_free(m);
    cfg_free(c);
    rc = cfg_load("config/trajd.conf", &c, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    cfg_free(c);
    rc = cfg_load("config/demo.conf", &c, err, sizeof err);
    if (rc)
        fail_msg("%s", err);
    cfg_free(c);
}

/* Given a missing file, then -CFG_EIO with the OS's reason. */
static void test_missing_file(void **state)
{
    (void)state;
    cfg_t *c = (cfg_t *)1;
    assert_int_equal(cfg_load("/nonexistent/trajd.conf", &c, err, sizeof err), -CFG_EIO);
    assert_null(c);
    assert_non_null(strstr(err, "No such file"));
}

/* The safety monitor's default bounds (issue 10 item 3, daemon/core/core.c
 * obj_safety_limits): derived from the engine's limits in force, the
 * acceleration bound on by default; off without an acceleration limit or
 * with the uniform parameterisation; an explicit key wins.  Read as the
 * daemon sets them: the monitor of the object core_open makes (no clock is
 * started, nothing ticks). */
static double safety_of(const char *extra, double *speed)
{
    char text[1024], why[512];
    snprintf(text, sizeof text, "%s%s", OBJ, extra);
    cfg_t *c = load_ok(text);
    int e = 0;
    loop_t *loop = loop_new(&e);
    assert_non_null(loop);
    stats_t stats;
    memset(&stats, 0, sizeof stats);
    core_t *core = NULL;
    if (core_open(loop, c, &stats, NULL, &core, why, sizeof why) != 0)
        fail_msg("core_open: %s", why);
    safety_limits_t lim = core->obj[0].safety.lim;
    core_close(core);
    loop_free(loop);
    cfg_free(c);
    *speed = lim.max_speed_m_s;
    return lim.max_accel_m_s2;
}

static void test_safety_defaults(void **state)
{
    (void)state;
    double v;
    /* profile auto: max_speed 400, max_accel 30, scale_accel 5 (engine.h) */
    assert_true(fabs(safety_of("", &v) - 2 * (3 * 30 + 5)) < 1e-9);
    assert_true(fabs(v - 800) < 1e-9);
    assert_true(
        fabs(safety_of("max_accel_m_s2 = 10\nscale_accel_m_s2 = 4\nmax_speed_m_s = 20\n", &v) -
             2 * (3 * 10 + 4)) < 1e-9);
    assert_true(fabs(v - 40) < 1e-9);
    assert_true(fabs(safety_of("max_accel_m_s2 = 1\ntransfer_accel_m_s2 = 50\n", &v) - 100) < 1e-9);
    assert_true(safety_of("profile = machine\n", &v) <= 0);
    /* profile air: 30 m/s^2 since issue 27, so checked as auto */
    assert_true(fabs(safety_of("profile = air\n", &v) - 2 * (3 * 30 + 5)) < 1e-9);
    assert_true(safety_of("method = bspline\nparam = uniform\n", &v) <= 0);
    assert_true(fabs(safety_of("safety_max_accel_m_s2 = 0\n", &v)) <= 0);
    assert_true(fabs(safety_of("safety_max_accel_m_s2 = 12\n", &v) - 12) < 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_minimal),         cmocka_unit_test(test_values),
        cmocka_unit_test(test_errors),          cmocka_unit_test(test_clock_keys),
        cmocka_unit_test(test_documented_conf), cmocka_unit_test(test_control_socket_keys),
        cmocka_unit_test(test_missing_file),    cmocka_unit_test(test_ids),
        cmocka_unit_test(test_safety_defaults), cmocka_unit_test(test_can_ids),
        cmocka_unit_test(test_reload_check),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
