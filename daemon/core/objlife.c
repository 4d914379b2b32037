/* objlife.c - an object's inputs and commands, through the one owner of its
 * motion (lib/engine/lifecycle.h): waypoints, stop, start, clear, override,
 * holds, drive positions (core.h). */
#include <math.h>
#include <stdio.h>

#include "core.h"
#include "log.h"

lifecycle_t *obj_lc(obj_t *o)
{
    /* bound here, not at creation only: an object carried over a reload, or
     * one a test builds by hand, keeps one owner for its engine */
    o->lc.engine = o->engine;
    o->lc.safety = &o->safety;
    if (o->lc.period_ns <= 0)
        o->lc.period_ns = 1;
    return &o->lc;
}

/* One clock (lib/engine/CLOCK.md): an undecided object's first waypoint
 * decides whether its times are epoch time (within clock_window_s of now). */
static void obj_clock_decide(obj_t *o, const engine_waypoint_t *wp, int64_t real_ns)
{
    if (o->clocked >= 0 || !isfinite(wp->t_s))
        return;
    o->clocked = fabs(wp->t_s - (double)real_ns * 1e-9) <= o->clock_window_s;
    log_msg(LOG_INFO, "object '%s': first waypoint at t = %.3f s: %s", o->name, wp->t_s,
            o->clocked ? "epoch time, played out on the daemon's clock"
                       : "relative time, the object keeps its own origin");
}

int obj_push_from(obj_t *o, const engine_waypoint_t *wp, const char *src)
{
    if (o->stopping) {
        /* counted for the exit line, the first said (they were counted by
         * their transport alone, as refused, and nothing said why) */
        if (o->stop_refused++ == 0)
            log_msg(LOG_NOTICE, "object '%s': waypoint from %s refused: %s", o->name,
                    src ? src : "an unknown source",
                    o->stopping == OBJ_STOPPING_REMOVED
                        ? "a reload removes the object (it brakes to rest; the later ones are "
                          "counted, and said once it is gone)"
                        : "trajd is stopping (the later ones are counted on the exit line)");
        return -ENGINE_ESTATE;
    }
    int64_t real_ns = o->clocked ? core_real_ns() : 0;
    obj_clock_decide(o, wp, real_ns);
    rejlog_offered(&o->rejlog, wp, src);
    int rc = lc_push(obj_lc(o), wp);
    rejlog_drain(&o->rejlog, o->engine);
    if (rc == 0 && o->clocked == 1 && o->drift)
        playout_drift_add(o->drift, real_ns, wp->t_s);
    return rc;
}

static void sync_held(obj_t *o)
{
    o->held = (o->lc.hold & LC_HOLD_FEED) != 0;
}

void obj_hold(obj_t *o)
{
    (void)lc_event(obj_lc(o), LC_EV_HEARTBEAT_LOST, NULL);
    sync_held(o);
}

/* The feed override in percent (core.h obj_command, LC_EV_OVERRIDE). */
static int obj_set_override(obj_t *o, unsigned percent)
{
    lc_arg_t a = {percent / 100.0, NULL, NULL};
    if (percent > 200)
        return -ENGINE_ERANGE;
    return lc_event(obj_lc(o), percent ? LC_EV_OVERRIDE : LC_EV_OVERRIDE_ZERO, &a);
}

int obj_drive_event(obj_t *o, lc_event_t ev, const double *pos_m)
{
    lifecycle_t *lc = obj_lc(o);
    lc_state_t from = lc_state(lc);
    lc_arg_t a = {0, NULL, pos_m};
    /* a drive event the owner does not take now (drives enabled again while
     * the engine moves: daemon/can brings it to rest first) is no command
     * refused: not counted as one */
    uint64_t refused = lc->n.refused;
    int rc = lc_event(lc, ev, &a);
    lc->n.refused = refused;
    sync_held(o);
    if (rc < 0)
        return rc;
    return ev == LC_EV_DRIVE_ENABLED && lc_table[from][ev].action == LC_A_ADOPT;
}

/* 1 if one more command line of o may be logged this second (at most
 * OBJ_CMD_LOG_PER_S), with more filled with the count of lines not shown
 * before ("" if none); 0 (counted) if not. */
