/* core.c - objects, output clock, tick, stop policy (see core.h). */
#include "core.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "angle.h"
#include "carry.h"
#include "cfgload.h"
#include "delay.h"
#include "engine_settings.h"
#include "grave.h"
#include "log.h"
#include "reload.h"

/* Private part of the core, after the public struct. */
typedef struct {
    core_t pub;
    int clock_fd;
    int64_t wall_base_ns;     /* CLOCK_MONOTONIC of deadline 0 */
    int64_t wall_period_ns;   /* period_ns / speed, whole ns */
    uint64_t next_k;          /* index of the next deadline not yet served */
    int64_t stop_deadline_ns; /* CLOCK_MONOTONIC after which stopping gives up */
    uint64_t ticks_at_stop;
    int opened[CFG_TRANSPORTS_MAX];
    int64_t rt_off_ns; /* CLOCK_REALTIME - CLOCK_MONOTONIC (real_offset) */
    int have_rt_off;
    struct gone *gone; /* objects reloads removed, where they came to rest */
    unsigned ngone;
} core_priv_t;

/* An object a reload removed (it braked to rest along its path, then went):
 * where it rests, kept over later reloads while it is gone, so that one of
 * its name added back starts there, as an object whose settings changed
 * does, and reaches its track by a transfer, not from its first waypoint (a
 * fresh object's position: a step of the distance between them). */
struct gone {
    char name[CFG_NAME_MAX];
    double pos[ENGINE_AXES];
};

static int in_cfg(const cfg_t *cfg, const char *name)
{
    for (unsigned i = 0; i < cfg->nobj; i++)
        if (strcmp(cfg->obj[i].name, name) == 0)
            return 1;
    return 0;
}

/* Where prev's object name went to rest, if a reload removed it; or NULL. */
static const double *gone_pos(const core_t *prev, const char *name)
{
    const core_priv_t *p = (const core_priv_t *)prev;
    for (unsigned i = 0; prev && !prev->stopping && i < p->ngone; i++)
        if (strcmp(p->gone[i].name, name) == 0)
            return p->gone[i].pos;
    return NULL;
}

/* c's gone objects: prev's still gone, and prev's objects c does not have
 * that had a position.  0 or -ENOMEM. */
static int gone_note(core_t *c, const core_t *prev)
{
    core_priv_t *p = (core_priv_t *)c;
    const core_priv_t *q = (const core_priv_t *)prev;
    if (!prev || !(q->ngone + prev->nobj))
        return 0;
    p->gone = calloc(q->ngone + prev->nobj, sizeof *p->gone);
    if (!p->gone)
        return -ENOMEM;
    for (unsigned i = 0; i < q->ngone; i++)
        if (!in_cfg(c->cfg, q->gone[i].name))
            p->gone[p->ngone++] = q->gone[i];
    for (unsigned i = 0; i < prev->nobj; i++) {
        const obj_t *o = &prev->obj[i];
        if (in_cfg(c->cfg, o->name) || o->sp.cycle == 0 || (o->sp.flags & ENGINE_SP_NO_POSITION))
            continue;
        struct gone *g = &p->gone[p->ngone++];
        snprintf(g->name, sizeof g->name, "%s", o->name);
        memcpy(g->pos, o->sp.pos_m, sizeof g->pos);
    }
    return 0;
}

int64_t core_mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

int64_t core_real_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

double obj_delay_s(const core_t *c, const obj_t *o)
{
    if (o->clocked == 1)
        return c->cfg->daemon.delay_s;
    if (!o->engine)
        return NAN;
    engine_delay_t d;
    engine_delay(o->engine, &d);
    return d.delay_s;
}

void obj_counts_take(obj_t *o, const engine_t *e)
{
    engine_status_t st;
    engine_status(e, &st);
    engine_status_add_counts(&o->counts_before, &st);
    if (st.accepted)
        o->counts_before.last_seq = st.last_seq;
    o->has_counts_before = 1;
}

void obj_reset_counters(obj_t *o)
{
    engine_reset_counters(o->engine);
    if (o->retiring)
        engine_reset_counters(o->retiring);
    uint32_t last_seq = o->counts_before.last_seq; /* (not a counter: kept) */
    memset(&o->counts_before, 0, sizeof o->counts_before);
    o->counts_before.last_seq = last_seq;
    o->has_counts_before = 0;
    o->reset_seq++;
    o->lc.n.refused_full = 0;
    o->skipped_ticks = 0;
    o->out_lost = 0;
    o->out_fault = 0;
    o->out_errors = 0;
    engine_status(o->engine, &o->status);
}

