/*
 * can_transport.h - the "can" transport of trajd: waypoints in and setpoints out over
 * SocketCAN (daemon/can/can_socket.h) or a candump log (daemon/can/can_logfile.h), with the
 * frames of lib/proto/canproto.h, driven by daemon/can/can_port.h.
 *
 * Its configuration: can_cfg.h.
 */
#ifndef TRAJD_CAN_TRANSPORT_H
#define TRAJD_CAN_TRANSPORT_H

#include <limits.h>
#include "canerr.h"
#include "can_cfg.h"
#include "canproto.h"
#include "transport.h"

extern const transport_t can_transport;

/* CAN bus state (values follow linux/can/netlink.h, plus DOWN; published
 * into the core's stats as its CORE_BUS_*, core.h). */
typedef enum {
    CAN_BUS_UNUSED = 0, /* no object uses CAN */
    CAN_BUS_ERROR_ACTIVE = 1,
    CAN_BUS_ERROR_WARNING = 2,
    CAN_BUS_ERROR_PASSIVE = 3,
    CAN_BUS_OFF = 4,
    CAN_BUS_DOWN = 5, /* interface down or gone; reopening */
} can_bus_state_t;

#endif
