/* silence.c - a trajectory's tail plays out after a silence (see silence.h). */
#include "silence.h"

#include <math.h>

#include "delay.h"
#include "engine_int.h"

/* The waypoint an underrun waited for came, stamped t_s.  Late (its arrival
 * after the one before later than their stamps by more than the jitter D
 * holds, and a tick): counted, D learns (play_underrun_counted).  A regular
 * sender's on time, its stamp a whole number of intervals after the one
 * before (engine_input_hole): the silence was fixes lost, not the input
 * late: a slowdown for them (reserve_slowed), D kept (issue 26: the 24 h
 * run, 1 % lost, two in a row now and then). */
static void silence_ended(engine_t *e, double t_s)
{
    double gap = t_s - e->out.und_t;
    if (e->sil.arrived && engine_input_hole(e, gap)) {
        engine_delay_t d;
        engine_delay(e, &d);
        /* it arrived by the next tick: at most a period after the last one */
        double waited = (double)(e->out.last_now + e->cfg.period_ns - e->sil.arrival_ns) * 1e-9;
        if (waited - gap <= d.jitter_s + 2.0 * e->period_s) {
            e->out.und_pending = 0;
            e->st.reserve_slowed++;
            return;
        }
    }
    play_underrun_counted(e); /* the waypoint it waited for came: late */
}

void engine_silence_push(engine_t *e, const engine_waypoint_t *wp)
{
    int gap = e->sil.n && wp->t_s - e->sil.last_t > e->cfg.max_gap_s;
    if (e->sil.closed && gap)
        e->st.gaps++; /* the trajectory a silence ended was ended by a gap too */
    if (e->sil.closed || gap || (e->in.open && e->sil.traj != e->solve.traj)) {
        /* a new trajectory (or the first): its timing starts afresh */
        e->sil.n = 0;
        e->sil.int_max = 0.0;
        e->sil.closed = 0;
    }
    e->sil.traj = e->in.open ? e->solve.traj : e->solve.traj + 1;
    if (e->sil.n && wp->t_s > e->sil.last_t && wp->t_s - e->sil.last_t <= e->cfg.max_gap_s)
        e->sil.int_max = fmax(e->sil.int_max, wp->t_s - e->sil.last_t); /* a gap is none */
    if (!e->sil.n || wp->t_s > e->sil.last_t) {
        if ((e->st.underruns || e->out.und_pending) && isnan(e->st.underrun_next_t_s) &&
            wp->t_s > e->st.underrun_newest_t_s)
            e->st.underrun_next_t_s = wp->t_s; /* the silence the last underrun met ends */
        if (e->out.und_pending && wp->t_s > e->out.und_t)
            silence_ended(e, wp->t_s);
        e->sil.last_t = wp->t_s;
        e->sil.n++;
    }
    /* arrived by the next tick (engine_silence_tick), the first one too:
     * waypoints pushed before it (a writer quicker than the daemon's first
     * deadline, an engine a reload starts while its predecessor brakes)
     * are the input's as much as any, and its silence ends them too */
    e->sil.fresh = 1;
}

/* The trajectory has the lookahead's intervals (la_steady + 1): its timing
 * is known (span_max measures as many), and its output may have started. */
static int engine_silence_judged(const engine_t *e)
{
    return e->sil.n >= (uint64_t)e->la_steady + 2;
}

int64_t engine_silence_at_ns(const engine_t *e)
{
    if (!engine_silence_pending(e) || !e->sil.arrived)
        return INT64_MAX;
    double at = (double)e->sil.arrival_ns + engine_silence_limit_s(e) * 1e9;
    return at < 9e18 ? (int64_t)at + 1 : INT64_MAX; /* the first tick past the limit */
}

int engine_silence_soon(const engine_t *e)
{
    return engine_silence_pending(e) && engine_silence_judged(e);
}

double engine_silence_limit_s(const engine_t *e)
{
    engine_delay_t d;
    /* too few intervals to tell its timing (a short move, a lone
     * waypoint): max_gap_s, after which a waypoint would start a new
     * trajectory anyway */
    if (!engine_silence_judged(e))
        return e->cfg.max_gap_s;
    engine_delay(e, &d);
    /* the output stands D behind the newest waypoint and needs the
     * lookahead's waypoints to go on: what is left of D is the slack and
     * the stop reserve; and never within the input's own timing (its
     * longest interval so far, SILENCE_INTERVALS times: a late fix of a
     * jittery sender, a walk's long pause) */
    double s = fmax(d.delay_s - d.lookahead_s, SILENCE_INTERVALS * e->sil.int_max);
    return fmin(s, e->cfg.max_gap_s);
}

int engine_silence_pending(const engine_t *e)
{
    /* (a lone first waypoint is still the acceptance's: the trajectory
     * opens with its verdict, engine_finish gives it) */
    return (e->in.open || accept_pending(&e->in.policy)) && (e->sil.arrived || e->sil.fresh) &&
           !e->clk.on && e->sil.n > 0;
}

int engine_silence_tick(engine_t *e, int64_t now_ns)
{
    if (e->sil.fresh) {
        /* pushed since the last tick: arrived by this one (never earlier:
         * a caller late by a stall pushes what came meanwhile first, and
         * its own lateness is no silence of the sender) */
        e->sil.fresh = 0;
        e->sil.arrived = 1;
        e->sil.arrival_ns = now_ns;
        return 0;
    }
    if (!engine_silence_pending(e) || now_ns <= e->sil.arrival_ns)
        return 0;
    double limit = engine_silence_limit_s(e);
    if ((double)(now_ns - e->sil.arrival_ns) * 1e-9 <= limit)
        return 0;
    e->sil.arrived = 0;
    e->sil.closed = 1;
    e->st.silent_ends++;
    if (e->out.und_pending && e->out.und_traj == e->sil.traj && !(e->sil.last_t > e->out.und_t)) {
        /* the output ran short with no waypoint since: that was the input's
         * end, now known, not a late waypoint: not counted, nothing learnt
         * (its ticks are in underrun_ticks, as they were sent); its log line
         * says so (engine_underrun_format) */
        e->out.und_pending = 0;
        e->st.underrun_silence_s = limit;
    }
    (void)engine_finish(e); /* -ENGINE_ENUMERIC cannot happen with finite data */
    return 1;
}
