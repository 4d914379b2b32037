/*
 * outworker.h - a writer thread beside the tick (issue 28): file output is
 * formatted and written there, never on the clock's thread.  The thread
 * runs at SCHED_OTHER whatever the tick's policy (SCHED_FIFO with
 * [realtime] fifo_priority), so it never delays a tick on the tick's CPU.
 *
 * The tick wakes it once per tick (outworker_wake, after spsc_publish): an
 * eventfd write, and only when the thread is asleep.  The thread sleeps in
 * outworker_wait when it has nothing to do.  outworker_stop asks it to finish
 * (it drains what was published, then returns) and joins it.
 */
#ifndef TRAJD_OUTWORKER_H
#define TRAJD_OUTWORKER_H

#include <pthread.h>
#include <stdatomic.h>

typedef struct {
    pthread_t th;
    int started;
    int efd;
    _Atomic int sleeping;
    _Atomic int stop;
} outworker_t;

/* fn(arg) on a new SCHED_OTHER thread named name (at most 15 chars), whatever
 * the creator's policy, every signal blocked in it.  0 or an error number. */
int worker_spawn(pthread_t *th, void *(*fn)(void *), void *arg, const char *name);

/* Start fn(arg) on a new SCHED_OTHER thread named name (at most 15 chars),
 * every signal blocked in it.  0 or -errno. */
int outworker_start(outworker_t *w, void *(*fn)(void *), void *arg, const char *name);

/* Tick side: wake the thread if it sleeps.  Never blocks. */
void outworker_wake(outworker_t *w);

/* Thread side: sleep until woken, unless idle(arg) says there is work
 * already (it is asked again after the thread announced its sleep, so a
 * wake-up is never lost). */
void outworker_wait(outworker_t *w, int (*idle)(void *), void *arg);

/* Thread side: 1 once outworker_stop was called (read it before the last
 * look at the ring: what was published before the stop is then seen). */
int outworker_stopping(outworker_t *w);

/* Ask the thread to finish and join it (a no-op if never started). */
void outworker_stop(outworker_t *w);

#endif
