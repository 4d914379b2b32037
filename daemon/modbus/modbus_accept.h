/*
 * modbus_accept.h - the Modbus listener out of file descriptors (issue 28):
 * daemon/core/acceptguard.h's reserve fd, refusals and back-off on the
 * server's own epoll set.  A refused client's connection is closed at once
 * (Modbus has no word for "out of fds"), counted in mb_refused.
 */
#ifndef TRAJD_MODBUS_ACCEPT_H
#define TRAJD_MODBUS_ACCEPT_H

#include <stdint.h>
#include <sys/socket.h>

#include "acceptguard.h"

typedef acceptguard_t mb_accept_t;

/* Open the reserve fd and the timer (ag_init); ag_fini closes them.  0 or
 * -errno (then nothing is open). */
int mb_accept_init(mb_accept_t *a);

/*
 * accept4(lfd, sa, sl, SOCK_NONBLOCK | SOCK_CLOEXEC), and on a shortage:
 * close up to AG_REFUSE_MAX pending connections through the reserve fd
 * (EMFILE, ENFILE), adding them to *refused, take lfd out of the epoll set
 * ep and arm the back-off timer.  Returns what accept4 returns (errno kept).
 */
int mb_accept(mb_accept_t *a, int ep, int lfd, struct sockaddr *sa, socklen_t *sl,
              uint64_t *refused);

/* The back-off timer (a->timer_fd) fired: put lfd back into ep with data. */
void mb_accept_resume(mb_accept_t *a, int ep, int lfd, uint64_t data);

/* The listening socket systemd passed (sd_listen_fds), or -1. */
int mb_systemd_listener(void);

#endif
