/* objlog.c - an object's log lines (core.h): the play-out delay D at start,
 * at each trajectory's start and when it grows, underruns, slowdowns,
 * warnings and refusals.  The tick only notes (objlog_note_start); the
 * once-a-second housekeeping logs (objlog_roll, from core_stats_roll), as
 * log.h asks. */
#include <math.h>
#include <stdio.h>

#include "core.h"
#include "delay.h"
#include "log.h"

/* Issue 26: the D a trajectory's output holds, logged as it starts streaming
 * (lib/engine/delay.h): the first OBJ_DELAY_LOG_FIRST trajectories of an
 * object, then every OBJ_DELAY_LOG_EVERY-th (a sender that starts one a
 * second does not flood the log; the status and trajreplay --summary show
 * the last).  Each underrun and each growth of D are logged at the same
 * rate (obj_log_nth). */
#define OBJ_DELAY_LOG_FIRST 20
#define OBJ_DELAY_LOG_EVERY 100

/* 1 if the n-th (from 1) of an object's events is logged. */
static int obj_log_nth(uint64_t n)
{
    return n <= OBJ_DELAY_LOG_FIRST || n % OBJ_DELAY_LOG_EVERY == 0;
}

/* One line: "object 'a': <what>play-out delay D ..." (delay.h's format) of d. */
static void obj_log_delay_of(const obj_t *o, const engine_delay_t *d, const char *what)
{
    char line[768];
    engine_delay_format(d, line, sizeof line);
    log_msg(LOG_INFO, "object '%s': %splay-out delay %s", o->name, what, line);
}

/* The same, of the D o's engine holds now. */
static void obj_log_delay(const obj_t *o, const char *what)
{
    engine_delay_t d;
    engine_delay(o->engine, &d);
    obj_log_delay_of(o, &d, what);
}

/* In the tick: a trajectory that started streaming is noted with its D (a
 * copy, no line: log.h), for objlog_roll to tell: at its first row on its
 * curve, not on the transfer to it (a transfer that leads to a start not yet
 * due comes before the start states its D: lib/engine/transfer.h). */
void objlog_note_start(obj_t *o)
{
    if (o->sp.track == o->delay_track || o->sp.state != ENGINE_STATE_STREAMING ||
        (o->sp.flags & ENGINE_SP_TRANSFER))
        return;
    o->delay_track = o->sp.track;
    if (o->delay_logs++ >= OBJ_DELAY_LOG_FIRST && o->sp.track % OBJ_DELAY_LOG_EVERY)
        return;
    if (o->delay_pending)
        o->delay_superseded++; /* a later start before its line: said with the next */
    o->delay_pending = 1;
    o->delay_pending_track = o->sp.track;
    engine_delay(o->engine, &o->delay_pending_d);
}

/* Housekeeping: the start noted (objlog_note_start), if any and *budget
 * allows (one line of it used). */
static void log_track_delay(obj_t *o, unsigned *budget)
{
    char what[160];
    if (!o->delay_pending || !*budget)
        return;
    if (o->delay_superseded)
        snprintf(what, sizeof what,
                 "trajectory %u streams (%llu more started since the last such line, not told "
                 "one by one): ",
                 (unsigned)o->delay_pending_track, (unsigned long long)o->delay_superseded);
    else
        snprintf(what, sizeof what, "trajectory %u streams: ", (unsigned)o->delay_pending_track);
    obj_log_delay_of(o, &o->delay_pending_d, what);
    o->delay_pending = 0;
    o->delay_superseded = 0;
    (*budget)--;
}

/* Issue 26: every object's play-out delay D and its parts (lib/engine/delay.h),
 * at start and at each reload: what its engine holds (a carried engine: the D
 * it stated), or what its settings need before any input. */
void objlog_delays(const core_t *c)
{
    for (unsigned i = 0; i < c->nobj; i++)
        if (c->obj[i].engine && !c->obj[i].carried) /* a carried one's was told */
            obj_log_delay(&c->obj[i], "");
}

static void log_rejection(void *ctx, const char *line)
{
    log_obj(LOG_WARNING, (const char *)ctx, "%s", line); /* ctx: the object's name */
}

