/*
 * fake_can_io.h - one fake CAN transport (can_port_io_t, daemon/can/can_port.h)
 * for the C tests of daemon/can: frames queued in are received in order,
 * frames sent are recorded; the interface can be down (send -ENETDOWN), a
 * send can fail with a chosen error, and a reopen can succeed.
 */
#ifndef TRAJD_FAKE_CAN_IO_H
#define TRAJD_FAKE_CAN_IO_H

#include "can_port.h"

#define FAKE_CAN_MAX 4096

typedef struct {
    canproto_frame_t in[FAKE_CAN_MAX]; /* queued for recv */
    unsigned nin, next;
    canproto_frame_t out[FAKE_CAN_MAX]; /* sent */
    unsigned nout;
    int up;           /* 0: send -ENETDOWN, is_up 0 */
    int fail_with;    /* send returns this (negative) while set */
    int reopen_ok;    /* maintain brings a down interface up */
    int room_limited; /* a full transmit queue: send takes one of room, else -ENOBUFS */
    unsigned room;
} fake_can_io_t;

/* The ops; their io argument is a fake_can_io_t. */
extern const can_port_io_t fake_can_ops;

/* Empty and up. */
void fake_can_reset(fake_can_io_t *x);

#endif