/*
 * The derived acceleration bound (m/s^2): 2 x max(3 a_w + scale_accel_m_s2,
 * transfer_accel_m_s2), a_w = max_accel_m_s2 in force (the curve through
 * waypoints whose implied acceleration is at most a_w stays within 3 a_w, the
 * time scaling adds at most scale_accel_m_s2: lib/engine/TIMESCALE.md).  0
 * (not checked) without an acceleration limit (profiles machine, none)
 * and with param = uniform (the paper's parameterisation steps the velocity
 * at waypoints by design: lib/engine/DESIGN.md).
 */
static double obj_safety_accel(const engine_config_t *e)
{
    double aw = engine_config_max_accel(e);
    if (e->param != ENGINE_PARAM_TIME || !(aw > 0))
        return 0; /* no bound the curve keeps: not checked */
    /* the curve through waypoints of implied acceleration <= aw stays within
     * 3 aw (diagonal dominance), the time scaling adds scale_accel_m_s2, a
     * transfer at most its configured acceleration; twice that */
    return 2.0 * fmax(3.0 * aw + e->scale_accel_m_s2, e->transfer_accel_m_s2);
}

/*
 * The safety monitor's bounds for object o (core_open sets them, a reload
 * again): its safety_* keys, and where a key is not given, derived from its
 * engine limits (the ones in force, the profile's included): speed 2 x
 * max_speed_m_s (the engine's transfer peaks at 1.5 x; no speed limit leaves
 * it unchecked), no absolute step bound, acceleration derived as
 * obj_safety_accel says; per axis SAFETY_AXIS_MARGIN (safety.h) above the
 * engine's per-axis limits.
 */
void obj_safety_limits(const cfg_obj_t *o, safety_limits_t *lim)
{
    memset(lim, 0, sizeof *lim);
    lim->max_step_m = o->safety_max_step_m >= 0 ? o->safety_max_step_m : 0;
    lim->max_speed_m_s = o->safety_max_speed_m_s >= 0 ? o->safety_max_speed_m_s
                                                      : 2.0 * engine_config_max_speed(&o->engine);
    lim->max_accel_m_s2 = o->safety_max_accel_m_s2 >= 0 ? o->safety_max_accel_m_s2
                                                        : obj_safety_accel(&o->engine);
    lim->tol_m = SAFETY_TOL_M_DEFAULT;
    lim->box = o->box; /* position_min_m .. position_max_m (cfg_box.h) */
    memcpy(lim->box_min_m, o->box_min_m, sizeof lim->box_min_m);
    memcpy(lim->box_max_m, o->box_max_m, sizeof lim->box_max_m);
    /* issue 32: the engine keeps the per-axis limits along the path; the
     * monitor holds them independently, SAFETY_AXIS_MARGIN above (the
     * finite differences of the setpoints it measures by) */
    safety_axis_limits(lim, o->engine.axis_max_speed_m_s, o->engine.axis_max_accel_m_s2,
                       o->engine.axis_max_jerk_m_s3);
}

/* The setpoint as latitude/longitude/height (geographic objects, about the
 * daemon's one datum: left pending for core_obj_geo, which an output that
 * writes it calls) and the heading axis at its track time.  In the tick: no
 * allocation. */
static void obj_frames(const cfg_t *cfg, obj_t *o)
{
    const engine_setpoint_t *sp = &o->sp;
    o->geo[0] = o->geo[1] = o->geo[2] = NAN;
    o->heading_deg = o->heading_unwrapped_deg = NAN;
    o->geo_pending = o->cfg->geographic && cfg->datum_set && isfinite(sp->pos_m[0]) &&
                     isfinite(sp->pos_m[1]) && isfinite(sp->pos_m[2]);
    if (o->cfg->heading.n && isfinite(sp->t_s) && isfinite(sp->pos_m[0])) {
        o->heading_unwrapped_deg = angle_pchip_eval(o->cfg->heading.t_s, o->cfg->heading.deg,
                                                    o->cfg->heading.n, sp->t_s, &o->heading_hint);
        o->heading_deg = angle_wrap_deg(o->heading_unwrapped_deg);
    }
}

const double *core_obj_geo(const core_t *c, obj_t *o)
{
    if (o->geo_pending) {
        o->geo_pending = 0;
        (void)geo_from_enu_track(&c->cfg->datum, o->sp.pos_m, o->cfg->geo_no_alt, o->geo);
    }
    return o->geo;
}

obj_t *core_obj_find(core_t *c, const char *name)
{
    for (unsigned i = 0; i < c->nobj; i++)
        if (strcmp(c->obj[i].name, name) == 0)
            return &c->obj[i];
    return NULL;
}

