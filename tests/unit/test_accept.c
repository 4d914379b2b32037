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
 *
 * And the policy's pair cache changes no verdict: test_same_verdicts_as_
 * reference drives lib/engine/accept.c and the former code
 * (tests/helpers/accept_ref.h) with the same random dirty tracks.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "accept.h"
#include "accept_ref.h"
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

/* max_lookahead of replay's engine (0: the default) */
static unsigned replay_max_lookahead;
static double replay_delay_s; /* delay_s of replay's engine (0: the settings' D) */

/* replay rows on a virtual clock; status at the end */
static void replay(const engine_waypoint_t *rows, int n, engine_status_t *st, int *finished)
{
    engine_config_t c;
    engine_config_default(&c);
    if (replay_max_lookahead)
        c.max_lookahead = replay_max_lookahead;
    c.delay_s = replay_delay_s;
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

/* The bad row of kind after fix site, replayed (replay): 0 if it alone is
 * refused, every good fix kept, with at most under_ok underruns and no hard
 * stop, to the end; else 1, with a line (label before it).  *st: the
 * status. */
static int bad_fix_run_ok(const char *label, int kind, int site, uint64_t under_ok,
                          engine_status_t *st)
{
    static engine_waypoint_t rows[N_FIX + 1];
    int fin, n = build(rows, site, kind);
    replay(rows, n, st, &fin);
    if (st->underruns <= under_ok && st->accepted == N_FIX && st->rejected == 1 &&
        !st->hard_stops && fin)
        return 0;
    print_message("%s%s after fix %d: accepted %llu rejected %llu underruns %llu hard stops %llu "
                  "finished %d\n",
                  label, kind_name[kind], site, (unsigned long long)st->accepted,
                  (unsigned long long)st->rejected, (unsigned long long)st->underruns,
                  (unsigned long long)st->hard_stops, fin);
    return 1;
}

static int bad_fix_run(const char *label, int kind, int site, engine_status_t *st)
{
    return bad_fix_run_ok(label, kind, site, 0, st);
}

static void test_one_bad_fix_costs_nothing(void **state)
{
    (void)state;
    engine_config_t c, r;
    engine_config_default(&c);
    /* the fragment period S = F - O of the default (fragment, overlap auto) */
    assert_int_equal(engine_config_resolve(&c, &r), 0);
    unsigned sites = 3 * (r.fragment - r.overlap);
    int bad = 0;

    assert_true(sites >= 3);
    for (int kind = 0; kind < K_COUNT; kind++) {
        int underruns = 0, lost = 0;
        for (int site = 40; site < 40 + (int)sites; site++) {
            engine_status_t st;
            bad += bad_fix_run("", kind, site, &st);
            underruns += st.underruns != 0;
            lost += st.accepted != N_FIX;
        }
        print_message("%s: %d of %u sites with an underrun, %d losing good fixes\n",
                      kind_name[kind], underruns, sites, lost);
    }
    assert_int_equal(bad, 0);
}

/*
 * Issue 31: max_lookahead 1 keeps a fix as it arrives when it follows the
 * anchor (accept.h at_arrival).  The same bad rows at every site (one
 * fragment period is moot here: no fragments) must still be refused alone,
 * every good fix kept, with no underrun and no hard stop: a bad row waits
 * for its neighbour as before, and the good fix after it, judged against
 * the anchor, is kept as it arrives.  But for the jump: its row is stamped
 * an interval after the good fix that follows it in the file, so that fix
 * (replayed in file order) arrives an interval late, and the local
 * methods' slack is in time (lib/engine/delay.h ENGINE_DELAY_TICKS, issue
 * 31): one underrun, after which D holds an interval more (start_slack
 * auto learns it).
 */
static void test_at_arrival_one_bad_fix(void **state)
{
    (void)state;
    int bad = 0;

    replay_max_lookahead = 1;
    for (int kind = 0; kind < K_COUNT; kind++)
        for (int site = 40; site < 46; site++) {
            engine_status_t st;
            bad += bad_fix_run_ok("max_lookahead 1, ", kind, site, kind == K_JUMP, &st);
        }
    replay_max_lookahead = 0;
    assert_int_equal(bad, 0);
}

/* kept so far (engine_status accepted) */
static uint64_t kept(engine_t *e)
{
    engine_status_t st;
    engine_status(e, &st);
    return st.accepted;
}

/*
 * When a fix is kept (issue 31): the boat's fixes pushed one at a time,
 * each kept as it is pushed with max_lookahead 1 (resolved to a local
 * method, the acceptance at_arrival), one push later with max_lookahead 2
 * (the next neighbour confirms it).  With the source's velocity on every
 * fix, fix 40 reporting 20 m/s north on a boat at 5 m/s (the second signal
 * disagrees with its chord, and then with the chord after it) waits for its
 * neighbour, and so does fix 41 after it; both are then kept: the velocity
 * alone refuses nothing.
 */
static void test_at_arrival_when_kept(void **state)
{
    (void)state;
    for (unsigned ml = 1; ml <= 2; ml++)
        for (int vel = 0; vel < 2; vel++) {
            engine_config_t c;
            engine_config_default(&c);
            c.max_lookahead = ml;
            engine_t *e = engine_new(&c, NULL);
            assert_non_null(e);
            unsigned all = 0, waited = 0, first_wait = 0;
            for (int i = 0; i < 60; i++) {
                engine_waypoint_t w;
                boat(&w, i);
                if (vel) {
                    w.has_vel = 1; /* d/dt of boat() */
                    w.vel_m_s[0] = 50.0 * 0.02 / DT_S * cos(0.02 * i);
                    w.vel_m_s[1] = 50.0 * 0.02 / DT_S * sin(0.02 * i);
                    if (i == 40) {
                        w.vel_m_s[0] = 0;
                        w.vel_m_s[1] = 20.0;
                    }
                }
                assert_int_equal(engine_push(e, &w), 0);
                if (i < 10)
                    continue; /* past the first trajectory's confirmation */
                if (kept(e) == (uint64_t)i + 1) {
                    all++; /* every fix pushed so far kept */
                } else {
                    waited++;
                    if (!first_wait)
                        first_wait = (unsigned)i;
                }
            }
            engine_status_t st;
            engine_status(e, &st);
            print_message("max_lookahead %u%s: %u pushes found every fix kept, %u found one "
                          "waiting (the first: fix %u); rejected %llu\n",
                          ml, vel ? ", velocities" : "", all, waited, first_wait,
                          (unsigned long long)st.rejected);
            assert_int_equal(st.rejected, 0);
            if (ml == 1) {
                assert_int_equal(waited, vel ? 2 : 0);
                if (vel)
                    assert_int_equal(first_wait, 40);
            } else {
                assert_int_equal(all, 0);
            }
            engine_free(e);
        }
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

/* what replay_sp saw on the way: the fastest setpoint, the refused seqs */
typedef struct {
    double vmax;
    unsigned nrej;
    uint32_t rej_seq[4];
} seen_t;

static void see(engine_t *e, const engine_setpoint_t *sp, seen_t *seen)
{
    engine_rejection_t r;
    double v2 = 0;
    for (int k = 0; k < ENGINE_AXES; k++)
        v2 += sp->vel_m_s[k] * sp->vel_m_s[k];
    if (sqrt(v2) > seen->vmax)
        seen->vmax = sqrt(v2);
    while (engine_rejection_next(e, &r) == 1)
        if (seen->nrej++ < 4)
            seen->rej_seq[seen->nrej - 1] = r.seq;
}

/* replay as replay() does, also giving the last setpoint (and with seen,
 * what happened on the way) */
static void replay_sp(const engine_waypoint_t *rows, int n, engine_status_t *st,
                      engine_setpoint_t *last, seen_t *seen)
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
        if (seen)
            see(e, last, seen);
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
    replay_sp(rows, n, &st, &sp, NULL);
    assert_int_equal(sp.state, ENGINE_STATE_FINISHED);
    assert_int_equal(st.rejected, 0);
    assert_int_equal(st.accepted, N_FIX);
    assert_int_equal(st.tracks, 2); /* the old one abandoned for a second */
    assert_float_equal(sp.pos_m[1], rows[N_FIX - 1].pos_m[1], 1e-9);

    assert_true(c.confirm >= 2);
    n = build_moved(rows, 100, (int)c.confirm - 1, 1000.0);
    replay_sp(rows, n, &st, &sp, NULL);
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

/* ---- the same verdicts as the reference (tests/helpers/accept_ref.h) ------ */

/* 64-bit LCG (Knuth's MMIX constants): more resolution than urand for the
 * positions and times of the differential test */
static uint64_t rng_state;
static double rnd(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) * (1.0 / 9007199254740992.0);
}

static unsigned rndn(unsigned n)
{
    return (unsigned)(rnd() * n) % n;
}

/* The next waypoint of a dirty track: a base motion (random walk, steady
 * course, standing still with noise) at a regular, jittered or bursty
 * rate, with faults mixed in: spikes, repeats of the last position (frozen
 * receiver), equal stamps, exact duplicates, late and backwards stamps,
 * gaps, far jumps in time and space, bursts off the track. */
typedef struct {
    double t, dt, pos[3], vel[3], noise;
    engine_waypoint_t last, prev;
    unsigned seq, fault_pct, bursty, burst_left;
    double burst_off[3];
} track_t;

static void track_init(track_t *tr)
{
    static const double dts[] = {0.001, 0.1, 0.2, 1.0, 5.0};
    static const double speeds[] = {0.0, 1.0, 5.0, 30.0, 250.0};
    double sp = speeds[rndn(5)];
    memset(tr, 0, sizeof *tr);
    tr->dt = dts[rndn(5)];
    tr->t = rnd() * 1000.0;
    for (int k = 0; k < 3; k++) {
        tr->pos[k] = (rnd() - 0.5) * 1e4;
        tr->vel[k] = (rnd() - 0.5) * sp;
    }
    tr->noise = rndn(2) ? 0.0 : 3.0 * rnd();
    tr->fault_pct = (unsigned[]){0, 2, 10, 30}[rndn(4)];
    tr->bursty = rndn(3) == 0;
}

static void track_base(track_t *tr, engine_waypoint_t *w)
{
    double step = tr->dt;
    if (tr->bursty)
        step *= (double)rndn(4) * 0.5; /* 0: the same stamp again */
    else if (rndn(2))
        step *= 0.5 + rnd(); /* jitter */
    tr->t += step;
    for (int k = 0; k < 3; k++) {
        if (rndn(4) == 0)
            tr->vel[k] += (rnd() - 0.5) * 2.0 * (1.0 + fabs(tr->vel[k]));
        tr->pos[k] += tr->vel[k] * step;
        w->pos_m[k] = tr->pos[k] + (rnd() - 0.5) * tr->noise;
    }
    w->t_s = tr->t;
}

static void track_fault(track_t *tr, engine_waypoint_t *w)
{
    switch (rndn(9)) {
    case 0: /* spike */
        for (int k = 0; k < 3; k++)
            w->pos_m[k] += (rnd() - 0.5) * 600.0;
        break;
    case 1: /* repeat of the last position, later (frozen receiver) */
        memcpy(w->pos_m, tr->last.pos_m, sizeof w->pos_m);
        break;
    case 2: /* equal stamp, other position */ w->t_s = tr->last.t_s; break;
    case 3: /* exact duplicate of the last or the one before */
        *w = rndn(2) ? tr->last : tr->prev;
        return;
    case 4: /* late or backwards stamp */
        w->t_s = tr->last.t_s - tr->dt * (double)rndn(12) * 0.5;
        break;
    case 5: /* a gap, plausible or far */
        tr->t += tr->dt * (double)(rndn(2) ? 30 + rndn(2000) : 1000000);
        w->t_s = tr->t;
        break;
    case 6: /* a burst off the track, far in space */
        tr->burst_left = 1 + rndn(5);
        for (int k = 0; k < 3; k++)
            tr->burst_off[k] = (rnd() - 0.5) * 4000.0;
        break;
    case 7: /* the clock restarts */
        tr->t = rnd() * 10.0;
        w->t_s = tr->t;
        break;
    default: /* a stamp within a nanosecond of the last */
        w->t_s = tr->last.t_s + (rnd() - 0.5) * 2e-9;
        break;
    }
}

static void track_next(track_t *tr, engine_waypoint_t *w)
{
    track_base(tr, w);
    if (tr->burst_left) {
        tr->burst_left--;
        for (int k = 0; k < 3; k++)
            w->pos_m[k] += tr->burst_off[k];
    } else if (rndn(100) < tr->fault_pct)
        track_fault(tr, w);
    w->seq = ++tr->seq;
    tr->prev = tr->last;
    tr->last = *w;
}

static void random_config(accept_config_t *c)
{
    static const double speeds[] = {0.0, 5.0, 40.0, 100.0, 400.0};
    static const double accels[] = {0.0, 3.0, 30.0};
    static const double gaps[] = {0.5, 5.0, 60.0, 1e9};
    memset(c, 0, sizeof *c); /* at_arrival and any field not set below: off, as the
                                reference's former policy has them */
    c->max_speed_m_s = speeds[rndn(5)];
    c->max_accel_m_s2 = accels[rndn(3)];
    c->max_gap_s = gaps[rndn(4)];
    c->learned = (int)rndn(2);
    c->stale = (int)rndn(2);
    c->window = rndn(ACCEPT_WINDOW_MAX + 2); /* 0 and 9: clamped */
    c->confirm = rndn(ACCEPT_WINDOW_MAX + 2);
    c->rules = ACCEPT_RULES_FORMER; /* the reference is the policy before issue 27 */
}

static int same_wp(const engine_waypoint_t *p, const engine_waypoint_t *q)
{
    return memcmp(&p->t_s, &q->t_s, sizeof p->t_s) == 0 &&
           memcmp(p->pos_m, q->pos_m, sizeof p->pos_m) == 0 && p->seq == q->seq;
}

static void assert_same_state(accept_t *a, const aref_t *r)
{
    double l1 = accept_speed_limit(a), l2 = aref_speed_limit(r);
    double s1 = accept_recent_speed(a), s2 = aref_recent_speed(r);
    assert_int_equal(accept_pending(a), r->npend);
    assert_memory_equal(&l1, &l2, sizeof l1);
    assert_memory_equal(&s1, &s2, sizeof s1);
    if (r->npend)
        assert_true(same_wp(accept_first(a), &r->pend[0]));
}

/* every verdict there is now, from both: the same, in the same order */
static unsigned drain_both(accept_t *a, aref_t *r, int closing, unsigned long *kinds)
{
    accept_verdict_t v1, v2;
    unsigned n = 0;
    for (;;) {
        int d1 = accept_decide(a, closing, &v1), d2 = aref_decide(r, closing, &v2);
        assert_int_equal(d1, d2);
        if (!d1)
            return n;
        assert_int_equal(v1.kind, v2.kind);
        assert_int_equal(v1.reason, v2.reason);
        assert_int_equal(v1.gap, v2.gap);
        assert_true(same_wp(&v1.wp, &v2.wp));
        kinds[v1.kind == ACCEPT_DROP ? 2 + v1.reason : (int)v1.kind]++;
        assert_same_state(a, r);
        n++;
    }
}

/* accept_check on a random triple of the track against the reference's */
static void check_triple(const accept_t *a, const aref_t *r, const engine_waypoint_t *w)
{
    double vlim = rndn(2) ? 0.0 : 50.0 * rnd();
    const engine_waypoint_t *pre = rndn(3) ? &w[0] : NULL;
    assert_int_equal(accept_check(a, pre, &w[1], &w[2], vlim),
                     aref_check(r, pre, &w[1], &w[2], vlim));
}

static void run_track(unsigned npts, unsigned long *kinds)
{
    accept_config_t cfg;
    accept_t a;
    aref_t r;
    track_t tr;
    engine_waypoint_t w, tri[3] = {{0}};

    random_config(&cfg);
    accept_init(&a, &cfg);
    aref_init(&r, &cfg);
    track_init(&tr);
    for (unsigned i = 0; i < npts; i++) {
        track_next(&tr, &w);
        assert_int_equal(accept_offer(&a, &w), aref_offer(&r, &w));
        assert_same_state(&a, &r);
        drain_both(&a, &r, 0, kinds);
        tri[0] = tri[1], tri[1] = tri[2], tri[2] = w;
        check_triple(&a, &r, tri);
        if (rndn(400) == 0) { /* the engine finishes, stops or is cleared */
            unsigned what = rndn(3);
            if (what < 2)
                drain_both(&a, &r, 1, kinds);
            if (what == 2) {
                accept_reset(&a);
                aref_reset(&r);
            } else {
                accept_close(&a);
                aref_close(&r);
            }
            assert_same_state(&a, &r);
        }
    }
    drain_both(&a, &r, 1, kinds);
    assert_int_equal(accept_pending(&a), 0);
}

/* a walker at 1.5 m/s, a fix every 5 s (visnjan's pace and rate,
 * tests/data/ATTRIBUTION.md), on a gentle curve */
static void walker(engine_waypoint_t *w, int i)
{
    memset(w, 0, sizeof *w);
    w->t_s = i * 5.0;
    w->pos_m[0] = 300.0 * sin(0.025 * i);
    w->pos_m[1] = 300.0 * (1.0 - cos(0.025 * i));
}

/* N_FIX fixes of kind (0: boat, 1: walker) with a spike 300 m off the path
 * at the middle of the interval after fix `site`, or half an interval
 * before the first fix (site -1); returns the row count, *spike its seq */
static int build_early(engine_waypoint_t *rows, int kind, int site, uint32_t *spike)
{
    int n = 0;
    for (int i = -1; i < N_FIX; i++) {
        engine_waypoint_t a, b;
        if (i >= 0)
            (kind ? walker : boat)(&rows[n++], i);
        if (i != site)
            continue;
        (kind ? walker : boat)(&a, i < 0 ? 0 : i);
        (kind ? walker : boat)(&b, i + 1);
        for (int k = 0; k < ENGINE_AXES; k++)
            b.pos_m[k] = i < 0 ? a.pos_m[k] : 0.5 * (a.pos_m[k] + b.pos_m[k]);
        b.t_s = i < 0 ? a.t_s - 0.5 * (b.t_s - a.t_s) : 0.5 * (a.t_s + b.t_s);
        b.pos_m[1] += 300.0;
        rows[n++] = b;
        *spike = (uint32_t)n; /* its seq (below) */
    }
    for (int r = 0; r < n; r++)
        rows[r].seq = (uint32_t)r + 1;
    return n;
}

/*
 * Issue 12 "keep the good data": a spike before the first kept interval
 * (nothing kept yet, so no recent speed: the learned limit comes from the
 * window's chords alone).  Given the boat (5 m/s, 5 Hz) and a walker (1.5
 * m/s, a fix every 5 s), with one row 300 m off the path in the middle of
 * the interval after fix 0..9 (the first window and beyond it) or half an
 * interval before fix 0, when replayed with the default configuration,
 * then the spike alone is refused (its seq the one refusal), every good
 * fix is kept, the output never runs faster than twice the object's speed
 * (a kept spike makes it run at 60..3000 m/s), and it ends finished.
 */
static void test_spike_before_first_interval(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX + 1];
    static const double speed[2] = {5.0, 1.5}; /* m/s: boat(), walker() */
    int bad = 0;

    for (int kind = 0; kind < 2; kind++)
        for (int site = -1; site < 10; site++) {
            engine_status_t st;
            engine_setpoint_t last;
            seen_t seen = {0};
            uint32_t spike = 0;
            int n = build_early(rows, kind, site, &spike);
            replay_sp(rows, n, &st, &last, &seen);
            if (st.accepted != N_FIX || st.rejected != 1 || seen.nrej != 1 ||
                seen.rej_seq[0] != spike || seen.vmax > 2.0 * speed[kind] ||
                last.state != ENGINE_STATE_FINISHED) {
                print_message("%s, spike after fix %d (seq %u): accepted %llu rejected %llu "
                              "(first seq %u), fastest setpoint %.1f m/s, %s\n",
                              kind ? "walker" : "boat", site, spike,
                              (unsigned long long)st.accepted, (unsigned long long)st.rejected,
                              seen.nrej ? seen.rej_seq[0] : 0, seen.vmax,
                              engine_state_name(last.state));
                bad++;
            }
        }
    assert_int_equal(bad, 0);
}

