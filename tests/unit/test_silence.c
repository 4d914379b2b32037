/*
 * test_silence.c - a trajectory's tail plays out (issue 26 item 2,
 * lib/engine/silence.h), and the delay D the engine states (delay.h).
 *
 * A synthetic track at 10 Hz (x = 10 sin(0.05 i), y = 10 cos(0.03 i),
 * t = 0.1 i) is pushed on a virtual clock when its time comes, the output
 * ticking at 100 Hz with the default configuration, as trajreplay and the
 * daemon do; engine_finish is never called.  Before: the output stopped
 * short of the first piece's end (t_s 28.04 of 29.9) and stood in UNDERRUN
 * through the silence until the next piece came.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "delay.h"
#include "engine.h"

#define PERIOD_NS 10000000LL

static engine_waypoint_t wp_at(int i, double t)
{
    engine_waypoint_t w;
    memset(&w, 0, sizeof w);
    w.t_s = t;
    w.pos_m[0] = 10 * sin(0.05 * i);
    w.pos_m[1] = 10 * cos(0.03 * i);
    w.seq = (uint32_t)i + 1;
    return w;
}

typedef struct {
    double reach_s;  /* now when the output first stood on the first piece's last waypoint */
    double t_first;  /* the largest t_s of the first piece */
    int under_ticks; /* setpoints in UNDERRUN */
    int under1;      /* ... of the first piece (track 1) */
    int went_back;   /* ticks after which the underrun count was lower than before */
    engine_status_t st;
    engine_delay_t d;
} run_t;

/* Two pieces of n waypoints each, the second after a silence of gap_s
 * (arrival = timestamp); ticks until end_s. */
static void run(int n, double gap_s, double end_s, run_t *r)
{
    engine_config_t c;
    engine_config_default(&c);
    int err = -1, next = 0;
    engine_t *e = engine_new(&c, &err);
    assert_non_null(e);
    memset(r, 0, sizeof *r);
    r->reach_s = NAN;
    engine_waypoint_t w[2000];
    assert_true(2 * n <= 2000);
    for (int i = 0; i < 2 * n; i++)
        w[i] = wp_at(i, 0.1 * i + (i >= n ? gap_s : 0.0));
    engine_waypoint_t last = wp_at(n - 1, 0.1 * (n - 1));
    for (int64_t k = 0; (double)k * PERIOD_NS * 1e-9 <= end_s; k++) {
        double now_s = (double)(k * PERIOD_NS) * 1e-9;
        while (next < 2 * n && w[next].t_s <= now_s + 1e-9)
            assert_true(engine_push(e, &w[next++]) >= 0);
        engine_setpoint_t sp;
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.state == ENGINE_STATE_UNDERRUN) {
            r->under_ticks++;
            r->under1 += sp.track == 1;
        }
        uint64_t before = r->st.underruns;
        engine_status(e, &r->st);
        r->went_back += r->st.underruns < before; /* a client reading it saw it go back */
        if (sp.track == 1 && sp.t_s > r->t_first)
            r->t_first = sp.t_s;
        if (isnan(r->reach_s) && sp.track == 1 &&
            hypot(sp.pos_m[0] - last.pos_m[0], sp.pos_m[1] - last.pos_m[1]) < 1e-9 &&
            fabs(sp.t_s - last.t_s) < 1e-9)
            r->reach_s = now_s;
    }
    engine_status(e, &r->st);
    engine_delay(e, &r->d);
    engine_free(e);
}

/* Given 30 s at 10 Hz, 300 s of silence and 30 s more, then the first
 * piece plays out to its last waypoint within 10 s of its arrival, one
 * silent end is counted, no underrun, and the second piece starts a new
 * trajectory. */
static void test_tail_plays_out(void **state)
{
    (void)state;
    run_t r;
    run(300, 300.0, 370.0, &r);
    assert_true(r.t_first >= 29.9 - 1e-9);
    assert_false(isnan(r.reach_s));
    assert_true(r.reach_s - 29.9 <= 10.0);
    /* the output plays on at once: the silence limit (D less the
     * lookahead) and the tail (the lookahead) are within D */
    assert_true(r.reach_s - 29.9 <= r.d.delay_s + 1.5);
    assert_int_equal(r.st.underruns, 0);
    /* (the second piece's own end, silent too, is reached by 370 s since its
     * transfer takes the object's pace (transfer.h TRANSFER_REACH_S): there the
     * output runs short 0.4 s before the silence, D less the lookahead, ends
     * it: not counted, but not yet the tail played out at once either) */
    assert_int_equal(r.under1, 0);
    assert_int_equal(r.st.hard_stops, 0);
    assert_true(r.st.silent_ends >= 1);
    assert_int_equal(r.st.tracks, 2);
}

