/*
 * test_lifecycle.c - the one owner of an object's motion (lib/engine/lifecycle.h,
 * lib/engine/LIFECYCLE.md): every cell of its table, with the object moving.
 *
 * The property test drives an object along a circle (2 m/s, waypoints at
 * 10 Hz, sent on as in real time) and fires random events of every kind at
 * random ticks, from whatever state the object is in, relative and on the
 * epoch clock.  On every setpoint (the references are the object's own
 * configured limits, and the positions alone, by finite differences as the
 * safety monitor judges them):
 *   - no step beyond v T (one period T, also after a stall of N periods),
 *   - no change of velocity beyond a T, except on the tick the monitor's
 *     fault freezes the commanded state (its own hold, lifecycle.h); a drive
 *     fault or boot-up brakes the object to rest within its limits,
 *   - the first setpoint after a re-anchor at the drives is their reported
 *     position,
 *   - held (by the monitor, or at rest after a drive's) or stopped
 *     (latched), the position does not move,
 *   - the safety monitor, set to those limits, never refuses a setpoint.
 * Every cell (state x event) of the table is hit.
 * v = max_speed_m_s; a = 3 max_accel_m_s2 + scale_accel_m_s2 (the curve
 * through waypoints of implied acceleration a_w stays within 3 a_w, the time
 * scaling adds scale_accel_m_s2; transfers are configured below both).
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "catchup.h"
#include "engine.h"
#include "lifecycle.h"
#include "safety.h"

#define PERIOD_NS 10000000LL /* 100 Hz */
#define T_S 0.01
#define WP_EVERY 10           /* ticks between waypoints: 10 Hz */
#define EPOCH_S 1700000000.0  /* the clocked variant's sender time base */
#define DELAY_NS 3000000000LL /* its play-out delay D */
#define TOL_M 1e-9

typedef struct {
    engine_config_t cfg;
    engine_t *e;
    safety_t sf;
    lifecycle_t lc;
    double vlim, alim;
    int clocked;
    int64_t now;     /* the caller's clock (ns) */
    int64_t clk_off; /* the daemon's view of the sender's clock, less the truth */
    int64_t pause_until;
    uint32_t seq;
    int64_t next_wp; /* sim time of the next waypoint */
    double drive[3]; /* the drive's position */
    int drive_lost;
    int anchor_pending;
    double anchor[3];
    engine_setpoint_t prev;
    int nprev;    /* setpoints with a position in a row: 0, 1, 2+ */
    double pv[3]; /* velocity by finite differences at the last one */
    lc_state_t prev_state;
    int freeze_ok; /* this tick may stop the commanded state at once */
    uint64_t ticks;
    unsigned *hits; /* LC_STATE_COUNT x LC_EV_COUNT */
    double max_step, max_dv;
    uint64_t allowed_faults; /* monitor refusals a test provokes on purpose */
    lc_event_t last_ev;      /* for the failure messages */
    uint64_t last_ev_tick;
} sim_t;

static void track(double t, double *p)
{
    p[0] = 10.0 * cos(0.2 * t);
    p[1] = 10.0 * sin(0.2 * t);
    p[2] = 0.1 * t;
}

static void config(engine_config_t *c)
{
    engine_config_default(c);
    c->period_ns = PERIOD_NS;
    c->max_speed_m_s = 5.0;
    c->max_accel_m_s2 = 2.0;
    c->transfer_speed_m_s = 3.0;
    c->transfer_accel_m_s2 = 1.0;
    c->scale_accel_m_s2 = 2.0;
    c->scale_jerk_m_s3 = 20.0;
    c->max_gap_s = 2.0;
}

static void sim_init(sim_t *s, int clocked, unsigned *hits)
{
    memset(s, 0, sizeof *s);
    config(&s->cfg);
    s->e = engine_new(&s->cfg, NULL);
    assert_non_null(s->e);
    s->vlim = ENGINE_SPEED_CAP * s->cfg.max_speed_m_s; /* engine.h: the output's bound */
    s->alim = 3.0 * s->cfg.max_accel_m_s2 + s->cfg.scale_accel_m_s2;
    safety_limits_t lim = {.max_speed_m_s = s->vlim * 1.0001,
                           .max_accel_m_s2 = s->alim * 1.0001,
                           .tol_m = SAFETY_TOL_M_DEFAULT};
    safety_init(&s->sf, &lim);
    assert_int_equal(lc_init(&s->lc, s->e, &s->sf, PERIOD_NS, 0), 0);
    s->clocked = clocked;
    s->now = 1000 * PERIOD_NS;
    s->next_wp = s->now;
    s->hits = hits;
    s->prev_state = lc_state(&s->lc);
}

static void sim_free(sim_t *s)
{
    lc_free(&s->lc);
    engine_free(s->e);
}

static double sim_t_s(const sim_t *s, int64_t at)
{
    return (s->clocked ? EPOCH_S : 0.0) + (double)at * 1e-9;
}

static void hit(sim_t *s, lc_event_t ev)
{
    if (ev != LC_EV_WAYPOINT) {
        s->last_ev = ev;
        s->last_ev_tick = s->ticks;
    }
    if (s->hits)
        s->hits[lc_state(&s->lc) * LC_EV_COUNT + ev]++;
}

/* The waypoints due by now (all of them at once after a stall). */
static void send_due(sim_t *s)
{
    while (s->next_wp <= s->now) {
        if (s->next_wp >= s->pause_until) {
            engine_waypoint_t w;
            memset(&w, 0, sizeof w);
            w.t_s = sim_t_s(s, s->next_wp);
            track((double)s->next_wp * 1e-9, w.pos_m);
            w.seq = ++s->seq;
            hit(s, LC_EV_WAYPOINT);
            (void)lc_push(&s->lc, &w);
        }
        s->next_wp += WP_EVERY * PERIOD_NS;
    }
}

