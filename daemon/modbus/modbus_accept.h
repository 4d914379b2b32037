/*
 * modbus_accept.h - the Modbus listener out of file descriptors (issue 28).
 *
 * When accept4() fails with EMFILE or ENFILE the pending connection stays in
 * the listen backlog and the (level-triggered) listener stays readable: a
 * loop polling it would spin.  Instead:
 *   - one fd is kept in reserve (/dev/null, opened at start): it is closed,
 *     the pending connections are accepted and closed at once (the client
 *     sees its connection end instead of hanging in the backlog), each
 *     counted as refused (mb_refused), and the reserve is opened again;
 *   - the listener is then not polled for a back-off period, 100 ms doubling
 *     to 1 s while the shortage lasts, back to 100 ms after an accept that
 *     succeeds;
 *   - a warning is logged at most once a second with the counts.
 * ENOBUFS/ENOMEM (no memory for the socket) pause the same way, without
 * the reserve.
 */
#ifndef TRAJD_MODBUS_ACCEPT_H
#define TRAJD_MODBUS_ACCEPT_H

#include <stdint.h>
#include <sys/socket.h>

#define MB_ACCEPT_BACKOFF_MIN_MS 100
#define MB_ACCEPT_BACKOFF_MAX_MS 1000
#define MB_ACCEPT_REFUSE_MAX 64 /* connections closed per shortage event */

typedef struct {
    int open;           /* mb_accept_init succeeded */
    int reserve_fd;     /* /dev/null, or -1 */
    int timer_fd;       /* the back-off timer (timerfd), or -1 */
    int paused;         /* the listener is out of the poll set */
    int64_t backoff_ms; /* length of the next pause */
    int64_t pause_ms;   /* length of the last pause */
    int last_errno;     /* of the last shortage */
    uint64_t shortages; /* accept4 failures with EMFILE/ENFILE/ENOBUFS/ENOMEM */
    uint64_t refused;   /* connections accepted and closed for want of an fd */
    uint64_t pauses;    /* back-off periods */
    uint64_t logged_refused, logged_shortages;
    int64_t logged_ns; /* CLOCK_MONOTONIC of the last warning, 0: none yet */
} mb_accept_t;

/* Open the reserve fd and the timer.  0 or -errno (then nothing is open). */
int mb_accept_init(mb_accept_t *a);
void mb_accept_fini(mb_accept_t *a);

/*
 * accept4(lfd, sa, sl, SOCK_NONBLOCK | SOCK_CLOEXEC), and on a shortage:
 * close up to MB_ACCEPT_REFUSE_MAX pending connections through the reserve fd
 * (EMFILE, ENFILE), adding them to *refused, take lfd out of the epoll set
 * ep and arm the back-off timer.  Returns what accept4 returns (errno kept).
 */
int mb_accept(mb_accept_t *a, int ep, int lfd, struct sockaddr *sa, socklen_t *sl,
              uint64_t *refused);

/* The back-off timer (a->timer_fd) fired: put lfd back into ep with data. */
void mb_accept_resume(mb_accept_t *a, int ep, int lfd, uint64_t data);

/* The listening socket systemd passed (sd_listen_fds), or -1. */
int mb_systemd_listener(void);

/* Log new refusals (at most once a second unless final). */
void mb_accept_report(mb_accept_t *a, int final);

#endif
