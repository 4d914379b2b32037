/* replay_transport.c - replay input transport (see replay_transport.h). */
#include "replay_transport.h"
#include "cfg_files.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core.h"
#include "keep.h"
#include "log.h"
#include "replay.h"

static void obj_default(void *ocfg)
{
    replay_transport_obj_cfg_t *r = ocfg;
    r->format = TRACK_FMT_AUTO;
    r->start_s = 0;
}

static int obj_key(void *ocfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    replay_transport_obj_cfg_t *r = ocfg;
    if (strcmp(kv->key, "track") == 0) {
        r->line = kv->line;
        return cfg_get_path(kv, r->path, sizeof r->path, why, wl);
    }
    if (strcmp(kv->key, "format") == 0) {
        int i, rc = cfg_get_enum(kv, track_format_names, &i, why, wl);
        if (rc == 0)
            r->format = (track_format_t)i;
        return rc;
    }
    if (strcmp(kv->key, "skip_bad") == 0)
        return cfg_get_bool(kv, &r->skip_bad, why, wl);
    if (strcmp(kv->key, "start_s") == 0)
        return cfg_get_double(kv, 0, 1e6, &r->start_s, why, wl);
    return -CFG_EUNKNOWN;
}

/* Same input: same file (unchanged: one shared track), format and start. */
static int obj_same(const void *a, const void *b)
{
    const replay_transport_obj_cfg_t *x = a, *y = b;
    return strcmp(x->path, y->path) == 0 && x->format == y->format && x->skip_bad == y->skip_bad &&
           memcmp(&x->start_s, &y->start_s, sizeof x->start_s) == 0 &&
           (!x->loaded || (x->ref && x->ref == y->ref)); /* the same file, unchanged */
}

static void obj_fini(void *ocfg)
{
    replay_transport_obj_cfg_t *r = ocfg;
    if (r->loaded && r->ref)
        track_cache_put(r->ref);
    else if (r->loaded)
        track_free(&r->trk);
    memset(&r->trk, 0, sizeof r->trk);
    r->ref = NULL;
    r->loaded = 0;
}

/* One datum for every geographic track: [daemon] origin, or the first fix of
 * the geographic object with the lowest id (never the first in the file);
 * each geographic track is re-expressed about it. */
static int set_datum(cfg_t *cfg, int *line, char *why, size_t wl)
{
    const cfg_obj_t *first = NULL;
    const replay_transport_obj_cfg_t *r0 = NULL;
    for (unsigned i = 0; i < cfg->nobj; i++) {
        const cfg_obj_t *o = &cfg->obj[i];
        const replay_transport_obj_cfg_t *r = o->tcfg[transport_index(&replay_transport)];
        if (o->input == &replay_transport && r->trk.geographic && (!first || o->id < first->id)) {
            first = o;
            r0 = r;
        }
    }
    if (!first)
        return 0;
    const cfg_daemon_t *d = &cfg->daemon;
    double g[3] = {r0->trk.geo[0][0], r0->trk.geo[0][1],
                   isnan(r0->trk.geo[0][2]) ? 0.0 : r0->trk.geo[0][2]};
    if (d->origin_given)
        memcpy(g, d->origin, sizeof g);
    (void)geo_enu_init(g[0], g[1], g[2], &cfg->datum); /* checked when read */
    cfg->datum_set = 1;
    cfg->datum_line = d->origin_given ? d->origin_line : first->line;
    for (unsigned i = 0; i < cfg->nobj; i++) {
        cfg_obj_t *o = &cfg->obj[i];
        replay_transport_obj_cfg_t *r = o->tcfg[transport_index(&replay_transport)];
        if (o->input != &replay_transport || !r->trk.geographic)
            continue;
        if (track_cache_reframe(&r->ref, &r->trk, g[0], g[1], g[2]) < 0) {
            *line = cfg->datum_line;
            snprintf(why, wl, "object '%s': cannot express its track about the datum", o->name);
            return -CFG_EVALUE;
        }
        o->geographic = 1;
        o->geo_no_alt = track_no_altitude(&r->trk); /* up 0 at the datum's height */
        o->heading.t_s = r->trk.heading_t;          /* a private copy has its own */
        o->heading.deg = r->trk.heading;
    }
    return 0;
}

/*
 * 0 if some waypoint of trk passes the engine's checks on a waypoint alone
 * (engine_waypoint_check with the object's settings); else -CFG_EVALUE and
 * why says how many were refused for which reason and the first line: no
 * engine with these settings would accept any of them (the neighbours only
 * refuse more), so the object could never move.
 */