static void fire(sim_t *s, lc_event_t ev, double ratio)
{
    lc_arg_t a = {ratio, NULL, s->drive};
    lc_state_t st = lc_state(&s->lc);
    hit(s, ev);
    int rc = lc_event(&s->lc, ev, &a);
    if ((ev == LC_EV_DRIVE_ENABLED || ev == LC_EV_FIRST_POSITION) && rc == 0 &&
        ((st == LC_HELD && s->lc.have_reported) /* noted (not while a drive hold brakes) */ ||
         (st == LC_NO_POSITION && s->lc.have_sent == 0) ||
         (st == LC_NO_POSITION && s->drive_lost))) {
        s->anchor_pending = 1;
        memcpy(s->anchor, s->drive, sizeof s->anchor);
    }
    if (ev == LC_EV_SAFETY) /* the monitor's own hold; a drive's brakes (issue 23) */
        s->freeze_ok = 1;
    if ((ev == LC_EV_DRIVE_LOST || ev == LC_EV_DRIVE_BOOTUP) && lc_state(&s->lc) == LC_HELD)
        s->anchor_pending = 0; /* where the drives are must come again */
}

/* Event ev, as it happens to a moving object (the sender's pauses for the
 * curve's own events, a late tick for a stall, a jump of the clock). */
static void do_event(sim_t *s, lc_event_t ev)
{
    switch (ev) {
    case LC_EV_WAYPOINT: /* one now (they come every 10 ticks anyway) */
        s->pause_until = 0;
        s->next_wp = s->now;
        send_due(s);
        return;
    case LC_EV_GAP:
        hit(s, ev);
        (void)lc_event(&s->lc, ev, NULL);
        s->pause_until = s->now + (int64_t)((s->cfg.max_gap_s + 1.0) * 1e9);
        return;
    case LC_EV_UNDERRUN:
        hit(s, ev);
        (void)lc_event(&s->lc, ev, NULL);
        s->pause_until = s->now + 1000000000LL;
        return;
    case LC_EV_END_OF_INPUT:
        fire(s, ev, 0);
        s->pause_until = s->now + 3000000000LL;
        return;
    case LC_EV_OVERRIDE: fire(s, ev, 0.3 + 1.5 * rand() / (double)RAND_MAX); return;
    case LC_EV_DRIVE_LOST:
    case LC_EV_DRIVE_BOOTUP:
        fire(s, ev, 0);
        if (lc_state(&s->lc) == LC_HELD) { /* it coasted on: not where trajd held it */
            s->drive_lost = 1;
            for (int k = 0; k < 3; k++)
                s->drive[k] += 0.5 * (rand() / (double)RAND_MAX - 0.5);
        }
        return;
    case LC_EV_STALL: {
        hit(s, ev);
        s->now += (int64_t)(2 + rand() % 150) * PERIOD_NS; /* the tick comes late */
        return;
    }
    case LC_EV_CLOCK_STEP:
        hit(s, ev);
        if (s->clocked)
            s->clk_off += (int64_t)((rand() % 2 ? 1 : -1) *
                                    (0.5 + 3.0 * rand() / (double)RAND_MAX) * 1e9);
        else
            (void)lc_event(&s->lc, ev, NULL);
        return;
    default: fire(s, ev, 0); return;
    }
}

static void random_event(sim_t *s)
{
    do_event(s, (lc_event_t)(rand() % LC_EV_COUNT));
}

/* One tick and the invariants on its setpoint. */
static void tick_check(sim_t *s)
{
    engine_setpoint_t sp;
    engine_clock_t clk = {(int64_t)(EPOCH_S * 1e9) + s->now + s->clk_off, DELAY_NS, 1.0, 0.05};
    send_due(s);
    assert_int_equal(lc_tick(&s->lc, s->now, s->clocked ? &clk : NULL, &sp), 0);
    lc_state_t st = lc_state(&s->lc);
    int has = !(sp.flags & ENGINE_SP_NO_POSITION);
    if (getenv("LC_DEBUG") && s->ticks + 30 > (uint64_t)atoll(getenv("LC_DEBUG")))
        fprintf(stderr, "tick %llu %s hold %u fault %d x %.6f %.6f fl %x\n",
                (unsigned long long)s->ticks, lc_state_name(st), s->lc.hold, s->sf.fault,
                sp.pos_m[0], sp.pos_m[1], sp.flags);
    if (!has) {
        s->nprev = 0;
    } else if (s->anchor_pending && st != LC_HELD) {
        /* re-anchored at the drives: exactly where they said they are */
        for (int k = 0; k < 3; k++)
            if (!(fabs(sp.pos_m[k] - s->anchor[k]) <= TOL_M))
                fail_msg("re-anchored at %.9g, the drive reported %.9g (axis %d, state %s -> %s, "
                         "tick %llu, last event %s at %llu)",
                         sp.pos_m[k], s->anchor[k], k, lc_state_name(s->prev_state),
                         lc_state_name(st), (unsigned long long)s->ticks, lc_event_name(s->last_ev),
                         (unsigned long long)s->last_ev_tick);
        s->anchor_pending = 0;
        s->nprev = 1;
    } else if (s->nprev > 0) {
        double d2 = 0, v[3], dv2 = 0;
        for (int k = 0; k < 3; k++) {
            double d = sp.pos_m[k] - s->prev.pos_m[k];
            d2 += d * d;
            v[k] = d / T_S;
            dv2 += (v[k] - s->pv[k]) * (v[k] - s->pv[k]);
        }
        double step = sqrt(d2), dv = sqrt(dv2);
        if (step > s->vlim * T_S * 1.0001 + TOL_M)
            fail_msg("step %.6g m > v T = %.6g m (state %s -> %s, tick %llu)", step, s->vlim * T_S,
                     lc_state_name(s->prev_state), lc_state_name(st), (unsigned long long)s->ticks);
        int frozen_now = st == LC_HELD && s->prev_state != LC_HELD && (s->lc.hold & LC_HOLD_SAFETY);
        if (s->nprev > 1 && !frozen_now && !s->freeze_ok && dv > s->alim * T_S * 1.0001 + 1e-6)
            fail_msg("velocity change %.6g m/s > a T = %.6g m/s (state %s -> %s, tick %llu)", dv,
                     s->alim * T_S, lc_state_name(s->prev_state), lc_state_name(st),
                     (unsigned long long)s->ticks);
        /* held by the monitor, held at rest after a drive's brake, or latched:
         * not one nanometre */
        int at_rest = fabs(s->pv[0]) + fabs(s->pv[1]) + fabs(s->pv[2]) <= 1e-9;
        if ((st == LC_HELD && s->prev_state == LC_HELD &&
             ((s->lc.hold & LC_HOLD_SAFETY) || at_rest)) ||
            (st == LC_STOPPED && s->prev_state == LC_STOPPED))
            assert_true(step <= TOL_M);
        s->max_step = fmax(s->max_step, step);
        if (s->nprev > 1 && !frozen_now && !s->freeze_ok)
            s->max_dv = fmax(s->max_dv, dv);
        memcpy(s->pv, v, sizeof v);
        s->nprev = 2;
    } else {
        s->nprev = 1;
        memset(s->pv, 0, sizeof s->pv); /* a first position is at rest */
    }
    if (s->freeze_ok && st == LC_HELD)
        s->freeze_ok = 0;
    else if (s->freeze_ok && st != LC_HELD)
        s->freeze_ok = 0; /* the fault event found nothing to freeze */
    if (!s->drive_lost && has)
        memcpy(s->drive, sp.pos_m, sizeof s->drive); /* a drive follows its targets */
    if (st != LC_HELD && st != LC_NO_POSITION)
        s->drive_lost = 0;
    s->prev = sp;
    s->prev_state = st;
    s->ticks++;
    uint64_t first = 0; /* the monitor never had to step in */
    for (int k = 0; k < SAFETY_FAULT_COUNT; k++)
        first += s->sf.by[k];
    if (first > s->allowed_faults)
        fail_msg("safety monitor: %s (%.6g, bound %.6g), state %s -> %s, tick %llu; last "
                 "event %s at tick %llu",
                 safety_strerror(s->sf.fault), s->sf.last_value, s->sf.last_limit,
                 lc_state_name(s->prev_state), lc_state_name(st), (unsigned long long)s->ticks,
                 lc_event_name(s->last_ev), (unsigned long long)s->last_ev_tick);
    s->now += PERIOD_NS;
}

