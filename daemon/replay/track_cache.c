/* track_cache.c - loaded tracks shared by the live configurations (see track_cache.h). */
#include "track_cache.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

struct track_ref {
    struct track_ref *next;
    unsigned refs;
    char *path;
    track_format_t fmt;
    unsigned flags;
    struct stat st; /* the file when it was loaded */
    int have_st;    /* st is valid (else never taken again) */
    track_t trk;
};

static track_ref_t *cache; /* the live references */
/* cache and every refs: the loop drops references while a reload's worker takes them */
static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;

static int same_file(const struct stat *a, const struct stat *b)
{
    return a->st_dev == b->st_dev && a->st_ino == b->st_ino && a->st_size == b->st_size &&
           a->st_mtim.tv_sec == b->st_mtim.tv_sec && a->st_mtim.tv_nsec == b->st_mtim.tv_nsec &&
           a->st_ctim.tv_sec == b->st_ctim.tv_sec && a->st_ctim.tv_nsec == b->st_ctim.tv_nsec;
}

track_ref_t *track_cache_get(const char *path, track_format_t fmt, unsigned flags, track_t *trk,
                             int *cached, char *err, size_t errlen)
{
    struct stat st;
    int have = stat(path, &st) == 0 && S_ISREG(st.st_mode);
    *cached = 0;
    pthread_mutex_lock(&mu);
    for (track_ref_t *r = cache; have && r; r = r->next)
        if (r->have_st && r->fmt == fmt && r->flags == flags && strcmp(r->path, path) == 0 &&
            same_file(&r->st, &st)) {
            r->refs++;
            *trk = r->trk;
            *cached = 1;
            pthread_mutex_unlock(&mu);
            return r;
        }
    pthread_mutex_unlock(&mu);
    track_ref_t *r = calloc(1, sizeof *r);
    if (r)
        r->path = strdup(path);
    if (!r || !r->path) {
        if (r)
            free(r);
        snprintf(err, errlen, "%s: out of memory", path);
        return NULL;
    }
    /* stat before the load: a file changed meanwhile is parsed again next time */
    if (track_load_opts(path, fmt, flags, &r->trk, err, errlen) < 0) {
        free(r->path);
        free(r);
        return NULL;
    }
    r->refs = 1;
    r->fmt = fmt;
    r->flags = flags;
    r->st = st;
    r->have_st = have;
    pthread_mutex_lock(&mu);
    r->next = cache;
    cache = r;
    pthread_mutex_unlock(&mu);
    *trk = r->trk;
    return r;
}

void track_cache_put(track_ref_t *ref)
{
    if (!ref)
        return;
    pthread_mutex_lock(&mu);
    if (--ref->refs > 0) {
        pthread_mutex_unlock(&mu);
        return;
    }
    for (track_ref_t **p = &cache; *p; p = &(*p)->next)
        if (*p == ref) {
            *p = ref->next;
            break;
        }
    pthread_mutex_unlock(&mu);
    track_free(&ref->trk);
    free(ref->path);
    free(ref);
}

static int same_frame(const track_t *trk, double lat0, double lon0, double alt0)
{
    return !trk->geographic || (memcmp(&trk->lat0_deg, &lat0, sizeof lat0) == 0 &&
                                memcmp(&trk->lon0_deg, &lon0, sizeof lon0) == 0 &&
                                memcmp(&trk->alt0_m, &alt0, sizeof alt0) == 0);
}

/* A copy of n elements of size sz at p (NULL stays NULL); -1 if out of memory. */
static int dup_array(void *dst, const void *p, size_t n, size_t sz)
{
    void *q = NULL;
    if (p && n) {
        q = malloc(n * sz);
        if (!q)
            return -1;
        memcpy(q, p, n * sz);
    }
    memcpy(dst, &q, sizeof q);
    return 0;
}

/* trk becomes a deep copy of its own; *refp dropped and NULL.  0 or -1. */
static int make_private(track_ref_t **refp, track_t *trk)
{
    track_t c = *trk;
    c.wp = NULL;
    c.line = NULL;
    c.geo = NULL;
    c.geo_vel = NULL;
    c.heading_t = c.heading = NULL;
    c.reports = NULL;
    if (dup_array(&c.wp, trk->wp, trk->n, sizeof *trk->wp) < 0 ||
        dup_array(&c.line, trk->line, trk->n, sizeof *trk->line) < 0 ||
        dup_array(&c.geo, trk->geo, trk->n, sizeof *trk->geo) < 0 ||
        dup_array(&c.geo_vel, trk->geo_vel, trk->geo_vel ? trk->n : 0, sizeof *trk->geo_vel) < 0 ||
        dup_array(&c.heading_t, trk->heading_t, trk->nheading, sizeof *trk->heading_t) < 0 ||
        dup_array(&c.heading, trk->heading, trk->nheading, sizeof *trk->heading) < 0 ||
        dup_array(&c.reports, trk->reports, trk->nreports, sizeof *trk->reports) < 0) {
        track_free(&c);
        return -1;
    }
    *trk = c;
    track_cache_put(*refp);
    *refp = NULL;
    return 0;
}

int track_cache_reframe(track_ref_t **refp, track_t *trk, double lat0, double lon0, double alt0)
{
    if (same_frame(trk, lat0, lon0, alt0))
        return 0;
    pthread_mutex_lock(&mu);
    int alone = *refp && (*refp)->refs == 1;
    pthread_mutex_unlock(&mu);
    if (alone) {
        if (track_reframe(&(*refp)->trk, lat0, lon0, alt0) < 0)
            return -1;
        *trk = (*refp)->trk;
        return 0;
    }
    if (*refp && make_private(refp, trk) < 0)
        return -1;
    return track_reframe(trk, lat0, lon0, alt0);
}
