/*
 * test_accept_same.c - the acceptance policy's faster chain search changes
 * no verdict (issue 28).
 *
 * lib/engine/accept.c and the policy as it was before (tests/helpers/
 * accept_prev.h, the former files kept verbatim) are driven with the same
 * seeded tracks and configurations, and every answer of the two must be the
 * same: the return of each offer and each decide, every field of every
 * verdict (kind, reason, gap, stop, shift_s bit for bit, the waypoint with
 * its stamp as re-estimated), the counters of accept_decide_counted, and
 * between verdicts the waypoints held, the oldest one's stamp, the speed
 * limit, the recent speed and their median, bit for bit.
 *
 * The tracks: the rough walk of bench_engine (white-noise velocity), the
 * circle, smooth random motion, and stop-and-go motion whose stops are runs
 * of repeats; into them, at a rate of 0..30 %, spikes, frozen repeats,
 * equal and near-equal stamps, exact duplicates, backwards stamps, gaps
 * (plausible and far), bursts off the track, restarted clocks, NaN and
 * infinite values, and the source's velocity, right or wrong.  The
 * configurations: the engine's default (profile auto) and random ones
 * (limits, windows, confirm, rules, at_arrival), with the engine's finish,
 * clear and stop (close, reset) at random.  The counts of each verdict
 * show the tracks reach every kind and reason.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "accept.h"
#include "accept_prev.h"
#include "engine.h"

static uint64_t rng_state;

/* xorshift64* (the seed must not be 0), 53 bits in [0, 1) */
static double rnd(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}

static unsigned rndn(unsigned n)
{
    return (unsigned)(rnd() * n) % n;
}

enum { M_ROUGH, M_CIRCLE, M_SMOOTH, M_STOPGO, M_COUNT };

typedef struct {
    int motion;
    double t, dt, pos[3], vel[3], phase, radius, speed, noise;
    unsigned fault_pct, seq, run_left, burst_left, vel_pct;
    int bursty;
    double burst_off[3];
    engine_waypoint_t last, prev;
} track_t;

static void track_init(track_t *tr)
{
    memset(tr, 0, sizeof *tr);
    tr->motion = (int)rndn(M_COUNT);
    tr->dt = (double[]){0.1, 0.2, 1.0, 0.05}[rndn(4)];
    tr->t = rnd() * 100.0;
    for (int k = 0; k < 3; k++) {
        tr->pos[k] = (rnd() - 0.5) * 1e4;
        tr->vel[k] = (rnd() - 0.5) * (double[]){1.0, 10.0, 60.0, 300.0}[rndn(4)];
    }
    tr->radius = 5.0 + rnd() * 100.0;
    tr->speed = (double[]){0.5, 5.0, 30.0, 250.0}[rndn(4)];
    tr->noise = rndn(2) ? 0.0 : 3.0 * rnd();
    tr->fault_pct = (unsigned[]){0, 1, 5, 10, 30}[rndn(5)];
    tr->vel_pct = (unsigned[]){0, 0, 50, 100}[rndn(4)];
    tr->bursty = rndn(4) == 0;
}

/* smooth random motion: the velocity changes now and then */
static void move_smooth(track_t *tr, double step)
{
    for (int k = 0; k < 3; k++) {
        if (rndn(4) == 0)
            tr->vel[k] += (rnd() - 0.5) * 2.0 * (1.0 + fabs(tr->vel[k]));
        tr->pos[k] += tr->vel[k] * step;
    }
}