static void run_random(int clocked, unsigned seed, unsigned *hits, double *max_step, double *max_dv)
{
    sim_t s;
    srand(seed);
    sim_init(&s, clocked, hits);
    for (int i = 0; i < 12000; i++) { /* 120 s */
        if (i > 300 && rand() % 120 == 0)
            random_event(&s);
        tick_check(&s);
    }
    *max_step = fmax(*max_step, s.max_step);
    *max_dv = fmax(*max_dv, s.max_dv);
    sim_free(&s);
}

/* Given random sequences of every event, with the object moving, relative
 * and on the epoch clock, then the invariants above hold on every setpoint
 * and every cell of the table is visited. */
static void test_property_every_cell(void **state)
{
    (void)state;
    static unsigned hits[LC_STATE_COUNT * LC_EV_COUNT];
    double max_step = 0, max_dv = 0;
    memset(hits, 0, sizeof hits);
    for (unsigned seed = 1; seed <= 60; seed++)
        run_random((int)(seed & 1), seed, hits, &max_step, &max_dv);
    unsigned visited = 0;
    for (int c = 0; c < LC_STATE_COUNT * LC_EV_COUNT; c++)
        visited += hits[c] != 0;
    fprintf(stderr,
            "random sequences: %u of %d cells visited (test_every_cell_directed: all); largest "
            "step %.4g m (v T %.4g), largest velocity change %.4g m/s (a T %.4g)\n",
            visited, LC_STATE_COUNT * LC_EV_COUNT, max_step, ENGINE_SPEED_CAP * 5.0 * T_S, max_dv,
            8.0 * T_S);
    assert_true(visited > LC_STATE_COUNT * LC_EV_COUNT / 2); /* the sequences did wander */
}

static engine_setpoint_t run(sim_t *s, int n);

/* Run until the object is in state st (at most n ticks); 1 if it got there. */
static int run_until(sim_t *s, lc_state_t st, int n)
{
    for (int i = 0; i < n && lc_state(&s->lc) != st; i++)
        run(s, 1);
    return lc_state(&s->lc) == st;
}

/* Bring a moving object into state st by what would bring it there. */
static int reach(sim_t *s, lc_state_t st)
{
    run(s, 800); /* moving at 2 m/s */
    switch (st) {
    case LC_NO_POSITION:
        fire(s, LC_EV_DRIVE_LOST, 0);
        run(s, 5);
        fire(s, LC_EV_CLEAR, 0); /* carried out once the object braked to rest */
        return run_until(s, LC_NO_POSITION, 1000);
    case LC_WAITING:
        s->pause_until = s->now + 600 * 1000000000LL;
        fire(s, LC_EV_CLEAR, 0);
        return run_until(s, LC_WAITING, 1000);
    case LC_STREAMING: break;
    case LC_UNDERRUN:
        s->pause_until = s->now + 6 * 1000000000LL;
        return run_until(s, LC_UNDERRUN, 1000);
    case LC_TRANSFER:
        s->pause_until = s->now + (int64_t)((s->cfg.max_gap_s + 2.0) * 1e9);
        return run_until(s, LC_TRANSFER, 3000);
    case LC_STOPPING: fire(s, LC_EV_STOP, 0); break;
    case LC_STOPPED: fire(s, LC_EV_STOP, 0); return run_until(s, LC_STOPPED, 1000);
    case LC_HELD: fire(s, LC_EV_DRIVE_LOST, 0); break;
    case LC_FEED_HELD: fire(s, LC_EV_HEARTBEAT_LOST, 0); break;
    case LC_FINISHED:
        fire(s, LC_EV_END_OF_INPUT, 0);
        s->pause_until = s->now + 600 * 1000000000LL;
        return run_until(s, LC_FINISHED, 2000);
    default: break;
    }
    return lc_state(&s->lc) == st;
}

