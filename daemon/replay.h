/*
 * replay.h - feed a loaded track into an engine on the engine's clock.
 *
 * Waypoint i is due at start_ns + (t_i - t_0) seconds of *engine* time (the
 * now_ns passed to engine_tick).  The daemon scales wall-clock to engine time
 * by its replay speed, trajreplay uses a virtual clock; both call
 * replay_feed(r, e, now_ns) right before engine_tick(e, now_ns, ...), so they
 * produce the same setpoints.  A waypoint refused with ENGINE_EFULL is kept
 * and offered again at the next call (nothing accepted and then lost).
 * After the last waypoint, engine_finish() is called once.
 */
#ifndef TRAJD_REPLAY_H
#define TRAJD_REPLAY_H

#include <stdint.h>
#include "engine.h"
#include "track.h"

typedef struct {
    const track_t *trk;
    size_t next;          /* index of the next waypoint to offer */
    int64_t start_ns;     /* engine time at which waypoint 0 is due */
    int finished;         /* engine_finish() has been called */
    uint64_t retries;     /* offers refused with ENGINE_EFULL */
    uint64_t refused;     /* waypoints the engine rejected (bad data) */
} replay_t;

void replay_init(replay_t *r, const track_t *trk, int64_t start_ns);

/* Offer every waypoint due at or before now_ns.  Returns how many were offered. */
int replay_feed(replay_t *r, engine_t *e, int64_t now_ns);

/* 1 once every waypoint was offered and engine_finish() called. */
int replay_done(const replay_t *r);

#endif
