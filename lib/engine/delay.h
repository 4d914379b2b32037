/*
 * delay.h - the play-out delay D of an engine, stated (issue 26): how far the
 * output trails the input in steady streaming, and what it is made of.
 *
 * On regular input of interval h the output stands D behind the newest
 * waypoint received, where
 *
 *     D = L h           lookahead: the solver makes a segment final once L
 *                       more waypoints are in (engine_lookahead; with
 *                       start_slack set, less the slack)
 *       + slack         start_slack auto (the default), in time: the
 *                       fragments' an input interval less what the stop
 *                       reserve holds beyond v/(2a) (its jerk term and
 *                       margin), so that D = (L + 1) h + v/(2a) where they
 *                       fit, and ENGINE_DELAY_TICKS periods at least; the
 *                       local methods' (issue 31) an interval, at most
 *                       ENGINE_DELAY_TICKS periods (at the low-latency end a
 *                       whole interval would be a third of D:
 *                       tests/oracle/test_hermite.py test_low_latency_delay).
 *                       On top: the arrivals' jitter J (those later than the
 *                       least-delayed one says, beyond a period of tick
 *                       rounding: catchup.c; D grows to it as it is seen,
 *                       engine_delay_grow) and an interval per underrun
 *                       learnt (a fix lost where the solver needs the most
 *                       lookahead, or later than the slack).  start_slack S
 *                       set: S intervals, counted (L then less S, + 1)
 *       + B             stop reserve: the curve kept solved ahead of the
 *                       output so that, should the input stop, the time
 *                       scaling brings it to rest on data: a stop from rate
 *                       1 at the top speed v, within scale_accel_m_s2 a and
 *                       scale_jerk_m_s3 j: v/(2a) + a/(2j) (ts_stop_dist),
 *                       plus TS_MARGIN_TICKS periods
 *
 * The engine starts a trajectory's output once it is D behind less what the
 * ramp from rest to rate 1 loses (a start from rest loses a stop's track
 * time: the ramp itself builds the stop reserve), so the steady delay is D.
 * Where the ramp loses more than B (a REST start's curve is faster than
 * its waypoints where it ramps, or bends harder: the limits are converted
 * at its speed bound), the excess is a lag the catch-up wins back
 * (catchup.h), not a longer D: 0.19 s on the 10 Hz track of
 * tests/e2e/test_delay.py (its D 2.476 s, B 0.646 s).  A live re-anchor
 * needs more of the new curve than D holds beyond its lookahead: the old
 * curve's tail is played slower for it (join.c join_wait_rate).  With a
 * fixed start_slack the start counts waypoints and D is where that start
 * leaves the output (the wait plus the ramp's loss).  With delay_s set
 * (engine_config_t), D is delay_s: it must be at least what the settings
 * need (engine_delay_check).  On the caller's clock (engine_set_clock) D is
 * the clock's, and a start's ramp is a lag the clock wins back (CLOCK.md
 * "Behind"), not a longer D.
 *
 * Pure: no clock, no I/O.
 */
#ifndef TRAJD_DELAY_H
#define TRAJD_DELAY_H

#include <stddef.h>

#include "engine.h"

/* start_slack auto: the local methods' slack is an input interval, at most
 * this many output periods, the fragments' at least this many: beyond them
 * the slack is what the arrivals measure (J) and the underruns teach.  An
 * arrival is taken at the first tick after it, and the braking for the end
 * of the solved curve is decided a tick ahead with TS_MARGIN_TICKS and the
 * rises of the limits ahead in hand: 2 periods fall short (the output slows
 * for the reserve on the regular 10 Hz tracks of tests/oracle/test_hermite.py
 * and tests/e2e/test_delay.py at --max-lookahead 1 and 2). */
#define ENGINE_DELAY_TICKS 3u

typedef struct {
    double interval_s;    /* h: the input's interval (0: unknown) */
    double speed_m_s;     /* v: the top speed the stop reserve is for */
    unsigned lookahead_n; /* L: intervals of lookahead (start_slack set: L - S + 1) */
    unsigned slack_n;     /* start_slack auto: intervals learnt; set: S */
    unsigned slack_ticks; /* start_slack auto: ENGINE_DELAY_TICKS (0: set) */
    double lookahead_s;   /* lookahead_n h */
    double slack_s;       /* the slack in time, J and the intervals learnt (auto); S h */
    double jitter_s;      /* J, where it sets the slack (else 0) */
    double stop_s;        /* B */
    double need_s;        /* lookahead_s + slack_s + B: what the settings need */
    double delay_s;       /* D: need_s, or delay_s when set (>= need_s then) */
    double asked_s;       /* delay_s as set (or the clock's D), 0 if not: D above it is
                             what the input needs, said so (engine_delay_format) */
    int method;           /* engine_method_t resolved: the local methods' (issue 31) where
                             max_lookahead is too short for any fragment */
} engine_delay_t;

/*
 * The delay of configuration cfg (resolved or not) for input of interval
 * interval_s (0: unknown, the interval parts are 0) and top speed speed_m_s
 * (<= 0: the speed limit in force, engine_config_max_speed: the profile's or
 * the configured one; without a limit, 1 m/s).  Returns 0, or
 * -ENGINE_ECONFIG (cfg does not resolve; *d zeroed).
 */
int engine_delay_of(const engine_config_t *cfg, double interval_s, double speed_m_s,
                    engine_delay_t *d);