/* Given a moving object brought into each state, when each event happens,
 * then the invariants hold through it and through a clear and a start
 * after it (every cell, relative and on the epoch clock). */
static void test_every_cell_directed(void **state)
{
    (void)state;
    static unsigned hits[LC_STATE_COUNT * LC_EV_COUNT];
    memset(hits, 0, sizeof hits);
    for (int clocked = 0; clocked < 2; clocked++)
        for (int st = 0; st < LC_STATE_COUNT; st++)
            for (int ev = 0; ev < LC_EV_COUNT; ev++) {
                sim_t s;
                srand((unsigned)(st * LC_EV_COUNT + ev));
                sim_init(&s, clocked, NULL);
                if (!reach(&s, (lc_state_t)st))
                    fail_msg("state %s not reached", lc_state_name((lc_state_t)st));
                s.hits = hits;
                do_event(&s, (lc_event_t)ev);
                s.hits = NULL;
                run(&s, 500);
                s.pause_until = 0;
                fire(&s, LC_EV_CLEAR, 0);
                if (s.drive_lost || lc_state(&s.lc) == LC_NO_POSITION)
                    fire(&s, LC_EV_DRIVE_ENABLED, 0);
                fire(&s, LC_EV_START, 0);
                run(&s, 1500);
                sim_free(&s);
            }
    for (int st = 0; st < LC_STATE_COUNT; st++)
        for (int ev = 0; ev < LC_EV_COUNT; ev++)
            if (hits[st * LC_EV_COUNT + ev] != 2) /* once relative, once clocked */
                fail_msg("cell %s x %s: %u times", lc_state_name((lc_state_t)st),
                         lc_event_name((lc_event_t)ev), hits[st * LC_EV_COUNT + ev]);
}

/* Every cell of the table is defined: an action, and a state or SAME/CURVE. */
static void test_table_complete(void **state)
{
    (void)state;
    for (int st = 0; st < LC_STATE_COUNT; st++)
        for (int ev = 0; ev < LC_EV_COUNT; ev++) {
            lc_cell_t c = lc_table[st][ev];
            assert_true(c.action > LC_A_UNDEFINED && c.action < LC_ACTION_COUNT);
            assert_true(c.next < LC_STATE_COUNT || c.next == LC_NEXT_SAME ||
                        c.next == LC_NEXT_CURVE);
            assert_string_not_equal(lc_action_name((lc_action_t)c.action), "?");
        }
}

/* One row of LIFECYCLE.md's table, as lc_table has it. */
static void table_row(int ev, char *out, size_t len)
{
    size_t n = (size_t)snprintf(out, len, "| %s |", lc_event_name((lc_event_t)ev));
    for (int st = 0; st < LC_STATE_COUNT && n < len; st++) {
        lc_cell_t c = lc_table[st][ev];
        const char *a = lc_action_name((lc_action_t)c.action);
        if (c.next == LC_NEXT_SAME)
            n += (size_t)snprintf(out + n, len - n, " %s |", a);
        else
            n += (size_t)snprintf(out + n, len - n, " %s \u2192 %s |", a,
                                  c.next == LC_NEXT_CURVE ? "c"
                                                          : lc_state_name((lc_state_t)c.next));
    }
}

/* The document's table (lib/engine/LIFECYCLE.md) is lc_table, cell for cell:
 * the one table, in code and in the document. */
static void test_document_is_the_table(void **state)
{
    (void)state;
    FILE *f = fopen("lib/engine/LIFECYCLE.md", "r");
    if (!f)
        f = fopen("../../lib/engine/LIFECYCLE.md", "r");
    assert_non_null(f); /* run from the repository's root (tests/run.sh does) */
    static char doc[65536];
    size_t n = fread(doc, 1, sizeof doc - 1, f);
    fclose(f);
    doc[n] = 0;
    for (int ev = 0; ev < LC_EV_COUNT; ev++) {
        char row[1024];
        table_row(ev, row, sizeof row);
        strcat(row, "\n");
        if (!strstr(doc, row))
            fail_msg("LIFECYCLE.md lacks the row %s", row);
    }
}

/* Run n ticks with the sender on; returns the last setpoint. */
static engine_setpoint_t run(sim_t *s, int n)
{
    for (int i = 0; i < n; i++)
        tick_check(s);
    return s->prev;
}

static double dist(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

/* Given an object moving at 2 m/s, when the safety monitor refuses a
 * setpoint (its speed bound lowered below the motion), then the curve stops
 * advancing (the output stands on the held position, tick after tick), and
 * after clear (the bound restored) it resumes from the held position by a
 * transfer and moves on, never refused again. */
static void test_clear_after_safety_hold(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 0, NULL);
    engine_setpoint_t sp = run(&s, 800);
    assert_int_equal(lc_state(&s.lc), LC_STREAMING);
    safety_limits_t low = {
        .max_speed_m_s = 1.0, .max_accel_m_s2 = s.alim, .tol_m = SAFETY_TOL_M_DEFAULT};
    safety_set_limits(&s.sf, &low);
    engine_setpoint_t raw;
    assert_int_equal(lc_tick(&s.lc, s.now, NULL, &raw), 0);
    s.now += PERIOD_NS;
    assert_true(raw.flags & ENGINE_SP_FAULT);
    assert_int_equal(lc_state(&s.lc), LC_HELD);
    double held[3];
    memcpy(held, raw.pos_m, sizeof held);
    assert_true(dist(held, sp.pos_m) < 1e-12); /* the last one sent */
    engine_status_t st0, st1;
    engine_status(s.e, &st0);
    safety_limits_t ok = {.max_speed_m_s = s.vlim * 1.0001,
                          .max_accel_m_s2 = s.alim * 1.0001,
                          .tol_m = SAFETY_TOL_M_DEFAULT};
    safety_set_limits(&s.sf, &ok);
    uint64_t v0 = s.sf.violations;
    s.allowed_faults = 1; /* the refusal above was the point */
    s.prev = raw;
    s.prev_state = LC_HELD;
    s.nprev = 1;
    sp = run(&s, 500);
    engine_status(s.e, &st1);
    assert_true(dist(sp.pos_m, held) < 1e-12);      /* held, 5 s */
    assert_int_equal(st1.setpoints, st0.setpoints); /* the curve did not advance */
    assert_true(lc_buffered(&s.lc) > 0);            /* what came meanwhile is kept */
    lc_arg_t none = {0, NULL, NULL};
    assert_int_equal(lc_event(&s.lc, LC_EV_CLEAR, &none), 0);
    assert_int_equal(safety_fault(&s.sf), 0);
    int transfer = 0;
    for (int i = 0; i < 1500; i++) {
        sp = run(&s, 1);
        transfer |= lc_state(&s.lc) == LC_TRANSFER;
    }
    assert_true(transfer);                   /* joined by a transfer */
    assert_true(dist(sp.pos_m, held) > 1.0); /* and moving on the track again */
    assert_int_equal(lc_state(&s.lc), LC_STREAMING);
    assert_true(v0 >= 1);
    sim_free(&s);
}

