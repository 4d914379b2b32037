/*
 * can_cfg.h - the configuration of the "can" transport (daemon/can/can_cfg.c): its keys,
 * each value checked once, where its key is parsed, and the checks of a whole file.
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
 *   can.cia402 = off | targets | feedback | managed (targets: needs initial_position),
 *   can.cia402_cob_x / _y / _z (0 = axis not sent),
 *   can.cia402_counts_per_m = 10000, can.cia402_controlword = no
 *   deprecated, still read: can.cia402 = yes / no, can.cia402_feedback, can.cia402_enable
 */
#ifndef TRAJD_CAN_CFG_H
#define TRAJD_CAN_CFG_H

#include <limits.h>
#include <stdint.h>

#include "can_logfile.h"
#include "can_port.h"
#include "canproto.h"
#include "cfg.h"

/* Highest can.index (and object id) with default ids: 0x680+n .. 0x6C0+n. */
#define CAN_INDEX_MAX 15

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
    /* log_in read whole by the check (can_cfg_check, on the configuration's worker,
     * cfgload.h), owned by this configuration; the transport's open replays it without
     * reading the file again.  NULL: no log_in, or no object uses CAN. */
    can_logfile_input_t *log_in_frames;
    int heartbeat_node; /* trajd's heartbeat as CANopen master: 0x700 + this, 0 = none */
    int heartbeat_ms;   /* its period, default 100 */
} can_cfg_t;

typedef struct {
    int index; /* -1 = the object's index */
    canproto_ids_t ids;
    unsigned given; /* bit per id key given explicitly */
    /* can.cia402 as read, into ids.cia402 by can_obj_ids: on (not off), and the former keys
     * cia402_feedback (default yes) and cia402_enable, which the modes set too */
    int cia402_on, cia402_feedback, cia402_enable;
    /* given (1) or not (0): the mode (the new form: off, targets, feedback, managed), and
     * the former keys, with their values (a former key that contradicts the mode is
     * refused, in either order).  No line numbers: the struct is compared whole at a
     * reload (a key moved is no change) */
    int mode_given, mode, feedback_given, feedback_value, enable_given, enable_value;
} can_obj_cfg_t;

/* The transport's cfg_default, cfg_key, obj_cfg_default, obj_key (transport.h). */
void can_cfg_default(void *p);
int can_cfg_key(void *p, const cfg_kv_t *kv, char *why, size_t wl);
void can_obj_cfg_default(void *p);
int can_obj_key(void *p, const cfg_kv_t *kv, char *why, size_t wl);
/* The transport's cfg_fini: frees log_in_frames. */
void can_cfg_fini(void *p);

/* Its check (log_in read whole into log_in_frames, ids, clashes, drives, bus load, then
 * can_box.h) and reload_check (no CAN id of an object that stays may move). */
int can_cfg_check(cfg_t *cfg, int *line, char *why, size_t wl);
int can_cfg_reload_check(const cfg_t *old, const cfg_t *nw, int *line, char *why, size_t wl);

/* 1 if object o sends or receives on CAN. */
int can_cfg_uses(const cfg_obj_t *o);

/* can_port's configuration from [can]; period_ns: the wall-clock period (engine period /
 * speed), since lateness is wall time. */
void can_cfg_port(const can_cfg_t *c, int64_t period_ns, can_port_config_t *pc);

/*
 * The ids of an object (defaults for its can.index, or if not given for its
 * id = N, never its place in the file; then the keys given).  For the tests
 * and the bus-load message.
 */
void can_obj_ids(const can_obj_cfg_t *oc, unsigned obj_id, canproto_ids_t *ids);

#endif