/* Missed deadlines stepped one by one at most (about 20 ms of work for 4 objects). */
#define CORE_CATCHUP_MAX 100000u

/* 1 if transport t of c is open (a reload's rollback may leave one closed:
 * reopen_old). */
static int transport_open(const core_t *c, const transport_t *t)
{
    return ((const core_priv_t *)c)->opened[transport_index(t)];
}

/* Clocked inputs, then every engine, at engine time now_ns; real_ns is
 * CLOCK_REALTIME at the deadline, from which the play-out clock (one for all
 * objects on it, lib/engine/CLOCK.md) is advanced.  sent: this deadline's
 * setpoints go out (the others, stepped over, are neither judged nor sent). */
static void step_engines(core_t *c, int64_t now_ns, int64_t real_ns, int sent)
{
    stats_t *s = c->stats;
    if (!c->stopping)
        for (unsigned i = 0; i < c->nobj; i++) {
            obj_t *o = &c->obj[i];
            if (o->cfg->input->pre_tick && transport_open(c, o->cfg->input))
                o->cfg->input->pre_tick(c->tstate[transport_index(o->cfg->input)], o, now_ns);
        }
    s->clock_now_ns = playout_clock_now(&s->pclock, real_ns, playout_drift_eps(&s->drift),
                                        &s->clock_rate);
    engine_clock_t clk = {s->clock_now_ns, (int64_t)llround(c->cfg->daemon.delay_s * 1e9),
                          s->clock_rate, c->cfg->daemon.catchup};
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        if (i + 2 < c->nobj && c->obj[i + 2].engine)
            engine_prefetch(c->obj[i + 2].engine); /* many objects: their misses overlap */
        if (!o->retiring) { /* the owner: one period of the curve, judged, sent */
            if (sent)
                lc_tick(obj_lc(o), now_ns, o->clocked == 1 ? &clk : NULL, &o->sp);
            else
                lc_step_unsent(obj_lc(o), now_ns, o->clocked == 1 ? &clk : NULL);
            continue;
        }
        if (o->clocked == 1)
            (void)engine_set_clock(o->retiring, &clk); /* cannot fail: cfg bounds */
        /* the predecessor brakes, one period of its curve a tick as its owner
         * went (lc_tick: after a stall the next target is one period on) */
        engine_setpoint_t own;
        o->retire_ns += c->period_ns;
        engine_tick(o->retiring, o->retire_ns, &own);
        o->sp = own;
        /* what goes out is judged, the setpoint that hands over too (a hold
         * keeps the held position: the new engine starts there) */
        if (sent)
            (void)safety_check(&o->safety, &o->sp);
        o->sp.now_ns = now_ns;
        /* once at rest the new engine starts there */
        if ((own.flags & ENGINE_SP_HOLD) && own.state != ENGINE_STATE_STREAMING &&
            own.state != ENGINE_STATE_UNDERRUN) {
            if (!(o->sp.flags & ENGINE_SP_NO_POSITION))
                (void)engine_set_position(o->engine, o->sp.pos_m); /* within max_abs_m: checked */
            obj_counts_take(o, o->retiring);                       /* its counts go on */
            grave_put(o->retiring); /* freed beside the loop (an munmap) */
            o->retiring = NULL;
            safety_limits_t lim; /* the new engine's bounds, from rest */
            obj_safety_limits(o->cfg, &lim);
            safety_set_limits(&o->safety, &lim);
        }
    }
}

/* CLOCK_REALTIME - CLOCK_MONOTONIC, kept while it moves by less than 1 ms
 * (it only changes when the system clock is set), so that the play-out
 * clock is a function of the deadline, not of when the two were read.  Read
 * between two monotonic reads, and only when those are close (not
 * preempted in between). */
static int64_t real_offset(core_priv_t *p)
{
    for (int i = 0; i < 3; i++) {
        int64_t m1 = core_mono_ns(), r = core_real_ns(), m2 = core_mono_ns();
        if (m2 - m1 > 100000)
            continue;
        int64_t off = r - (m1 + (m2 - m1) / 2);
        if (!p->have_rt_off || llabs(off - p->rt_off_ns) > 1000000) {
            p->rt_off_ns = off;
            p->have_rt_off = 1;
        }
        break;
    }
    if (!p->have_rt_off) { /* never read calmly: take it as it is */
        p->rt_off_ns = core_real_ns() - core_mono_ns();
        p->have_rt_off = 1;
    }
    return p->rt_off_ns;
}