/* Given an object moving, when it is stopped and its sender goes on for 10 s,
 * then it stays at rest (latched: STOPPED), the waypoints are buffered and
 * counted; start joins the live track by a transfer, the buffered waypoints
 * already in the past dropped and counted; a second stop latches again. */
static void test_stop_latches_until_start(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 0, NULL);
    run(&s, 800);
    lc_arg_t none = {0, NULL, NULL};
    assert_int_equal(lc_event(&s.lc, LC_EV_STOP, &none), 0);
    assert_int_equal(lc_state(&s.lc), LC_STOPPING);
    engine_setpoint_t sp = run(&s, 300);
    assert_int_equal(lc_state(&s.lc), LC_STOPPED);
    double rest[3];
    memcpy(rest, sp.pos_m, sizeof rest);
    sp = run(&s, 1000); /* the sender goes on: 100 waypoints */
    assert_int_equal(lc_state(&s.lc), LC_STOPPED);
    assert_true(dist(sp.pos_m, rest) < 1e-12);
    assert_true(s.lc.n.buffered >= 100);
    double newest = s.lc.newest_t, delay = s.lc.delay_s;
    assert_true(delay > 0.5 && delay < 5.0); /* how far behind its data it ran */
    assert_int_equal(lc_event(&s.lc, LC_EV_START, &none), 0);
    assert_true(s.lc.n.dropped_past > 0); /* the old ones: only the newest are joined */
    int transfer = 0;
    double joined_t = NAN;
    for (int i = 0; i < 3000; i++) {
        engine_setpoint_t p = run(&s, 1);
        if (lc_state(&s.lc) == LC_TRANSFER)
            transfer = 1;
        else if (transfer && isnan(joined_t))
            joined_t = p.t_s;
    }
    assert_true(transfer);
    assert_int_equal(lc_state(&s.lc), LC_STREAMING);
    /* the live track: the trajectory it joined starts as far behind the
     * newest waypoint at the start as the object ran behind its data */
    assert_true(joined_t >= newest - delay - 0.1 - 1e-9);
    assert_true(joined_t <= newest - delay + 0.1 + 1e-9);
    assert_int_equal(lc_event(&s.lc, LC_EV_STOP, &none), 0);
    run(&s, 300);
    assert_int_equal(lc_state(&s.lc), LC_STOPPED);
    sim_free(&s);
}

/* Given an object that never streamed, stopped (a job written while it waits
 * for its start), when 300 waypoints are written (x 0 .. 29.9 m, 0.1 s apart),
 * then the latch buffer keeps the first LC_LATCH_MIN and refuses the others
 * with -ENGINE_EFULL, counted (the sender is told, as by the engine's full
 * buffer), the room shown is 0; start plays the whole buffered job from its
 * first waypoint, none dropped as past.  Before, a ring of 64 kept the
 * newest, every write was taken, and start dropped all but the lookahead's:
 * of 200 written over Modbus, 181 were gone with no counter. */
static void test_job_written_while_stopped(void **state)
{
    (void)state;
    engine_config_t c;
    config(&c);
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    lifecycle_t lc;
    assert_int_equal(lc_init(&lc, e, NULL, PERIOD_NS, 0), 0);
    lc_arg_t none = {0, NULL, NULL};
    assert_int_equal(lc_event(&lc, LC_EV_STOP, &none), 0);
    assert_int_equal(lc_state(&lc), LC_STOPPED);
    for (int i = 0; i < 300; i++) {
        engine_waypoint_t w = {.t_s = 0.1 * i, .pos_m = {0.1 * i, 0, 0}, .seq = (uint32_t)i + 1};
        lc_arg_t a = {0, &w, NULL};
        assert_int_equal(lc_event(&lc, LC_EV_WAYPOINT, &a), i < LC_LATCH_MIN ? 0 : -ENGINE_EFULL);
    }
    assert_int_equal(lc.n.refused_full, 300 - LC_LATCH_MIN);
    /* the sender offering the last one again (a replay at every tick, a Modbus
     * client retrying) is the same refusal: counted once (a held replay
     * counted 57 134 for a track of 600 rows) */
    for (int k = 0; k < 5; k++) {
        engine_waypoint_t w = {.t_s = 0.1 * 299, .pos_m = {0.1 * 299, 0, 0}, .seq = 300};
        lc_arg_t a = {0, &w, NULL};
        assert_int_equal(lc_event(&lc, LC_EV_WAYPOINT, &a), -ENGINE_EFULL);
    }
    assert_int_equal(lc.n.refused_full, 300 - LC_LATCH_MIN);
    assert_int_equal(lc_free_room(&lc, 4096), 0);
    assert_int_equal(lc_event(&lc, LC_EV_START, &none), 0);
    assert_int_equal(lc.n.dropped_past, 0);
    double xmin = INFINITY, xmax = -INFINITY;
    engine_setpoint_t sp;
    for (int64_t k = 0; k < 10000; k++) {
        assert_int_equal(lc_tick(&lc, (1000 + k) * PERIOD_NS, NULL, &sp), 0);
        if (!(sp.flags & ENGINE_SP_NO_POSITION)) {
            xmin = fmin(xmin, sp.pos_m[0]);
            xmax = fmax(xmax, sp.pos_m[0]);
        }
    }
    assert_true(xmin <= 1e-9);
    assert_true(xmax >= 0.1 * (LC_LATCH_MIN - 1) - 1e-6);
    lc_free(&lc);
    engine_free(e);
}