static void track_base(track_t *tr, engine_waypoint_t *w)
{
    double step = tr->dt;
    memset(w, 0, sizeof *w);
    if (tr->bursty)
        step *= (double)rndn(4) * 0.5; /* 0: the same stamp again */
    else if (rndn(3) == 0)
        step *= 0.5 + rnd(); /* jitter */
    tr->t += step;
    switch (tr->motion) {
    case M_ROUGH: /* bench_engine's walk: a random step per axis */
        for (int k = 0; k < 3; k++)
            tr->pos[k] += (rnd() - 0.5) * 2.0 * tr->dt * 10.0;
        break;
    case M_CIRCLE:
        tr->phase += tr->speed * step / tr->radius;
        tr->pos[0] = tr->radius * cos(tr->phase);
        tr->pos[1] = tr->radius * sin(tr->phase);
        break;
    case M_STOPGO:
        if (tr->run_left) { /* standing: the same position */
            tr->run_left--;
            break;
        }
        if (rndn(12) == 0)
            tr->run_left = (unsigned[]){1, 2, 3, 7, 12, 300}[rndn(6)];
        move_smooth(tr, step);
        break;
    default: move_smooth(tr, step); break;
    }
    for (int k = 0; k < 3; k++)
        w->pos_m[k] = tr->pos[k] + (tr->run_left ? 0.0 : (rnd() - 0.5) * tr->noise);
    w->t_s = tr->t;
    if (rndn(100) < tr->vel_pct) { /* the source's velocity: the chord's, noisy or wrong */
        w->has_vel = 1;
        for (int k = 0; k < 3; k++)
            w->vel_m_s[k] = (w->pos_m[k] - tr->last.pos_m[k]) / tr->dt +
                            (rndn(8) ? (rnd() - 0.5) : (rnd() - 0.5) * 100.0);
    }
}

static void track_fault(track_t *tr, engine_waypoint_t *w)
{
    switch (rndn(12)) {
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
    case 8: /* not a number, or infinite */
        if (rndn(2))
            w->pos_m[rndn(3)] = rndn(2) ? NAN : INFINITY;
        else
            w->t_s = rndn(2) ? NAN : -INFINITY;
        break;
    case 9: /* a small spike (noise that a loose limit lets through) */
        for (int k = 0; k < 3; k++)
            w->pos_m[k] += (rnd() - 0.5) * 20.0 * tr->dt * (1.0 + fabs(tr->vel[k]));
        break;
    default: /* a stamp within a nanosecond of the last */
        w->t_s = tr->last.t_s + (rnd() - 0.5) * 2e-9;
        break;
    }
}

/* the next waypoint: the motion (off by a burst's offset while one lasts),
 * or now and then a fault instead */
static void track_next(track_t *tr, engine_waypoint_t *w)
{
    int burst = tr->burst_left > 0;
    track_base(tr, w);
    for (int k = 0; burst && k < 3; k++)
        w->pos_m[k] += tr->burst_off[k];
    if (burst)
        tr->burst_left--;
    else if (rndn(100) < tr->fault_pct)
        track_fault(tr, w);
    w->seq = ++tr->seq;
    tr->prev = tr->last;
    tr->last = *w;
}

/* the engine's default (profile auto), as bench_engine's, or a random one */
static void random_config(accept_config_t *c)
{
    static const double speeds[] = {0.0, 5.0, 40.0, 100.0, 400.0};
    static const double accels[] = {0.0, 3.0, 30.0, 100.0};
    static const double gaps[] = {0.5, 5.0, 60.0, 1e9};
    memset(c, 0, sizeof *c);
    if (rndn(3) == 0) {
        engine_config_t e;
        engine_config_default(&e);
        c->max_speed_m_s = engine_config_max_speed(&e);
        c->max_accel_m_s2 = engine_config_max_accel(&e);
        c->max_gap_s = e.max_gap_s;
        c->learned = 1;
        c->stale = 1;
        c->window = rndn(2) ? ACCEPT_WINDOW_MAX : 1 + rndn(ACCEPT_WINDOW_MAX);
        c->confirm = e.confirm;
        c->at_arrival = rndn(4) == 0;
        return;
    }
    c->max_speed_m_s = speeds[rndn(5)];
    c->max_accel_m_s2 = accels[rndn(4)];
    c->max_gap_s = gaps[rndn(4)];
    c->learned = (int)rndn(2);
    c->stale = (int)rndn(2);
    c->window = rndn(ACCEPT_WINDOW_MAX + 2); /* 0 and 9: clamped */
    c->confirm = rndn(ACCEPT_WINDOW_MAX + 2);
    switch (rndn(4)) {
    case 0: c->rules = ACCEPT_RULES_FORMER; break;
    case 1: c->rules = rndn(ACCEPT_RULES_ALL + 1); break;
    default: c->rules = 0; /* all */
    }
    c->at_arrival = rndn(3) == 0;
}