/*
 * Serve deadline k; deadlines k0 .. k-1 were missed.  In real time (speed 1)
 * the objects move on by one period from the last setpoint sent, never by
 * the periods missed (lifecycle.h, LC_EV_STALL: a stall of N periods is no
 * step of N periods; the lag is won back by the clock's catch-up, or
 * reported).  Faster or slower than real time (a replay: nothing physical
 * follows) inputs and engines are stepped through each missed deadline
 * (nothing is output for them), so every engine sees each waypoint at the
 * same tick as trajreplay does and the setpoints stay identical to it; only
 * deadline k's setpoints go out, flagged ENGINE_SP_SKIPPED.
 */
static void note_played(obj_t *o);

/* o's status as of now (o->status, each tick): its engine's, with the
 * counts of the engines it had before a reload that changed its settings and
 * of the one still braking.  The last waypoint the object took is its
 * engine's or, until the new engine takes one, the last of those before it
 * (a sender paced by it sees it go on). */
static void obj_status_of(const obj_t *o, engine_status_t *out)
{
    engine_status(o->engine, out);
    int own = out->accepted != 0;
    if (o->has_counts_before) { /* (not every tick of every object: a reload's) */
        engine_status_add_counts(out, &o->counts_before);
        if (!own && o->counts_before.accepted)
            out->last_seq = o->counts_before.last_seq;
    }
    if (o->retiring) { /* still braking for a reload: its counts are the object's */
        engine_status_t st;
        engine_status(o->retiring, &st);
        engine_status_add_counts(out, &st);
        if (!own && st.accepted)
            out->last_seq = st.last_seq;
    }
}

uint64_t obj_accepted(const obj_t *o)
{
    engine_status_t st;
    obj_status_of(o, &st);
    return st.accepted;
}

static void tick(core_priv_t *p, uint64_t k0, uint64_t k, int64_t wake_ns, int64_t late_ns)
{
    core_t *c = &p->pub;
    int64_t now_ns = c->t0_ns + (int64_t)k * c->period_ns;
    c->now_ns = now_ns;
    c->cycle = k;
    /* for transports: lateness against the deadline this tick serves (the
     * newest), i.e. how stale its setpoint is when sent */
    c->late_ns = wake_ns - (p->wall_base_ns + (int64_t)k * p->wall_period_ns);

    /* after a long stall (suspend) the engines step over the oldest deadlines
     * inside one call instead: bounded work, exactness kept for ordinary misses */
    uint64_t from = k - k0 > CORE_CATCHUP_MAX ? k - CORE_CATCHUP_MAX : k0;
    if (!(fabs(c->cfg->daemon.speed - 1.0) > 0))
        from = k; /* real time: a stall is no step */
    int64_t rt_off = real_offset(p);
    for (uint64_t j = from; j <= k; j++)
        step_engines(c, c->t0_ns + (int64_t)j * c->period_ns,
                     p->wall_base_ns + (int64_t)j * p->wall_period_ns + rt_off, j == k);
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        if (k > k0) {
            o->sp.flags |= ENGINE_SP_SKIPPED;
            o->skipped_ticks += k - k0;
        }
        note_played(o);
        rejlog_drain(&o->rejlog, o->engine); /* verdicts given by a finish or a tick */
        obj_status_of(o, &o->status);
        o->status.skipped_ticks += o->skipped_ticks;
        /* stopped or held: the room of the buffer its waypoints go to, and
         * what it refused full, as the engine's own full buffer counts */
        o->status.free = lc_free_room(&o->lc, o->status.free);
        o->status.full += o->lc.n.refused_full;
        o->status.unjudged += o->lc.n.dropped_past + o->lc.n.dropped_full; /* the latch's */
        objlog_note_start(o);
        obj_frames(c->cfg, o);
    }
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        for (unsigned j = 0; j < o->cfg->noutput; j++) {
            const transport_t *t = o->cfg->output[j];
            if (!p->opened[transport_index(t)]) { /* left closed by a reload (reopen_old) */
                o->out_lost++;
                o->out_fault = 1;
                c->stats->out_lost++;
                c->stats->out_fault = 1;
            } else if (t->setpoint) {
                t->setpoint(c->tstate[transport_index(t)], o, &o->sp);
            }
        }
    }
    for (unsigned t = 0; transport_table[t]; t++)
        if (p->opened[t] && transport_table[t]->cycle)
            transport_table[t]->cycle(c->tstate[t], c, now_ns);
    if (c->tap)
        c->tap(c->tap_ctx, c);

    stats_t *s = c->stats;
    s->ticks++;
    uint64_t late_us = late_ns > 0 ? (uint64_t)(late_ns / 1000) : 0;
    lat_add(&s->late_hist, late_us);
    if (core_mono_ns() > p->wall_base_ns + (int64_t)(k + 1) * p->wall_period_ns)
        s->overruns++;
    if (s->exit_code)
        loop_stop(c->loop, s->exit_code); /* e.g. a Unix filter whose reader left */
    else if (core_done(c))
        loop_stop(c->loop, 0);
}

