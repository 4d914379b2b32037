/*
 * test_accept.c - one bad fix costs nothing but itself (issue 12): the
 * acceptance policy (lib/engine/accept.h) judges each waypoint with its
 * neighbours, and its verdicts must come within the start slack the output
 * keeps for them, or the output runs dry while a bad fix waits for its
 * verdict.
 *
 * The track: a boat on a circle of 50 m radius at 5 m/s, a fix every 0.2 s
 * (the NMEA 2000 figure-eight's rate, tests/data/ATTRIBUTION.md), pushed on
 * a virtual clock when its time comes, the output ticking at 100 Hz with the
 * default configuration.  Into it, one bad row between two fixes, at every
 * site over three fragment periods (the solver's lookahead depends on where
 * a waypoint falls in the fragment grid, lib/engine/frag.h):
 *   spike  300 m off the path, halfway between the two fixes;
 *   back   a re-sent fix from 1 s before (a backwards stamp);
 *   stale  the previous fix's position again, halfway (a frozen receiver);
 *   jump   1 km off, with the next fix's time plus 0.1 s.
 * Each run must refuse exactly the bad row and keep every good fix, stream
 * with no underrun and no hard stop, and end finished.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "engine.h"

#define PERIOD_NS 10000000LL
#define N_FIX 200
#define DT_S 0.2

enum { K_SPIKE, K_BACK, K_STALE, K_JUMP, K_COUNT };
static const char *const kind_name[K_COUNT] = {"spike", "back", "stale", "jump"};

static void boat(engine_waypoint_t *w, int i)
{
    memset(w, 0, sizeof *w);
    w->t_s = i * DT_S;
    w->pos_m[0] = 50.0 * sin(0.02 * i);
    w->pos_m[1] = 50.0 * (1.0 - cos(0.02 * i));
    w->seq = (uint32_t)i + 1;
}

/* the fixes with one bad row after fix `site`; returns the row count */
static int build(engine_waypoint_t *rows, int site, int kind)
{
    int n = 0;
    for (int i = 0; i < N_FIX; i++) {
        boat(&rows[n++], i);
        if (i != site)
            continue;
        engine_waypoint_t b, nx;
        boat(&nx, i + 1);
        b = rows[n - 1];
        b.t_s = 0.5 * (b.t_s + nx.t_s);
        switch (kind) {
        case K_SPIKE: b.pos_m[0] = 0.5 * (rows[n - 1].pos_m[0] + nx.pos_m[0]) + 300.0; break;
        case K_BACK: boat(&b, i - 5); break;
        case K_STALE: break;
        case K_JUMP:
            b = nx;
            b.t_s += 0.1;
            b.pos_m[1] += 1000.0;
            break;
        }
        rows[n++] = b;
    }
    for (int r = 0; r < n; r++)
        rows[r].seq = (uint32_t)r + 1;
    return n;
}

/* replay rows on a virtual clock; status at the end */
static void replay(const engine_waypoint_t *rows, int n, engine_status_t *st, int *finished)
{
    engine_config_t c;
    engine_config_default(&c);
    int err = -1, next = 0;
    engine_t *e = engine_new(&c, &err);
    engine_setpoint_t sp;
    assert_non_null(e);
    *finished = 0;
    for (int64_t k = 0; k < 100000 && !*finished; k++) {
        double now_s = (double)(k * PERIOD_NS) * 1e-9;
        /* in file order, each when its time has come (a backwards one at once) */
        while (next < n && rows[next].t_s <= now_s + 1e-9) {
            (void)engine_push(e, &rows[next]);
            if (++next == n)
                assert_int_equal(engine_finish(e), 0);
        }
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        *finished = sp.state == ENGINE_STATE_FINISHED;
    }
    engine_status(e, st);
    engine_free(e);
}