/* where a difference was found, for the failure message */
static unsigned cur_track, cur_point;

static void same_bits(double x, double y, const char *what)
{
    if (memcmp(&x, &y, sizeof x) != 0)
        fail_msg("track %u point %u: %s %.17g, was %.17g", cur_track, cur_point, what, x, y);
}

static void same_int(long x, long y, const char *what)
{
    if (x != y)
        fail_msg("track %u point %u: %s %ld, was %ld", cur_track, cur_point, what, x, y);
}

static void same_state(accept_t *a, accept_prev_t *p)
{
    same_int(accept_pending(a), accept_prev_pending(p), "pending");
    same_bits(accept_first_t(a), accept_prev_first_t(p), "first_t");
    same_bits(accept_speed_limit(a), accept_prev_speed_limit(p), "speed limit");
    same_bits(accept_recent_speed(a), accept_prev_recent_speed(p), "recent speed");
    same_bits(accept_recent_median(a), accept_prev_recent_median(p), "recent median");
}

static void same_verdict(const accept_verdict_t *v, const accept_verdict_t *w)
{
    same_int(v->kind, w->kind, "kind");
    same_int(v->reason, w->reason, "reason");
    same_int(v->gap, w->gap, "gap");
    same_int(v->stop, w->stop, "stop");
    same_bits(v->shift_s, w->shift_s, "shift_s");
    if (memcmp(&v->wp, &w->wp, sizeof v->wp) != 0)
        fail_msg("track %u point %u: verdict on seq %u (t %.17g), was seq %u (t %.17g)", cur_track,
                 cur_point, v->wp.seq, v->wp.t_s, w->wp.seq, w->wp.t_s);
}

static void same_status(const engine_status_t *s, const engine_status_t *t)
{
    same_int((long)s->accepted, (long)t->accepted, "accepted");
    same_int((long)s->stops, (long)t->stops, "stops");
    same_int((long)s->stop_fixes, (long)t->stop_fixes, "stop_fixes");
    same_int((long)s->retimed, (long)t->retimed, "retimed");
    same_bits(s->retime_max_s, t->retime_max_s, "retime_max_s");
}

/* counts of the verdicts seen: kinds, drop reasons, stops, re-stamped */
typedef struct {
    unsigned long kind[5], reason[ENGINE_ERROR_COUNT], stop[4], shifted;
} counts_t;

static void count(counts_t *n, const accept_verdict_t *v)
{
    if (v->kind >= 0 && v->kind < 5)
        n->kind[v->kind]++;
    if (v->kind == ACCEPT_DROP && v->reason >= 0 && v->reason < ENGINE_ERROR_COUNT)
        n->reason[v->reason]++;
    if (v->stop >= 0 && v->stop < 4)
        n->stop[v->stop]++;
    n->shifted += v->shift_s > 0 || v->shift_s < 0;
}

/* every verdict there is now, from both (decide_counted as the engine asks,
 * or decide itself); the same, in the same order */
static void drain(accept_t *a, accept_prev_t *p, int closing, engine_status_t *s,
                  engine_status_t *t, counts_t *n)
{
    int counted = rndn(4) != 0;
    for (;;) {
        accept_verdict_t v, w;
        int d1, d2;
        memset(&v, 0xa5, sizeof v);
        memset(&w, 0xa5, sizeof w);
        d1 = counted ? accept_decide_counted(a, closing, &v, s) : accept_decide(a, closing, &v);
        d2 = counted ? accept_prev_decide_counted(p, closing, &w, t)
                     : accept_prev_decide(p, closing, &w);
        same_int(d1, d2, "decide");
        same_status(s, t);
        if (!d1)
            return;
        same_verdict(&v, &w);
        count(n, &v);
        same_state(a, p);
    }
}