/*
 * The pair cache of lib/engine/accept.c (chords and velocities computed once
 * per pair of waypoints held) gives the verdicts of the policy as it was
 * (tests/helpers/accept_ref.h): over 3000 random dirty tracks and
 * configurations, the same return of every offer and decide, the same
 * verdict (kind, reason, gap, waypoint), the same speed limit and recent
 * speed bit for bit, the same waypoints held.  The counts of each verdict
 * show the tracks reach every kind and reason.
 */
static void test_same_verdicts_as_reference(void **state)
{
    unsigned long kinds[2 + ENGINE_ERROR_COUNT] = {0};
    (void)state;
    rng_state = 12345;
    for (int t = 0; t < 3000; t++)
        run_track(50 + rndn(400), kinds);
    printf("verdicts: take %lu start %lu drop:", kinds[ACCEPT_TAKE], kinds[ACCEPT_START]);
    for (int e = 0; e < ENGINE_ERROR_COUNT; e++)
        if (kinds[2 + e])
            printf(" %s %lu", engine_reason_name(e) ? engine_reason_name(e) : "?", kinds[2 + e]);
    printf("\n");
    assert_true(kinds[ACCEPT_TAKE] > 0 && kinds[ACCEPT_START] > 0);
    static const int reasons[] = {ENGINE_EBACKWARDS, ENGINE_ESAMETIME,    ENGINE_ESPEED,
                                  ENGINE_EACCEL,     ENGINE_EUNCONFIRMED, ENGINE_ESTALE};
    for (size_t i = 0; i < sizeof reasons / sizeof reasons[0]; i++)
        assert_true(kinds[2 + reasons[i]] > 0);
}