/* engine_delay_of for a resolved configuration r whose lookahead
 * (engine_lookahead) is la: what an engine, which holds both, uses. */
void engine_delay_parts(const engine_config_t *r, unsigned la, double interval_s, double speed_m_s,
                        engine_delay_t *d);

/* The max_lookahead delay_s picks (engine_input.c engine_pick): of 1 ..
 * cfg->max_lookahead, the longest whose need (delay_s aside) at interval_s
 * and speed_m_s is within cfg->delay_s; cfg->max_lookahead itself where
 * delay_s is 0, the interval unknown or none fits. */
unsigned engine_lookahead_for_delay(const engine_config_t *cfg, double interval_s,
                                    double speed_m_s);

/* The stop reserve alone: B above for top speed v (>= 1 m/s is used). */
double engine_delay_stop_s(const engine_config_t *cfg, double speed_m_s);

/*
 * delay_s against what the settings need: 0 if delay_s is 0 (auto) or at
 * least the stop reserve at the speed limit in force plus the lookahead and
 * slack at interval_s (0: unknown, not counted); else -ENGINE_ECONFIG with
 * why holding the numbers, e.g. "delay_s 2 s is shorter than the settings
 * need: 40.1 s = stop reserve 40.1 s (from 400 m/s at scale_accel_m_s2 5)
 * + 18 input intervals (lookahead 18, slack 0) x the interval + a few ticks;
 * raise delay_s, or lower max_speed_m_s".
 */
int engine_delay_check(const engine_config_t *cfg, double interval_s, char *why, size_t whylen);

/* One line: "D 2.476 s = lookahead 18 x 0.1 s + slack 0.030 s (an interval
 * less the stop's a/(2j) and margin, at least 3 ticks) + stop reserve
 * 0.646 s (from 5.76 m/s)"; returns snprintf's length. */
int engine_delay_format(const engine_delay_t *d, char *buf, size_t len);

/*
 * The last underrun of status st (engine_status_t underrun_*) in one line:
 * "underrun at t = 12.345 s: no waypoint after t = 12.2 s until t = 12.8 s,
 * a silence of 0.6 s, longer than the 0.4 s D holds for one (the interval
 * and the jitter slack)"; "... until now" while none came; "within the ..."
 * where the silence was shorter (D too short for this input's timing); "...
 * taken as its end" where the silence then ended the trajectory (silence.h).
 * Returns snprintf's length, 0 (buf "") before any underrun.
 */
int engine_underrun_format(const engine_status_t *st, char *buf, size_t len);

/* 1 if status st holds an underrun not told yet: its underrun_t_s differs
 * from told_t_s (NaN: none told), and the silence it met has ended, or
 * ended its trajectory (or at_end: the replay is over).  What trajd and
 * trajreplay log by. */
int engine_underrun_due(const engine_status_t *st, double told_t_s, int at_end);

/*
 * The D an engine holds its output at (delay_run.c): the one it stated when
 * its last trajectory's output started, or, before any start, what its
 * settings and the input measured so far need.  The interval and the top
 * speed are measured on the input (the longest recent interval, the fastest
 * recent chord).
 */
void engine_delay(const engine_t *e, engine_delay_t *d);

/* Engine-internal (engine_tick.c): 1 once the output of the trajectory at the
 * queue head (a segment) may start and stand D behind the newest waypoint
 * after its ramp from rest; engine_delay_note records the D of a start.
 * lag (may be NULL): the ramp's loss if engine_delay_ready simulated it, else
 * NAN; engine_delay_note takes it back on the same tick instead of simulating
 * the same ramp again (NAN: it does). */
int engine_delay_ready(const engine_t *e, double *lag);
void engine_delay_note(engine_t *e, double lag);
/* Engine-internal (engine_scale.c): 1 if the output, held back by the curve
 * ahead, is short of its stop reserve while the input is on time: the
 * newest waypoint arrived within the interval and slack D holds for one
 * (and a tick), and the solved curve ends within D's lookahead of it, in
 * time or, fixes lost, in waypoints (at most la_steady nodes after its end,
 * the acceptance judging at most a refused fix's next).  The object then moves faster than the
 * speed the reserve was sized for (D grows with the input's top speed), or a
 * fix was lost within the lookahead (D grows with the intervals): a
 * slowdown for the reserve, counted in reserve_slowed, not an underrun.
 * Returns 2 for fixes lost (the span longer in time only), 1 otherwise. */
int engine_delay_reserve_short(const engine_t *e);

/* 1 if the input's intervals are whole numbers of one interval (its lost
 * fixes aside, engine_interval_holes): a regular sender. */
int engine_input_regular(const engine_t *e);
/* 1 if a regular sender's stamps gap_s apart are fixes lost between them:
 * a whole number (2 or more) of its interval. */
int engine_input_hole(const engine_t *e, double gap_s);
/* Engine-internal (engine_scale.c: the output back at rate 1 after its
 * start's ramp, an underrun or a slowdown for the reserve): a fixed
 * start_slack's output is not steered back to D (catchup.h), so the D stated
 * becomes where it now trails (engine_lag_trailing). */
void engine_delay_restate(engine_t *e);
/* Engine-internal (an underrun, play_count_underrun): the D the input
 * measured now, if longer than the D stated, is stated instead (intervals
 * longer than at the start): the output then stands that far behind. */
void engine_delay_grow(engine_t *e);

#endif
