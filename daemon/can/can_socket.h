/*
 * can_socket.h - SocketCAN transport (can-utils style): if_nametoindex -> bind ->
 * CAN_RAW_FILTER for exactly the ids in use -> CAN_RAW_FD_FRAMES, non-blocking.
 *
 * The interface going down or being removed is a state, not an error: send
 * and recv report it, the socket is closed, and can_socket_maintain() (called
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

#define CAN_SOCKET_MAX_FILTERS 64
/* Reopen attempts while DOWN, at most this often. */
#define CAN_SOCKET_REOPEN_NS 200000000LL

typedef enum {
    CAN_SOCKET_DOWN = 0, /* no usable socket: interface down, missing or not yet opened */
    CAN_SOCKET_UP = 1,
} can_socket_state_t;

typedef struct {
    uint64_t tx_frames;       /* whole frames written */
    uint64_t tx_dropped_full; /* ENOBUFS / EAGAIN: queue or buffer full */
    uint64_t tx_dropped_down; /* interface down or missing */
    uint64_t tx_errors;       /* other write errors, short writes */
    uint64_t rx_frames;
    uint64_t rx_errors;   /* short reads, error frames */
    uint64_t rx_overflow; /* frames the kernel dropped, trajd's receive queue full
                             (SO_MEMINFO: a stall longer than the queue holds) */
    uint64_t downs;       /* transitions UP -> DOWN */
    uint64_t reopens;     /* transitions DOWN -> UP */
    int last_errno;
} can_socket_stats_t;

typedef struct can_socket can_socket_t;

/*
 * Create (does not open: call can_socket_maintain or can_socket_open).  rx_ids: the
 * ids to receive (exact 11-bit match each), n_rx <= CAN_SOCKET_MAX_FILTERS; 0
 * ids = receive nothing.  fd_frames: enable CAN FD (needs an MTU 72 iface).
 * Returns NULL on a bad argument or no memory.
 */
can_socket_t *can_socket_new(const char *ifname, int fd_frames, const uint32_t *rx_ids,
                             unsigned n_rx);

/* Close and free; NULL is a no-op. */
void can_socket_free(can_socket_t *b);

/*
 * Open now: 0, or -errno (-ENODEV: no such interface, -ENETDOWN: it is not
 * up, -EAFNOSUPPORT: no CAN in this kernel, ...).  State UP on success.
 */
int can_socket_open(can_socket_t *b);

/* While DOWN and at least CAN_SOCKET_REOPEN_NS after the last attempt, try to
 * reopen.  Returns 1 if it went UP now, else 0. */
int can_socket_maintain(can_socket_t *b, int64_t now_ns);

/* Socket for epoll (EPOLLIN), or -1 while DOWN: re-register after a state change. */
int can_socket_fd(const can_socket_t *b);

can_socket_state_t can_socket_state(const can_socket_t *b);

/*
 * Write one frame, non-blocking.  Returns 0 (sent whole), -ENOBUFS / -EAGAIN
 * (dropped, counted), -ENETDOWN / -ENODEV / -ENXIO (dropped; now DOWN),
 * -EINVAL (frame not sendable: FD frame without FD enabled), other -errno.
 */
int can_socket_send(can_socket_t *b, const canproto_frame_t *f);

/*
 * Read one frame if one is waiting.  Returns 1 (frame in f), 0 (none), or
 * -errno (-ENETDOWN etc.: now DOWN).  Error frames are counted and skipped.
 */
int can_socket_recv(can_socket_t *b, canproto_frame_t *f);

void can_socket_stats(can_socket_t *b, can_socket_stats_t *st);

#endif
