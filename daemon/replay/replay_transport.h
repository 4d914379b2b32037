/*
 * replay_transport.h - the "replay" input transport: an object's waypoints come from
 * a logged track (daemon/replay/track.h), fed to its engine on ENGINE time by
 * daemon/replay/replay.h right before each engine_tick, exactly as trajreplay does,
 * so the daemon's output of a track is byte-identical to trajreplay's.
 * The wall-clock pace is [daemon] speed (1.0 = real time).
 *
 * Object keys ([object.NAME]):
 *   replay.track   = FILE      track file, relative to the config's directory (required)
 *   replay.format  = auto      a name of track_format_names (track.h)
 *   replay.skip_bad = no       yes: a malformed line is skipped, counted and
 *                              logged (warning "file:line: what"), not an error
 *   replay.start_s = 0         engine time (s after start) at which the first waypoint is due
 * The track is loaded when the config is checked (start, reload, --check-config),
 * so a missing or bad file rejects the config with its own file:line message.
 * A reload takes the running configuration's track when the file is unchanged
 * (track_cache.h): it is not parsed again, and the object is carried over if
 * nothing else of it changed; a changed file makes it a changed object.
 */
#ifndef TRAJD_REPLAYIN_H
#define TRAJD_REPLAYIN_H

#include "track.h"
#include "track_cache.h"
#include "transport.h"

typedef struct {
    char path[PATH_MAX];
    track_format_t format;
    double start_s;
    int skip_bad;     /* TRACK_SKIP_BAD */
    int line;         /* line of replay.track, for messages */
    track_t trk;      /* loaded by check(): a shallow copy of ref's (track_cache.h) */
    track_ref_t *ref; /* the shared track (NULL: trk is its own, track_free it) */
    int loaded;
} replay_transport_obj_cfg_t;

extern const transport_t replay_transport;

#endif
