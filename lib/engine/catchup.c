/* catchup.c - the lag won back (see catchup.h). */
#include "catchup.h"

#include <math.h>
#include <string.h>

#include "delay.h"
#include "engine_int.h"
#include "timescale.h"

/* A new input trajectory (or a sender that began afresh): no sample yet. */
static void lag_reset(engine_t *e)
{
    e->lag.traj = e->solve.traj;
    e->lag.have = 0;
    e->lag.ahead = 0;
    e->lag.steer = 0;
}

void engine_lag_push(engine_t *e, double t_s)
{
    engine_lag_t *l = &e->lag;
    if (!l->pending || t_s > l->pend_max)
        l->pend_max = t_s;
    if (!l->pending || t_s < l->pend_min)
        l->pend_min = t_s;
    l->pending = 1;
}

/* The least-delayed sample, aged to the tick at_ns (catchup.h). */
static double offset_at(const engine_t *e, int64_t at_ns)
{
    double age = (double)(at_ns - e->lag.off_at_ns) * 1e-9;
    return e->lag.off_s - CATCHUP_DECAY_PPM * 1e-6 * (age > 0 ? age : 0.0);
}

/* The input's interval as the delay measures it (0: not yet). */
static double interval_of(const engine_t *e)
{
    engine_delay_t d;
    engine_delay(e, &d);
    return d.interval_s;
}

void engine_lag_note(engine_t *e, int64_t now_ns)
{
    engine_lag_t *l = &e->lag;

    if (l->traj != e->solve.traj)
        lag_reset(e);
    if (!l->pending)
        return;
    /* the newest stamp pushed since the last tick, arrived by this one: a
     * sample of the sender's time (relative to this tick's own time: both
     * may be large on an epoch time base, their difference is what counts).
     * Every row that passed engine_waypoint_check counts, kept or refused:
     * its stamp is the sender's clock whatever its position, and the output
     * then does not depend on when the acceptance gives its verdicts */
    double off = l->pend_max - (double)now_ns * 1e-9;
    l->pending = 0;
    double swing = fmax(CATCHUP_SWING_S, CATCHUP_SWING_INTERVALS * interval_of(e));
    if (!l->have) {
        l->off_first = off;
        l->first_ns = now_ns;
        /* a first batch whose stamps span more than the swing came at once:
         * loaded, not sent as it went */
        if (l->pend_max - l->pend_min > swing)
            l->ahead = 1;
    } else if (off - l->off_first >
               swing + CATCHUP_DECAY_PPM * 1e-6 * (double)(now_ns - l->first_ns) * 1e-9) {
        /* the stamps run ahead of their arrivals by more than latency and
         * drift swing: a program uploaded or a buffer filled ahead of time,
         * not a live sender; nothing to win back, its output plays at rate 1 */
        l->ahead = 1;
    }
    if (!l->have || off > offset_at(e, now_ns)) {
        l->off_s = off;
        l->off_at_ns = now_ns;
    } else if (!l->ahead) {
        /* later than the least-delayed sample says: the arrivals' jitter,
         * beyond the period its tick rounds an arrival to; the slack holds
         * it in time (delay.h), D grows to it */
        double late = offset_at(e, now_ns) - off - e->period_s;
        if (late > l->jit_s) {
            l->jit_s = late;
            engine_delay_grow(e);
        }
    }
    l->have = 1;
    l->seen_ns = now_ns;
}

/* The lag beyond D now (catchup.h), with the D stated in *d; 0 (and *d
 * unread) when none is told: no sample of the trajectory played, stamps
 * ahead of time, a start not governed by D (start_slack set, delay_s not)
 * or D not measured; and, open set, the trajectory's input closed (what is
 * steered: a closed trajectory's tail plays out as it was stamped, the
 * sender's time running on through the silence; its lag is told, lag_s). */
static double lag_of(const engine_t *e, engine_delay_t *d, int open)
{
    if (!e->lag.have || e->lag.ahead || e->lag.traj != e->out.traj || !e->out.have_now ||
        (open && !e->in.open) || !(e->slack_auto || e->cfg.delay_s > 0) || !e->delay.noted)
        return 0.0;
    engine_delay(e, d);
    if (!(d->interval_s > 0))
        return 0.0;
    double now = (double)e->out.last_now * 1e-9;
    /* D as stated (engine_delay: the slack learnt since the start in it).
     * The sender's time is aged to the last tick that brought a sample, not
     * to now: the lag then changes only at ticks after a push, which end
     * the rate decision kept (plain_window, engine_tick.c) */
    double D = d->delay_s;
    return (now + offset_at(e, e->lag.seen_ns) - D) - e->out.t;
}