/* Given an object moving at 2 m/s, when its caller stalls 100 periods (1 s),
 * then the next setpoint goes on from the last one sent (one period of
 * motion, not 100), the stall is counted, and a relative object reports the
 * lag. */
/* Given the circle at 2 m/s with y held to 0.8 m/s (issue 32: the per-axis
 * limits slow it along its path, so it falls behind its input) and
 * max_lag_s 2, when the lag passes 2 s, then the lifecycle's lag event
 * stops the object from motion to rest (every tick within the speed and
 * acceleration bounds: tick_check), latched while the sender goes on; a
 * start brings it back to the live track by a transfer, streaming again;
 * and that trajectory, slowed as much, is stopped by its own lag event. */
static void test_lag_stop_from_motion(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 0, NULL);
    lc_free(&s.lc);
    engine_free(s.e);
    s.cfg.axis_max_speed_m_s[1] = 0.8;
    s.cfg.max_lag_s = 2.0;
    s.e = engine_new(&s.cfg, NULL);
    assert_non_null(s.e);
    assert_int_equal(lc_init(&s.lc, s.e, &s.sf, PERIOD_NS, 0), 0);
    assert_true(run_until(&s, LC_STOPPING, 20000));
    double v = 0; /* the object was moving when the event came */
    for (int k = 0; k < 3; k++)
        v += s.pv[k] * s.pv[k];
    assert_true(sqrt(v) > 0.3);
    assert_int_equal(s.lc.n.events[LC_EV_LAG], 1);
    engine_status_t st;
    engine_status(s.e, &st);
    assert_true(st.axis_lag_s > 2.0 && st.axis_lag_stops == 1);
    assert_true(run_until(&s, LC_STOPPED, 3000));
    engine_setpoint_t sp = run(&s, 500); /* the sender goes on: latched */
    assert_int_equal(lc_state(&s.lc), LC_STOPPED);
    double rest[3];
    memcpy(rest, sp.pos_m, sizeof rest);
    sp = run(&s, 200);
    assert_true(dist(sp.pos_m, rest) < 1e-12);
    lc_arg_t none = {0, NULL, NULL};
    assert_int_equal(lc_event(&s.lc, LC_EV_START, &none), 0);
    int moving = 0;
    for (int i = 0; i < 3000 && !moving; i++) {
        sp = run(&s, 1);
        moving = lc_state(&s.lc) == LC_STREAMING && dist(sp.pos_m, rest) > 1.0;
    }
    assert_true(moving);
    /* the trajectory it joined lags again: stopped again, once */
    assert_true(run_until(&s, LC_STOPPED, 20000));
    assert_int_equal(s.lc.n.events[LC_EV_LAG], 2);
    sim_free(&s);
}

static void test_stall_goes_on_from_last_sent(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 0, NULL);
    engine_setpoint_t a = run(&s, 800);
    s.now += 99 * PERIOD_NS;
    engine_setpoint_t b = run(&s, 1); /* tick_check: step <= v T */
    /* one period at the track's 2 m/s, or at the rate a catch-up wins back
     * a start's lag at (catchup.h) */
    assert_true(dist(a.pos_m, b.pos_m) < 2.1 * (1 + CATCHUP_DEFAULT) * T_S);
    assert_true(dist(a.pos_m, b.pos_m) > 1.0 * T_S); /* and it moved on */
    assert_true(b.flags & ENGINE_SP_SKIPPED);
    assert_int_equal(s.lc.n.events[LC_EV_STALL], 1);
    assert_int_equal(s.lc.n.stalled_periods, 99);
    assert_true(fabs(s.lc.n.lag_s - 0.99) < 1e-9);
    run(&s, 500);
    sim_free(&s);
}

/* Given an object on the epoch clock moving, when it stalls 2 s, then it
 * goes on from the last setpoint and wins the lag back within the catch-up
 * (5 %): its data age returns to D. */
static void test_stall_clocked_catches_up(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 1, NULL);
    engine_setpoint_t a = run(&s, 6000);
    double age0 = a.age_s;
    assert_true(fabs(age0 - 3.0) < 0.01);
    s.now += 199 * PERIOD_NS;
    engine_setpoint_t b = run(&s, 1);
    assert_true(b.age_s > age0 + 1.9); /* 2 s behind now */
    b = run(&s, 8000);                 /* 80 s: 2 s at 5 % take 40 s, and the ramps */
    assert_true(fabs(b.age_s - 3.0) < 0.01);
    sim_free(&s);
}

/* Given an object moving at 2 m/s, when one of its drives leaves Operation
 * Enabled (or boots), then the object is held and its commanded state brakes
 * to rest along the path within its limits (tick_check: no velocity change
 * beyond a T on any tick, the monitor never steps in), within the stopping
 * distance, and stays there while waypoints keep coming (buffered); a
 * position reported while it brakes is not noted -- not
 * frozen at once, a step the other axes' drives could not follow (issue 23). */
