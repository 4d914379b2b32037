/*
 * can_port.h - the CAN side of trajd, independent of the daemon's core: objects
 * (ids, waypoint reassembly, counters) on one transport (SocketCAN or a
 * candump log), waypoints in through hooks, setpoints out once per cycle.
 *
 * Seams (CANopenNode style: the protocol logic never touches the OS):
 *  - can_port_io_t: send / recv / maintain of a transport (can_socket.h, can_logfile.h,
 *    or a fake in the tests);
 *  - can_port_hooks_t: what to do with a waypoint or command for an object
 *    (the daemon calls obj_push / engine_*; tests use fakes);
 *  - each object's CiA 402 drives are can_drive.h's (bring-up, feedback,
 *    heartbeats, RPDO targets): this port calls them, they send through it.
 *
 * Per cycle (can_port_cycle, called once per tick after every object's
 * setpoint was handed over with can_port_setpoint):
 *   1. SYNC (if enabled), always, even when the caller is late;
 *   2. per object its own SETPOINT frame(s) and its CiA 402 RPDOs (a CSP
 *      drive applies the target received after SYNC k at SYNC k + 1: one
 *      cycle of latency, the CiA 402 norm).  If the caller was later than
 *      max_late_ns for this cycle, the own frames are not sent (counted as
 *      dropped, late) but SYNC and the RPDOs are: what the drive sees on a
 *      late cycle is its SYNC and its target late by the lateness, and it
 *      applies the target at the next SYNC as on any cycle, so the
 *      positions it follows are exactly the planned ones.  A deadline missed
 *      altogether (the daemon woke after the next one: core.h) has no SYNC:
 *      the drive sees one SYNC interval of two periods and a target two
 *      periods ahead; drives that count SYNC loss count it (the daemon counts
 *      it too: stats.missed_ticks).  RPDOs are never sent
 *      while the setpoint has no position (ENGINE_SP_NO_POSITION);
 *   3. STATUS frames that are due (every status_period_ns, or at once after a
 *      rejection, a loss, a malformed frame or a change of engine state, at
 *      most one per object per cycle); for an object with CiA 402 drives,
 *      STATUS2 page 4 is one of its pages, and a change of it makes a STATUS due.
 * With cia402 managed and cia402_controlword, the RPDO's controlword is the one
 * the bring-up last wrote to 0x6040 (Enable operation only while it enables
 * the drive; Disable voltage before any), never a fixed value.
 * A frame the transport cannot take (queue full, interface down) is dropped
 * and counted; the rest of that object's frames this cycle are not attempted
 * (the setpoint is dropped whole).  Nothing is kept for later: after a fault
 * the next cycle sends the current setpoint, never a backlog.
 *
 * Not thread-safe: one loop thread calls everything.  No allocation after
 * can_port_new.
 */
#ifndef TRAJD_CANPORT_H
#define TRAJD_CANPORT_H

#include <stdint.h>
#include "can_axis.h"
#include "can_drive.h"
#include "canerr.h"
#include "canproto.h"
#include "cia402.h"
#include "engine.h"
#include "lifecycle.h"

/* Slots per object for interleaved waypoint frames (see canproto_rx_init). */
#define CAN_PORT_RX_SLOTS 2

typedef struct {
    /* 0, or -errno: -ENOBUFS/-EAGAIN = full, -ENETDOWN/-ENODEV/-ENXIO = down. */
    int (*send)(void *io, const canproto_frame_t *f);
    /* 1 = a frame in f, 0 = none now, -errno. now_ns: engine time (log replay). */
    int (*recv)(void *io, int64_t now_ns, canproto_frame_t *f);
    /* Reopen if down; 1 if the transport came up now. May be NULL. */
    int (*maintain)(void *io, int64_t now_ns);
    /* 1 if usable now. */
    int (*is_up)(const void *io);
} can_port_io_t;

