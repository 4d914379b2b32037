/* outworker.c - a writer thread beside the tick (see outworker.h). */
#include "outworker.h"

#include <errno.h>
#include <sched.h>
#include <signal.h>
#include <stdint.h>
#include <sys/eventfd.h>
#include <unistd.h>

int worker_spawn(pthread_t *th, void *(*fn)(void *), void *arg, const char *name)
{
    pthread_attr_t a;
    struct sched_param sp = {.sched_priority = 0};
    int rc = pthread_attr_init(&a);
    if (!rc)
        rc = pthread_attr_setinheritsched(&a, PTHREAD_EXPLICIT_SCHED);
    if (!rc)
        rc = pthread_attr_setschedpolicy(&a, SCHED_OTHER);
    if (!rc)
        rc = pthread_attr_setschedparam(&a, &sp);
    /* the thread takes no signal (the loop's signalfd does): created with
     * every signal blocked, the creator's mask put back after */
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    if (!rc)
        rc = pthread_create(th, &a, fn, arg);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    pthread_attr_destroy(&a);
    if (!rc)
        pthread_setname_np(*th, name);
    return rc;
}

int outworker_start(outworker_t *w, void *(*fn)(void *), void *arg, const char *name)
{
    w->started = 0;
    atomic_init(&w->sleeping, 0);
    atomic_init(&w->stop, 0);
    w->efd = eventfd(0, EFD_CLOEXEC);
    if (w->efd < 0)
        return -errno;
    int rc = worker_spawn(&w->th, fn, arg, name);
    if (rc) {
        close(w->efd);
        w->efd = -1;
        return -rc;
    }
    w->started = 1;
    return 0;
}

void outworker_wake(outworker_t *w)
{
    if (atomic_exchange(&w->sleeping, 0)) {
        uint64_t one = 1;
        ssize_t n = write(w->efd, &one, sizeof one);
        (void)n; /* EAGAIN only at a count of 2^64 - 2: it is awake then */
    }
}

void outworker_wait(outworker_t *w, int (*idle)(void *), void *arg)
{
    atomic_store(&w->sleeping, 1);
    if (!idle(arg) || atomic_load(&w->stop)) {
        atomic_store(&w->sleeping, 0);
        return;
    }
    uint64_t v;
    while (read(w->efd, &v, sizeof v) < 0 && errno == EINTR)
        ;
}

int outworker_stopping(outworker_t *w)
{
    return atomic_load(&w->stop);
}

void outworker_stop(outworker_t *w)
{
    if (!w->started)
        return;
    atomic_store(&w->stop, 1);
    uint64_t one = 1;
    ssize_t n = write(w->efd, &one, sizeof one);
    (void)n;
    pthread_join(w->th, NULL);
    close(w->efd);
    w->efd = -1;
    w->started = 0;
}