static int check_usable(const cfg_obj_t *o, const replay_transport_obj_cfg_t *r, char *why,
                        size_t wl)
{
    size_t nf = 0, nr = 0;
    for (size_t k = 0; k < r->trk.n; k++) {
        int rc = engine_waypoint_check(&o->engine, &r->trk.wp[k]);
        if (rc == 0)
            return 0;
        if (rc == -ENGINE_ERANGE)
            nr++;
        else
            nf++;
    }
    snprintf(why, wl,
             "[object.%s] replay.track: %s: no usable waypoint: all %zu rejected (%s %zu, %s %zu; "
             "max_abs_m = %g), the first at line %u",
             o->name, r->path, r->trk.n, engine_reason_name(ENGINE_ERANGE), nr,
             engine_reason_name(ENGINE_ENOTFINITE), nf, o->engine.max_abs_m,
             r->trk.line ? (unsigned)r->trk.line[0] : 0u);
    return -CFG_EVALUE;
}

/* Load every replayed object's track, so a bad file rejects the config. */
static int check(cfg_t *cfg, int *line, char *why, size_t wl)
{
    const engine_waypoint_t *mine[CFG_OBJECTS_MAX]; /* tracks this config loaded itself */
    unsigned nmine = 0;
    for (unsigned i = 0; i < cfg->nobj; i++) {
        cfg_obj_t *o = &cfg->obj[i];
        if (o->input != &replay_transport)
            continue;
        replay_transport_obj_cfg_t *r = o->tcfg[transport_index(&replay_transport)];
        if (!r->path[0]) {
            *line = o->line;
            snprintf(why, wl, "[object.%s] replay.track is missing", o->name);
            return -CFG_EMISSING;
        }
        if (r->loaded)
            continue;
        char err[512];
        int cached = 0;
        r->ref = track_cache_get(r->path, r->format, r->skip_bad ? TRACK_SKIP_BAD : 0, &r->trk,
                                 &cached, err, sizeof err);
        if (!r->ref) {
            *line = r->line;
            snprintf(why, wl, "[object.%s] replay.track: %s", o->name, err);
            return -CFG_EVALUE;
        }
        r->loaded = 1;
        int shared = 0; /* with an object of this config: nothing to say */
        for (unsigned k = 0; k < nmine && !shared; k++)
            shared = mine[k] == r->trk.wp;
        if (!shared && nmine < CFG_OBJECTS_MAX)
            mine[nmine++] = r->trk.wp; /* said once per track and configuration */
        if (cached && !shared)         /* a running configuration's, kept by a reload */
            log_msg(LOG_INFO,
                    "object '%s': replay.track %s unchanged (%zu waypoints): not parsed "
                    "again",
                    o->name, r->path, r->trk.n);
        o->heading.t_s = r->trk.heading_t;
        o->heading.deg = r->trk.heading;
        o->heading.n = r->trk.nheading;
        for (size_t k = 0; k < r->trk.nreports; k++)
            log_msg(LOG_WARNING, "object '%s': replay: skipped %s", o->name, r->trk.reports[k]);
        if (r->trk.ignored)
            log_msg(LOG_NOTICE, "object '%s': replay: ignored %zu records without a usable fix",
                    o->name, r->trk.ignored);
        if (r->trk.skipped > r->trk.nreports)
            log_msg(LOG_WARNING, "object '%s': replay: skipped %zu bad lines in all", o->name,
                    r->trk.skipped);
        if (r->trk.n == 0) {
            *line = r->line;
            snprintf(why, wl, "[object.%s] replay.track: %s has no waypoints", o->name, r->path);
            return -CFG_EVALUE;
        }
    }
    int rc = set_datum(cfg, line, why, wl);
    for (unsigned i = 0; i < cfg->nobj && rc == 0; i++) { /* positions about the datum */
        const cfg_obj_t *o = &cfg->obj[i];
        const replay_transport_obj_cfg_t *r = o->tcfg[transport_index(&replay_transport)];
        if (o->input == &replay_transport && (rc = check_usable(o, r, why, wl)) < 0)
            *line = r->line;
    }
    return rc;
}

typedef struct {
    replay_t *r; /* per object index (NULL if not replayed) */
    /* per object index: a changed object's replay goes on after this track
     * time once its old engine rests (obj_t resume_t_s); NAN: none */
    double *resume;
    unsigned char *resumed; /* ... and went on so: the rows before were its old engine's */
    unsigned n;
    core_t *c;
} replay_transport_t;

/* Where each replay stood when a reload closed it, for the replay the reload
 * opens (keep.h): a carried object's goes on from the row after the last one
 * it gave (the acceptance may still hold that one: offering it again would be
 * a duplicate). */
typedef struct {
    size_t next;
    int finished;
} kept_pos_t;

