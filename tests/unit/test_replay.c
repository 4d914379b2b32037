/* test_replay.c - the replay feeder (due times, EFULL kept and retried,
 * backward/NaN rows, finish once) against the real engine, and the csv_format
 * text form (round trip through libc's strtod, bit for bit). */
#include "test.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"
#include "replay.h"
#include "csv_format.h"
#include "track.h"

static track_t make_track(size_t n, double dt_s)
{
    track_t t;
    memset(&t, 0, sizeof t);
    t.n = n;
    t.wp = calloc(n, sizeof *t.wp);
    assert_non_null(t.wp);
    for (size_t i = 0; i < n; i++) {
        t.wp[i].t_s = 10.0 + (double)i * dt_s; /* not starting at 0: due times are relative */
        t.wp[i].pos_m[0] = sin((double)i * 0.1) * 20;
        t.wp[i].pos_m[1] = (double)i * 0.5;
        t.wp[i].seq = (uint32_t)(i + 1);
    }
    return t;
}

/* Given waypoints 1/3 s apart, when asked, then due times are
 * start + round((t_i - t_0) * 1e9) ns, and a waypoint due exactly at now is
 * offered at now. */
static void test_due_times(void **state)
{
    (void)state;
    track_t t = make_track(4, 1.0 / 3.0);
    engine_config_t cfg;
    engine_config_default(&cfg);
    engine_t *e = engine_new(&cfg, NULL);
    assert_non_null(e);
    replay_t r;
    replay_init(&r, &t, 5000);
    assert_int_equal(replay_next_due_ns(&r), 5000);
    assert_int_equal(replay_feed(&r, e, 4999), 0);
    assert_int_equal(replay_feed(&r, e, 5000), 1);
    assert_int_equal(replay_next_due_ns(&r), 5000 + 333333333);
    assert_int_equal(replay_feed(&r, e, 5000 + 333333332), 0);
    assert_int_equal(replay_feed(&r, e, 5000 + 666666667), 2);
    assert_false(replay_done(&r));
    assert_int_equal(replay_feed(&r, e, INT64_MAX), 1);
    assert_true(replay_done(&r));
    assert_int_equal(replay_next_due_ns(&r), INT64_MAX);
    engine_status_t st;
    engine_status(e, &st);
    assert_int_equal(st.accepted, 4);
    engine_free(e);
    track_free(&t);
}

/* Given an engine with the smallest capacity the configuration allows and a
 * track that is all due at once, when fed tick by tick, then EFULL refusals
 * are retried, every waypoint is accepted exactly once (none lost), and the
 * engine finishes on the last one. */
static void test_efull_retried(void **state)
{
    (void)state;
    const size_t n = 400;
    track_t t = make_track(n, 0.05);
    engine_config_t cfg;
    engine_config_default(&cfg);
    cfg.fragment = 8;
    cfg.overlap = 4;
    cfg.max_accel_m_s2 = 0; /* the made-up track turns at 80 m/s^2: keep every waypoint */
    /* The smallest capacity engine_config_check accepts (its rule is the
     * engine's business: search up from lookahead + fragment). */
    const char *why = NULL;
    for (cfg.capacity = engine_lookahead(&cfg) + cfg.fragment;
         engine_config_check(&cfg, &why) && cfg.capacity < 10000; cfg.capacity++)
        ;
    if (engine_config_check(&cfg, &why))
        fail_msg("config: %s", why);
    engine_t *e = engine_new(&cfg, NULL);
    assert_non_null(e);
    int *results = malloc(n * sizeof *results);
    for (size_t i = 0; i < n; i++)
        results[i] = 12345;
    replay_t r;
    replay_init(&r, &t, -1000000000000LL); /* everything due long ago */
    r.results = results;
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    int64_t now = 0;
    for (int k = 0; k < 200000 && !(replay_done(&r) && sp.state == ENGINE_STATE_FINISHED); k++) {
        now = (int64_t)k * cfg.period_ns;
        replay_feed(&r, e, now);
        assert_int_equal(engine_tick(e, now, &sp), 0);
    }
    engine_status_t st;
    engine_status(e, &st);
    assert_true(r.retries > 0);
    assert_int_equal(st.accepted, n);
    /* Whether the engine also counts EFULL in rejected is its choice; the
     * bad-data rejections must be none, and every EFULL was retried. */
    assert_int_equal(st.rejected - st.rejected_by[ENGINE_EFULL], 0);
    assert_true(st.rejected_by[ENGINE_EFULL] == 0 || st.rejected_by[ENGINE_EFULL] == r.retries);
    assert_int_equal(r.next, n);
    assert_int_equal(r.refused, 0);
    for (size_t i = 0; i < n; i++)
        assert_int_equal(results[i], 0);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    for (int k = 0; k < 3; k++)
        assert_true(fabs(sp.pos_m[k] - t.wp[n - 1].pos_m[k]) < 1e-9);
    free(results);
    engine_free(e);
    track_free(&t);
}

