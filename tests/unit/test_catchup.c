/*
 * test_catchup.c - the lag won back and the sender's clock followed (issue
 * 26 item 3, lib/engine/catchup.h), on a virtual clock.
 *
 * The regular 10 Hz track x = 10 sin(0.05 i), y = 10 cos(0.03 i) is pushed
 * when the sender's clock says its stamp has come, the output ticking at
 * 100 Hz with the default configuration (start_slack auto).  A sender
 * whose clock runs fast or slow by 500 ppm (drift_max_ppm's default) stamps
 * waypoint i at 0.1 i while it sends it at 0.1 i / (1 + ppm 1e-6) of ours.
 * Before: the output played at rate 1 whatever the sender's pace, so a fast
 * sender's lag grew by its drift and a slow one's ran the buffer dry.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "catchup.h"
#include "delay.h"
#include "engine.h"

#define PERIOD_NS 10000000LL

static engine_waypoint_t wp_at(int i)
{
    engine_waypoint_t w;
    memset(&w, 0, sizeof w);
    w.t_s = 0.1 * i;
    w.pos_m[0] = 10 * sin(0.05 * i);
    w.pos_m[1] = 10 * cos(0.03 * i);
    w.seq = (uint32_t)i + 1;
    return w;
}

typedef struct {
    double delay_start; /* now - t_s on the sender's clock, mean over 20..30 s */
    double delay_end;   /* ... over the last 10 s of streaming */
    double rate_max;    /* the largest |v| over the curve's own speed there */
    int under_sending;  /* UNDERRUN setpoints while the sender still sends */
    engine_status_t st;
    engine_delay_t d;
} run_t;

/* n waypoints sent with the clock error ppm; all those from index bulk on
 * pushed at once when waypoint bulk is due (bulk < 0: none) */
static void run(int n, double ppm, int bulk, run_t *r)
{
    engine_config_t c;
    engine_config_default(&c);
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    memset(r, 0, sizeof *r);
    r->under_sending = 0;
    int next = 0, n20 = 0, nend = 0;
    double sum20 = 0, sumend = 0, last_stream = 0;
    engine_setpoint_t sp;
    static double dl[200000], nw[200000];
    int rows = 0;
    for (int64_t k = 0; k < 400000; k++) {
        double now = (double)k * PERIOD_NS * 1e-9;
        while (next < n && 0.1 * next / (1.0 + ppm * 1e-6) <= now + 1e-9) {
            if (next == bulk) {
                for (; next < n; next++) {
                    engine_waypoint_t w = wp_at(next);
                    assert_int_equal(engine_push(e, &w), 0);
                }
                break;
            }
            engine_waypoint_t w = wp_at(next++);
            assert_int_equal(engine_push(e, &w), 0);
        }
        if (next == n && k % 100 == 0 && now > 0.1 * n + 30)
            break;
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.state == ENGINE_STATE_UNDERRUN && next < n)
            r->under_sending++; /* (the end of input without a FINISH is a silence) */
        if (sp.state == ENGINE_STATE_STREAMING && sp.t_s > 1.0 && sp.t_s < 0.1 * (n - 30)) {
            /* the delay on the sender's clock: what D is stated in */
            double d = now * (1.0 + ppm * 1e-6) - sp.t_s;
            if (now >= 20 && now < 30) {
                sum20 += d;
                n20++;
            }
            if (rows < 200000) {
                dl[rows] = d;
                nw[rows++] = now;
            }
            last_stream = now;
            /* the curve's own speed at t_s: the track's, within its spline */
            double i = sp.t_s / 0.1, vx = 0.5 * 10 * cos(0.05 * i) * 1.0,
                   vy = -0.3 * 10 * sin(0.03 * i);
            double v = hypot(vx, vy), got = hypot(sp.vel_m_s[0], sp.vel_m_s[1]);
            if (v > 1.0)
                r->rate_max = fmax(r->rate_max, got / v);
        }
    }
    for (int j = 0; j < rows; j++)
        if (nw[j] > last_stream - 10) {
            sumend += dl[j];
            nend++;
        }
    assert_true(n20 > 0 && nend > 0);
    r->delay_start = sum20 / n20;
    r->delay_end = sumend / nend;
    engine_status(e, &r->st);
    engine_delay(e, &r->d);
    engine_free(e);
}

/*
 * Given a sender whose clock runs 500 ppm fast or slow, when 2 000 s of the
 * track are sent, then the output follows its pace: no underrun, and the
 * delay (on the sender's clock) at the end is the delay at the start
 * within an input interval (before: 1 s more for the fast sender,
 * underruns for the slow one), won back or given back at no more than 5 %
 * of rate; a sender on time is steered once, for the lag its start's ramp
 * left beyond the stop reserve (delay.h), and stands at D after it.
 */
static void test_sender_drift_followed(void **state)
{
    (void)state;
    const double ppms[] = {0.0, 500.0, -500.0};
    for (int i = 0; i < 3; i++) {
        run_t r;
        run(20000, ppms[i], -1, &r);
        print_message("sender %+.0f ppm: delay %.4f s at 20 s, %.4f s at the end (D %.4f); "
                      "%d underrun ticks while it sends, %llu catch-ups, rate at most %.4f\n",
                      ppms[i], r.delay_start, r.delay_end, r.d.delay_s, r.under_sending,
                      (unsigned long long)r.st.catchups, r.rate_max);
        assert_int_equal(r.under_sending, 0);
        assert_int_equal(r.st.hard_stops, 0);
        assert_true(fabs(r.delay_end - r.delay_start) <= 0.1);
        assert_true(i == 0 ? r.st.catchups <= 1 : r.st.catchups >= 1);
        if (i == 0) /* on D, 20 s in and at the end */
            assert_true(fabs(r.delay_start - r.d.delay_s) < 0.01 &&
                        fabs(r.delay_end - r.d.delay_s) < 0.01);
        assert_true(r.rate_max <= 1.0 + CATCHUP_DEFAULT + 0.01);
    }
}

/*
 * Given the track sent at its pace for 5 s and then the rest pushed at once
 * (a buffer filled ahead of time: its stamps are no sender's clock), then
 * nothing is won back once it is: the output plays at its stamps' pace (a
 * catch-up of the start's lag may have begun while the sender was live).
 */
static void test_loaded_ahead_not_steered(void **state)
{
    (void)state;
    run_t r;
    run(1200, 0.0, 50, &r);
    print_message("loaded ahead: %llu catch-ups, delay %.4f s then %.4f s\n",
                  (unsigned long long)r.st.catchups, r.delay_start, r.delay_end);
    assert_true(r.st.catchups <= 1);
    assert_int_equal(r.st.underruns, 0);
    assert_true(fabs(r.delay_end - r.delay_start) < 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sender_drift_followed),
        cmocka_unit_test(test_loaded_ahead_not_steered),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
