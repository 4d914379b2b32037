/*
 * carry.c - what a reload carries over of each object (see carry.h): whether
 * its engine goes on (carry_source), the engine a changed one brakes with
 * until the new one takes over where it rests (retire_moving), where its
 * input goes on (carry_resume_input), and its counts.
 */
#include "carry.h"

#include <math.h>
#include <stdio.h>
#include <stddef.h>
#include <string.h>

#include "engine_settings.h"
#include "log.h"

/* One clock: 0 (relative) for a replay input, with clock = relative, or
 * at a replay speed; 1 with clock = epoch; -1 (the first waypoint decides)
 * with clock = auto. */
int carry_clock_initial(const cfg_t *cfg, const cfg_obj_t *o)
{
    if (strcmp(o->input->name, "replay") == 0 || cfg->daemon.clock == CFG_CLOCK_RELATIVE ||
        fabs(cfg->daemon.speed - 1.0) > 0)
        return 0;
    return cfg->daemon.clock == CFG_CLOCK_EPOCH ? 1 : -1;
}

/* 1 if object qc (of the running config) and o (the new one) have the same
 * input with the same settings (a replayed track: the same file, unchanged). */
static int same_input(const cfg_obj_t *qc, const cfg_obj_t *o)
{
    const transport_t *in = o->input;
    if (qc->input != in)
        return 0;
    const void *a = cfg_obj_transport(qc, in), *b = cfg_obj_transport(o, in);
    return in->obj_cfg_same ? in->obj_cfg_same(a, b)
                            : !(in->obj_cfg_size && memcmp(a, b, in->obj_cfg_size) != 0);
}

/* the safety bounds an engine keeps (engine.h cap_*) */
static const struct {
    const char *key, *what;
    size_t off;
} caps[] = {
    {"safety_max_speed_m_s", "m/s of output speed", offsetof(engine_config_t, cap_speed_m_s)},
    {"safety_max_accel_m_s2", "m/s^2 of output acceleration",
     offsetof(engine_config_t, cap_accel_m_s2)},
};

/* The first of caps[] that differs between qc and o (its values into *c0,
 * *c1), or -1 */
static int cap_changed(const cfg_obj_t *qc, const cfg_obj_t *o, double *c0, double *c1)
{
    for (size_t i = 0; i < sizeof caps / sizeof caps[0]; i++) {
        memcpy(c0, (const char *)&qc->engine + caps[i].off, sizeof *c0);
        memcpy(c1, (const char *)&o->engine + caps[i].off, sizeof *c1);
        if (*c0 < *c1 || *c0 > *c1)
            return (int)i;
    }
    return -1;
}

/* 1 if an engine built for qc serves o: the same bounds it keeps, engine
 * settings and input (what carry_source asks of the settings alone) */
static int settings_same(const cfg_obj_t *qc, const cfg_obj_t *o)
{
    double c0, c1;
    return cap_changed(qc, o, &c0, &c1) < 0 && engine_config_same(&qc->engine, &o->engine) &&
           same_input(qc, o);
}

/* q's engine moves (its last setpoint not a hold): a reload that changes q
 * keeps it braking (retire_moving). */
static int moving_engine(const obj_t *q)
{
    return q->engine && q->sp.cycle != 0 &&
           !(q->sp.flags & (ENGINE_SP_HOLD | ENGINE_SP_NO_POSITION));
}

/* The norm of v. */
static double norm3(const double v[ENGINE_AXES])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* 1 if the safety bounds of o (the new config) would refuse q's motion as
 * the monitor measured it (the speed and acceleration of the last setpoints
 * sent, per axis too, and the position in the box).  Such an object is not
 * carried over: it brakes to rest under the bounds it was planned for
 * (retire_moving) and a new engine goes on from there under the new ones.
 * Carried, the monitor held it in one tick (a reload to safety_max_speed_m_s
 * 8 at 9.8 m/s: a step to rest, exit 75).  Bounds its motion keeps (the same
 * ones, a reload that changes nothing) never refuse it: judged one period on
 * by extrapolation, a drive's 12 m/s^2 bound was "passed" at 12.46 on an
 * unchanged reload (test_drive_events_uml.sh).  why (NULL: not said) gets the
 * bound. */