static void on_clock(loop_t *l, int fd, uint32_t events, void *ctx)
{
    core_priv_t *p = ctx;
    uint64_t n = 0;
    (void)l;
    (void)events;
    int64_t wake_ns = core_mono_ns();
    if (read(fd, &n, sizeof n) != (ssize_t)sizeof n || n == 0)
        return; /* EAGAIN: spurious wake-up */
    /* n deadlines passed since the last read: serve only the latest.
     * Lateness is counted from the oldest one, the deadline we were due to
     * serve, so a skip shows in the histogram as lateness >= one period. */
    int64_t late_ns = wake_ns - (p->wall_base_ns + (int64_t)p->next_k * p->wall_period_ns);
    uint64_t k0 = p->next_k, k = k0 + n - 1;
    p->pub.stats->missed_ticks += n - 1;
    p->next_k = k + 1;
    struct timespec c0, c1; /* the tick's own CPU time (a vDSO-less call each, ~0.2 us) */
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    tick(p, k0, k, wake_ns, late_ns);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    int64_t cpu_ns = (c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec);
    lat_add(&p->pub.stats->work_hist, cpu_ns > 0 ? (uint64_t)cpu_ns / 1000 : 0);
}

/* o->played_t_s after this tick's setpoint (core.h). */
static void note_played(obj_t *o)
{
    const engine_setpoint_t *sp = &o->sp;
    if ((sp->state != ENGINE_STATE_STREAMING && sp->state != ENGINE_STATE_UNDERRUN &&
         sp->state != ENGINE_STATE_FINISHED) ||
        (sp->flags & (ENGINE_SP_TRANSFER | ENGINE_SP_NO_POSITION)) || !isfinite(sp->t_s))
        return;
    if (sp->track != o->played_track) { /* another trajectory: from its own times */
        o->played_track = sp->track;
        o->played_t_s = sp->t_s;
    } else if (!(sp->t_s <= o->played_t_s)) {
        o->played_t_s = sp->t_s;
    }
}

/* Step 1 of core_open: an object per config entry, a new engine unless one is
 * carried over from prev.  0, or -ENOMEM with why (prev untouched). */
static int new_objects(core_t *c, core_t *prev, char *why, size_t whylen)
{
    const cfg_t *cfg = c->cfg;
    for (unsigned i = 0; i < cfg->nobj; i++) {
        obj_t *o = &c->obj[i];
        int err = 0;
        snprintf(o->name, sizeof o->name, "%s", cfg->obj[i].name);
        o->index = i;
        o->cfg = &cfg->obj[i];
        o->born_ns = c->t0_ns;
        o->drift = &c->stats->drift;
        o->clock_window_s = cfg->daemon.clock_window_s;
        o->clocked = carry_clock_initial(cfg, o->cfg);
        o->resume_t_s = NAN;
        o->played_t_s = NAN;
        if (carry_source(prev, cfg, o->cfg, NULL, 0)) {
            lc_free(&o->lc); /* one built beside (cfgload.c) goes: carry_objects moves q's */
            continue;
        }
        carry_resume_input(o, prev);
        o->engine = cfg_take_engine(cfg, i); /* built beside the running core */
        if (!o->engine)
            o->engine = engine_new(&cfg->obj[i].engine, &err);
        /* its owner built there too, about that engine (cfgload.c), or here */
        int owned = o->engine && o->lc.buf && o->lc.engine == o->engine;
        if (!o->engine || (!owned && lc_init(&o->lc, o->engine, &o->safety, c->period_ns, 0) < 0)) {
            snprintf(why, whylen, "object '%s': engine: %s", o->name,
                     engine_strerror(o->engine ? ENGINE_ENOMEM : err));
            return -ENOMEM;
        }
        /* relative time too wins back its lag at [daemon] catchup (catchup.h) */
        (void)engine_set_catchup(o->engine, cfg->daemon.catchup); /* cfg bounds: 0 .. 1 */
        safety_limits_t lim;
        obj_safety_limits(o->cfg, &lim);
        safety_init(&o->safety, &lim);
        rejlog_init(&o->rejlog); /* a carried object keeps its own (carry_objects) */
        /* An object of the same name that was not carried over (its settings
         * changed) stands where its output stood: the new engine starts there
         * and reaches its first trajectory by a transfer, never a step. */
        obj_t *q = prev && !prev->stopping ? core_obj_find(prev, o->name) : NULL;
        if (q) { /* its holds and a stop's latch stay (lib/engine/LIFECYCLE.md) */
            lc_inherit(&o->lc, &q->lc);
            o->held = q->held;
        }
        const double *at = q && q->sp.cycle != 0 && !(q->sp.flags & ENGINE_SP_NO_POSITION)
                               ? q->sp.pos_m
                           : q ? NULL
                               : gone_pos(prev, o->name); /* added back: where it went */
        if (at) {
            if (engine_set_position(o->engine, at) < 0) {
                snprintf(why, whylen, "object '%s': its position is outside the new max_abs_m",
                         o->name);
                return -EINVAL;
            }
        } else if (o->cfg->has_initial_position &&
                   engine_set_position(o->engine, o->cfg->initial_position_m) < 0) {
            snprintf(why, whylen, "object '%s': initial_position outside max_abs_m", o->name);
            return -EINVAL;
        }
        engine_status(o->engine, &o->status);
    }
    return 0;
}

