/* cfgload.c - a reload's configuration loaded on a worker thread (see cfgload.h). */
#include "cfgload.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "carry.h"
#include "core.h"
#include "log.h"
#include "outworker.h"

struct cfgload {
    pthread_t th;
    int efd;
    char *path;
    const cfg_t *running;
    cfg_t *out; /* the result, NULL if refused */
    int rc;
    char err[1024];
};

static atomic_int cancel_flag;

/* The smallest page Linux maps (build_engines writes one byte in each). */
#define CFGLOAD_PAGE 4096u

int cfgload_cancelled(void)
{
    return atomic_load(&cancel_flag);
}

static void nice_self(void)
{
    /* this thread only (a Linux thread is its own scheduling entity) */
    id_t tid = (id_t)syscall(SYS_gettid);
    errno = 0;
    int cur = getpriority(PRIO_PROCESS, tid);
    int want = (errno ? 0 : cur) + CFGLOAD_NICE;
    if (setpriority(PRIO_PROCESS, tid, want > 19 ? 19 : want) < 0)
        log_msg(LOG_INFO, "reload worker: nice +%d not set (%s): it runs at the loop's nice",
                CFGLOAD_NICE, strerror(errno));
}

/* Write a zero into each page of the zeroed p[0 .. size): calloc's fresh
 * pages are mapped at their first touch, here rather than in the loop. */
static void touch_pages(void *p, size_t size)
{
    for (size_t k = 0; k < size; k += CFGLOAD_PAGE)
        ((volatile char *)p)[k] = 0;
}

/* An object array built here and not taken: the owners' latches with it. */
static void objs_fini(void *objs, unsigned n)
{
    obj_t *o = objs;
    for (unsigned i = 0; i < n; i++)
        lc_free(&o[i].lc);
    free(objs);
}

/* The engines the objects that c adds or changes need, built here beside the
 * running core (cfg_t prebuilt): each one's memory zeroed and its settings
 * resolved off the tick (1 024 of them took 0.2 s; in the loop, a reload that
 * changed 256 objects missed 20 ticks at 100 Hz: tests/e2e/
 * test_reload_nohold.py test_reload_changes_many).  An engine not built (no
 * memory, a SIGTERM) is built by core_open as before. */
static void build_engines(cfg_t *c, const cfg_t *running)
{
    /* the object array too, each page written (calloc's fresh pages are
     * mapped at their first touch: by the loop, in core_open) */
    size_t size = (size_t)c->nobj * sizeof(obj_t);
    obj_t *objs = NULL;
    c->prebuilt_objs = calloc(1, sizeof *c->prebuilt_objs);
    if (c->prebuilt_objs && size > 0 && (objs = calloc(c->nobj, sizeof(obj_t)))) {
        touch_pages(objs, size);
        c->prebuilt_objs->objs = objs;
        c->prebuilt_objs->fini = objs_fini;
    }
    c->prebuilt = calloc(c->nobj, sizeof *c->prebuilt);
    for (unsigned i = 0; c->prebuilt && i < c->nobj && !cfgload_cancelled(); i++) {
        if (!carry_needs_engine(running, &c->obj[i]))
            continue;
        c->prebuilt[i] = engine_new(&c->obj[i].engine, NULL);
        /* and its owner (lifecycle.h) with its latch's 16 kB written: in the
         * loop, lc_init took 12 ms of the 256 objects' 21 (core_open) */
        lifecycle_t *lc = objs && c->prebuilt[i] ? &objs[i].lc : NULL;
        if (lc && lc_init(lc, c->prebuilt[i], &objs[i].safety, c->daemon.period_ns, 0) == 0)
            touch_pages(lc->buf, lc->cap * sizeof *lc->buf);
    }
}

void *cfgload_take_objs(const cfg_t *c)
{
    void *m = c->prebuilt_objs ? c->prebuilt_objs->objs : NULL;
    if (m)
        c->prebuilt_objs->objs = NULL;
    return m;
}

static void *work(void *arg)
{
    cfgload_t *l = arg;
    nice_self();
    l->rc = cfg_load(l->path, &l->out, l->err, sizeof l->err);
    if (l->rc == 0 && l->running)
        l->rc = cfg_reload_check(l->running, l->out, l->err, sizeof l->err);
    if (l->rc == 0)
        build_engines(l->out, l->running);
    if (l->rc < 0) {
        cfg_free(l->out);
        l->out = NULL;
    }
    uint64_t one = 1;
    ssize_t n = write(l->efd, &one, sizeof one); /* the loop takes it (cfgload_finish) */
    (void)n;
    return NULL;
}

static void free_load(cfgload_t *l)
{
    if (l->efd >= 0)
        close(l->efd);
    cfg_free(l->out);
    free(l->path);
    free(l);
}

cfgload_t *cfgload_start(const char *path, const cfg_t *running, int *err)
{
    cfgload_t *l = calloc(1, sizeof *l);
    if (!l) {
        *err = -ENOMEM;
        return NULL;
    }
    l->efd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    l->path = strdup(path);
    l->running = running;
    if (l->efd < 0 || !l->path) {
        *err = l->efd < 0 ? -errno : -ENOMEM;
        free_load(l);
        return NULL;
    }
    atomic_store(&cancel_flag, 0);
    int rc = worker_spawn(&l->th, work, l, "trajd-reload");
    if (rc) {
        *err = -rc;
        free_load(l);
        return NULL;
    }
    return l;
}

int cfgload_fd(const cfgload_t *l)
{
    return l->efd;
}

int cfgload_finish(cfgload_t *l, cfg_t **out, char *err, size_t errlen)
{
    pthread_join(l->th, NULL);
    int rc = l->rc;
    *out = l->out;
    l->out = NULL;
    if (rc < 0)
        snprintf(err, errlen, "%s", l->err);
    free_load(l);
    return rc;
}

void cfgload_drop(cfgload_t *l)
{
    if (!l)
        return;
    atomic_store(&cancel_flag, 1);
    pthread_join(l->th, NULL);
    atomic_store(&cancel_flag, 0);
    free_load(l);
}

static pthread_t freer; /* cfgload_retire's thread, while freer_on */
static int freer_on;

static void *free_work(void *arg)
{
    nice_self();
    cfg_free(arg);
    return NULL;
}

void cfgload_retire(cfg_t *old)
{
    if (!old)
        return;
    cfgload_retire_join(); /* the previous one: done long ago */
    int rc = worker_spawn(&freer, free_work, old, "trajd-free");
    if (rc) { /* counted nowhere else: said, then done here */
        log_msg(LOG_WARNING,
                "reload: no thread to free the old configuration (%s): freed in "
                "the loop",
                strerror(rc));
        cfg_free(old);
        return;
    }
    freer_on = 1;
}

void cfgload_retire_join(void)
{
    if (freer_on)
        pthread_join(freer, NULL);
    freer_on = 0;
}
