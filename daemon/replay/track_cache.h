/*
 * track_cache.h - tracks loaded by the configurations alive in this process,
 * shared between them: a reload whose object names the same file, unchanged
 * (same device, inode, size, mtime and ctime), with the same format and
 * skip_bad, takes the running configuration's track instead of parsing it
 * again (issue 28 item 2: a reload of an unchanged 1e6-waypoint track costs
 * no parse).  A file that changed in any of these is parsed again, and its
 * object is then a changed object (replay_transport obj_same).
 *
 * A track_ref_t is counted: each configuration holds one reference per
 * object; the last put frees it.  Geographic tracks are re-expressed about
 * the configuration's datum (track_reframe): track_cache_private makes a
 * configuration's copy first when that datum differs, so a running
 * configuration never sees its waypoints move.  Thread-safe: a reload's
 * worker (cfgload.h) takes references while the loop drops others.
 */
#ifndef TRAJD_TRACK_CACHE_H
#define TRAJD_TRACK_CACHE_H

#include "track.h"

typedef struct track_ref track_ref_t;

/*
 * The track at path loaded with fmt and flags (track_load_opts): a new
 * reference to the one already loaded if the file is unchanged (*cached set
 * to 1), else loaded now (*cached 0).  *trk is set to a shallow copy (its
 * arrays belong to the reference: never track_free it).  Returns the
 * reference, or NULL with the loader's message in err.
 */
track_ref_t *track_cache_get(const char *path, track_format_t fmt, unsigned flags, track_t *trk,
                             int *cached, char *err, size_t errlen);

/* Drop a reference (NULL: no-op); the last frees the track. */
void track_cache_put(track_ref_t *ref);

/*
 * track_reframe for a shared track: nothing if trk is already expressed about
 * lat0, lon0, alt0 (or not geographic); else in place if *refp is its only
 * user, else trk becomes a deep copy of its own first (*refp dropped and set
 * to NULL: trk is then released with track_free), so a running configuration
 * never sees its waypoints move.  0, or -1 (out of memory, or track_reframe's).
 */
int track_cache_reframe(track_ref_t **refp, track_t *trk, double lat0, double lon0, double alt0);

#endif