/* param = uniform on irregular intervals (ENGINE_UNIFORM_RATIO_WARN): once per object. */
static void warn_uniform(obj_t *o)
{
    if (o->uniform_warned || !o->status.uniform_irregular)
        return;
    o->uniform_warned = 1;
    log_msg(LOG_WARNING,
            "object '%s': param = uniform on irregular intervals: %llu waypoints so far between "
            "intervals differing by more than %.2gx (worst %.3gx, at t = %.3f s): the velocity "
            "steps by that ratio there (param = time, the default, is C2 in time)",
            o->name, (unsigned long long)o->status.uniform_irregular, ENGINE_UNIFORM_RATIO_WARN,
            o->status.uniform_ratio_max, o->status.uniform_ratio_t_s);
}

/* issue 32: the per-axis limits, said once each: a track that exceeds them
 * (its lag grows: more than a tenth of the time streamed lost to them), and
 * each stop because the lag passed max_lag_s or before a segment beyond the
 * axes (both the lifecycle's lag event). */
static void warn_axis(obj_t *o)
{
    const engine_status_t *st = &o->status;
    double streamed_s = (double)st->setpoints * (double)o->cfg->engine.period_ns * 1e-9;
    if (!o->axis_warned && st->axis_lost_s > 1.0 && st->axis_lost_s > 0.1 * streamed_s) {
        o->axis_warned = 1;
        log_msg(LOG_WARNING,
                "object '%s': its track exceeds the per-axis limits (axis_max_*): %.1f s lost "
                "to them so far over %llu segments; its output lags its input by %.1f s beyond "
                "D and the lag grows while the track does",
                o->name, st->axis_lost_s, (unsigned long long)st->axis_slowed, st->axis_lag_s);
    }
    if (!o->limits_warned && st->limits_lost_s > 1.0 && st->limits_lost_s > 0.1 * streamed_s) {
        o->limits_warned = 1;
        /* the safety bounds the engine keeps (engine.h cap_*) among them */
        const engine_config_t *ec = &o->cfg->engine;
        log_msg(LOG_WARNING,
                "object '%s': its curve exceeds its own speed or acceleration limit "
                "(max_speed_m_s, max_accel_m_s2: the profile's%s%s): %.1f s lost to them so far "
                "over %llu segments; its output lags its input by that much beyond D and the lag "
                "grows while the track does (jittery stamps bend the curve: profile = none, or "
                "a higher max_accel_m_s2)",
                o->name, ec->cap_speed_m_s > 0 ? "; safety_max_speed_m_s, which it keeps" : "",
                ec->cap_accel_m_s2 > 0 ? "; safety_max_accel_m_s2, which it keeps" : "",
                st->limits_lost_s, (unsigned long long)st->limits_slowed);
    }
    if (st->axis_lag_stops != o->axis_stops_logged) {
        o->axis_stops_logged = st->axis_lag_stops;
        log_msg(LOG_ERR,
                "object '%s': stopped on its path: the per-axis limits made it lag its input "
                "by more than max_lag_s %g s beyond D (lifecycle event 'lag beyond max_lag_s', "
                "%llu so far); latched until start or clear",
                o->name, o->cfg->engine.max_lag_s, (unsigned long long)st->axis_lag_stops);
    }
    if (st->axis_beyond != o->axis_beyond_logged) {
        o->axis_beyond_logged = st->axis_beyond;
        log_msg(LOG_ERR,
                "object '%s': stopped on its path before a segment its axes cannot follow: "
                "the track is over 100 times faster there on an axis than its axis_max_* "
                "(lifecycle event 'lag beyond max_lag_s', %llu so far); latched until start "
                "or clear",
                o->name, (unsigned long long)st->axis_beyond);
    }
}

/* issue 26: each underrun once the silence it met ended, where and why
 * (engine_underrun_format), at obj_log_nth's rate.  One whose input never
 * resumed is the input's end: a silent end takes it back
 * (lib/engine/silence.h), unlogged. */
static void log_underrun(obj_t *o)
{
    const engine_status_t *st = &o->status;
    char msg[320];
    if (!engine_underrun_due(st, o->und_logged ? o->und_t : NAN, 0))
        return;
    o->und_t = st->underrun_t_s;
    if (!obj_log_nth(++o->und_logged))
        return;
    (void)engine_underrun_format(st, msg, sizeof msg);
    log_msg(LOG_WARNING, "object '%s': %s (%llu underruns so far)", o->name, msg,
            (unsigned long long)st->underruns);
}