static void test_drive_lost_brakes_within_limits(void **state)
{
    (void)state;
    for (int boot = 0; boot < 2; boot++) {
        sim_t s;
        sim_init(&s, boot, NULL);
        engine_setpoint_t sp = run(&s, 800);
        double v = sqrt(sp.vel_m_s[0] * sp.vel_m_s[0] + sp.vel_m_s[1] * sp.vel_m_s[1] +
                        sp.vel_m_s[2] * sp.vel_m_s[2]);
        assert_true(v > 1.5);
        fire(&s, boot ? LC_EV_DRIVE_BOOTUP : LC_EV_DRIVE_LOST, 0);
        assert_int_equal(lc_state(&s.lc), LC_HELD);
        engine_setpoint_t h = run(&s, 1);
        assert_true(dist(h.pos_m, sp.pos_m) > 0.5 * v * T_S); /* braking, not frozen */
        /* the drives enabled again while it brakes: not where they will stand, not noted
         * (a clear would re-anchor the braking axes behind where they are) */
        assert_int_equal(lc_set_position(&s.lc, h.pos_m), 0);
        assert_int_equal(s.lc.have_reported, 0);
        h = run(&s, 300);
        assert_int_equal(lc_state(&s.lc), LC_HELD);
        assert_true(fabs(h.vel_m_s[0]) + fabs(h.vel_m_s[1]) + fabs(h.vel_m_s[2]) < 1e-9);
        double a = s.cfg.scale_accel_m_s2;
        assert_true(dist(h.pos_m, sp.pos_m) <= v * v / (2 * a) + 2 * v * T_S + 0.05);
        engine_setpoint_t later = run(&s, 300);
        assert_true(dist(later.pos_m, h.pos_m) < 1e-12); /* held at rest */
        assert_true(lc_buffered(&s.lc) > 0);
        sim_free(&s);
    }
}

/* Given an object moving, when one of its drives leaves Operation Enabled,
 * then the commanded state brakes to rest and is held; a position the
 * drives report while held is not kept (each axis re-anchors at its 0x6064
 * as reported after the clear); after clear nothing is sent (NO_POSITION)
 * until the drives report (0.3 m off), the first setpoint is that position,
 * and the object joins the track by a transfer from there.  A clear while
 * it still brakes is carried out at rest. */
static void test_drive_lost_reanchors_at_drive(void **state)
{
    (void)state;
    for (int given_before_clear = 0; given_before_clear < 3; given_before_clear++) {
        sim_t s;
        sim_init(&s, 0, NULL);
        run(&s, 800);
        fire(&s, LC_EV_DRIVE_LOST, 0);
        s.drive_lost = 1;
        s.drive[0] += 0.3;
        engine_setpoint_t h;
        if (given_before_clear == 2) { /* clear at once, while it brakes */
            lc_arg_t none = {0, NULL, NULL};
            assert_int_equal(lc_event(&s.lc, LC_EV_CLEAR, &none), 0);
            assert_int_equal(lc_state(&s.lc), LC_HELD);
            h = run(&s, 1);
            assert_true(fabs(h.vel_m_s[0]) + fabs(h.vel_m_s[1]) > 0.5); /* still braking */
            h = run(&s, 300);
            assert_true(h.flags & ENGINE_SP_NO_POSITION); /* at rest: cleared, the drives awaited */
            assert_int_equal(lc_state(&s.lc), LC_NO_POSITION);
            assert_int_equal(lc_set_position(&s.lc, s.drive), 0);
            s.anchor_pending = 1;
            memcpy(s.anchor, s.drive, sizeof s.anchor);
            run(&s, 1);
            assert_int_equal(s.anchor_pending, 0);
            assert_true(run_until(&s, LC_STREAMING, 3000)); /* joined the track */
            sim_free(&s);
            continue;
        }
        h = run(&s, 300);
        assert_true(fabs(h.vel_m_s[0]) + fabs(h.vel_m_s[1]) + fabs(h.vel_m_s[2]) < 1e-9);
        engine_setpoint_t sp = h;
        h = run(&s, 200);
        assert_true(dist(h.pos_m, sp.pos_m) < 1e-12);
        lc_arg_t none = {0, NULL, NULL};
        if (given_before_clear) {
            double stale[3] = {s.drive[0] - 0.2, s.drive[1], s.drive[2]};
            assert_int_equal(lc_set_position(&s.lc, stale), 0); /* taken, not kept */
            assert_int_equal(s.lc.have_reported, 0);
        }
        assert_int_equal(lc_event(&s.lc, LC_EV_CLEAR, &none), 0);
        h = run(&s, 50);
        assert_true(h.flags & ENGINE_SP_NO_POSITION); /* nothing a drive would follow */
        assert_int_equal(lc_state(&s.lc), LC_NO_POSITION);
        assert_int_equal(lc_set_position(&s.lc, s.drive), 0);
        s.anchor_pending = 1;
        memcpy(s.anchor, s.drive, sizeof s.anchor);
        run(&s, 1); /* tick_check: exactly at the drive's position */
        assert_int_equal(s.anchor_pending, 0);
        int transfer = 0;
        for (int i = 0; i < 1500; i++) {
            run(&s, 1);
            transfer |= lc_state(&s.lc) == LC_TRANSFER;
        }
        assert_true(transfer);
        assert_int_equal(lc_state(&s.lc), LC_STREAMING);
        sim_free(&s);
    }
}

/* Given an object on the epoch clock moving, when CLOCK_REALTIME steps 5 s
 * ahead, then 5 s back, then no setpoint steps (tick_check) and the object
 * returns to the play time. */
static void test_clock_step(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 1, NULL);
    run(&s, 1500);
    s.clk_off += 5000000000LL;
    run(&s, 3);
    assert_true(s.lc.n.clock_steps >= 1);
    run(&s, 2000);
    s.clk_off -= 5000000000LL;
    run(&s, 3);
    assert_true(s.lc.n.clock_steps >= 2);
    engine_setpoint_t b = run(&s, 15000);
    assert_true(fabs(b.age_s - 3.0) < 0.01);
    sim_free(&s);
}

/* Given two trajectories 5 s apart in time and 40 m apart in space, then
 * during the transfer between them t_s says where the object is heading: it
 * runs on towards the second's first time and reaches it as the transfer
 * ends, never standing at a time of the first trajectory. */