static void pos_kept_store(const replay_transport_t *s, const core_t *c)
{
    for (unsigned i = 0; i < s->n && i < c->nobj; i++) {
        if (c->obj[i].cfg->input != &replay_transport)
            continue;
        kept_pos_t k = {s->r[i].next, s->r[i].finished};
        (void)keep_put("replay", c->obj[i].name, &k, sizeof k); /* none kept: by last_seq */
    }
}

/* Object o's replay position kept by the reload (1), or 0. */
static int pos_kept_take(const obj_t *o, size_t *next, int *finished)
{
    kept_pos_t k;
    if (!keep_take("replay", o->name, &k, sizeof k))
        return 0;
    *next = k.next;
    *finished = k.finished;
    return 1;
}

/* Changed objects whose resumption the reload names one by one; the rest in
 * one line (256 lines at once outran the log's reader and were dropped). */
#define RESUME_NAMED 4u

static int open_(core_t *c, void **state, char *why, size_t wl)
{
    replay_transport_t *s = calloc(1, sizeof *s);
    if (s) {
        s->r = calloc(c->nobj, sizeof *s->r);
        s->resume = calloc(c->nobj, sizeof *s->resume);
        s->resumed = calloc(c->nobj, sizeof *s->resumed);
    }
    if (!s || !s->r || !s->resume || !s->resumed) {
        if (s) {
            free(s->r);
            free(s->resume);
            free(s->resumed);
        }
        free(s);
        snprintf(why, wl, "out of memory");
        return -12; /* -ENOMEM */
    }
    s->n = c->nobj;
    s->c = c;
    unsigned nres = 0; /* changed objects resumed */
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        s->resume[i] = NAN;
        if (o->cfg->input != &replay_transport)
            continue;
        const replay_transport_obj_cfg_t *rc = cfg_obj_transport(o->cfg, &replay_transport);
        replay_t *r = &s->r[i];
        replay_init(r, &rc->trk, o->born_ns + (int64_t)llround(rc->start_s * 1e9));
        size_t next = 0;
        int fin = 0;
        if (o->carried && pos_kept_take(o, &next, &fin) && next <= rc->trk.n) {
            /* Reload with the engine kept: resume after the row the replay
             * gave last (the same track: a carried object's settings are) */
            r->next = next;
            r->finished = fin;
        } else if (o->carried && o->status.accepted > 0) {
            /* (its position not kept: after the row the engine accepted
             * last; rows carry their 1-based row number as seq) */
            size_t k = (size_t)o->status.last_seq - 1; /* row k has seq k + 1 (track.c) */
            if (o->status.last_seq >= 1 && k < rc->trk.n && rc->trk.wp[k].seq == o->status.last_seq)
                r->next = k + 1; /* in the loop, between two ticks: no scan of the track */
            if (r->next >= rc->trk.n)
                r->finished = 1; /* the old replay called engine_finish already */
        } else if (!o->carried && isfinite(o->resume_t_s)) {
            s->resume[i] = o->resume_t_s; /* a changed object: pre_tick resumes it */
            if (++nres <= RESUME_NAMED)
                log_msg(LOG_NOTICE,
                        "object '%s': its replay resumes after the row where its old engine "
                        "comes to rest (it has played to t = %.3f s): a reload that changed "
                        "its settings never plays its track again",
                        o->name, o->resume_t_s);
        }
    }
    if (nres > RESUME_NAMED) /* one line for the rest, not one an object */
        log_msg(LOG_NOTICE,
                "%u more objects' replays resume likewise, each after the row where its old "
                "engine comes to rest",
                nres - RESUME_NAMED);
    keep_drop("replay");
    *state = s;
    return 0;
}

typedef struct {
    obj_t *o;
    const replay_transport_obj_cfg_t *rc; /* looked up at the first row due (push_obj) */
} push_ctx_t;

/* Offer a row, named "file:line" for the rejection log (rows carry their
 * 1-based index in the track as seq; a long path keeps its end). */
static int push_obj(void *ctx, const engine_waypoint_t *wp)
{
    push_ctx_t *p = ctx;
    if (!p->rc)
        p->rc = cfg_obj_transport(p->o->cfg, &replay_transport);
    const track_t *trk = &p->rc->trk;
    char src[REJLOG_SRC_LEN];
    size_t i = (size_t)wp->seq - 1;
    int has_line = wp->seq >= 1 && i < trk->n && trk->line;
    (void)rejlog_src_file(src, p->rc->path, has_line, has_line ? trk->line[i] : 0);
    return obj_push_from(p->o, wp, src);
}

/* The first row of track trk later than t_s (rows in time order: a row out
 * of order only moves where the search lands). */
