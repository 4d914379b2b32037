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

/* CAN bus state (values follow linux/can/netlink.h, plus DOWN; the Modbus
 * register map publishes them as its MBMAP_CAN_*). */
typedef enum {
    CAN_BUS_UNUSED = 0, /* no object uses CAN */
    CAN_BUS_ERROR_ACTIVE = 1,
    CAN_BUS_ERROR_WARNING = 2,
    CAN_BUS_ERROR_PASSIVE = 3,
    CAN_BUS_OFF = 4,
    CAN_BUS_DOWN = 5, /* interface down or gone; reopening */
} can_bus_state_t;

struct core;

/*
 * The bus state of c's CAN transport as of its last housekeeping timer
 * (every 100 ms), and in *load_permille the worst-case bus load of the
 * configured traffic in 0.1 %.  CAN_BUS_UNUSED and 0 when CAN is not open.
 * For the Modbus status registers; any time, also in the tick.
 */
can_bus_state_t can_transport_bus(const struct core *c, uint32_t *load_permille);

/* The error-frame counters of c's CAN bus (lib/proto/canerr.h) as of the last
 * housekeeping timer; all 0 when CAN is not open. */
void can_transport_bus_errors(const struct core *c, canerr_bus_t *out);
/* What the Modbus registers say of object obj's CiA 402 drives. */
typedef struct {
    canproto_status2_drive_t d; /* as STATUS2 page 4 */
    uint64_t emcy;              /* EMCY frames from its drives */
    uint64_t sdo_aborts;
    uint32_t last_abort; /* abort code of the last SDO abort, 0 = none */
    uint64_t hb_lost;    /* heartbeat consumer timeouts */
    uint64_t tx_clamped; /* setpoints with a value clipped to its field (can_box.h) */
} can_drive_info_t;

/* Object obj's drives (config index).  Returns 1 if it has CiA 402 drives trajd
 * hears from, else 0 (*out zeroed, states CANPROTO_S2_NO_DRIVE).  Any time,
 * also in the tick. */
int can_transport_drive(const struct core *c, unsigned obj, can_drive_info_t *out);

#endif