/* The verdicts of rows (all of them offered, then closed) with rules, into
 * out (kind * 256 + reason, then the kept stamp's bits folded in); returns
 * their count */
static int verdicts(const engine_waypoint_t *rows, int n, unsigned rules, uint64_t *out)
{
    accept_config_t ac;
    static accept_t a;
    accept_verdict_t v;
    engine_config_t c;
    int k = 0;
    engine_config_default(&c);
    memset(&ac, 0, sizeof ac);
    ac.max_speed_m_s = engine_config_max_speed(&c);
    ac.max_accel_m_s2 = engine_config_max_accel(&c);
    ac.max_gap_s = c.max_gap_s;
    ac.learned = ac.stale = 1;
    ac.window = ACCEPT_WINDOW_MAX;
    ac.confirm = c.confirm;
    ac.rules = rules;
    accept_init(&a, &ac);
    for (int i = 0; i < n; i++) {
        accept_offer(&a, &rows[i]);
        while (accept_decide(&a, i == n - 1, &v)) {
            uint64_t bits;
            memcpy(&bits, &v.wp.t_s, sizeof bits);
            out[k++] = ((uint64_t)v.kind * 256u + (uint64_t)v.reason) ^ (bits * 31u);
        }
    }
    return k;
}

/*
 * ACCEPT_RULE_LATE looks at stamps, not at the pace alone: on regular
 * stamps (5 Hz) with one fix whose position lies back along the path (an
 * interval's worth: at its predecessor's pace it reads late, and its
 * successor cannot follow it), at every site of 20, the verdicts with the
 * rule are those without it, bit for bit.  The rule as first written
 * (the pace alone) re-stamped such fixes.
 */