static size_t row_after(const track_t *trk, double t_s)
{
    size_t lo = 0, hi = trk->n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (trk->wp[mid].t_s > t_s)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* A changed object's replay (s->resume): nothing while its old engine brakes
 * (core.c: the new engine starts where it rests), then on from the first row
 * after where it rests, on the old schedule (obj_t born_ns): the object goes on
 * along its track, never back to its start.  1 while it waits. */
static int resume_wait(replay_transport_t *s, obj_t *o)
{
    double t = s->resume[o->index];
    if (o->retiring)
        return 1;
    if (o->played_t_s > t)
        t = o->played_t_s; /* as far as the old engine played, braking to rest */
    double kept = lc_buffered_newest_t(&o->lc);
    if (kept > t) /* a stop's latch kept the rows up to there (lc_inherit): not twice */
        t = kept;
    replay_t *r = &s->r[o->index];
    r->next = row_after(r->trk, t);
    s->resume[o->index] = NAN;
    s->resumed[o->index] = 1;
    return 0;
}

static void pre_tick(void *state, obj_t *o, int64_t now_ns)
{
    replay_transport_t *s = state;
    replay_t *r = &s->r[o->index];
    if (!isnan(s->resume[o->index]) && resume_wait(s, o))
        return;
    int was_done = replay_done(r);
    push_ctx_t ctx = {o, NULL}; /* (no row due at most ticks) */
    (void)replay_feed_via(r, push_obj, &ctx, o->engine, now_ns);
    if (was_done || !replay_done(r))
        return;
    /* The track ran out: say so if none of it was usable (the object then
     * waits with nothing buffered, which exit_when_done counts as done). */
    engine_status_t st;
    engine_status(o->engine, &st);
    if (st.accepted == 0 && !s->resumed[o->index]) { /* (resumed at its end: all played) */
        const replay_transport_obj_cfg_t *rc = cfg_obj_transport(o->cfg, &replay_transport);
        log_msg(LOG_ERR,
                "object %s: replay.track %s: no usable waypoint: all %zu rejected; trajd "
                "will exit with status %d",
                o->cfg->name, rc->path, r->trk->n, CORE_EXIT_NO_INPUT);
        s->c->stats->no_input++;
    } else if (st.rejected * 10 > r->trk->n) { /* issue 24: more than 10 % refused */
        const replay_transport_obj_cfg_t *rc = cfg_obj_transport(o->cfg, &replay_transport);
        log_msg(LOG_WARNING,
                "object %s: replay.track %s: %.1f %% of its %zu fixes were refused (more than "
                "10 %%): check the profile, the time column and the units",
                o->cfg->name, rc->path, 100.0 * (double)st.rejected / (double)r->trk->n, r->trk->n);
    }
}

static int input_done(void *state, const obj_t *o)
{
    replay_transport_t *s = state;
    return replay_done(&s->r[o->index]);
}

static void close_(void *state, core_t *c)
{
    replay_transport_t *s = state;
    if (!s)
        return;
    if (c && !c->stopping)
        pos_kept_store(s, c); /* the next open (a reload's) goes on from there */
    free(s->resume);
    free(s->resumed);
    free(s->r);
    free(s);
}

/* Each replay.track is read (cfg_files.h). */
static void files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx)
{
    for (unsigned i = 0; i < cfg->nobj; i++)
        if (cfg_obj_uses(&cfg->obj[i], &replay_transport) & 1) {
            char what[64];
            snprintf(what, sizeof what, "[object.%s] replay.track", cfg->obj[i].name);
            const replay_transport_obj_cfg_t *r = cfg_obj_transport(&cfg->obj[i],
                                                                    &replay_transport);
            add(ctx, r->path, 0, cfg->obj[i].line, what);
        }
}

/* The status and exit lines: the bad lines skipped (replay.skip_bad) and the
 * records without a usable fix of the tracks replayed, so that they are not
 * told only once, in the start's log (core_summary). */
static int summary(const core_t *c, char *buf, size_t len)
{
    size_t skipped = 0, ignored = 0;
    for (unsigned i = 0; i < c->nobj; i++) {
        if (c->obj[i].cfg->input != &replay_transport)
            continue;
        const replay_transport_obj_cfg_t *r = cfg_obj_transport(c->obj[i].cfg, &replay_transport);
        skipped += r->trk.skipped;
        ignored += r->trk.ignored;
    }
    if (!skipped && !ignored)
        return 0;
    return snprintf(buf, len, ", track lines skipped %zu, records without a fix %zu", skipped,
                    ignored);
}

const transport_t replay_transport = {
    .name = "replay",
    .roles = TRANSPORT_INPUT,
    .obj_cfg_size = sizeof(replay_transport_obj_cfg_t),
    .obj_cfg_default = obj_default,
    .obj_key = obj_key,
    .obj_cfg_fini = obj_fini,
    .obj_cfg_same = obj_same,
    .check = check,
    .open = open_,
    .pre_tick = pre_tick,
    .close = close_,
    .input_done = input_done,
    .files = files,
    .summary = summary,
};
