/*
 * silence.h - a trajectory's tail plays out (issue 26 item 2).
 *
 * The solver makes a segment final only once the lookahead's waypoints are
 * in, so when the input falls silent the last lookahead's worth of a
 * trajectory would wait for the next trajectory (the output standing in
 * UNDERRUN short of the last waypoint received).  The engine gets no clock,
 * but it knows the tick times (engine_tick's now_ns): the first one after a
 * push is that waypoint's arrival (a caller that was late pushes first what
 * came meanwhile: its own lateness is no silence of the sender).  Once the input has been silent for
 * longer than the part of D beyond the lookahead (delay.h: the jitter slack
 * plus the stop reserve; the output would otherwise run dry) and than
 * SILENCE_INTERVALS times its longest interval in the trajectory (its own
 * timing), at most max_gap_s, the engine
 * closes the trajectory as engine_finish does: the configured end condition
 * on its last waypoint, the output plays on to it and rests there
 * (FINISHED).  Waypoints that come later start a new trajectory, reached by
 * a transfer.  Counted in engine_status_t silent_ends (and in gaps too if
 * the next waypoint comes more than max_gap_s later).  Not for an engine on
 * the one clock (engine_set_clock): there a silence is a lag the catch-up
 * wins back (CLOCK.md).
 *
 * Pure: the times are the caller's tick times.
 */
#ifndef TRAJD_SILENCE_H
#define TRAJD_SILENCE_H

#include <stdint.h>

#include "engine.h"

/* The silence is at least the input's longest interval in the trajectory
 * so far this many times.  Before the trajectory has the lookahead's worth
 * of intervals (a short move, a stream's start), D is what its intervals
 * and chords so far give; a lone waypoint's silence is max_gap_s.  On the real
 * tracks (tests/data) the largest ratio of an interval (below max_gap_s) to
 * the longest one before it in its trajectory, from its lookahead's worth on,
 * is 2.7 on gpxgo_visnjan (a 41 s pause of a walk logged every 1 to 15 s),
 * 2.5 on the figure-eight (a late fix: 0.496 s after 0.2 s), 1.4 on
 * gpxpy_cerknicko-jezero, 2.7 on the G-code toolpath timed by feed rate of
 * tests/oracle/test_profile_kinds.py (a 6.45 s line after short chords);
 * replayed, none of them ends a trajectory by a silence short of a gap
 * (tests/e2e/test_delay.py TestTailPlaysOut, test_profile_kinds.py). */
#define SILENCE_INTERVALS 6.0

/* Engine-internal (engine_input.c, engine_tick.c).  engine_push: note that wp arrived (by the
 * next tick) and its interval. */
void engine_silence_push(engine_t *e, const engine_waypoint_t *wp);

/* engine_tick, before the output steps: close the input trajectory if the
 * input has been silent for longer than D less the lookahead at now_ns.
 * Returns 1 if it did. */
int engine_silence_tick(engine_t *e, int64_t now_ns);

/* 1 while a silent end may come without a push: the input trajectory is
 * open, has a waypoint and the engine is not on the
 * clock (engine_status's stalled is 0 then: the ticks are not all holds). */
int engine_silence_pending(const engine_t *e);

/* The tick time past which the silence closes the input trajectory, should
 * no waypoint come (engine_status_t silence_at_ns); INT64_MAX if none. */
int64_t engine_silence_at_ns(const engine_t *e);

/* engine_silence_pending, for a trajectory whose timing is measured (its
 * silence judged by D, seconds): what keeps an engine from being stalled
 * (engine_status); a shorter one's, max_gap_s, does not (a caller that
 * skips idle time to the next waypoint due over max_gap_s later, as
 * trajreplay does, meets the same end: a gap). */
int engine_silence_soon(const engine_t *e);

/* The silence after which the input trajectory is closed, seconds (at most
 * max_gap_s). */
double engine_silence_limit_s(const engine_t *e);

#endif
