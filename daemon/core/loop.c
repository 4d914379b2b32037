/* loop.c - one epoll loop with fd callbacks (see loop.h). */
#include "loop.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#define LOOP_BATCH 64 /* events taken per epoll_wait */

typedef struct {
    int fd;       /* -1 when the slot is free */
    uint32_t gen; /* bumped when the slot is freed: stale events are ignored */
    loop_fn fn;
    void *ctx;
    loop_timer_fn timer_fn; /* set for loop_timer_add timers */
    void *timer_ctx;
} loop_entry_t;

struct loop {
    int epfd;
    loop_entry_t *e;
    unsigned n, cap; /* slots used (high-water), allocated */
    int stop, code;
};

loop_t *loop_new(int *err)
{
    loop_t *l = calloc(1, sizeof *l);
    if (!l) {
        if (err)
            *err = -ENOMEM;
        return NULL;
    }
    l->epfd = epoll_create1(EPOLL_CLOEXEC);
    if (l->epfd < 0) {
        if (err)
            *err = -errno;
        free(l);
        return NULL;
    }
    if (err)
        *err = 0;
    return l;
}

void loop_free(loop_t *l)
{
    if (!l)
        return;
    for (unsigned i = 0; i < l->n; i++)
        if (l->e[i].fd >= 0 && l->e[i].timer_fn)
            close(l->e[i].fd);
    close(l->epfd);
    free(l->e);
    free(l);
}

static int find(const loop_t *l, int fd)
{
    for (unsigned i = 0; i < l->n; i++)
        if (l->e[i].fd == fd)
            return (int)i;
    return -1;
}

static int add_entry(loop_t *l, int fd, uint32_t events, loop_fn fn, void *ctx, loop_timer_fn tfn,
                     void *tctx)
{
    if (fd < 0 || (!fn && !tfn))
        return -EINVAL;
    if (find(l, fd) >= 0)
        return -EEXIST;
    unsigned i;
    for (i = 0; i < l->n; i++)
        if (l->e[i].fd < 0)
            break;
    if (i == l->n) {
        if (l->n == l->cap) {
            unsigned cap = l->cap ? l->cap * 2 : 16;
            loop_entry_t *e = realloc(l->e, cap * sizeof *e);
            if (!e)
                return -ENOMEM;
            l->e = e;
            l->cap = cap;
        }
        l->e[l->n].gen = 0;
        l->e[l->n].fd = -1; /* free until the add succeeds */
        l->n++;
    }
    loop_entry_t *e = &l->e[i];
    struct epoll_event ev = {.events = events, .data.u64 = ((uint64_t)e->gen << 32) | i};
    if (epoll_ctl(l->epfd, EPOLL_CTL_ADD, fd, &ev) < 0)
        return -errno; /* the slot stays free (fd -1): valgrind saw find() and loop_free()
                        * read an appended slot's fd and timer_fn never written */
    e->fd = fd;
    e->fn = fn;
    e->ctx = ctx;
    e->timer_fn = tfn;
    e->timer_ctx = tctx;
    return 0;
}

int loop_add(loop_t *l, int fd, uint32_t events, loop_fn fn, void *ctx)
{
    if (!fn)
        return -EINVAL;
    return add_entry(l, fd, events, fn, ctx, NULL, NULL);
}

int loop_mod(loop_t *l, int fd, uint32_t events)
{
    int i = find(l, fd);
    if (i < 0)
        return -ENOENT;
    struct epoll_event ev = {.events = events,
                             .data.u64 = ((uint64_t)l->e[i].gen << 32) | (unsigned)i};
    return epoll_ctl(l->epfd, EPOLL_CTL_MOD, fd, &ev) < 0 ? -errno : 0;
}

int loop_del(loop_t *l, int fd)
{
    int i = find(l, fd);
    if (i < 0)
        return -ENOENT;
    /* The fd may already be closed by its owner (epoll then dropped it). */
    int rc = epoll_ctl(l->epfd, EPOLL_CTL_DEL, fd, NULL) < 0 ? -errno : 0;
    if (rc == -EBADF || rc == -ENOENT)
        rc = 0;
    l->e[i].fd = -1;
    l->e[i].gen++;
    return rc;
}

int loop_timer_add(loop_t *l, int64_t period_ns, loop_timer_fn fn, void *ctx)
{
    if (period_ns <= 0 || !fn)
        return -EINVAL;
    int fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (fd < 0)
        return -errno;
    struct itimerspec its = {
        .it_interval = {.tv_sec = period_ns / 1000000000, .tv_nsec = period_ns % 1000000000},
    };
    its.it_value = its.it_interval;
    if (timerfd_settime(fd, 0, &its, NULL) < 0) {
        int rc = -errno;
        close(fd);
        return rc;
    }
    int rc = add_entry(l, fd, EPOLLIN, NULL, NULL, fn, ctx);
    if (rc < 0) {
        close(fd);
        return rc;
    }
    return fd;
}

int loop_timer_del(loop_t *l, int timer_fd)
{
    int i = find(l, timer_fd);
    if (i < 0 || !l->e[i].timer_fn)
        return -ENOENT;
    int rc = loop_del(l, timer_fd);
    close(timer_fd);
    return rc;
}

int loop_run(loop_t *l)
{
    struct epoll_event ev[LOOP_BATCH];
    l->stop = 0;
    while (!l->stop) {
        int n = epoll_wait(l->epfd, ev, LOOP_BATCH, -1);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return -errno;
        }
        for (int k = 0; k < n; k++) {
            unsigned i = (unsigned)(ev[k].data.u64 & 0xffffffffu);
            uint32_t gen = (uint32_t)(ev[k].data.u64 >> 32);
            if (i >= l->n || l->e[i].fd < 0 || l->e[i].gen != gen)
                continue; /* deleted earlier in this batch */
            loop_entry_t *e = &l->e[i];
            if (e->timer_fn) {
                uint64_t exp = 0;
                if (read(e->fd, &exp, sizeof exp) == (ssize_t)sizeof exp && exp > 0)
                    e->timer_fn(l, exp, e->timer_ctx);
            } else {
                e->fn(l, e->fd, ev[k].events, e->ctx);
            }
        }
    }
    return l->code;
}

void loop_stop(loop_t *l, int code)
{
    l->stop = 1;
    l->code = code;
}