static void test_one_bad_fix_costs_nothing(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX + 1];
    engine_config_t c;
    engine_config_default(&c);
    int bad = 0;

    for (int kind = 0; kind < K_COUNT; kind++) {
        int underruns = 0, lost = 0;
        for (int site = 40; site < 40 + 3 * (int)(c.fragment - c.overlap); site++) {
            engine_status_t st;
            int fin, n = build(rows, site, kind);
            replay(rows, n, &st, &fin);
            if (st.underruns || st.accepted != N_FIX || st.rejected != 1 || st.hard_stops || !fin) {
                print_message("%s after fix %d: accepted %llu rejected %llu underruns %llu "
                              "hard stops %llu finished %d\n",
                              kind_name[kind], site, (unsigned long long)st.accepted,
                              (unsigned long long)st.rejected, (unsigned long long)st.underruns,
                              (unsigned long long)st.hard_stops, fin);
                bad++;
            }
            underruns += st.underruns != 0;
            lost += st.accepted != N_FIX;
        }
        print_message("%s: %d of %u sites with an underrun, %d losing good fixes\n",
                      kind_name[kind], underruns, 3 * (c.fragment - c.overlap), lost);
    }
    assert_int_equal(bad, 0);
}

/*
 * A run of repeats longer than the judging window (accept.h,
 * ACCEPT_STALE_STOP_M_S2): the boat's receiver freezes for 3 s (15 fixes
 * repeat the position of the fix before, then the true positions resume:
 * frozen, then a jump), and a walker at 1.2 m/s and 1 Hz stands 30 s on one
 * bit-identical position (a receiver's static hold).  The frozen run is
 * refused as stale and every good fix around it kept (keeping the run made
 * the jump after it look like 60 m/s: the 4 good fixes after it were
 * refused); the walker's stand is kept whole.
 */
static void test_long_frozen_run(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX + 60];
    engine_status_t st;
    int fin, n = 0;

    for (int i = 0; i < N_FIX; i++) {
        boat(&rows[n], i);
        if (i >= 100 && i < 115)
            memcpy(rows[n].pos_m, rows[99].pos_m, sizeof rows[n].pos_m);
        n++;
    }
    replay(rows, n, &st, &fin);
    print_message("boat frozen 3 s: accepted %llu, stale %llu, rejected %llu\n",
                  (unsigned long long)st.accepted,
                  (unsigned long long)st.rejected_by[ENGINE_ESTALE],
                  (unsigned long long)st.rejected);
    assert_int_equal(st.accepted, N_FIX - 15);
    assert_int_equal(st.rejected_by[ENGINE_ESTALE], 15);
    assert_int_equal(st.rejected, 15);
    assert_int_equal(st.hard_stops, 0);
    assert_true(fin);

    n = 0;
    for (int i = 0; i < 150; i++, n++) {
        memset(&rows[n], 0, sizeof rows[n]);
        rows[n].t_s = i;
        rows[n].pos_m[0] = 1.2 * (i < 50 ? i : i < 80 ? 50 : i - 30);
        rows[n].pos_m[1] = 0.2 * sin(0.1 * i);
        if (i >= 50 && i < 80)
            rows[n].pos_m[1] = 0.2 * sin(5.0);
        rows[n].seq = (uint32_t)n + 1;
    }
    replay(rows, n, &st, &fin);
    print_message("walker standing 30 s: accepted %llu, rejected %llu\n",
                  (unsigned long long)st.accepted, (unsigned long long)st.rejected);
    assert_int_equal(st.accepted, 150);
    assert_int_equal(st.rejected, 0);
    assert_true(fin);
}

/* The boat's fixes with fixes [from, from + n) moved `off` metres north
 * (a relocated object, or a burst of bad fixes); returns the row count. */
static int build_moved(engine_waypoint_t *rows, int from, int n, double off)
{
    for (int i = 0; i < N_FIX; i++) {
        boat(&rows[i], i);
        if (i >= from && i < from + n)
            rows[i].pos_m[1] += off;
    }
    return N_FIX;
}