/* Given 40 s at 10 Hz that stop at 2.9 m/s with no FINISH, 15 s of silence
 * and 40 s more, then the output, which runs short of solved curve before
 * the silence is long enough to tell an end (it brakes on its stop reserve),
 * counts no underrun once the silence ends the trajectory: nothing newer had
 * come, so it was the input's end, and start_slack auto learns nothing from
 * it (the lookahead stays 18; before: 1 underrun, lookahead 19, and D an
 * interval longer for the next piece).  Nor is it counted and then taken
 * back (a Modbus or CAN client saw underruns go 1 then 0), and its log line
 * is due at the silent end, saying so (trajd logged nothing). */
static void test_end_is_no_underrun(void **state)
{
    (void)state;
    run_t r;
    run(400, 15.0, 100.0, &r);
    print_message("end at speed: %llu underruns, %d underrun ticks, %llu silent ends, "
                  "lookahead %u\n",
                  (unsigned long long)r.st.underruns, r.under_ticks,
                  (unsigned long long)r.st.silent_ends, r.st.lookahead);
    assert_int_equal(r.st.underruns, 0);
    assert_int_equal(r.went_back, 0);
    assert_true(isfinite(r.st.underrun_silence_s));
    assert_true(engine_underrun_due(&r.st, NAN, 0));
    char line[400];
    assert_true(engine_underrun_format(&r.st, line, sizeof line) > 0);
    assert_non_null(strstr(line, "taken as its end"));
    assert_int_equal(r.st.lookahead, 18);
    assert_true(r.st.silent_ends >= 1);
    assert_int_equal(r.st.tracks, 2);
    assert_int_equal(r.st.hard_stops, 0);
}

/* Waypoint i of the 4 s batch the tests below write: a circle of 3 m at
 * 6 m/s, 10 Hz, from t = 0.1 s. */
static engine_waypoint_t circle_at(int i)
{
    engine_waypoint_t w;
    memset(&w, 0, sizeof w);
    w.seq = (uint32_t)i + 1;
    w.t_s = 0.1 * (i + 1);
    w.pos_m[0] = 3.0 * cos(0.2 * i);
    w.pos_m[1] = 3.0 * sin(0.2 * i);
    return w;
}

/* An engine of the default configuration with the batch (circle_at 0..39)
 * pushed and never ticked; *last: the batch's last waypoint. */
static engine_t *batch_pushed(engine_waypoint_t *last)
{
    engine_config_t c;
    engine_config_default(&c);
    int err = -1;
    engine_t *e = engine_new(&c, &err);
    assert_non_null(e);
    for (int i = 0; i < 40; i++) {
        *last = circle_at(i);
        assert_true(engine_push(e, last) >= 0);
    }
    return e;
}

/* Given 4 s of waypoints (a circle of 3 m at 6 m/s, 10 Hz) pushed before
 * the engine's first tick, as a Modbus writer quicker than trajd's first
 * deadline after start sends them, or a sender writing into the engine a
 * reload starts while its predecessor still brakes, and then nothing (no
 * FINISH), then the silence ends the trajectory as it does for waypoints
 * pushed between ticks: the output plays out to the last waypoint and
 * finishes, one silent end, no underrun counted.  Before: waypoints pushed
 * before the first tick never arrived for the silence, and the output
 * stood in UNDERRUN short of the tail until the next trajectory came. */
static void test_tail_plays_out_loaded_before_first_tick(void **state)
{
    (void)state;
    engine_waypoint_t w;
    engine_t *e = batch_pushed(&w);
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    double reach_s = NAN;
    for (int64_t k = 0; k <= 3000 && isnan(reach_s); k++) {
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.state == ENGINE_STATE_FINISHED)
            reach_s = (double)k * PERIOD_NS * 1e-9;
    }
    engine_status_t st;
    engine_status(e, &st);
    engine_free(e);
    print_message("loaded before the first tick: finished at %.2f s, %llu silent ends\n", reach_s,
                  (unsigned long long)st.silent_ends);
    assert_false(isnan(reach_s));
    assert_true(fabs(sp.pos_m[0] - w.pos_m[0]) < 1e-9 && fabs(sp.pos_m[1] - w.pos_m[1]) < 1e-9);
    assert_true(fabs(sp.t_s - w.t_s) < 1e-9);
    assert_int_equal(st.silent_ends, 1);
    assert_int_equal(st.underruns, 0);
    assert_int_equal(st.hard_stops, 0);
}