typedef struct {
    /* Offer a waypoint; returns what engine_push returns. */
    int (*push)(void *ctx, const engine_waypoint_t *wp);
    /* A command frame arrived.  Returns 0, or < 0: refused (counted as
     * cmd_refused, e.g. an override > 0 while the object is held). */
    int (*command)(void *ctx, canproto_cmd_t cmd, unsigned arg);
    /* Current engine status (state, last_seq, free). */
    void (*status)(void *ctx, engine_status_t *st);
    /* A feedback TPDO of one of the object's drives arrived, or a CLEAR after
     * a drive hold made every axis re-anchor at its 0x6064 (may be NULL).
     * With d->need_anchor, the drives are enabled again (LC_EV_DRIVE_ENABLED
     * at d->anchor_m).  Returns 1 if the engine now stands at d->anchor_m, at
     * rest (the owner adopted it), else 0 (e.g. held: noted only). */
    int (*feedback)(void *ctx, const can_port_drive_t *d);
    /* An event of the object's drives for its owner (may be NULL;
     * lib/engine/LIFECYCLE.md): LC_EV_DRIVE_LOST (a drive left Operation
     * Enabled: fault, quick stop, disabled), LC_EV_DRIVE_BOOTUP (a drive
     * heard before sent its boot-up), LC_EV_HEARTBEAT_LOST (once until a
     * CLEAR), LC_EV_HEARTBEAT_BACK. */
    void (*drive_event)(void *ctx, lc_event_t ev);
} can_port_hooks_t;

typedef struct {
    int sync;                 /* send a SYNC frame each cycle */
    uint32_t sync_id;         /* default 0x080 */
    uint8_t sync_overflow;    /* 0: SYNC with DLC 0; 2..240: DLC 1, counter 1..overflow */
    int64_t status_period_ns; /* STATUS period, default 100 ms; 0 = only on events */
    int64_t max_late_ns;      /* cycle later than this is not sent; <= 0 = never drop */
    uint8_t hb_node;          /* trajd's own heartbeat (CiA 301 producer, NMT state
                               * operational) on 0x700 + hb_node; 0 = none */
    int64_t hb_period_ns;     /* its period (default 100 ms) */
    int64_t period_ns;        /* the cycle's period (in the now_ns of can_port_cycle): a
                               * longer gap between two cycles is trajd's own stall,
                               * excused from heartbeat ages (0: none) */
} can_port_config_t;

void can_port_config_default(can_port_config_t *c);

typedef struct {
    uint64_t setpoints_sent; /* cycles whose frames all went out */
    uint64_t dropped_late;   /* cycles not sent: caller late */
    uint64_t dropped_full;   /* cycles not (wholly) sent: ENOBUFS / EAGAIN */
    uint64_t dropped_down;   /* cycles not sent: interface down */
    uint64_t dropped_error;  /* cycles not sent: other write error (EINVAL: FD on a classic MTU) */
    uint64_t dropped_pos;    /* of the four above, cycles whose setpoint carried a position
                                (not the n/a of an object waiting): motion the drives missed */
    uint64_t tx_clamped;     /* setpoints with a value clamped to its field */
    uint64_t status_sent;
    uint64_t status_dropped; /* STATUS and STATUS2 frames the transport refused (queue full,
                                down): the next one carries the counters on */
    uint64_t waypoints_accepted;
    uint64_t waypoints_rejected; /* engine refused (not EFULL) */
    uint64_t waypoints_full;     /* engine EFULL: not consumed, sender must repeat */
    uint64_t engine_duplicates;
    uint64_t drive_frames;   /* feedback TPDOs received */
    uint64_t drive_lost;     /* times the drives left Operation Enabled while the object ran */
    uint64_t drive_bad;      /* feedback TPDOs too short */
    uint64_t sdo_aborts;     /* SDO writes a drive refused (last_abort says why) */
    uint64_t sdo_timeouts;   /* SDO writes resent after no reply */
    uint64_t sdo_stale;      /* SDO replies not for the request in flight, ignored */
    uint64_t emcy;           /* EMCY frames from the object's drives */
    uint64_t heartbeat_lost; /* a drive's heartbeat not heard within cia402_heartbeat_ms */
    uint32_t last_abort;     /* abort code of the last SDO abort (cia402_sdo_abort_text) */
    uint16_t last_abort_index;
    uint16_t last_emcy;       /* error code of the last EMCY */
    uint64_t cmd_refused;     /* command frames refused (can_port_allow_commands) */
    uint8_t last_refused;     /* canproto_cmd_t of the last one */
    uint32_t last_refused_id; /* CAN id it came on */
    int last_refused_err;     /* why: 0 not allowed (not writable), else the hook's -ENGINE_E* */
    canproto_rx_stats_t rx;   /* reassembly counters */
} can_port_obj_stats_t;