/* Given a backward step, an exact duplicate and a NaN time, when due, then
 * each is offered at once (not waited for) and the engine's verdict is
 * counted: backward and NaN refused, duplicate dropped. */
static void test_bad_rows_offered_at_once(void **state)
{
    (void)state;
    track_t t = make_track(6, 1.0);
    t.wp[2].t_s = t.wp[1].t_s - 0.5; /* backward */
    t.wp[3] = t.wp[1];               /* duplicate of row 1 (row 2 was refused) */
    t.wp[4].t_s = NAN;
    engine_config_t cfg;
    engine_config_default(&cfg);
    engine_t *e = engine_new(&cfg, NULL);
    replay_t r;
    int results[6];
    replay_init(&r, &t, 0);
    r.results = results;
    /* At 1 s: rows 0, 1 are due; 2 (backward), 3 (t = 1 s) and 4 (NaN) too. */
    assert_int_equal(replay_feed(&r, e, 1000000000), 5);
    assert_int_equal(results[0], 0);
    assert_int_equal(results[1], 0);
    /* the backward step's verdict comes with its neighbours (engine_finish
     * at the latest), recorded when it comes */
    assert_int_equal(results[3], ENGINE_DUPLICATE);
    assert_int_equal(results[4], -ENGINE_ENOTFINITE);
    assert_int_equal(r.refused, 1);
    assert_int_equal(r.duplicates, 1);
    assert_false(replay_done(&r));
    assert_int_equal(replay_next_due_ns(&r), 5000000000);
    assert_int_equal(replay_feed(&r, e, 5000000000), 1);
    assert_true(replay_done(&r));
    assert_int_equal(results[2], -ENGINE_EBACKWARDS);
    assert_int_equal(r.refused, 2);
    engine_free(e);
    track_free(&t);
}

/* Given an empty replay, then nothing happens (and no crash). */
static void test_empty(void **state)
{
    (void)state;
    replay_t r;
    replay_init(&r, NULL, 0);
    assert_int_equal(replay_feed(&r, NULL, 0), 0);
    assert_int_equal(replay_next_due_ns(&r), INT64_MAX);
}

