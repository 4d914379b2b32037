/*
 * can_drive.h - one object's CiA 402 drives as trajd commands them (issues 23,
 * 25): bring-up (NMT start, the configuration list, the controlword by SDO),
 * feedback (TPDO: statusword, 0x6064), heartbeats (consumer: the drives';
 * producer: trajd's own), EMCY, each axis' RPDO target (can_axis.h), and the
 * drives' events for the object's owner (lib/engine/LIFECYCLE.md).
 *
 * The CAN port (can_port.c) calls this file, never the reverse: frames go out
 * and events come back through can_drive_ops_t, which the port fills.  No I/O,
 * no clock, no allocation.  Not thread-safe (the loop thread).
 */
#ifndef TRAJD_CAN_DRIVE_H
#define TRAJD_CAN_DRIVE_H

#include <stdint.h>

#include "can_axis.h"
#include "canproto.h"
#include "cia402.h"
#include "engine.h"
#include "lifecycle.h"

/* What the drives of one object report (CiA 402 feedback TPDOs). */
typedef struct {
    uint16_t statusword[CANPROTO_CIA402_AXES];
    cia402_state_t state[CANPROTO_CIA402_AXES]; /* CIA402_STATE_UNKNOWN until heard */
    double pos_m[CANPROTO_CIA402_AXES];         /* position actual values (0x6064) in metres (scale,
                                          * sign and offset undone); 0 for axes without a drive */
    unsigned seen;                              /* bit per axis heard from */
    int all_seen;                               /* every axis with a COB-id was heard from */
    int all_enabled;                            /* and every one is in Operation Enabled */
    int was_enabled;    /* all were enabled, until this frame (a loss is this and !all_enabled) */
    unsigned enabled_n; /* times all_enabled became 1 (the log tells each, even when
                           the loop polls it after it was lost again) */
    unsigned lost_n;    /* ... and became 0 */
    int held;           /* bring-up: a drive left Operation Enabled; it stays disabled
                             * until a CLEAR command asks for a fault reset and re-enable */
    uint8_t nmt[CANPROTO_CIA402_AXES]; /* last heartbeat NMT state (CANPROTO_S2_NMT_NONE: none) */
    unsigned hb_lost;                  /* bit per axis: heartbeat not heard in time (consumer) */
    /* Every axis is in Operation Enabled but not every one takes the engine's
     * targets yet: the engine must stand at anchor_m (the drives' 0x6064 for a
     * drive just enabled, else the target it holds), at rest, before they do
     * (the feedback hook gives it: obj_drive_event). */
    int need_anchor;
    double anchor_m[CANPROTO_CIA402_AXES];
} can_port_drive_t;

/* What the drives need from their port and their object. */
typedef struct {
    /* A frame to the bus: 0, or -errno (not sent). */
    int (*send)(void *ctx, const canproto_frame_t *f);
    /* Something to report in the object's STATUS at once (last_err err). */
    void (*status_event)(void *ctx, uint8_t err);
    /* The drives' report (may be NULL): with d->need_anchor, every drive is
     * enabled again at d->anchor_m (LC_EV_DRIVE_ENABLED); returns 1 if the
     * engine now stands there, at rest (the owner adopted it), else 0. */
    int (*feedback)(void *ctx, const can_port_drive_t *d);
    /* LC_EV_DRIVE_LOST, LC_EV_DRIVE_BOOTUP, LC_EV_HEARTBEAT_LOST (once until a
     * clear), LC_EV_HEARTBEAT_BACK, for the object's owner (may be NULL). */
    void (*drive_event)(void *ctx, lc_event_t ev);
} can_drive_ops_t;

/* The drives' counters (can_port_obj_stats_t carries them out). */
typedef struct {
    uint64_t drive_frames;   /* feedback TPDOs received */
    uint64_t drive_lost;     /* times a drive left Operation Enabled */
    uint64_t drive_bad;      /* feedback TPDOs too short */
    uint64_t sdo_aborts;     /* SDO writes a drive refused */
    uint64_t sdo_timeouts;   /* SDO requests resent after no reply */
    uint64_t sdo_stale;      /* SDO replies not for the request in flight, ignored */
    uint64_t emcy;           /* EMCY frames */
    uint64_t heartbeat_lost; /* a heartbeat not heard within cia402_heartbeat_ms */
    uint32_t last_abort;     /* abort code of the last SDO abort */
    uint16_t last_abort_index;
    uint16_t last_emcy; /* error code of the last EMCY */
} can_drive_stats_t;