/* Given the engine a reload starts while its predecessor still brakes
 * (daemon/core/core.c step_engines: not ticked until then), fed the batch
 * meanwhile, then handed the predecessor's rest position
 * (engine_set_position, 2 m off the batch's first waypoint) and ticked, and
 * nothing more comes, then its silence ends the trajectory as for a batch
 * pushed between ticks: the output transfers from the position handed over,
 * plays the batch out to its last waypoint and finishes, one silent end, no
 * underrun.  Before: the batch never arrived for the silence (pushed before
 * the engine's first tick), and the output stood in UNDERRUN short of it. */
static void test_tail_plays_out_after_reload_handover(void **state)
{
    (void)state;
    engine_waypoint_t w;
    engine_t *e = batch_pushed(&w);
    const double at[ENGINE_AXES] = {5.0, 0.0, 0.0}; /* where the predecessor came to rest */
    assert_int_equal(engine_set_position(e, at), 0);
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    int finished = 0, under = 0;
    int64_t k0 = 250; /* the predecessor braked for 2.5 s first */
    for (int64_t k = k0; k <= k0 + 3000 && !finished; k++) {
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (k == k0) /* the first setpoint stands where the predecessor rests */
            assert_true(fabs(sp.pos_m[0] - at[0]) < 1e-9 && fabs(sp.pos_m[1]) < 1e-9);
        under += sp.state == ENGINE_STATE_UNDERRUN;
        finished = sp.state == ENGINE_STATE_FINISHED;
    }
    engine_status_t st;
    engine_status(e, &st);
    engine_free(e);
    assert_true(finished);
    assert_true(fabs(sp.pos_m[0] - w.pos_m[0]) < 1e-9 && fabs(sp.pos_m[1] - w.pos_m[1]) < 1e-9);
    assert_int_equal(st.silent_ends, 1);
    assert_int_equal(st.underruns, 0);
    assert_int_equal(under, 0);
    assert_int_equal(st.hard_stops, 0);
}

/* The circle (circle_at) pushed after
 * the first tick, split over the ticks as given (n1 waypoints on tick 1,
 * the rest on tick 2), then nothing: the D stated at the start, the ticks
 * in UNDERRUN, and whether the output finished on the last waypoint. */
static void upload(int n1, double *delay_s, int *under_ticks, int *finished)
{
    engine_config_t c;
    engine_config_default(&c);
    int err = -1, next = 0;
    engine_t *e = engine_new(&c, &err);
    assert_non_null(e);
    engine_setpoint_t sp;
    *under_ticks = *finished = 0;
    *delay_s = NAN;
    for (int64_t k = 0; k <= 3000 && !*finished; k++) {
        for (int j = 0; k >= 1 && next < 40 && (k > 1 || j < n1); j++, next++) {
            engine_waypoint_t w = circle_at(next);
            assert_true(engine_push(e, &w) >= 0);
        }
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        *under_ticks += sp.state == ENGINE_STATE_UNDERRUN;
        *finished = sp.state == ENGINE_STATE_FINISHED;
        if (k == 3) {
            engine_delay_t d;
            engine_delay(e, &d);
            *delay_s = d.delay_s;
        }
    }
    engine_free(e);
}

/* Given 4 s of waypoints written at once (a Modbus writer's batch, ahead of
 * its stamps: an upload, catchup.h), then nothing, then the D the start
 * states is what the input needs, whether the batch came on one tick or on
 * two, not where the batch left the start (its span, or the wait plus the
 * ramp's loss): the output stands further behind than D, unsteered, and the
 * writer's silence, measured against that D, ends the trajectory before the
 * output runs short of curve: no tick in UNDERRUN either way.  Before: D was
 * 4.87 s on one tick against 2.87 s on two (2.57 s is what the input needs),
 * and on one tick the output stood in UNDERRUN for 0.75 s before the
 * silence, 2 s later than on two, ended the trajectory. */