/* Step 3 of core_open: open every transport the config uses, in table order.
 * all: go on past one that fails (the first failure is returned, the others
 * logged). */
static int open_transports(core_priv_t *p, char *why, size_t whylen, int all)
{
    core_t *c = &p->pub;
    int first = 0;
    for (unsigned t = 0; transport_table[t]; t++) {
        const transport_t *tr = transport_table[t];
        if (!cfg_uses(c->cfg, tr) || !tr->open)
            continue;
        char w[256] = "";
        int rc = tr->open(c, &c->tstate[t], w, sizeof w);
        if (rc < 0) {
            c->tstate[t] = NULL;
            if (first) { /* (all) the first one is in why, the others logged */
                log_msg(LOG_CRIT, "reload: %s: %s", tr->name, w[0] ? w : strerror(-rc));
                continue;
            }
            snprintf(why, whylen, "%s: %s", tr->name, w[0] ? w : strerror(-rc));
            first = rc;
            if (!all)
                return rc;
            continue;
        }
        p->opened[t] = 1;
    }
    return first;
}

/* Close every open transport of p (reverse order); p may open them again. */
static void close_transports(core_priv_t *p)
{
    for (int t = (int)transport_count() - 1; t >= 0; t--) {
        if (p->opened[t] && transport_table[t]->close)
            transport_table[t]->close(p->pub.tstate[t], &p->pub);
        p->opened[t] = 0;
        p->pub.tstate[t] = NULL;
    }
}

/* A reload could not open the new transports: prev's reopen, its objects
 * resuming where they are (reload_mark_resume).  One that does not reopen
 * either (its CSV directory gone, a port taken meanwhile) is left closed:
 * the objects go on without it, never stopped for a file; an output's
 * setpoints are then counted lost (exit 74), an input gives nothing more.
 * 0 (logged). */
static int reopen_old(core_t **prevp)
{
    core_priv_t *q = (core_priv_t *)*prevp;
    char w[256] = "";
    reload_mark_resume(*prevp);
    int rc = open_transports(q, w, sizeof w, 1);
    if (rc == 0)
        return 0;
    if (!q->pub.stats->out_errno) /* what the exit line names (it said "Success") */
        q->pub.stats->out_errno = -rc;
    log_msg(LOG_CRIT,
            "reload: the running configuration's %s did not reopen: its objects go on without "
            "it (an output's setpoints counted lost: exit 74; an input gives nothing more) until a "
            "reload opens it again",
            w);
    return 0;
}

