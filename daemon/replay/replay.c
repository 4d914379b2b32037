/* replay.c - feed a track into an engine by engine time.  See replay.h. */
#include "replay.h"

#include <math.h>
#include <string.h>

static int64_t due_ns(const replay_t *r, size_t i);

void replay_init(replay_t *r, const track_t *trk, int64_t start_ns)
{
    memset(r, 0, sizeof *r);
    r->trk = trk;
    r->start_ns = start_ns;
    r->due_i = (size_t)-1;
}

/* due_ns of the next waypoint, kept while next and start_ns stay */
static int64_t next_due(replay_t *r)
{
    if (r->due_i != r->next || r->due_start != r->start_ns) {
        r->due = due_ns(r, r->next);
        r->due_i = r->next;
        r->due_start = r->start_ns;
    }
    return r->due;
}

static int64_t due_ns(const replay_t *r, size_t i)
{
    double dt_s = r->trk->wp[i].t_s - r->trk->wp[0].t_s;
    /* NaN fails both comparisons: offered at once.  Backward steps are due
     * before start_ns: offered at once as well. */
    if (!(dt_s > -REPLAY_T_MAX_S && dt_s < REPLAY_T_MAX_S))
        return INT64_MIN;
    int64_t d = (int64_t)llround(dt_s * 1e9);
    /* |d| <= 1e18 and start_ns is a clock near 0 or a monotonic time
     * (< 2^62): clamp instead of overflowing if it is not. */
    if (d > 0 && r->start_ns > INT64_MAX - d)
        return INT64_MAX;
    if (d < 0 && r->start_ns < INT64_MIN - d)
        return INT64_MIN;
    return r->start_ns + d;
}

int64_t replay_next_due_ns(const replay_t *r)
{
    if (!r->trk || r->next >= r->trk->n)
        return INT64_MAX;
    return due_ns(r, r->next);
}

static int push_engine(void *e, const engine_waypoint_t *wp)
{
    return engine_push(e, wp);
}

int replay_feed(replay_t *r, engine_t *e, int64_t now_ns)
{
    r->drain = 1;
    return replay_feed_via(r, push_engine, e, e, now_ns);
}

/* Record the verdicts the engine gave since the last call: refused later,
 * after engine_push returned 0 (those refused at once were counted then). */
static void read_rejections(replay_t *r, engine_t *e)
{
    engine_rejection_t j;
    while (engine_rejection_next(e, &j)) {
        size_t i = (size_t)j.seq - 1;
        int known = j.seq >= 1 && i < r->trk->n && r->trk->wp[i].seq == j.seq;
        /* engine_push returns these at once: counted when offered */
        if (j.reason == ENGINE_ENOTFINITE || j.reason == ENGINE_ERANGE ||
            j.reason == ENGINE_ENUMERIC)
            continue;
        r->refused++;
        if (known && r->results)
            r->results[i] = -j.reason;
    }
}

int replay_feed_via(replay_t *r, replay_push_fn push, void *ctx, engine_t *e, int64_t now_ns)
{
    int taken = 0;
    if (!r->trk)
        return 0;
    while (r->next < r->trk->n) {
        if (next_due(r) > now_ns)
            break;
        int rc = push(ctx, &r->trk->wp[r->next]);
        if (rc == -ENGINE_EFULL) {
            r->retries++;
            break;
        }
        r->last_rc = rc;
        if (r->results)
            r->results[r->next] = rc;
        if (rc == ENGINE_DUPLICATE)
            r->duplicates++;
        else if (rc < 0)
            r->refused++;
        r->next++;
        taken++;
        if (r->drain)
            read_rejections(r, e);
    }
    if (r->next >= r->trk->n && !r->finished) {
        (void)engine_finish(e);
        r->finished = 1;
        if (r->drain)
            read_rejections(r, e);
    }
    return taken;
}

int replay_done(const replay_t *r)
{
    return r->finished;
}