static void test_upload_delay_as_streamed(void **state)
{
    (void)state;
    double d1, d2;
    int u1, u2, f1, f2;
    upload(40, &d1, &u1, &f1);
    upload(20, &d2, &u2, &f2);
    print_message("batch on one tick: D %.3f s, %d underrun ticks; on two: D %.3f s, %d\n", d1, u1,
                  d2, u2);
    assert_true(f1 && f2);
    assert_true(fabs(d1 - d2) < 0.1);
    assert_int_equal(u1, 0);
    assert_int_equal(u2, 0);
}

/* Given a regular track whose input never pauses for longer than an
 * interval, then no silent end: one trajectory, streamed as before. */
static void test_no_silent_end_while_regular(void **state)
{
    (void)state;
    run_t r;
    run(300, 0.0, 58.0, &r);
    assert_int_equal(r.st.silent_ends, 0);
    assert_int_equal(r.st.tracks, 1);
    assert_int_equal(r.st.underruns, 0);
}

/* Given the regular track, then the D the engine states is its lookahead
 * (18 intervals), its slack (1) and a stop reserve of at least a stop from
 * the track's speed (5 m/s at the start: 5/(2*5) + 5/(2*50) s). */
static void test_delay_stated(void **state)
{
    (void)state;
    run_t r;
    run(300, 0.0, 40.0, &r);
    assert_int_equal(r.d.lookahead_n, 18);
    assert_int_equal(r.d.slack_n, 0); /* none learnt: the slack in time, 3 ticks */
    assert_int_equal(r.d.slack_ticks, ENGINE_DELAY_TICKS);
    assert_true(fabs(r.d.slack_s - ENGINE_DELAY_TICKS * 0.01) < 1e-9);
    assert_true(fabs(r.d.interval_s - 0.1) < 1e-9);
    assert_true(r.d.stop_s >= 4.9 / 10.0 + 0.05);
    assert_true(fabs(r.d.delay_s - (r.d.lookahead_s + r.d.slack_s + r.d.stop_s)) < 1e-9);
}

/* Given the default configuration, then engine_delay_of states 18
 * intervals, a slack of 3 ticks and a stop from the profile's 400 m/s;
 * delay_s = 2 is refused by engine_delay_check with the numbers, delay_s =
 * 60 is accepted. */
static void test_delay_of_config(void **state)
{
    (void)state;
    engine_config_t c;
    engine_delay_t d;
    char why[400];
    engine_config_default(&c);
    assert_int_equal(engine_delay_of(&c, 0.1, 0.0, &d), 0);
    assert_int_equal(d.lookahead_n + d.slack_n, 18);
    assert_true(fabs(d.slack_s - 3 * (double)c.period_ns * 1e-9) < 1e-9);
    assert_true(fabs(d.stop_s - (40.0 + 0.05 + 0.02)) < 1e-9);
    assert_true(fabs(d.delay_s - (1.8 + d.slack_s + d.stop_s)) < 1e-9);
    assert_int_equal(engine_delay_check(&c, 0.0, why, sizeof why), 0);
    c.delay_s = 2;
    assert_int_equal(engine_delay_check(&c, 0.0, why, sizeof why), -ENGINE_ECONFIG);
    assert_non_null(strstr(why, "delay_s 2 s is shorter than the settings need"));
    c.delay_s = 60;
    assert_int_equal(engine_delay_check(&c, 0.0, why, sizeof why), 0);
}

/* a 10 Hz line at 5 m/s along x, waypoint i */
static void line_wp(engine_waypoint_t *w, int i)
{
    memset(w, 0, sizeof *w);
    w->t_s = 0.1 * i;
    w->pos_m[0] = 0.5 * i;
}

/*
 * delay_s picks the lookahead (engine_input.c engine_pick, issue 31): given
 * delay_s 0.9 s and max_speed_m_s 6, when a 10 Hz line comes, then its first
 * 3 waypoints are held (buffered, not judged yet) and then the local method
 * whose D fits is taken (max_lookahead 2: 2 intervals + 0.03 s + a stop from
 * 6 m/s, 0.67 s = 0.9 s), every waypoint kept and D stated at delay_s; a
 * clear while waypoints are held drops them as unjudged (and the next ones
 * are held for the pick as before); a finish with fewer held offers them
 * (a two-waypoint trajectory plays); without delay_s nothing is held.
 */