int core_open(loop_t *loop, const cfg_t *cfg, stats_t *stats, core_t **prevp, core_t **out,
              char *why, size_t whylen)
{
    core_t *prev = prevp ? *prevp : NULL;
    core_priv_t *p = calloc(1, sizeof *p);
    int rc;
    *out = NULL;
    if (!p) {
        snprintf(why, whylen, "out of memory");
        return -ENOMEM;
    }
    core_t *c = &p->pub;
    p->clock_fd = -1;
    c->loop = loop;
    c->cfg = cfg;
    c->stats = stats;
    c->period_ns = cfg->daemon.period_ns;
    if (!prev) { /* the daemon's first core: its drift estimate and play-out clock start here */
        playout_drift_init(&stats->drift, cfg->daemon.drift_max_ppm);
        playout_clock_init(&stats->pclock);
    }
    double max_ppm = stats->drift.max_ppm; /* the running core's, if this one fails */
    stats->drift.max_ppm = cfg->daemon.drift_max_ppm;
    memset(&stats->bus, 0, sizeof stats->bus); /* until this core's transports publish */
    /* engine time goes on from the previous core, at its next deadline not
     * served (the one its clock's phase keeps: stats->clock_next_ns): carried
     * engines never see it go backwards, and a core closed before its clock
     * ever ticked (two reloads swapped one after the other) loses no period
     * (prev->now_ns + period was one period on: now_ns jumped two unflagged) */
    c->t0_ns = prev ? prev->t0_ns + (int64_t)((core_priv_t *)prev)->next_k * prev->period_ns : 0;
    c->now_ns = c->t0_ns;
    c->nobj = cfg->nobj;
    c->obj = cfgload_take_objs(cfg); /* zeroed, faulted in beside the loop */
    if (!c->obj)
        c->obj = calloc(cfg->nobj, sizeof *c->obj);
    if (!c->obj) {
        snprintf(why, whylen, "out of memory");
        rc = -ENOMEM;
        goto fail;
    }
    /* 1. new engines (may fail: prev is still untouched) */
    rc = new_objects(c, prev, why, whylen);
    if (rc == 0 && (rc = gone_note(c, prev)) < 0)
        snprintf(why, whylen, "out of memory");
    if (rc < 0)
        goto fail;
    /* 2. borrow the carried engines (cannot fail; prev untouched) */
    carry_objects(c, prev);
    /* 3. prev's transports close (one may hold a TCP port the new one
     * needs), the new ones open; if one cannot, prev's reopen and prev runs
     * on with its engines as they were */
    if (prev)
        close_transports((core_priv_t *)prev);
    rc = open_transports(p, why, whylen, 0);
    if (rc < 0) {
        close_transports(p);
        reload_unborrow(c);
        if (prev)
            (void)reopen_old(prevp);
        goto fail;
    }
    /* 4. commit: the engines are the new core's, the old core goes (its
     * clock's phase kept in stats->clock_next_ns for core_start) */
    if (prev) {
        reload_commit(c, prev);
        core_close(prev);
        *prevp = NULL;
    }
    objlog_delays(c);
    *out = c;
    return 0;
fail:
    core_close(c);
    if (prevp && *prevp)
        stats->drift.max_ppm = max_ppm;
    return rc;
}

int core_start(core_t *c)
{
    core_priv_t *p = (core_priv_t *)c;
    double speed = c->cfg->daemon.speed;
    p->wall_period_ns = (int64_t)llround((double)c->period_ns / speed);
    if (p->wall_period_ns < 1)
        p->wall_period_ns = 1;
    p->clock_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (p->clock_fd < 0)
        return -errno;
    /* a reload's core: its first deadline is the running core's next one,
     * even if it passed while the reload swapped (the timerfd then counts it,
     * and each one after it, as expired: on_clock counts them missed) */
    int64_t phase_ns = c->stats->clock_next_ns;
    p->wall_base_ns = phase_ns ? phase_ns : core_mono_ns() + p->wall_period_ns;
    p->next_k = 0;
    struct itimerspec its = {
        .it_value = {.tv_sec = p->wall_base_ns / 1000000000,
                     .tv_nsec = p->wall_base_ns % 1000000000},
        .it_interval = {.tv_sec = p->wall_period_ns / 1000000000,
                        .tv_nsec = p->wall_period_ns % 1000000000},
    };
    int rc = 0;
    if (timerfd_settime(p->clock_fd, TFD_TIMER_ABSTIME, &its, NULL) < 0)
        rc = -errno;
    else
        rc = loop_add(c->loop, p->clock_fd, EPOLLIN, on_clock, p);
    if (rc < 0) {
        close(p->clock_fd);
        p->clock_fd = -1;
    }
    return rc;
}

void core_stop(core_t *c)
{
    core_priv_t *p = (core_priv_t *)c;
    if (c->stopping)
        return;
    c->stopping = 1;
    p->stop_deadline_ns = core_mono_ns() + (int64_t)llround(c->cfg->daemon.stop_timeout_s * 1e9);
    p->ticks_at_stop = c->stats->ticks;
    for (unsigned i = 0; i < c->nobj; i++) {
        c->obj[i].stopping = 1;
        (void)lc_event(obj_lc(&c->obj[i]), LC_EV_SHUTDOWN, NULL);
        if (c->obj[i].retiring)
            engine_stop(c->obj[i].retiring);
    }
    for (unsigned t = 0; transport_table[t]; t++)
        if (p->opened[t] && transport_table[t]->stop)
            transport_table[t]->stop(c->tstate[t], c);
}

