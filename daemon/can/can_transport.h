/*
 * can_transport.h - the "can" transport of trajd: waypoints in and setpoints out over
 * SocketCAN (daemon/can/can_socket.h) or a candump log (daemon/can/can_logfile.h), with the
 * frames of lib/proto/canproto.h, driven by daemon/can/can_port.h.
 *
 * [can] keys (documented with defaults in config/trajd.conf):
 *   interface = can0            SocketCAN interface (ignored with log_in/log_out)
 *   log_in = FILE               read waypoint frames from a candump log instead of a socket
 *   log_out = FILE | -          write frames as a candump -L log instead of a socket
 *   log_ifname = can0           interface name written in log_out lines
 *   fd = no                     CAN FD on the socket (needed by any object with can.fd)
 *   bitrate = 500000            nominal bit rate, bit/s (bus-load check)
 *   data_bitrate = 2000000      CAN FD data-phase bit rate, bit/s (bus-load check)
 *   max_load_percent = 70       refuse a config whose worst-case bus load is above (0: no check)
 *   waypoint_hz = 10            expected waypoints per second per object (bus-load check)
 *   sync = no, sync_id = 0x080, sync_overflow = 0    SYNC frame per cycle (CiA 301)
 *   status_period_ms = 100      STATUS frame period per object (also sent on events)
 *   max_late_ms = -1            a cycle woken later than this is not sent (-1: half a period, 0: never)
 *   heartbeat_node = 0, heartbeat_ms = 100   trajd's heartbeat as CANopen master (0: none)
 * [object.NAME] keys:
 *   can.index = <object index>  n for the default ids (0x680+n ...)
 *   can.waypoint_id, can.waypoint_fd_id, can.setpoint_id, can.setpoint_fd_id, can.status_id
 *   can.fd = no, can.brs = no, can.own = yes
 *   can.cia402 = no, can.cia402_cob_x / _y / _z (0 = axis not sent),
 *   can.cia402_counts_per_m = 10000, can.cia402_controlword = no,
 *   can.cia402_feedback = yes with can.cia402 (no: needs initial_position)
 */
#ifndef TRAJD_CAN_TRANSPORT_H
#define TRAJD_CAN_TRANSPORT_H

#include <limits.h>
#include "canerr.h"
#include "canproto.h"
#include "transport.h"

typedef struct {
    char interface[32];
    char log_in[PATH_MAX];
    char log_out[PATH_MAX];
    char log_ifname[16];
    int log_time_engine;  /* [can] log_time = engine: log_out stamps from 0, not epoch */
    int log_out_truncate; /* [can] log_out_truncate: 1 yes, 0 no (append), -1 auto */
    int fd;
    double bitrate;
    double data_bitrate;
    double max_load_percent;
    double waypoint_hz;
    int sync;
    uint32_t sync_id;
    unsigned sync_overflow;
    double status_period_ms;
    double max_late_ms;
    int line_log_in;
    int heartbeat_node; /* trajd's heartbeat as CANopen master: 0x700 + this, 0 = none */
    int heartbeat_ms;   /* its period, default 100 */
} can_cfg_t;

typedef struct {
    int index; /* -1 = the object's index */
    canproto_ids_t ids;
    unsigned given;     /* bit per id key given explicitly */
    int feedback_given; /* can.cia402_feedback given (else: yes with can.cia402) */
} can_obj_cfg_t;

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

/* Highest can.index (and object id) with default ids: 0x680+n .. 0x6C0+n. */
#define CAN_INDEX_MAX 15

/*
 * The ids of an object (defaults for its can.index, or if not given for its
 * id = N, never its place in the file; then the keys given).  For the tests
 * and the bus-load message.
 */
void can_obj_ids(const can_obj_cfg_t *oc, unsigned obj_id, canproto_ids_t *ids);

#endif