/* issue 26: a slowdown for D's stop reserve (reserve_slowed, delay.h), at
 * obj_log_nth's rate. */
static void log_reserve_slowed(obj_t *o)
{
    uint64_t r = o->status.reserve_slowed;
    if (r == o->reserve_logged)
        return;
    o->reserve_logged = r;
    if (obj_log_nth(r))
        log_msg(LOG_NOTICE,
                "object '%s': short of its play-out delay's stop reserve on input that came on "
                "time (faster than the speed the reserve was sized for, or a fix lost within the "
                "lookahead): slowed along its path (%llu times so far), D grows to the input",
                o->name, (unsigned long long)r);
}

/* issue 26: D stated anew, longer, because the input's intervals or top
 * speed grew (engine_delay_grow): the new D and its parts, at obj_log_nth's
 * rate. */
static void log_delay_grown(obj_t *o)
{
    uint64_t n = o->status.delay_grown;
    if (n == o->grown_logged)
        return;
    o->grown_logged = n;
    if (!obj_log_nth(n))
        return;
    obj_log_delay(o, "its input's intervals, top speed or arrival jitter grew: ");
}

/* A new trajectory begun where nothing continued the current one (engine
 * reanchors: the input's time stepped back or far ahead, a log recorded
 * twice), at obj_log_nth's rate: it was only counted. */
static void log_reanchor(obj_t *o)
{
    const engine_status_t *st = &o->status;
    if (st->reanchors == o->reanchors_logged)
        return;
    o->reanchors_logged = st->reanchors;
    if (!obj_log_nth(st->reanchors))
        return;
    double d = st->reanchor_t_s - st->reanchor_from_t_s;
    log_msg(LOG_NOTICE,
            "object '%s': a new trajectory at its waypoint seq %lu, t = %.3f s: %.3f s %s the "
            "last waypoint kept (%.3f s), and nothing after it continues that one (a clock "
            "stepped %s, a log recorded twice, a jump): reached by a transfer (%llu re-anchors "
            "so far)",
            o->name, (unsigned long)st->reanchor_seq, st->reanchor_t_s, fabs(d),
            d < 0 ? "before" : "after", st->reanchor_from_t_s, d < 0 ? "back" : "ahead",
            (unsigned long long)st->reanchors);
}

void objlog_roll(core_t *c, unsigned start_budget)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        log_track_delay(&c->obj[i], &start_budget); /* a copy: carried ones too */
        if (c->obj[i].engine) {
            warn_uniform(&c->obj[i]);
            warn_axis(&c->obj[i]);
            log_underrun(&c->obj[i]);
            log_reserve_slowed(&c->obj[i]);
            log_delay_grown(&c->obj[i]);
            log_reanchor(&c->obj[i]);
            rejlog_drain(&c->obj[i].rejlog, c->obj[i].engine);
            rejlog_flush(&c->obj[i].rejlog, c->obj[i].name, log_rejection, (void *)c->obj[i].name);
        }
    }
}

/* What the first seconds of output are, per object: holding (state waiting,
 * no position before its first waypoint, or at rest at its initial_position)
 * until the lookahead is buffered (core.h). */
void objlog_first_seconds(const cfg_t *cfg)
{
    for (unsigned i = 0; i < cfg->nobj; i++) {
        const cfg_obj_t *o = &cfg->obj[i];
        const double *p = o->initial_position_m;
        /* delay_s set: the lookahead is picked from the first waypoints
         * (lib/engine/engine_input.c engine_pick), at most this one */
        char n[96];
        snprintf(n, sizeof n,
                 o->engine.delay_s > 0
                     ? "its lookahead is buffered (delay_s picks it: %u waypoints at most)"
                     : "at least %u waypoints are buffered",
                 engine_lookahead(&o->engine));
        if (o->has_initial_position) {
            log_msg(LOG_INFO,
                    "object '%s': holds (state waiting) at rest at its initial_position %g,%g,%g "
                    "until %s (the solver's lookahead and the "
                    "start slack), then reaches the first by a transfer and streams",
                    o->name, p[0], p[1], p[2], n);
            continue;
        }
        log_msg(LOG_INFO,
                "object '%s': holds (state waiting; no position, nan, before its first waypoint)"
                " until %s (the solver's lookahead and the start slack),"
                " then streams",
                o->name, n);
    }
}