static void run_track(unsigned npts, counts_t *n)
{
    accept_config_t cfg;
    accept_t a;
    accept_prev_t *p;
    engine_status_t s, t;
    track_t tr;
    engine_waypoint_t w, tri[3];

    memset(&s, 0, sizeof s);
    memset(&t, 0, sizeof t);
    memset(tri, 0, sizeof tri);
    random_config(&cfg);
    p = accept_prev_new(&cfg);
    /* the rules the policy before had (ACCEPT_RULE_LATE came after it:
     * tests/unit/test_accept.c test_late_fixes_cost_nothing) */
    if (!(cfg.rules & ACCEPT_RULES_FORMER)) {
        unsigned rules = cfg.rules ? cfg.rules & ~ACCEPT_RULE_LATE
                                   : ACCEPT_RULES_ALL & ~ACCEPT_RULE_LATE;
        cfg.rules = rules ? rules : ACCEPT_RULES_FORMER; /* (none of them) */
    }
    accept_init(&a, &cfg);
    assert_non_null(p);
    track_init(&tr);
    for (cur_point = 0; cur_point < npts; cur_point++) {
        double vlim = rndn(2) ? 0.0 : 50.0 * rnd();
        const engine_waypoint_t *pre;
        track_next(&tr, &w);
        same_int(accept_offer(&a, &w), accept_prev_offer(p, &w), "offer");
        same_state(&a, p);
        drain(&a, p, 0, &s, &t, n);
        tri[0] = tri[1], tri[1] = tri[2], tri[2] = w;
        pre = rndn(3) ? &tri[0] : NULL;
        same_int(accept_check(&a, pre, &tri[1], &tri[2], vlim),
                 accept_prev_check(p, pre, &tri[1], &tri[2], vlim), "check");
        if (rndn(300) == 0) { /* the engine finishes, stops or is cleared */
            unsigned what = rndn(3);
            if (what < 2)
                drain(&a, p, 1, &s, &t, n);
            if (what == 2) {
                accept_reset(&a);
                accept_prev_reset(p);
            } else {
                accept_close(&a);
                accept_prev_close(p);
            }
            same_state(&a, p);
        }
    }
    drain(&a, p, 1, &s, &t, n);
    same_int(accept_pending(&a), 0, "pending at the end");
    accept_prev_free(p);
}

/*
 * Given 4000 seeded tracks of 50..650 waypoints (rough walks, circles,
 * smooth and stop-and-go motion, with every kind of fault) and random
 * configurations, when both policies judge them, then every answer is the
 * same (see above), and the verdicts reach every kind, every reason, every
 * kind of stop and re-stamped fixes.
 */
static void test_same_verdicts_as_before(void **state)
{
    counts_t n;
    (void)state;
    memset(&n, 0, sizeof n);
    rng_state = 28;
    for (cur_track = 0; cur_track < 4000; cur_track++)
        run_track(50 + rndn(600), &n);
    printf("verdicts: take %lu start %lu drop %lu halt %lu dwell %lu; stops one %lu after %lu "
           "halt %lu; re-stamped %lu; drop:",
           n.kind[ACCEPT_TAKE], n.kind[ACCEPT_START], n.kind[ACCEPT_DROP], n.kind[ACCEPT_HALT],
           n.kind[ACCEPT_DWELL], n.stop[ACCEPT_STOP_ONE], n.stop[ACCEPT_STOP_AFTER],
           n.stop[ACCEPT_STOP_HALT], n.shifted);
    for (int e = 0; e < ENGINE_ERROR_COUNT; e++)
        if (n.reason[e])
            printf(" %s %lu", engine_reason_name(e) ? engine_reason_name(e) : "?", n.reason[e]);
    printf("\n");
    for (int k = 0; k < 5; k++)
        assert_true(n.kind[k] > 0);
    for (int k = 1; k < 4; k++)
        assert_true(n.stop[k] > 0);
    assert_true(n.shifted > 0);
    static const int reasons[] = {ENGINE_EBACKWARDS, ENGINE_ESAMETIME,    ENGINE_ESPEED,
                                  ENGINE_EACCEL,     ENGINE_EUNCONFIRMED, ENGINE_ESTALE};
    for (size_t i = 0; i < sizeof reasons / sizeof reasons[0]; i++)
        assert_true(n.reason[reasons[i]] > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_same_verdicts_as_before),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