static double bits_to_double(uint64_t u)
{
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* Given setpoints with awkward doubles, when formatted and read back with
 * libc's strtod, then every number comes back bit for bit, and the columns
 * are those of the header. */
static void test_csv_format_round_trip(void **state)
{
    (void)state;
    char hdr[512], line[CSV_FORMAT_LINE_MAX];
    int hl = csv_format_header(hdr, sizeof hdr);
    assert_int_equal(hl, (int)strlen(hdr));
    assert_string_equal(hdr, "object,now_ns,t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,"
                             "ay_m_s2,az_m_s2,state,flags,cycle,track\n");
    assert_int_equal(csv_format_header(hdr, 10), -1);

    const double vals[] = {0.1,
                           -0.0,
                           1.0 / 3.0,
                           6378137.123456789,
                           -1e-300,
                           bits_to_double(1), /* smallest subnormal */
                           1.7976931348623157e308,
                           123456.78901234567,
                           -2.5e-17,
                           1e22,
                           M_PI,
                           -M_E};
    const size_t nv = sizeof vals / sizeof vals[0];
    unsigned seed = 3;
    for (int round = 0; round < 2000; round++) {
        engine_setpoint_t sp;
        double d[10];
        for (int k = 0; k < 10; k++) {
            seed = seed * 1103515245u + 12345u;
            if (round < 100) {
                d[k] = vals[(size_t)(round + k) % nv];
            } else { /* random bit patterns that are finite */
                uint64_t u = ((uint64_t)seed << 32) ^ (uint64_t)(seed * 2654435761u);
                seed = seed * 1103515245u + 12345u;
                u ^= (uint64_t)seed << 13;
                d[k] = bits_to_double(u);
                if (!isfinite(d[k]))
                    d[k] = 1.5;
            }
        }
        memset(&sp, 0, sizeof sp);
        sp.now_ns = INT64_MAX - round;
        sp.t_s = d[0];
        for (int k = 0; k < 3; k++) {
            sp.pos_m[k] = d[1 + k];
            sp.vel_m_s[k] = d[4 + k];
            sp.acc_m_s2[k] = d[7 + k];
        }
        sp.state = (engine_state_t)(round % 4);
        sp.flags = 0x0f;
        sp.cycle = UINT32_MAX;
        sp.track = (uint32_t)round;
        int n = csv_format_format(line, sizeof line, "obj-1", &sp);
        assert_true(n > 0 && n == (int)strlen(line) && line[n - 1] == '\n');
        char *p = line;
        assert_int_equal(strncmp(p, "obj-1,", 6), 0);
        p += 6;
        char *end;
        assert_true(strtoll(p, &end, 10) == sp.now_ns && *end == ',');
        p = end + 1;
        for (int k = 0; k < 10; k++) {
            double v = strtod(p, &end);
            assert_true(*end == ',');
            assert_memory_equal(&v, &d[k], sizeof v); /* bit for bit, -0 included */
            p = end + 1;
        }
        end = strchr(p, ',');
        assert_non_null(end);
        *end = '\0';
        assert_string_equal(p, engine_state_name(sp.state));
        p = end + 1;
        unsigned long fl, cy, tr;
        assert_int_equal(sscanf(p, "%lu,%lu,%lu\n", &fl, &cy, &tr), 3);
        assert_true(fl == 15 && cy == UINT32_MAX && tr == (unsigned long)round);
    }
}

/* Given an object name that would break the columns, or a short buffer,
 * then -1. */
static void test_csv_format_refuses(void **state)
{
    (void)state;
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    char line[CSV_FORMAT_LINE_MAX];
    assert_int_equal(csv_format_format(line, sizeof line, "a,b", &sp), -1);
    assert_int_equal(csv_format_format(line, sizeof line, "a\nb", &sp), -1);
    assert_int_equal(csv_format_format(line, sizeof line, "a\"b", &sp), -1);
    char longname[CSV_FORMAT_OBJECT_MAX + 2];
    memset(longname, 'a', sizeof longname - 1);
    longname[sizeof longname - 1] = '\0';
    assert_int_equal(csv_format_format(line, sizeof line, longname, &sp), -1);
    longname[CSV_FORMAT_OBJECT_MAX] = '\0';
    assert_true(csv_format_format(line, sizeof line, longname, &sp) > 0);
    assert_int_equal(csv_format_format(line, 20, "x", &sp), -1);
    assert_true(csv_format_format(line, sizeof line, NULL, &sp) > 0);
    assert_int_equal(line[0], ',');
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_due_times),
        cmocka_unit_test(test_efull_retried),
        cmocka_unit_test(test_bad_rows_offered_at_once),
        cmocka_unit_test(test_empty),
        cmocka_unit_test(test_csv_format_round_trip),
        cmocka_unit_test(test_csv_format_refuses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
