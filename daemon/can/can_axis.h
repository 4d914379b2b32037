/*
 * can_axis.h - one CiA 402 drive axis as trajd commands it (issue 23), pure:
 * which target its RPDO carries this cycle, and the drive's state changes,
 * every one kept until the daemon logs it.  Used by can_port.c.
 *
 * The target of an axis whose drive trajd hears (feedback):
 *   - drive not heard yet: no RPDO;
 *   - drive not in Operation Enabled: its own position actual value 0x6064
 *     (a target that follows the drive, never one it would move to);
 *   - the first target after the drive entered Operation Enabled (or was
 *     found there, a restarted trajd adopting it): its 0x6064 again;
 *   - then the last target sent, held, until the engine's setpoint stands at
 *     rest on it (+-1 count): from then on ("live") the engine's targets;
 *   - a live axis whose object may not move (a drive of the object was lost
 *     and the engine came to rest) holds its last target again, and is live
 *     again only after the same match.
 * Without feedback: the engine's target whenever it has a position.
 */
#ifndef TRAJD_CAN_AXIS_H
#define TRAJD_CAN_AXIS_H

#include <stdint.h>

#include "cia402.h"

typedef struct {
    int live;     /* the engine's targets pass */
    int fresh;    /* the next target in Operation Enabled is the drive's 0x6064 */
    int pending;  /* re-anchored while fresh: live once that target is sent */
    int have_tgt; /* a target was sent */
    int32_t tgt;  /* the last one */
} can_axis_t;

typedef struct {
    int feedback;         /* the drive is heard (cia402 feedback or managed) */
    int seen;             /* heard since trajd started (or since its boot-up) */
    cia402_state_t state; /* as last heard */
    int32_t pos_inc;      /* its 0x6064 as last heard */
    int eng_ok;           /* the engine's setpoint has a position */
    int32_t eng_inc;      /* the engine's target for this axis */
    int eng_rest;         /* the engine's setpoint is at rest */
    int may_move;         /* 0: the object holds (a drive lost, the engine at rest) */
} can_axis_in_t;

/* The target for this cycle: 1 with *out, 0 = send no RPDO. */
int can_axis_target(can_axis_t *x, const can_axis_in_t *in, int32_t *out);

/* The engine was re-anchored at can_axis_anchor (obj_drive_event, LC_EV_DRIVE_ENABLED): its
 * targets pass from the next cycle (after the first target = 0x6064, if
 * that is still to be sent). */
void can_axis_anchored(can_axis_t *x);

/* A clear after a drive hold: the axis re-anchors at its drive's 0x6064 (its
 * next target in Operation Enabled is that, and the engine's pass only after
 * can_axis_anchored), not at the target it held. */
void can_axis_refresh(can_axis_t *x);

/* 1 if the configuration list of ids writes index:sub. */
int can_axis_list_writes(const canproto_ids_t *ids, uint16_t index, uint8_t sub);

/* Where the axis stands for the engine to re-anchor at: the drive's 0x6064
 * if its next target is its first after an enable, else the target held. */
int32_t can_axis_anchor(const can_axis_t *x, int32_t pos_inc);

/* ---- every state change of an object's drives, kept until logged ---- */
#define CAN_AXIS_LOG_MAX 32

typedef struct {
    int64_t t_ns; /* engine time of the frame */
    uint8_t axis;
    uint8_t node;
    uint8_t from, to; /* cia402_state_t; to = CIA402_STATE_UNKNOWN: boot-up */
    uint16_t statusword;
} can_axis_change_t;

typedef struct {
    can_axis_change_t e[CAN_AXIS_LOG_MAX];
    unsigned head, n; /* ring: n kept, the oldest at head */
    uint64_t total;   /* changes seen */
    uint64_t dropped; /* changes lost because the ring was full */
} can_axis_log_t;

void can_axis_log_put(can_axis_log_t *l, const can_axis_change_t *c);
/* The oldest change kept: 1 and removed into *c, 0 if none. */
int can_axis_log_take(can_axis_log_t *l, can_axis_change_t *c);

#endif