typedef struct {
    uint64_t rx_frames;
    uint64_t
        rx_foreign; /* frames with an id no object uses (log input; filters stop them on a socket) */
    uint32_t rx_foreign_first; /* the id of the first of them (CANPROTO_F_EFF in flags: 29 bits) */
    uint32_t rx_foreign_first_flags;
    uint64_t rx_errors;
    uint64_t sync_sent;
    uint64_t sync_dropped; /* SYNC frames the transport refused (queue full, down) */
    uint64_t cycles;
    uint64_t down_cycles; /* cycles during which the transport was down */
    uint64_t dropped_pos; /* the objects' dropped_pos summed: cycles with a position not
                             sent since the port opened (a reset-counters command leaves it) */
    uint64_t reopens;
} can_port_stats_t;

typedef struct can_port can_port_t;

/* Allocate for nobj objects (>= 1).  Returns NULL on bad arguments / no memory. */
can_port_t *can_port_new(const can_port_config_t *cfg, const can_port_io_t *io, void *io_ctx,
                         unsigned nobj);

/* Free; NULL is a no-op.  Does not close the transport. */
void can_port_free(can_port_t *p);

/*
 * Set object i's ids and hooks.  Returns 0, -CANPROTO_ECONFIG (ids invalid or
 * clashing with another object's), or -CANPROTO_EID (i out of range).
 */
int can_port_set_object(can_port_t *p, unsigned i, const canproto_ids_t *ids,
                        const can_port_hooks_t *hooks, void *ctx);

/* Read and handle every frame available now.  Returns frames handled or -errno. */
int can_port_rx(can_port_t *p, int64_t now_ns);

/*
 * Tell the port about object i's other outputs (csv/stdout): lost = lines
 * lost so far, fault = 1 once a write failed.  When lost grows or fault
 * appears, the next STATUS carries CANPROTO_ST_OUT_FAULT and last_err
 * CANPROTO_STERR_OUTPUT (sent at once, as after a rejection).
 */
void can_port_output_fault(can_port_t *p, unsigned i, uint64_t lost, int fault);

/*
 * Which commands object i obeys: bit (1u << canproto_cmd_t) per command
 * (default: all, CAN_PORT_CMD_ALL).  A command frame outside the mask is
 * refused: nothing happens, it is counted (stats cmd_refused, with its
 * command and id), reported in STATUS at once (last_err
 * CANPROTO_STERR_REFUSED).
 */
#define CAN_PORT_CMD_ALL 0xFFFFFFFFu
void can_port_allow_commands(can_port_t *p, unsigned i, uint32_t mask);

/*
 * Object i's STATUS2 page f->data[0] (1 .. CANPROTO_ST2_PAGES - 1; the id of
 * f is ignored: the object's status2_id is used), copied.  After each STATUS,
 * one STATUS2 page goes out: the first page whose bytes changed since it was
 * last sent, else the pages given so far in turn.  A change does not make a
 * STATUS due by itself (events do).
 */
void can_port_status2(can_port_t *p, unsigned i, const canproto_frame_t *f);
/* The same for a page of values that change all the time (page 3, the data
 * age): its new bytes never count as a change, so it goes out in turn (and
 * first when it is new) and never holds the other pages back. */
void can_port_status2_value(can_port_t *p, unsigned i, const canproto_frame_t *f);

/* Hand over object i's setpoint for this cycle (copied). */
void can_port_setpoint(can_port_t *p, unsigned i, const engine_setpoint_t *sp);