/* replay as replay() does, also giving the last setpoint */
static void replay_sp(const engine_waypoint_t *rows, int n, engine_status_t *st,
                      engine_setpoint_t *last)
{
    engine_config_t c;
    engine_config_default(&c);
    int err = -1, next = 0;
    engine_t *e = engine_new(&c, &err);
    assert_non_null(e);
    memset(last, 0, sizeof *last);
    for (int64_t k = 0; k < 200000 && last->state != ENGINE_STATE_FINISHED; k++) {
        double now_s = (double)(k * PERIOD_NS) * 1e-9;
        while (next < n && rows[next].t_s <= now_s + 1e-9) {
            (void)engine_push(e, &rows[next]);
            if (++next == n)
                assert_int_equal(engine_finish(e), 0);
        }
        assert_int_equal(engine_tick(e, k * PERIOD_NS, last), 0);
    }
    engine_status(e, st);
    engine_free(e);
}

/* Issue 11 "time sanity": given the boat relocated 1 km north from fix 100
 * on (every later fix consistent with the ones after it), then the engine
 * abandons the old trajectory for a new one once `confirm` fixes agree:
 * every fix kept, a new trajectory number, and the output ends on the last
 * moved fix.  Given only confirm - 1 moved fixes (then the boat back on its
 * track), then those are refused as unconfirmed (a new trajectory that
 * was not confirmed; test_far_burst_unconfirmed), and the trajectory is not
 * abandoned.  Given one fix far in the
 * future (t = 1e9 s) among them, then it alone is refused, with its own
 * reason: unconfirmed. */
static void test_far_start_needs_confirmation(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX + 1];
    engine_config_t c;
    engine_config_default(&c);
    engine_status_t st;
    engine_setpoint_t sp;

    int n = build_moved(rows, 100, N_FIX - 100, 1000.0);
    replay_sp(rows, n, &st, &sp);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_int_equal(st.rejected, 0);
    assert_int_equal(st.accepted, N_FIX);
    assert_int_equal(st.tracks, 2); /* the old one abandoned for a second */
    assert_float_equal(sp.pos_m[1], rows[N_FIX - 1].pos_m[1], 1e-9);

    assert_true(c.confirm >= 2);
    n = build_moved(rows, 100, (int)c.confirm - 1, 1000.0);
    replay_sp(rows, n, &st, &sp);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_int_equal(st.rejected, c.confirm - 1);
    assert_int_equal(st.rejected_by[ENGINE_EUNCONFIRMED], c.confirm - 1);
    assert_int_equal(st.accepted, N_FIX - (c.confirm - 1));
    assert_int_equal(st.tracks, 1);
    assert_float_equal(sp.pos_m[1], rows[N_FIX - 1].pos_m[1], 1e-9);

    n = build_moved(rows, 0, 0, 0.0);
    memmove(&rows[101], &rows[100], (size_t)(N_FIX - 100) * sizeof rows[0]);
    rows[100].t_s = 1e9; /* between fixes 99 and 100, all pushed at once */
    n++;
    engine_t *e;
    int err = -1;
    e = engine_new(&c, &err);
    assert_non_null(e);
    for (int r = 0; r < n; r++)
        (void)engine_push(e, &rows[r]);
    assert_int_equal(engine_finish(e), 0);
    for (int64_t k = 0; k < 200000; k++) {
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
    }
    engine_status(e, &st);
    engine_free(e);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_int_equal(st.rejected, 1);
    assert_int_equal(st.rejected_by[ENGINE_EUNCONFIRMED], 1);
    assert_int_equal(st.accepted, N_FIX);
    assert_int_equal(st.tracks, 1);
    assert_float_equal(sp.t_s, rows[n - 1].t_s, 1e-9);
}