static int cmd_log_allowed(obj_t *o, char *more, size_t len)
{
    int64_t s = core_mono_ns() / 1000000000;
    if (s != o->cmd_log_s) {
        o->cmd_log_s = s;
        o->cmd_log_n = 0;
    }
    if (o->cmd_log_n >= OBJ_CMD_LOG_PER_S) {
        o->cmd_log_dropped++;
        return 0;
    }
    o->cmd_log_n++;
    more[0] = 0;
    if (o->cmd_log_dropped)
        snprintf(more, len, " (%llu command lines not shown before)",
                 (unsigned long long)o->cmd_log_dropped);
    o->cmd_log_dropped = 0;
    return 1;
}

void obj_log_refused(obj_t *o, const char *what, const char *peer, const char *why)
{
    char more[64];
    obj_lc(o)->n.refused++; /* counted with the owner's own refusals */
    if (cmd_log_allowed(o, more, sizeof more))
        log_at(__FILE__, __LINE__, __func__, o->name, peer ? peer : "unknown", LOG_WARNING,
               "object '%s': command %s from %s refused: %s%s", o->name, what,
               peer ? peer : "an unknown peer", why, more);
}

void obj_reset_counters_from(obj_t *o, const char *peer)
{
    char more[64];
    obj_reset_counters(o);
    if (cmd_log_allowed(o, more, sizeof more))
        log_at(__FILE__, __LINE__, __func__, o->name, peer ? peer : "unknown", LOG_NOTICE,
               "object '%s': command reset counters from %s: counters reset%s", o->name,
               peer ? peer : "an unknown peer", more);
}

/* One line per command, at most OBJ_CMD_LOG_PER_S a second per object. */
static void log_command(obj_t *o, lc_event_t ev, unsigned arg, const char *peer, lc_state_t from,
                        int rc)
{
    char more[64];
    if (!cmd_log_allowed(o, more, sizeof more))
        return;
    char val[96] = "";
    if (ev == LC_EV_OVERRIDE || ev == LC_EV_OVERRIDE_ZERO)
        snprintf(val, sizeof val, " %u %%", arg);
    else if (ev == LC_EV_START || ev == LC_EV_CLEAR) {
        /* those since the last such line: this latch's (the totals, on every later start
         * or clear, read as if each one had buffered them) */
        uint64_t b = o->lc.n.buffered, d = o->lc.n.dropped_past + o->lc.n.dropped_full;
        if (b < o->cmd_buf_told || d < o->cmd_drop_told) /* counters reset since */
            o->cmd_buf_told = o->cmd_drop_told = 0;
        if (from == LC_STOPPED || from == LC_STOPPING || from == LC_HELD || b > o->cmd_buf_told ||
            d > o->cmd_drop_told)
            snprintf(val, sizeof val,
                     " (waypoints while stopped or held: %llu buffered, %llu dropped)",
                     (unsigned long long)(b - o->cmd_buf_told),
                     (unsigned long long)(d - o->cmd_drop_told));
        o->cmd_buf_told = b;
        o->cmd_drop_told = d;
    }
    /* while a reload's old engine brakes, the state is the new engine's: said */
    const char *retiring = o->retiring ? " (the new engine's, which starts where the "
                                         "old one, still braking for a reload, rests)"
                                       : "";
    log_at(__FILE__, __LINE__, __func__, o->name, peer ? peer : "unknown", LOG_NOTICE,
           "object '%s': command %s%s from %s in state %s%s: %s%s -> %s%s", o->name,
           lc_event_name(ev), val, peer ? peer : "an unknown peer", lc_state_name(from), retiring,
           rc < 0 ? "refused" : lc_action_name((lc_action_t)lc_table[from][ev].action),
           rc >= 0 && o->lc.clear_pending ? " (once braked to rest: a drive hold)" : "",
           lc_state_name(lc_state(&o->lc)), more);
}

int obj_command(obj_t *o, lc_event_t ev, unsigned arg, const char *peer)
{
    lifecycle_t *lc = obj_lc(o);
    lc_state_t from = lc_state(lc);
    int rc;
    switch (ev) {
    case LC_EV_OVERRIDE:
    case LC_EV_OVERRIDE_ZERO: rc = obj_set_override(o, arg); break;
    case LC_EV_STOP:
    case LC_EV_START:
    case LC_EV_CLEAR:
    case LC_EV_END_OF_INPUT: rc = lc_event(lc, ev, NULL); break;
    default: rc = -ENGINE_ERANGE; break;
    }
    sync_held(o);
    if (ev == LC_EV_CLEAR && rc >= 0)
        o->clear_seq++;
    log_command(o, ev, arg, peer, from, rc);
    return rc;
}
