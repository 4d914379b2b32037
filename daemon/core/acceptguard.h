/*
 * acceptguard.h - a listening socket out of file descriptors (issue 28).
 *
 * When accept4() fails with EMFILE or ENFILE the pending connection stays in
 * the listen backlog and the (level-triggered) listener stays readable: a
 * loop polling it would spin.  Instead:
 *   - one fd is kept in reserve (/dev/null, opened at start): it is closed,
 *     the pending connections are accepted, told why where the caller has a
 *     word for them, and closed at once (the client sees its connection end
 *     instead of hanging in the backlog), each counted as refused, and the
 *     reserve is opened again;
 *   - the listener is then not polled for a back-off period, 100 ms doubling
 *     to 1 s while the shortage lasts, back to 100 ms after an accept that
 *     succeeds (the caller takes it out of its poll set while paused, and
 *     back when the timer fires);
 *   - a warning is logged at most once a second with the counts.
 * ENOBUFS/ENOMEM (no memory for the socket) pause the same way, without
 * the reserve.  The Modbus listener (daemon/modbus/modbus_accept.h) and the
 * control socket (daemon/ctl/ctl.c) use it.
 */
#ifndef TRAJD_ACCEPTGUARD_H
#define TRAJD_ACCEPTGUARD_H

#include <stdint.h>

#define AG_BACKOFF_MIN_MS 100
#define AG_BACKOFF_MAX_MS 1000
#define AG_REFUSE_MAX 64 /* connections closed per shortage event */

typedef struct {
    const char *who;    /* the log line's subject ("modbus", "control") */
    const char *told;   /* what a refused client gets ("closed at once") */
    int open;           /* ag_init succeeded */
    int reserve_fd;     /* /dev/null, or -1 */
    int timer_fd;       /* the back-off timer (timerfd), or -1 */
    int paused;         /* the listener is out of the poll set */
    int64_t backoff_ms; /* length of the next pause */
    int64_t pause_ms;   /* length of the last pause */
    int last_errno;     /* of the last shortage */
    uint64_t shortages; /* accept4 failures with EMFILE/ENFILE/ENOBUFS/ENOMEM */
    uint64_t refused;   /* connections accepted and closed for want of an fd */
    uint64_t logged_shortages;
    int64_t logged_ns; /* CLOCK_MONOTONIC of the last warning, 0: none yet */
} acceptguard_t;

/* A refused client's fd, before it is closed: tell it why (err: the errno). */
typedef void (*ag_tell_fn)(int fd, int err, void *ctx);

/* Open the reserve fd and the timer (who, told: static strings for the log).
 * 0 or -errno (then nothing is open). */
int ag_init(acceptguard_t *a, const char *who, const char *told);
void ag_fini(acceptguard_t *a);

/* 1 if err (of accept4) is a shortage of fds or memory. */
int ag_is_shortage(int err);

/* accept4 on lfd failed with the shortage err (nothing done unless ag_init
 * succeeded): refuse up to AG_REFUSE_MAX
 * pending connections through the reserve (EMFILE, ENFILE; tell may be
 * NULL) and arm the back-off timer (a->paused: take lfd out of the poll
 * set).  Returns the connections refused. */
unsigned ag_shortage(acceptguard_t *a, int lfd, int err, ag_tell_fn tell, void *ctx);

/* An accept succeeded: the next pause is the shortest again. */
void ag_accepted(acceptguard_t *a);

/* a->timer_fd is readable: 1 if the listener was paused and goes back into
 * the poll set now (the caller puts it back), else 0. */
int ag_resume(acceptguard_t *a);

/* Log new refusals (at most once a second unless final). */
void ag_report(acceptguard_t *a, int final);

#endif
