/* grave.c - engines freed beside the loop (see grave.h). */
#include "grave.h"

#include <string.h>

#include "log.h"
#include "outworker.h"
#include "spsc.h"

/* Engines in flight at most: a reload of 1 024 changed objects retires as
 * many at once. */
#define GRAVE_CAP 2048u

static spsc_t ring;
static outworker_t w;
static int state; /* 0: not started, 1: running, -1: cannot start (free in the loop) */

static int ring_idle(void *arg)
{
    (void)arg;
    return spsc_avail(&ring) == 0;
}

static void *work(void *arg)
{
    (void)arg;
    for (;;) {
        int stopping = outworker_stopping(&w); /* before the last look (outworker.h) */
        size_t n = spsc_avail(&ring);
        for (size_t i = 0; i < n; i++) {
            engine_t *e;
            memcpy(&e, spsc_at(&ring, i), sizeof e);
            engine_free(e);
        }
        spsc_release(&ring, n);
        if (stopping && n == 0)
            return NULL;
        if (n == 0)
            outworker_wait(&w, ring_idle, NULL);
    }
}

static int start(void)
{
    if (spsc_init(&ring, sizeof(engine_t *), GRAVE_CAP) < 0) {
        log_msg(LOG_WARNING, "engine free worker: out of memory: engines are freed in the loop");
        return -1;
    }
    int rc = outworker_start(&w, work, NULL, "trajd-grave");
    if (rc < 0) {
        spsc_fini(&ring);
        log_msg(LOG_WARNING, "engine free worker: no thread (%s): engines are freed in the loop",
                strerror(-rc));
        return -1;
    }
    return 1;
}

void grave_put(engine_t *e)
{
    if (!e)
        return;
    if (state == 0)
        state = start();
    void *slot = state > 0 ? spsc_slot(&ring) : NULL;
    if (!slot) {
        engine_free(e);
        return;
    }
    memcpy(slot, &e, sizeof e);
    spsc_push(&ring);
    spsc_publish(&ring);
    outworker_wake(&w);
}

void grave_stop(void)
{
    if (state > 0) {
        outworker_stop(&w); /* the thread frees what was published, then returns */
        spsc_fini(&ring);
    }
    state = 0;
}