static void test_delay_s_picks_lookahead(void **state)
{
    (void)state;
    engine_config_t c;
    engine_config_default(&c);
    c.max_speed_m_s = 6.0;
    c.delay_s = 0.9;
    for (int mode = 0; mode < 3; mode++) {
        int err = -1;
        engine_t *e = engine_new(&c, &err);
        assert_non_null(e);
        engine_setpoint_t sp;
        engine_status_t st;
        engine_waypoint_t w;
        int n = mode == 2 ? 2 : 100, cleared = 0;
        for (int64_t k = 0; k < 2000; k++) {
            if (k % 10 == 0 && k / 10 < n) {
                line_wp(&w, (int)(k / 10));
                assert_int_equal(engine_push(e, &w), 0);
                engine_status(e, &st);
                if (k / 10 < 2) /* held: buffered, no verdict yet */
                    assert_int_equal(st.accepted, 0);
                if (k / 10 == n - 1 && mode == 2)
                    assert_int_equal(engine_finish(e), 0);
            }
            if (mode == 1 && k == 15 && !cleared) { /* two held */
                engine_clear(e);
                engine_status(e, &st);
                assert_int_equal(st.unjudged, 2);
                cleared = 1;
            }
            assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        }
        engine_status(e, &st);
        engine_delay_t d;
        engine_delay(e, &d);
        print_message("mode %d: accepted %llu, method %d, D %.3f s, underruns %llu\n", mode,
                      (unsigned long long)st.accepted, d.method, d.delay_s,
                      (unsigned long long)st.underruns);
        if (mode == 0) {
            assert_int_equal(st.accepted, 100);
            assert_int_equal(d.method, ENGINE_METHOD_HERMITE_C2);
            assert_true(fabs(d.delay_s - 0.9) < 1e-9);
            assert_int_equal(st.underruns, 0);
        } else if (mode == 1) {
            assert_int_equal(st.accepted, 98); /* the two before the clear: unjudged */
        } else {
            assert_int_equal(st.accepted, 2);
            assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
        }
        engine_free(e);
    }
    /* delay_s 2.5 s on the 10 Hz track of tests/e2e/test_delay.py: the
     * fragments at max_lookahead 18 fit the pick (2.37 s), and a REST
     * start's ramp that loses more than the stop reserve leaves a lag the
     * catch-up wins back (delay.h): D stays delay_s, and its line says so */
    {
        engine_config_t c2 = c;
        c2.delay_s = 2.5;
        int err2 = -1;
        engine_t *e = engine_new(&c2, &err2);
        assert_non_null(e);
        engine_setpoint_t sp;
        for (int64_t k = 0; k < 6000; k++) {
            if (k % 10 == 0) {
                engine_waypoint_t w;
                memset(&w, 0, sizeof w);
                int i = (int)(k / 10);
                w.t_s = 0.1 * i;
                w.pos_m[0] = 10 * sin(0.05 * i);
                w.pos_m[1] = 10 * cos(0.03 * i);
                assert_int_equal(engine_push(e, &w), 0);
            }
            assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        }
        engine_delay_t d;
        char line[600];
        engine_delay(e, &d);
        engine_delay_format(&d, line, sizeof line);
        print_message("%s\n", line);
        assert_true(fabs(d.delay_s - 2.5) < 1e-12);
        assert_non_null(strstr(line, "D 2.500 s (delay_s; the settings need lookahead 18 x"));
        engine_free(e);
    }
    /* without delay_s: nothing held, the default solver */
    c.delay_s = 0;
    int err = -1;
    engine_t *e = engine_new(&c, &err);
    engine_waypoint_t w;
    engine_status_t st;
    line_wp(&w, 0);
    assert_int_equal(engine_push(e, &w), 0);
    line_wp(&w, 1);
    assert_int_equal(engine_push(e, &w), 0);
    engine_status(e, &st);
    assert_int_equal(st.buffered, 2);
    engine_free(e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tail_plays_out),
        cmocka_unit_test(test_end_is_no_underrun),
        cmocka_unit_test(test_tail_plays_out_loaded_before_first_tick),
        cmocka_unit_test(test_upload_delay_as_streamed),
        cmocka_unit_test(test_tail_plays_out_after_reload_handover),
        cmocka_unit_test(test_no_silent_end_while_regular),
        cmocka_unit_test(test_delay_stated),
        cmocka_unit_test(test_delay_of_config),
        cmocka_unit_test(test_delay_s_picks_lookahead),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