/*
 * After `confirm` mutually consistent fixes far from the trajectory, a new
 * one starts there (issue 12 item 1, re-anchoring): from fix 100 on the
 * boat's fixes are 500 m north (a relocated object, a corrected datum).
 * Every fix is kept, the trajectory is re-anchored once (a transfer joins
 * them), nothing is refused.  Fewer far fixes than `confirm` (2 of 3) are
 * refused and abandon nothing.
 */
static void test_reanchor_after_confirm(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX];
    engine_status_t st;
    engine_config_t c;
    int fin;

    engine_config_default(&c);
    for (int far = 0; far < 2; far++) {
        for (int i = 0; i < N_FIX; i++) {
            boat(&rows[i], i);
            if (far ? i >= 100 : (i >= 100 && i < 100 + (int)c.confirm - 1))
                rows[i].pos_m[1] += 500.0;
        }
        replay(rows, N_FIX, &st, &fin);
        print_message("%s: accepted %llu rejected %llu reanchors %llu gaps %llu\n",
                      far ? "relocated from fix 100 on" : "2 far fixes",
                      (unsigned long long)st.accepted, (unsigned long long)st.rejected,
                      (unsigned long long)st.reanchors, (unsigned long long)st.gaps);
        assert_true(fin);
        assert_int_equal(st.hard_stops, 0);
        assert_int_equal(st.gaps, 0);
        if (far) {
            assert_int_equal(st.accepted, N_FIX);
            assert_int_equal(st.rejected, 0);
            assert_int_equal(st.reanchors, 1);
        } else {
            assert_int_equal(st.accepted, N_FIX - (c.confirm - 1));
            assert_int_equal(st.rejected, c.confirm - 1);
            assert_int_equal(st.reanchors, 0);
        }
    }
}

/*
 * Issue 11 "time sanity", far in space: a burst of confirm - 1 fixes 1 km
 * north of the boat, consistent among themselves (the boat's own motion,
 * shifted), then the boat on its old path again.  The burst would start a
 * new trajectory and is not confirmed: each of its fixes is refused as
 * unconfirmed (counted in rejected_by[ENGINE_EUNCONFIRMED], the daemon's
 * rejected_unconfirmed), not as speed, and every good fix is kept.  A lone
 * spike 1 km north (one fix, consistent with nothing held) stays speed.
 */
static void test_far_burst_unconfirmed(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX];
    engine_config_t c;
    engine_status_t st;
    int fin;

    engine_config_default(&c);
    assert_true(c.confirm >= 3); /* a burst of 2 mutually consistent fixes */
    for (int burst = 1; burst <= (int)c.confirm - 1; burst++) {
        int n = build_moved(rows, 120, burst, 1000.0);
        replay(rows, n, &st, &fin);
        print_message("burst of %d fixes 1 km off: accepted %llu, unconfirmed %llu, "
                      "speed %llu, accel %llu\n",
                      burst, (unsigned long long)st.accepted,
                      (unsigned long long)st.rejected_by[ENGINE_EUNCONFIRMED],
                      (unsigned long long)st.rejected_by[ENGINE_ESPEED],
                      (unsigned long long)st.rejected_by[ENGINE_EACCEL]);
        assert_true(fin);
        assert_int_equal(st.accepted, N_FIX - burst);
        assert_int_equal(st.rejected, burst);
        assert_int_equal(st.tracks, 1);
        assert_int_equal(st.reanchors, 0);
        if (burst == 1) { /* a lone spike: consistent with nothing */
            assert_int_equal(st.rejected_by[ENGINE_ESPEED], 1);
        } else {
            assert_int_equal(st.rejected_by[ENGINE_EUNCONFIRMED], burst);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_bad_fix_costs_nothing),
        cmocka_unit_test(test_long_frozen_run),
        cmocka_unit_test(test_reanchor_after_confirm),
        cmocka_unit_test(test_far_start_needs_confirmation),
        cmocka_unit_test(test_far_burst_unconfirmed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