static void test_transfer_t_s(void **state)
{
    (void)state;
    engine_config_t c;
    config(&c);
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    engine_waypoint_t w;
    for (int i = 0; i <= 40; i++) {
        memset(&w, 0, sizeof w);
        w.t_s = 0.1 * i;
        w.pos_m[0] = 0.1 * i;
        assert_int_equal(engine_push(e, &w), 0);
    }
    for (int i = 0; i <= 40; i++) {
        memset(&w, 0, sizeof w);
        w.t_s = 9.0 + 0.1 * i;
        w.pos_m[0] = 44.0 + 0.1 * i;
        assert_true(engine_push(e, &w) >= 0);
    }
    assert_int_equal(engine_finish(e), 0);
    engine_setpoint_t sp;
    double last_t = -1, first_xfer_t = NAN, end_xfer_t = NAN;
    int in_xfer = 0, n_xfer = 0;
    for (int64_t k = 0; k < 5000; k++) {
        assert_int_equal(engine_tick(e, k * PERIOD_NS, &sp), 0);
        if (sp.flags & ENGINE_SP_TRANSFER) {
            if (!in_xfer)
                first_xfer_t = sp.t_s;
            in_xfer = 1;
            n_xfer++;
            assert_true(sp.t_s >= last_t - 1e-9); /* runs on */
            assert_true(sp.t_s <= 9.0 + 1e-9);    /* towards the second's start */
            end_xfer_t = sp.t_s;
        } else if (in_xfer) {
            break;
        }
        last_t = sp.t_s;
    }
    assert_true(n_xfer > 100);
    assert_true(first_xfer_t < 9.0 - 1.0);      /* the transfer's time ahead */
    assert_true(fabs(end_xfer_t - 9.0) < 0.05); /* reached as it ends */
    assert_true(fabs(sp.t_s - 9.0) < 0.05);     /* and the track goes on */
    engine_free(e);
}

/* Given a stopped object and a held one, when a reload gives each a new
 * curve (its settings changed), then the new owner keeps the latch and the
 * hold, standing where the old one was sent: the sender going on does not
 * move it, and only start / clear do (as LIFECYCLE.md's reload row says). */
static void test_reload_keeps_latch_and_hold(void **state)
{
    (void)state;
    for (int held = 0; held < 2; held++) {
        sim_t s;
        sim_init(&s, 0, NULL);
        run(&s, 800);
        fire(&s, held ? LC_EV_DRIVE_LOST : LC_EV_STOP, 0);
        engine_setpoint_t at = run(&s, 400);
        assert_int_equal(lc_state(&s.lc), held ? LC_HELD : LC_STOPPED);
        /* the reload: a new engine and owner, from the old one */
        engine_t *e2 = engine_new(&s.cfg, NULL);
        assert_non_null(e2);
        lifecycle_t lc2;
        assert_int_equal(lc_init(&lc2, e2, &s.sf, PERIOD_NS, 0), 0);
        lc_inherit(&lc2, &s.lc);
        assert_int_equal(engine_set_position(e2, at.pos_m), 0);
        lc_free(&s.lc);
        engine_free(s.e);
        s.e = e2;
        s.lc = lc2;
        engine_setpoint_t b = run(&s, 500);
        assert_int_equal(lc_state(&s.lc), held ? LC_HELD : LC_STOPPED);
        assert_true(dist(b.pos_m, at.pos_m) < 1e-12);
        if (held) { /* a drive hold: after clear, the drives' position */
            s.drive_lost = 0;
            fire(&s, LC_EV_CLEAR, 0);
            assert_int_equal(lc_state(&s.lc), LC_NO_POSITION);
            assert_int_equal(lc_set_position(&s.lc, at.pos_m), 0);
        } else {
            fire(&s, LC_EV_START, 0);
        }
        b = run(&s, 1500);
        assert_true(dist(b.pos_m, at.pos_m) > 1.0); /* moving again */
        sim_free(&s);
    }
}

/* Given a moving object in a replay faster than real time, when the caller
 * steps over 5 deadlines (lc_step_unsent) and serves the 6th, then nothing
 * is judged or sent for the 5 (the commanded state stays the last sent), and
 * the 6th is where the curve is 6 periods on (as trajreplay's row for that
 * tick), judged once against the last one sent over the 6 periods. */
static void test_unsent_steps(void **state)
{
    (void)state;
    sim_t s;
    sim_init(&s, 0, NULL);
    engine_setpoint_t a = run(&s, 800);
    uint64_t checked = s.sf.checked;
    for (int i = 0; i < 5; i++) {
        send_due(&s);
        lc_step_unsent(&s.lc, s.now, NULL);
        s.now += PERIOD_NS;
    }
    assert_int_equal(s.sf.checked, checked);
    assert_true(dist(s.lc.sent.pos_m, a.pos_m) < 1e-12);
    engine_setpoint_t b;
    send_due(&s);
    assert_int_equal(lc_tick(&s.lc, s.now, NULL, &b), 0);
    assert_int_equal(s.sf.checked, checked + 1);
    assert_int_equal(s.sf.by[SAFETY_FSPEED] + s.sf.by[SAFETY_FACCEL], 0);
    double d = dist(a.pos_m, b.pos_m);
    assert_true(d > 5.5 * 2.0 * T_S && d < 6.5 * 2.0 * T_S); /* 6 periods at 2 m/s */
    assert_int_equal(s.lc.n.events[LC_EV_STALL], 0);
    sim_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_complete),
        cmocka_unit_test(test_document_is_the_table),
        cmocka_unit_test(test_clear_after_safety_hold),
        cmocka_unit_test(test_stop_latches_until_start),
        cmocka_unit_test(test_job_written_while_stopped),
        cmocka_unit_test(test_lag_stop_from_motion),
        cmocka_unit_test(test_stall_goes_on_from_last_sent),
        cmocka_unit_test(test_stall_clocked_catches_up),
        cmocka_unit_test(test_drive_lost_brakes_within_limits),
        cmocka_unit_test(test_drive_lost_reanchors_at_drive),
        cmocka_unit_test(test_clock_step),
        cmocka_unit_test(test_transfer_t_s),
        cmocka_unit_test(test_reload_keeps_latch_and_hold),
        cmocka_unit_test(test_unsent_steps),
        cmocka_unit_test(test_every_cell_directed),
        cmocka_unit_test(test_property_every_cell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
