/*
 * loop.h - the daemon's one event loop (epoll), in the style of Redis ae.c:
 * file descriptors registered with a callback and a void * context, run until
 * stopped.  Everything the daemon does happens in callbacks of this loop, in
 * one thread: the output clock (a timerfd, see core.h), signals (signalfd),
 * CAN sockets, Modbus clients, periodic housekeeping timers.  Callbacks must
 * not block: use non-blocking fds and come back on the next event.  Work that
 * would (a configuration's tracks parsed at a reload) runs on a thread of its
 * own and meets the loop through an fd (cfgload.h: an eventfd).
 *
 * Safe to call loop_add/loop_mod/loop_del from inside a callback, including
 * deleting the fd being served or another fd whose event is already pending in
 * the same batch (a deleted entry is never called again, even if a new fd
 * reuses its number in the same batch: entries carry a generation).
 *
 * Errors: 0 or -errno (system calls), -EEXIST (fd already registered),
 * -ENOENT (fd not registered), -EINVAL (bad argument).
 */
#ifndef TRAJD_LOOP_H
#define TRAJD_LOOP_H

#include <stdint.h>
#include <sys/epoll.h>

typedef struct loop loop_t;

/*
 * Callback: fd is ready with events (EPOLLIN, EPOLLOUT, EPOLLERR, EPOLLHUP ...
 * as epoll reports them).  ctx is what was given to loop_add.
 */
typedef void (*loop_fn)(loop_t *l, int fd, uint32_t events, void *ctx);

/* Periodic timer callback (loop_timer_add); expirations >= 1 since the last call. */
typedef void (*loop_timer_fn)(loop_t *l, uint64_t expirations, void *ctx);

/* New loop.  Returns NULL and sets *err (may be NULL) to -errno on failure. */
loop_t *loop_new(int *err);

/* Close the epoll fd and free the loop.  Registered fds are NOT closed (their
 * owners close them); timers made by loop_timer_add are.  NULL is a no-op. */
void loop_free(loop_t *l);

/* Watch fd for events (EPOLLIN | EPOLLOUT ...) and call fn(l, fd, ev, ctx). */
int loop_add(loop_t *l, int fd, uint32_t events, loop_fn fn, void *ctx);

/* Change the events watched on a registered fd. */
int loop_mod(loop_t *l, int fd, uint32_t events);

/* Stop watching fd (does not close it). */
int loop_del(loop_t *l, int fd);

/*
 * A periodic timer on CLOCK_MONOTONIC (a timerfd owned by the loop) for
 * housekeeping that is not the output clock: status lines, watchdog, CAN
 * reopen.  First expiry one period from now.  Returns the timer's fd (> 0,
 * the handle for loop_timer_del) or -errno.
 */
int loop_timer_add(loop_t *l, int64_t period_ns, loop_timer_fn fn, void *ctx);

/* Delete and close a timer made by loop_timer_add. */
int loop_timer_del(loop_t *l, int timer_fd);

/*
 * Dispatch events until loop_stop is called.  Returns the code given to
 * loop_stop, or -errno if epoll_wait failed (EINTR is retried).
 */
int loop_run(loop_t *l);

/* Make loop_run return code after the current batch of callbacks. */
void loop_stop(loop_t *l, int code);

#endif
