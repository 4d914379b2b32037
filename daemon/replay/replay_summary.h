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

#endif