static void test_late_needs_late_stamps(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX];
    static uint64_t with[2 * N_FIX], without[2 * N_FIX];
    for (int site = 40; site < 60; site++) {
        for (int i = 0; i < N_FIX; i++)
            boat(&rows[i], i);
        engine_waypoint_t back;
        boat(&back, site);
        for (int k = 0; k < 3; k++) /* a tenth of the way on from its predecessor */
            rows[site + 1].pos_m[k] = back.pos_m[k] +
                                      0.1 * (rows[site + 1].pos_m[k] - back.pos_m[k]);
        int n1 = verdicts(rows, N_FIX, 0, with);
        int n0 = verdicts(rows, N_FIX, ACCEPT_RULES_ALL & ~ACCEPT_RULE_LATE, without);
        assert_int_equal(n1, n0);
        assert_memory_equal(with, without, (size_t)n1 * sizeof with[0]);
    }
}

/*
 * ACCEPT_RULE_LATE (retime.c accept_retime_late): two fixes in a row written
 * late, their positions on the track at its pace but their stamps 1.48 and
 * 0.6 intervals late (the demo track's n2k_furuno_figure8_src52.csv at
 * 135.096 s and 135.120 s: 0.296 s and 0.12 s late at 5 Hz), so that the
 * first follows the anchor, the second follows the anchor, and the second
 * does not follow the first.  Replayed as they arrive, at every site of
 * three fragment periods: every fix kept (both re-stamped at the pace), no
 * underrun where D holds a fix 0.3 s late (delay_s 4.7 s: the settings' D
 * on this track holds 0.13 s, and a fix later than that is an underrun
 * whatever the acceptance does).  Before, the full window held both (its chains as long either
 * way) until its costs broke the tie and the first was re-stamped, then the
 * second likewise: 8 intervals each, and the output underran.
 */
