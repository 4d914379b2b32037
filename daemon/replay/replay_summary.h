/*
 * replay_summary.h - trajreplay's --summary: one "summary: name value" line
 * per counter on stderr, so scripts can read them (trajreplay(1)), and the
 * underruns told as they are known.
 */
#ifndef TRAJD_REPLAY_SUMMARY_H
#define TRAJD_REPLAY_SUMMARY_H

#include <stdint.h>

#include "engine.h"
#include "replay.h"
#include "track.h"

/* The counters of a replay of trk (r: its feed; max_v, max_a: the fastest
 * setpoint; ticks: setpoints written). */
void replay_print_summary(const track_t *trk, const replay_t *r, const engine_status_t *st,
                          double max_v, double max_a, uint64_t ticks);

/* The play-out delay D the engine held and its parts (lib/engine/delay.h),
 * and the method it resolved to. */
void replay_print_delay(const engine_t *e);

/* The per-axis limits stopped the output on its path (st: axis_lag_stops, a
 * lag beyond max_lag_s; axis_beyond, a segment over 100 times faster on an
 * axis than its limit; issue 32): say where on stderr, as "input:line: error:
 * ..." with the first waypoint it did not reach after stop_t_s (the output's
 * track time when it was first stopped; results[i] < 0 for i < judged: a
 * rejected waypoint, passed over).  Returns 1 if it was stopped, else 0. */
int replay_report_axis_stop(const char *input, const track_t *trk, const int *results,
                            size_t judged, const engine_status_t *st, double stop_t_s,
                            double max_lag_s);

#endif