typedef struct {
    canproto_ids_t ids; /* the object's (cia402, nodes, COB-ids, list) */
    can_drive_ops_t ops;
    void *ctx;      /* ops' */
    int64_t now_ns; /* of the frames being read (can_drive_rx), or the cycle */
    can_port_drive_t drive;
    /* bring-up (ids.cia402 managed) */
    unsigned nmt_done; /* bit per axis: NMT start sent (since its last boot-up) */
    unsigned sdo_next[CANPROTO_CIA402_AXES]; /* next configuration SDO */
    int sdo_wait[CANPROTO_CIA402_AXES];      /* 1 config SDO, 2 controlword, 3 0x1017 read */
    int64_t sdo_sent_ns[CANPROTO_CIA402_AXES];
    canproto_frame_t sdo_frame[CANPROTO_CIA402_AXES];
    int sdo_failed[CANPROTO_CIA402_AXES]; /* a configuration SDO was aborted */
    int cw_known[CANPROTO_CIA402_AXES];
    uint16_t cw_sent[CANPROTO_CIA402_AXES];
    int reset_req; /* CLEAR: fault reset and re-enable */
    int hb_hold;   /* a drive's heartbeat was lost: feed hold until CLEAR */
    int drv_hold;  /* a drive was lost or booted: the object held until CLEAR */
    int refresh;   /* cleared after a drive hold: every axis re-anchors at its 0x6064 once
                    * the engine's setpoint is at rest */
    int64_t hb_last_ns[CANPROTO_CIA402_AXES];
    int hb_lost[CANPROTO_CIA402_AXES];
    int hb_watch[CANPROTO_CIA402_AXES]; /* its producer time is known > 0: set or read back */
    int hb_armed[CANPROTO_CIA402_AXES]; /* and a heartbeat was heard since */
    int hb_read[CANPROTO_CIA402_AXES];  /* 0x1017 read back (or set by the list) */
    int64_t look_ns;                    /* when the bring-up last looked at the heartbeats */
    /* each axis' target, and the drives' losses (issue 23) */
    can_axis_t ax[CANPROTO_CIA402_AXES];
    int32_t pos_inc[CANPROTO_CIA402_AXES]; /* 0x6064 as last heard, in increments */
    unsigned still[CANPROTO_CIA402_AXES];  /* feedbacks in a row with 0x6064 unchanged (a
                                            * quick-stopped drive is let finish its ramp) */
    int axis_oe[CANPROTO_CIA402_AXES];     /* in Operation Enabled as last heard */
    int axis_held[CANPROTO_CIA402_AXES];   /* left Operation Enabled: disabled until CLEAR */
    int lost;           /* a drive of the object left Operation Enabled: the others brake with the
                   * object (held), then every axis holds until all are re-anchored */
    int eng_rest;       /* the last setpoint was at rest (or had no position) */
    can_axis_log_t chg; /* every state change, until logged */
    can_drive_stats_t st;
} can_drive_t;

/* Before the object is set: every axis unheard, no NMT state. */
void can_drive_init(can_drive_t *d);

/* The object's ids and the port's ops (ctx is theirs). */
void can_drive_setup(can_drive_t *d, const canproto_ids_t *ids, const can_drive_ops_t *ops,
                     void *ctx);

/* A reload's new port: d (set up, can_drive_setup) takes the state old had
 * (the same drives, running: their states, bring-up done, axes following,
 * holds), if both have the same ids; 1 if it did, 0 otherwise. */
int can_drive_adopt(can_drive_t *d, const can_drive_t *old);

/* A frame at now_ns: a feedback TPDO, or (managed) an SDO reply, heartbeat or
 * EMCY of one of the object's nodes: 1 if it was one (handled), else 0. */
int can_drive_rx(can_drive_t *d, const canproto_frame_t *f, int64_t now_ns);

/* A CLEAR command for the object: can_drive_clear_asked before the owner
 * takes it (a held drive gets its fault reset and is enabled again),
 * can_drive_cleared once it did (the holds released; after a drive hold
 * every axis re-anchors at its 0x6064). */
void can_drive_clear_asked(can_drive_t *d);
void can_drive_cleared(can_drive_t *d);

/* One cycle of the bring-up (managed; period_ns: the cycle's, to excuse
 * trajd's own stall from the heartbeat ages, 0 none). */
void can_drive_cycle(can_drive_t *d, int64_t now_ns, int64_t period_ns);

/* The RPDOs of this cycle for setpoint sp into f (room for
 * CANPROTO_CIA402_AXES): how many; *clamped set if a target was clipped. */
unsigned can_drive_rpdos(can_drive_t *d, const engine_setpoint_t *sp, canproto_frame_t *f,
                         int *clamped);

/* The drives in brief (STATUS2 page 4, Modbus): see can_port_drive_summary. */
int can_drive_summary(const can_drive_t *d, canproto_status2_drive_t *out);

/* The oldest state change not yet taken: see can_port_drive_change. */
int can_drive_change(can_drive_t *d, can_axis_change_t *c, uint64_t *dropped);

/* trajd's own heartbeat as CANopen master (node 1..127; 0 none). */
typedef struct {
    uint8_t node;
    int64_t period_ns;
    int64_t sent_ns;
    int any;
} can_drive_master_t;

/* Send it if due (send, ctx: as can_drive_ops_t's). */
void can_drive_master_heartbeat(can_drive_master_t *m, int64_t now_ns,
                                int (*send)(void *ctx, const canproto_frame_t *f), void *ctx);

#endif