/* The lag steered: only while the input is open. */
static double lag_now(const engine_t *e, engine_delay_t *d)
{
    return lag_of(e, d, 1);
}

double engine_lag_trailing(const engine_t *e)
{
    if (!e->lag.have || e->lag.ahead || e->lag.traj != e->out.traj || !e->out.have_now)
        return NAN;
    return (double)e->out.last_now * 1e-9 + offset_at(e, e->lag.seen_ns) - e->out.t;
}

/* Beyond this lag it is won back: half an input interval of d, two ticks at
 * least. */
static double band_on(const engine_t *e, const engine_delay_t *d)
{
    return fmax(0.5 * d->interval_s, 2.0 * e->period_s);
}

int engine_lag_pending(const engine_t *e)
{
    engine_delay_t d;
    if (e->lag.steer)
        return 1;
    if (!e->lag.have || e->lag.ahead || e->out.mode != OUT_STREAM)
        return 0; /* (stamps ahead of time: lag_now tells none) */
    /* within a tick of the band: decide() reads the lag before the tick's
     * step (now on, the output's track time not yet), a tick more than
     * after it, where plain_window asks; a window kept at a lag 0.6 ms
     * short of the band met a decision that steered at the next tick
     * (fuzz_lifecycle, engine_plain_check) */
    double lag = lag_now(e, &d);
    return lag < 0.0 || lag > 0.0 ? fabs(lag) + 2.0 * e->period_s > band_on(e, &d) : 0;
}

double engine_lag_target(engine_t *e, double target, double R, double A, double J)
{
    /* not on a join (join.c): it is made for rate 1, and its track time
     * is the warped one; the lag it leaves is won back after it */
    if (!(target >= 1.0 && target <= 1.0) || e->out.mode != OUT_STREAM || e->out.underrun ||
        e->out.cur.join) {
        e->lag.steer = 0;
        return target;
    }
    engine_delay_t d;
    /* read before this tick's step (step_once: the output's track time is
     * still the last tick's): the lag once the step is made, at the rate
     * the output runs at; read as it was, the output was steered a tick
     * closer than D (the 10 Hz track of tests/e2e/test_delay.py stood
     * 2.537 s behind its D of 2.546 s after its catch-up) */
    double T = e->period_s, at = e->scale.on ? e->scale.ts.rate : 1.0;
    double told = lag_of(e, &d, 0);
    if (told < 0.0 || told > 0.0)
        told -= at * T;
    /* told whether steered or not: a closed trajectory played behind its D
     * (its input came while a long transfer crossed a gap) said lag 0 */
    e->st.lag_s = told;
    double lag = e->in.open ? told : 0.0;
    if (!(lag < 0.0 || lag > 0.0)) {
        e->lag.steer = 0; /* none told (lag_now): d unread */
        return target;
    }
    if (!e->lag.steer) {
        /* from the unit grid only: a ramp (a start, a resume) is on its way
         * to rate 1 and would be steered by a lag it is itself winning */
        if (e->scale.on || !(fabs(lag) > band_on(e, &d)))
            return target;
    } else if (fabs(lag) < 0.1 * T) {
        e->lag.steer = 0;
        return target;
    }
    double c = e->clk.catchup, lead = ENGINE_CLOCK_GAIN * lag;
    /* slower by up to CATCHUP_GIVEBACK x c: an output ahead of its D (a D
     * that grew) falls back before it runs short */
    lead = lead > c ? c : lead < -CATCHUP_GIVEBACK * c ? -CATCHUP_GIVEBACK * c : lead;
    double r = target + lead;
    /* faster only where the curve ahead holds a stop from r, the slack and
     * a tick besides: winning back never runs into the data */
    if (r > target && !(isinf(R) || ts_stop_dist(r, 0.0, A, J) + d.slack_s + r * T < R))
        return target;
    if (!e->lag.steer) {
        e->lag.steer = 1;
        e->st.catchups++;
    }
    return r;
}
