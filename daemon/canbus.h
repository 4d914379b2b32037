/*
 * canbus.h - SocketCAN transport (can-utils style): if_nametoindex -> bind ->
 * CAN_RAW_FILTER for exactly the ids in use -> CAN_RAW_FD_FRAMES, non-blocking.
 *
 * The interface going down or being removed is a state, not an error: send
 * and recv report it, the socket is closed, and canbus_maintain() (called
 * from the loop) reopens it once the interface exists and is up again.
 * Frames that cannot be sent right now (ENOBUFS: TX queue full; EAGAIN:
 * socket buffer full; the interface is down) are dropped and counted, never
 * queued: a late setpoint is worthless, and a burst of stale ones after
 * recovery is what a drive must never see.
 */
#ifndef TRAJD_CANBUS_H
#define TRAJD_CANBUS_H

#include <stdint.h>
#include "canproto.h"

#define CANBUS_MAX_FILTERS 64
/* Reopen attempts while DOWN, at most this often. */
#define CANBUS_REOPEN_NS 200000000LL

typedef enum {
    CANBUS_DOWN = 0,   /* no usable socket: interface down, missing or not yet opened */
    CANBUS_UP = 1,
} canbus_state_t;

typedef struct {
    uint64_t tx_frames;        /* whole frames written */
    uint64_t tx_dropped_full;  /* ENOBUFS / EAGAIN: queue or buffer full */
    uint64_t tx_dropped_down;  /* interface down or missing */
    uint64_t tx_errors;        /* other write errors, short writes */
    uint64_t rx_frames;
    uint64_t rx_errors;        /* short reads, error frames */
    uint64_t downs;            /* transitions UP -> DOWN */
    uint64_t reopens;          /* transitions DOWN -> UP */
    int last_errno;
} canbus_stats_t;

typedef struct canbus canbus_t;

/*
 * Create (does not open: call canbus_maintain or canbus_open).  rx_ids: the
 * ids to receive (exact 11-bit match each), n_rx <= CANBUS_MAX_FILTERS; 0
 * ids = receive nothing.  fd_frames: enable CAN FD (needs an MTU 72 iface).
 * Returns NULL on a bad argument or no memory.
 */
canbus_t *canbus_new(const char *ifname, int fd_frames, const uint32_t *rx_ids, unsigned n_rx);

/* Close and free; NULL is a no-op. */
void canbus_free(canbus_t *b);

/*
 * Open now: 0, or -errno (-ENODEV: no such interface, -ENETDOWN: it is not
 * up, -EAFNOSUPPORT: no CAN in this kernel, ...).  State UP on success.
 */
int canbus_open(canbus_t *b);

/* While DOWN and at least CANBUS_REOPEN_NS after the last attempt, try to
 * reopen.  Returns 1 if it went UP now, else 0. */
int canbus_maintain(canbus_t *b, int64_t now_ns);

/* Socket for epoll (EPOLLIN), or -1 while DOWN: re-register after a state change. */
int canbus_fd(const canbus_t *b);

canbus_state_t canbus_state(const canbus_t *b);

/*
 * Write one frame, non-blocking.  Returns 0 (sent whole), -ENOBUFS / -EAGAIN
 * (dropped, counted), -ENETDOWN / -ENODEV / -ENXIO (dropped; now DOWN),
 * -EINVAL (frame not sendable: FD frame without FD enabled), other -errno.
 */
int canbus_send(canbus_t *b, const canproto_frame_t *f);

/*
 * Read one frame if one is waiting.  Returns 1 (frame in f), 0 (none), or
 * -errno (-ENETDOWN etc.: now DOWN).  Error frames are counted and skipped.
 */
int canbus_recv(canbus_t *b, canproto_frame_t *f);

void canbus_stats(const canbus_t *b, canbus_stats_t *st);

#endif
