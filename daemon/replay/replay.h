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
 *
 * Waypoints are offered in file order.  One whose time is earlier than an
 * earlier row's (a backward step) is already due, so it is offered at once
 * and the engine rejects it (ENGINE_EBACKWARDS), which is what counts it.
 * Due times are rounded to the nearest nanosecond.  A time that is not
 * finite or lies more than REPLAY_T_MAX_S from t_0 is offered at once too
 * (the engine rejects it) rather than making the replay wait for ever.
 */
#ifndef TRAJD_REPLAY_H
#define TRAJD_REPLAY_H

#include <stdint.h>
#include "engine.h"
#include "track.h"

/* Farther than this from the first waypoint (about 31 years) is not a time
 * to wait for: int64 nanoseconds reach 292 years, so this cannot overflow. */
#define REPLAY_T_MAX_S 1.0e9

typedef struct {
    const track_t *trk;
    size_t next;         /* index of the next waypoint to offer */
    int64_t start_ns;    /* engine time at which waypoint 0 is due */
    int finished;        /* engine_finish() has been called */
    uint64_t retries;    /* offers refused with ENGINE_EFULL */
    uint64_t refused;    /* waypoints the engine rejected (bad data) */
    uint64_t duplicates; /* waypoints the engine dropped as exact duplicates */
    int last_rc;         /* engine_push result of the last waypoint offered */
    int *results;        /* optional, caller-owned, trk->n entries (NULL = none):
                             engine_push result of each waypoint once taken,
                             then -reason if the engine refused it later */
    int drain;           /* replay_feed: read the engine's rejections (private) */
    size_t due_i;        /* private: due_ns(due_i) at start due_start is due, so */
    int64_t due_start;   /* that a tick with nothing due costs no llround */
    int64_t due;
} replay_t;

/* Start replaying trk (not copied: it must outlive r) with waypoint 0 due at
 * start_ns.  results is NULL; set it afterwards to record each outcome. */
void replay_init(replay_t *r, const track_t *trk, int64_t start_ns);

/*
 * Offer every waypoint due at or before now_ns, stopping at the first
 * ENGINE_EFULL (that waypoint is offered again next time).  Once all were
 * offered, calls engine_finish() (once).  Returns how many waypoints the
 * engine took (accepted, dropped as duplicates or rejected as bad data),
 * never an error: rejections are counted in r and in the engine's status.
 * The engine judges a waypoint with its neighbours, so its verdict may come
 * a few pushes later: replay_feed reads them (engine_rejection_next) and
 * records each in results[seq - 1] (the track loader numbers waypoints from
 * 1 in file order) and in refused.  replay_feed_via leaves them to its
 * caller (the daemon reads them where it logs them).
 */
int replay_feed(replay_t *r, engine_t *e, int64_t now_ns);

/* How replay_feed_via offers a waypoint: engine_push's contract (0,
 * ENGINE_DUPLICATE or -ENGINE_*; -ENGINE_EFULL = offer it again later). */
typedef int (*replay_push_fn)(void *ctx, const engine_waypoint_t *wp);

/*
 * replay_feed, offering each waypoint through push(ctx, wp) instead of
 * engine_push(e, wp): the daemon passes obj_push_from, the path every input takes.
 * e is still the engine that push feeds (engine_finish is called on it).
 */
int replay_feed_via(replay_t *r, replay_push_fn push, void *ctx, engine_t *e, int64_t now_ns);

/* Engine time at which the next waypoint is due (INT64_MAX if none left). */
int64_t replay_next_due_ns(const replay_t *r);

/* 1 once every waypoint was offered and engine_finish() called. */
int replay_done(const replay_t *r);

#endif