int core_done(const core_t *c)
{
    const core_priv_t *p = (const core_priv_t *)c;
    if (c->stopping) {
        if (core_mono_ns() >= p->stop_deadline_ns)
            return 1;
        /* engine_stop takes effect at the next tick: judge states after it */
        if (c->stats->ticks < p->ticks_at_stop + 2 && p->clock_fd >= 0)
            return 0;
        for (unsigned i = 0; i < c->nobj; i++) {
            engine_state_t s = c->obj[i].status.state;
            /* frozen by the monitor's hold; a drive's hold brakes to rest (FINISHED) */
            int held = (c->obj[i].lc.hold & LC_HOLD_SAFETY) != 0;
            if ((s != ENGINE_STATE_FINISHED && s != ENGINE_STATE_WAITING && !held) ||
                c->obj[i].retiring)
                return 0;
        }
        return 1;
    }
    if (!c->cfg->daemon.exit_when_done)
        return 0;
    for (unsigned i = 0; i < c->nobj; i++) {
        const obj_t *o = &c->obj[i];
        const transport_t *in = o->cfg->input;
        /* (latched by a stop, or held for a fault, with its buffer full: its
         * input can give no more before a start or a clear: as done as it
         * gets; a replay offered the next row at every tick for ever) */
        if (transport_open(c, in) &&
            (!in->input_done || !in->input_done(c->tstate[transport_index(in)], o)) &&
            !((o->lc.latched || (o->lc.hold & (LC_HOLD_SAFETY | LC_HOLD_DRIVE))) &&
              lc_free_room(&o->lc, 1) == 0))
            return 0;
        /* at rest on its last waypoint, or waiting with nothing buffered
         * (its input gave nothing usable: nothing more can happen), or held
         * by the monitor (frozen: only a clear moves it again; a drive's hold
         * brakes to rest, FINISHED) */
        if ((o->status.state != ENGINE_STATE_FINISHED &&
             !(o->status.state == ENGINE_STATE_WAITING && o->status.buffered == 0) &&
             !(o->lc.hold & LC_HOLD_SAFETY)) ||
            o->retiring)
            return 0;
    }
    return 1;
}

void core_close(core_t *c)
{
    if (!c)
        return;
    core_priv_t *p = (core_priv_t *)c;
    if (p->clock_fd >= 0) { /* the next core goes on in its phase (core_start) */
        c->stats->clock_next_ns = p->wall_base_ns + (int64_t)p->next_k * p->wall_period_ns;
        loop_del(c->loop, p->clock_fd);
        close(p->clock_fd);
    }
    for (int t = (int)transport_count() - 1; t >= 0; t--)
        if (p->opened[t] && transport_table[t]->close)
            transport_table[t]->close(c->tstate[t], c);
    if (c->obj)
        objlog_roll(c, UINT_MAX); /* engines carried to a new core were taken (NULL) */
    if (c->obj)
        for (unsigned i = 0; i < c->nobj; i++) {
            grave_put(c->obj[i].engine); /* freed beside the loop (grave.h) */
            lc_free(&c->obj[i].lc);
            grave_put(c->obj[i].retiring);
        }
    free(c->obj);
    free(p->gone);
    free(p);
}

void core_stats_roll(core_t *c)
{
    stats_t *s = c->stats;
    objlog_roll(c, OBJLOG_STARTS_PER_ROLL);
    /* safety violations, logged here (once a second at most per object), not in the tick */
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        const safety_t *sf = &o->safety;
        if (sf->violations == o->safety_logged)
            continue;
        double held[ENGINE_AXES] = {NAN, NAN, NAN};
        (void)safety_held(sf, held);
        int holding = (o->lc.hold & LC_HOLD_SAFETY) != 0;
        const char *why = safety_strerror(sf->fault        ? sf->fault
                                          : sf->last_fault ? sf->last_fault
                                                           : SAFETY_FNOTFINITE);
        if (holding)
            log_msg(LOG_ERR,
                    "object '%s': safety monitor: %s (%.6g, bound %.6g): setpoints not sent, "
                    "holding at (%.4f, %.4f, %.4f) until 'clear'; %llu refused so far",
                    o->name, why, sf->last_value, sf->last_limit, held[0], held[1], held[2],
                    (unsigned long long)sf->violations);
        else /* a clear came since: the hold is over, the count stays */
            log_msg(LOG_ERR,
                    "object '%s': safety monitor: %s (%.6g, bound %.6g): setpoints not sent "
                    "until the clear that released the hold; %llu refused so far",
                    o->name, why, sf->last_value, sf->last_limit,
                    (unsigned long long)sf->violations);
        o->safety_logged = sf->violations;
    }
    lat_summarize(&s->late_hist, &s->late);
    lat_summarize(&s->work_hist, &s->work);
}