static void test_late_fixes_cost_nothing(void **state)
{
    (void)state;
    static engine_waypoint_t rows[N_FIX];
    engine_config_t c, r;
    engine_config_default(&c);
    assert_int_equal(engine_config_resolve(&c, &r), 0);
    unsigned sites = 3 * (r.fragment - r.overlap), bad = 0, underran = 0;

    replay_delay_s = 4.7;
    for (int site = 40; site < 40 + (int)sites; site++) {
        engine_status_t st;
        int fin;
        for (int i = 0; i < N_FIX; i++) {
            boat(&rows[i], i);
            if (i == site + 1)
                rows[i].t_s += 1.48 * DT_S;
            if (i == site + 2)
                rows[i].t_s += 0.6 * DT_S;
        }
        replay(rows, N_FIX, &st, &fin);
        underran += st.underruns != 0;
        if (st.accepted != N_FIX || st.rejected || st.underruns || st.hard_stops || !fin ||
            st.retimed < 2) {
            print_message("late fixes after %d: accepted %llu rejected %llu underruns %llu "
                          "retimed %llu hard stops %llu finished %d\n",
                          site, (unsigned long long)st.accepted, (unsigned long long)st.rejected,
                          (unsigned long long)st.underruns, (unsigned long long)st.retimed,
                          (unsigned long long)st.hard_stops, fin);
            bad++;
        }
    }
    replay_delay_s = 0;
    print_message("two late fixes: %u of %u sites with an underrun\n", underran, sites);
    assert_int_equal(bad, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_one_bad_fix_costs_nothing),
        cmocka_unit_test(test_late_fixes_cost_nothing),
        cmocka_unit_test(test_late_needs_late_stamps),
        cmocka_unit_test(test_at_arrival_one_bad_fix),
        cmocka_unit_test(test_at_arrival_when_kept),
        cmocka_unit_test(test_long_frozen_run),
        cmocka_unit_test(test_reanchor_after_confirm),
        cmocka_unit_test(test_far_start_needs_confirmation),
        cmocka_unit_test(test_far_burst_unconfirmed),
        cmocka_unit_test(test_spike_before_first_interval),
        cmocka_unit_test(test_same_verdicts_as_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
