/*
 * catchup.h - the lag won back (issue 26, item 3): an output that is not on
 * a caller's clock (relative time: a replay, a CNC program, any sender whose
 * stamps are not epoch seconds) follows its own estimate of the sender's
 * time, so that after an underrun, a gap or a transfer its delay returns to
 * D, and a sender whose clock runs fast or slow is followed instead of
 * turning into lag or underruns.
 *
 * The sender's time now is estimated from the arrivals of its waypoints:
 * each newest waypoint, at the tick it arrived by, is a sample
 * off = t_stamp - t_arrival; latency only ever lowers a sample, so the
 * largest is kept (the least-delayed one), less CATCHUP_DECAY_PPM of the
 * time since it came, so that a sender whose clock runs slow is followed
 * too.  The lag is then
 *
 *     lag = (now + off - D) - t_out      D: the delay (delay.h), as measured
 *
 * Beyond half an input interval (and two ticks), the output's target rate
 * becomes 1 + min(ENGINE_CLOCK_GAIN lag, catchup) (at most CATCHUP_GIVEBACK
 * x catchup below 1 when the output is ahead), within the time scaling's
 * limits; within a
 * tick's tenth of the lag it goes back to rate 1 on the unit grid.  It
 * speeds up only where the curve ahead still holds a stop from the faster
 * rate plus the jitter slack, so winning back never runs into the data.
 *
 * Pure: the engine's own tick times, no clock.
 */
#ifndef TRAJD_CATCHUP_H
#define TRAJD_CATCHUP_H

#include <stdint.h>

#include "engine.h"

/* How fast the least-delayed sample ages (parts per million of the time
 * since it came): above any sender drift trajd follows (drift_max_ppm). */
#define CATCHUP_DECAY_PPM 1000.0
/* Stamps that come faster than time by more than this (s, or intervals of
 * the input, whichever is more) are ahead of time: an upload, not a live
 * sender; its output is not steered. */
#define CATCHUP_SWING_S 1.0
#define CATCHUP_SWING_INTERVALS 4.0
/* An output ahead of its D (lag < 0: a D that grew with the input's
 * intervals, engine_delay_grow) falls back at up to this many times the
 * catch-up (slower is never closer to the data): at the default 5 %, 20 %
 * slower until it stands at D. */
#define CATCHUP_GIVEBACK 4.0
/* The catch-up when no clock sets one (engine_set_clock): 5 %, as [daemon]
 * catchup's default. */
#define CATCHUP_DEFAULT 0.05

/* A waypoint of stamp t_s pushed: it arrives by the next tick. */
void engine_lag_push(engine_t *e, double t_s);

/* A tick at now_ns: the newest waypoint's arrival, if one came, is a sample
 * of the sender's time. */
void engine_lag_note(engine_t *e, int64_t now_ns);

/* The rate the unclocked output is asked for at this tick, given the rate
 * it is asked for otherwise (target: 1 streaming freely) and the time
 * scaling's room R and limits A, J (engine_scale.c); target itself when no
 * lag is to be won back. */
double engine_lag_target(engine_t *e, double target, double R, double A, double J);

/* How far the output trails the sender's time now (s): now + off - t_out,
 * the least-delayed sample's off; NAN without a sample of the trajectory
 * played, or with stamps ahead of time. */
double engine_lag_trailing(const engine_t *e);

/* 1 while a lag is being won back or is within a tick of the band where
 * that begins: no rate decision is then kept for the ticks ahead
 * (plain_window). */
int engine_lag_pending(const engine_t *e);

#endif