static int bounds_refuse(const obj_t *q, const cfg_obj_t *o, char *why, size_t len)
{
    const safety_t *s = &q->safety;
    if (!moving_engine(q) || safety_fault(s) || !s->have_pos)
        return 0;
    safety_limits_t lim;
    obj_safety_limits(o, &lim);
    int f = SAFETY_OK;
    double value = 0, limit = 0, v = s->have_vel ? norm3(s->last_vel) : 0.0,
           a = s->have_acc ? norm3(s->last_acc) : 0.0;
    if (lim.max_step_m > 0 && v * s->last_dt > lim.max_step_m)
        f = SAFETY_FSTEP, value = v * s->last_dt, limit = lim.max_step_m;
    else if (lim.max_speed_m_s > 0 && v > lim.max_speed_m_s)
        f = SAFETY_FSPEED, value = v, limit = lim.max_speed_m_s;
    else if (lim.max_accel_m_s2 > 0 && a > lim.max_accel_m_s2)
        f = SAFETY_FACCEL, value = a, limit = lim.max_accel_m_s2;
    for (int k = 0; f == SAFETY_OK && k < ENGINE_AXES; k++) {
        double p = s->last_pos[k], vk = s->have_vel ? fabs(s->last_vel[k]) : 0.0,
               ak = s->have_acc ? fabs(s->last_acc[k]) : 0.0;
        if (lim.box && (p < lim.box_min_m[k] || p > lim.box_max_m[k]))
            f = SAFETY_FBOX, value = p,
            limit = p < lim.box_min_m[k] ? lim.box_min_m[k] : lim.box_max_m[k];
        else if (lim.axis_speed_m_s[k] > 0 && vk > lim.axis_speed_m_s[k])
            f = SAFETY_FAXIS, value = vk, limit = lim.axis_speed_m_s[k];
        else if (lim.axis_accel_m_s2[k] > 0 && ak > lim.axis_accel_m_s2[k])
            f = SAFETY_FAXIS, value = ak, limit = lim.axis_accel_m_s2[k];
    }
    if (f != SAFETY_OK && why)
        snprintf(why, len, "its new safety bounds refuse its motion: %s (%.6g, bound %.6g)",
                 safety_strerror(f), value, limit);
    return f != SAFETY_OK;
}

/* The object of prev that o (in the new config) may take over, or NULL; why
 * (NULL: not said) gets the reason where its new safety bounds refuse its
 * motion, or its speed or acceleration cap changed (the rest is said elsewhere). */
obj_t *carry_source(core_t *prev, const cfg_t *cfg, const cfg_obj_t *o, char *why, size_t len)
{
    if (!prev || prev->stopping)
        return NULL;
    obj_t *q = core_obj_find(prev, o->name);
    if (!q || !q->engine || bounds_refuse(q, o, why, len))
        return NULL;
    /* the safety bounds its engine keeps (engine.h cap_*): the old ones */
    double cap0, cap1;
    int i = cap_changed(q->cfg, o, &cap0, &cap1);
    if (i >= 0) {
        if (why && moving_engine(q))
            snprintf(why, len, "its %s changed, which its engine keeps (%g -> %g %s, 0: none)",
                     caps[i].key, cap0, cap1, caps[i].what);
        return NULL;
    }
    if (!settings_same(q->cfg, o))
        return NULL;
    if (q->clocked == 1 && carry_clock_initial(cfg, o) == 0)
        return NULL; /* an engine on the clock cannot leave it: a new one */
    return q;
}

int carry_needs_engine(const cfg_t *running, const cfg_obj_t *o)
{
    /* carry_source's tests of the settings alone (the running object's
     * motion, its clock, a stopping core are for the loop to judge) */
    const cfg_obj_t *qc = running ? cfg_obj_by_name(running, o->name) : NULL;
    return !qc || !settings_same(qc, o);
}

/* A changed object (a new engine) whose input stays the same goes on along it
 * after as far as its old engine played (the replay, replay_transport.c: after
 * that track time, on the old schedule), never from the input's start again:
 * o->resume_t_s, o->born_ns.  Left NAN where it played nothing. */
void carry_resume_input(obj_t *o, core_t *prev)
{
    obj_t *q = prev && !prev->stopping ? core_obj_find(prev, o->name) : NULL;
    if (!q || !same_input(q->cfg, o->cfg) || !isfinite(q->played_t_s))
        return; /* (nothing played: a waiting object's input starts again, none skipped) */
    /* as far as it played: not the setpoint's t_s, which a transfer (a reload
     * before this one, still joining its track) counts from its own start
     * behind the track: resumed there, the object went back 8.8 m */
    o->resume_t_s = q->played_t_s;
    o->played_t_s = q->played_t_s;
    o->played_track = q->played_track;
    o->born_ns = q->born_ns;
}