/*
 * Send this cycle (see the top of this file).  now_ns: engine time of the
 * tick; late_ns: how late the caller woke for it (0 if unknown).
 */
void can_port_cycle(can_port_t *p, int64_t now_ns, int64_t late_ns);

/* A reload: object i (set) takes the drives' state of the port that ran them
 * (can_port_drive_state of the old port's object; can_drive_adopt), and the
 * port the SYNC counter it had reached.  1 if adopted. */
int can_port_adopt(can_port_t *p, unsigned i, const can_drive_t *old, uint8_t sync_counter);
/* What object i's CAN side keeps over a reload (can_transport.c, keep.h):
 * its counters (STATUS, STATUS2, the exit summary: an ordinary reload must
 * not zero what peers count by, nor send them a counter that wrapped back)
 * and its waypoint reassembly (the sequence history and the waypoints in
 * flight: the first waypoint after it is not counted lost). */
typedef struct {
    can_port_obj_stats_t st;
    canproto_rx_t rx; /* its slots are those below */
    canproto_slot_t slots[CAN_PORT_RX_SLOTS];
} can_port_kept_t;
void can_port_keep(const can_port_t *p, unsigned i, can_port_kept_t *k);
/* Object i (set) takes what k holds. */
void can_port_restore(can_port_t *p, unsigned i, const can_port_kept_t *k);
/* Object i's drives' state, for can_port_adopt (NULL if i is out of range). */
const can_drive_t *can_port_drive_state(const can_port_t *p, unsigned i);
uint8_t can_port_sync_counter(const can_port_t *p);

/* Object i was cleared by a command from elsewhere (trajctl, Modbus): its
 * drives as after a CAN CLEAR the object accepted (a held drive is reset
 * and enabled again, its holds released). */
void can_port_cleared(can_port_t *p, unsigned i);

/* Object i's counters were reset by a command from elsewhere (trajctl,
 * Modbus): its CAN counters (reassembly, drives, STATUS) too, as after a CAN
 * reset-counters command. */
void can_port_reset_counters(can_port_t *p, unsigned i);

/* Housekeeping (reopen a down transport).  Returns 1 if it came up now. */
int can_port_maintain(can_port_t *p, int64_t now_ns);

/* The port's own counters (the CAN transport logs them when it closes). */
void can_port_stats(const can_port_t *p, can_port_stats_t *st);

/* The bus state and error counters decoded from the error frames received
 * (socket: CAN_RAW_ERR_FILTER; log input: "2000xxxx#" lines). */
const canerr_bus_t *can_port_bus_errors(const can_port_t *p);
void can_port_obj_stats(const can_port_t *p, unsigned i, can_port_obj_stats_t *st);

/* The oldest state change of object i's drives not yet taken (every one, in
 * order, also those shorter than a status period): 1 and *c, 0 if none.
 * *dropped: changes lost since the last call because more than
 * CAN_AXIS_LOG_MAX came between two calls (may be NULL). */
int can_port_drive_change(can_port_t *p, unsigned i, can_axis_change_t *c, uint64_t *dropped);

/* What object i's drives last reported (NULL if i is out of range). */
const can_port_drive_t *can_port_drive(const can_port_t *p, unsigned i);

/*
 * Object i's drives in brief (STATUS2 page 4, Modbus): state per axis, held,
 * heartbeat lost, the statusword and NMT state of the first axis not in
 * Operation Enabled (else the first), the last EMCY code.  Returns 1 if the
 * object has CiA 402 drives it hears from (cia402 with feedback or enable), else
 * 0 (out zeroed, states CANPROTO_S2_NO_DRIVE).
 */
int can_port_drive_summary(const can_port_t *p, unsigned i, canproto_status2_drive_t *out);

/*
 * Worst-case bus load of this port's configuration: rate_hz setpoint
 * cycles, status as configured, waypoint_hz expected waypoints per object.
 * Returns the load (0..1+), or a negative value for invalid bitrates.
 */
double can_port_busload(const can_port_t *p, double rate_hz, double waypoint_hz, double bitrate,
                        double data_bitrate);

#endif
