/*
 * fdlimit.h - the file descriptors a configuration holds open, against
 * RLIMIT_NOFILE.  Each transport states its own (transport_t.fds: sockets,
 * files, and the clients it may accept); the core adds its own (stdio, the
 * loop, its timers and signals, the workers, the log, the control socket and
 * its CTL_CLIENTS_MAX clients).  --check-config states the need and refuses a
 * configuration whose descriptors, clients left out, pass the hard limit; the
 * start and each reload raise the soft limit towards the need (the hard limit
 * at most), and a need that still does not fit is logged with what to raise.
 * Clients beyond the limit are refused as they come (modbus_accept.c).
 */
#ifndef TRAJD_FDLIMIT_H
#define TRAJD_FDLIMIT_H

#include <stddef.h>

#include "cfg.h"

/* The core's own descriptors, its control clients included, with a margin. */
#define FDLIMIT_CORE 48

typedef struct {
    unsigned need;                 /* held open while running: the core's and the transports' */
    unsigned clients;              /* ... and what peers may add at most (Modbus TCP clients) */
    unsigned long long soft, hard; /* RLIMIT_NOFILE (RLIM_INFINITY as ULLONG_MAX) */
} fdlimit_t;

/* The need of c, and the limits now. */
void fdlimit_of(const cfg_t *c, fdlimit_t *f);

/*
 * Raise the soft limit to need + clients, at most to the hard one (never
 * lower it).  Returns 0 if need + clients fit, 1 if need fits and clients do
 * not, -1 if need does not; why says so (and if the raise failed, why), ""
 * when it all fits.  f's soft is updated.
 */
int fdlimit_fit(fdlimit_t *f, char *why, size_t whylen);

/* 0 if need fits the hard limit, else -1 with why (--check-config). */
int fdlimit_check(const fdlimit_t *f, char *why, size_t whylen);

#endif