/* A reloaded object that gets a new engine while its old one moves: the old
 * one is kept braking to rest (engine_stop, at reload_commit) and hands over
 * there.  Borrowed: prev keeps its engines until the reload commits. */
static void retire_moving(obj_t *o, core_t *prev)
{
    obj_t *q = prev && !prev->stopping ? core_obj_find(prev, o->name) : NULL;
    if (!q)
        return;
    /* its counts go on over the reload: those of the engines it had (a
     * retiring one's at its handover, step_engines) */
    o->counts_before = q->counts_before;
    o->has_counts_before = q->has_counts_before;
    if (!o->carried && q->engine && (q->retiring || !moving_engine(q)))
        obj_counts_take(o, q->engine); /* given up here */
    if (q->retiring) {                 /* still braking from an earlier reload */
        o->retiring = q->retiring;
        o->retire_ns = q->retire_ns;
    } else if (!o->carried && moving_engine(q)) {
        o->retiring = q->engine;
        o->retire_ns = obj_lc(q)->eng_ns; /* its curve's time as its owner left it */
    } else {
        return;
    }
    o->sp = q->sp;
    /* the braking is judged against what was sent, and by the bounds it was
     * planned for: the new configuration's judge the new engine, from rest
     * (given at the handover, step_engines).  Judged by tighter new ones, the
     * first braking row was refused and the object frozen in one tick: 4 m/s
     * to 0 (test_lifecycle_daemon.py) */
    o->safety = q->safety;
}

/* Step 2 of core_open: borrow the engines of prev's carried objects (cannot
 * fail; prev untouched: reload_commit or reload_unborrow settles it). */
void carry_objects(core_t *c, core_t *prev)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        char why[160] = "";
        obj_t *o = &c->obj[i], *q = carry_source(prev, c->cfg, o->cfg, why, sizeof why);
        if (!q) {
            if (why[0])
                log_msg(LOG_NOTICE,
                        "object '%s': %s: it brakes to rest along its path under the bounds it "
                        "was planned for, and goes on from there under the new ones",
                        o->name, why);
            retire_moving(o, prev);
            continue;
        }
        o->engine = q->engine;
        o->sp = q->sp;
        o->status = q->status;
        o->skipped_ticks = q->skipped_ticks;
        o->safety = q->safety;
        safety_limits_t lim;
        obj_safety_limits(o->cfg, &lim);
        safety_set_limits(&o->safety, &lim); /* the new config's bounds */
        o->safety_logged = q->safety_logged;
        o->born_ns = q->born_ns;
        if (o->clocked != 0)
            o->clocked = q->clocked; /* its engine stays on the clock, or decided */
        o->out_lost = q->out_lost;
        o->out_fault = q->out_fault;
        o->rejlog = q->rejlog;
        o->uniform_warned = q->uniform_warned;
        /* what was told of the carried counters: not told again (a clear after a
         * reload repeated the last start's latch figures) */
        o->cmd_buf_told = q->cmd_buf_told;
        o->cmd_drop_told = q->cmd_drop_told;
        o->axis_warned = q->axis_warned;
        o->limits_warned = q->limits_warned;
        o->axis_stops_logged = q->axis_stops_logged;
        o->axis_beyond_logged = q->axis_beyond_logged;
        o->und_t = q->und_t;
        o->und_logged = q->und_logged;
        o->grown_logged = q->grown_logged;
        o->reanchors_logged = q->reanchors_logged;
        o->reserve_logged = q->reserve_logged;
        o->played_t_s = q->played_t_s;
        o->played_track = q->played_track;
        o->delay_track = q->delay_track; /* its trajectory's start was told (a line still
                                          * pending, by the old core as it closes): not again */
        o->delay_logs = q->delay_logs;
        o->out_errors = q->out_errors;
        o->held = q->held; /* its engine keeps the override 0 */
        o->carried = 1;
        o->lc = q->lc; /* the owner goes with its engine: latch, holds, commanded state */
        q->lc.buf = NULL;
        q->lc.cap = q->lc.len = 0;
        (void)obj_lc(o);
        retire_moving(o, prev);
    }
}
