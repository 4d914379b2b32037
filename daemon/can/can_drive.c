/* can_drive.c - one object's CiA 402 drives (see can_drive.h). */
#include "can_drive.h"

#include <math.h>
#include <string.h>

#define CAN_DRIVE_SDO_TIMEOUT_NS 500000000LL /* an SDO request unanswered this long is resent */

static void status_event(can_drive_t *o, uint8_t err)
{
    if (o->ops.status_event)
        o->ops.status_event(o->ctx, err);
}

static void reanchor_at_drives(can_drive_t *o);

/* Axis a of object o changed state (from its TPDO, or to CIA402_STATE_UNKNOWN
 * at its boot-up): the change is kept for the log; leaving Operation Enabled
 * is a loss (returns 1): that drive is disabled until CLEAR (with the
 * bring-up); the caller tells the owner, which holds the object (its other
 * axes brake along the path, then every axis holds). */
static int axis_state(can_drive_t *o, unsigned a, cia402_state_t to, uint16_t sw)
{
    can_port_drive_t *d = &o->drive;
    if (to == d->state[a] && to != CIA402_STATE_UNKNOWN)
        return 0;
    can_axis_change_t c = {
        o->now_ns,   (uint8_t)a, (uint8_t)canproto_cia402_node(&o->ids, a), (uint8_t)d->state[a],
        (uint8_t)to, sw};
    can_axis_log_put(&o->chg, &c);
    cia402_state_t from = d->state[a];
    d->state[a] = to;
    if (to == CIA402_OPERATION_ENABLED) {
        o->axis_oe[a] = 1;
        o->axis_held[a] = 0;
        return 0;
    }
    if (from == CIA402_STATE_UNKNOWN && o->ids.cia402 == CANPROTO_CIA402_MANAGED &&
        (to == CIA402_FAULT || to == CIA402_FAULT_REACTION)) {
        /* found in a fault (a restarted trajd, a reload, a drive that
         * faulted before): resetting it is the operator's decision, as after
         * a fault seen here: held until CLEAR */
        o->st.drive_lost++;
        status_event(o, CANPROTO_STERR_DRIVE);
        o->axis_held[a] = 1;
        o->lost = 1;
        return 1;
    }
    if (!o->axis_oe[a])
        return 0;
    o->axis_oe[a] = 0;
    o->st.drive_lost++;
    status_event(o, CANPROTO_STERR_DRIVE);
    if (o->ids.cia402 == CANPROTO_CIA402_MANAGED)
        o->axis_held[a] = 1; /* re-enabling is the operator's decision: CLEAR */
    o->lost = 1;
    return 1;
}

/* Tell the object's owner (lib/engine/LIFECYCLE.md's drive events). */
static void drive_event(can_drive_t *o, lc_event_t ev)
{
    if (ev == LC_EV_DRIVE_LOST || ev == LC_EV_DRIVE_BOOTUP)
        o->drv_hold = 1;
    if (o->ops.drive_event)
        o->ops.drive_event(o->ctx, ev);
}

/* The summary flags of o's drives, and what the engine must re-anchor at. */
static void drive_summary(can_drive_t *o)
{
    can_port_drive_t *d = &o->drive;
    int before = d->all_enabled;
    d->all_seen = d->all_enabled = 1;
    d->held = 0;
    int live = 1;
    for (unsigned k = 0; k < CANPROTO_CIA402_AXES; k++)
        if (o->ids.cia402_cob_id[k]) {
            d->all_seen &= (d->seen >> k) & 1u;
            d->all_enabled &= d->state[k] == CIA402_OPERATION_ENABLED;
            d->held |= o->axis_held[k];
            live &= o->ax[k].live;
            d->anchor_m[k] = canproto_cia402_pos_m(&o->ids, k,
                                                   can_axis_anchor(&o->ax[k], o->pos_inc[k]));
        }
    d->all_enabled &= d->all_seen;
    if (d->all_enabled && !before)
        d->enabled_n++;
    else if (!d->all_enabled && before)
        d->lost_n++;
    d->need_anchor = d->all_enabled && !live;
    if (d->all_enabled) {
        o->reset_req = 0;
        o->lost = 0;
    }
}

/* What o's drives report to the owner; with need_anchor, the drives enabled
 * again at anchor_m: the axes take the engine's targets once it stands there. */
static void offer_feedback(can_drive_t *o)
{
    can_port_drive_t *d = &o->drive;
    if (o->ops.feedback && o->ops.feedback(o->ctx, d) > 0 && d->need_anchor) {
        for (unsigned k = 0; k < CANPROTO_CIA402_AXES; k++)
            if (o->ids.cia402_cob_id[k])
                can_axis_anchored(&o->ax[k]);
        d->need_anchor = 0;
    }
}

/* A CLEAR after a drive hold, once the engine's setpoint is at rest: every
 * axis re-anchors at its drive's 0x6064 (issue 23), not at a target it held:
 * its next target in Operation Enabled is its 0x6064 again, and the engine is
 * given those positions at the first TPDO with every drive enabled. */
static void reanchor_at_drives(can_drive_t *o)
{
    o->refresh = 0;
    for (unsigned k = 0; k < CANPROTO_CIA402_AXES; k++)
        if (o->ids.cia402_cob_id[k])
            can_axis_refresh(&o->ax[k]);
    drive_summary(o); /* need_anchor: offered at the drives' next TPDO */
}

/* A feedback TPDO of axis a of object o. */
static void drive_feedback(can_drive_t *o, unsigned a, const canproto_frame_t *f)
{
    can_port_drive_t *d = &o->drive;
    uint16_t sw;
    int32_t inc;
    if (cia402_decode_feedback(f, &sw, &inc) < 0) {
        o->st.drive_bad++;
        status_event(o, CANPROTO_STERR_MALFORMED);
        return;
    }
    o->st.drive_frames++;
    d->statusword[a] = sw;
    o->still[a] = inc == o->pos_inc[a] ? o->still[a] + 1 : 0;
    o->pos_inc[a] = inc;
    d->pos_m[a] = canproto_cia402_pos_m(&o->ids, a, inc);
    d->seen |= 1u << a;
    if (axis_state(o, a, cia402_state(sw), sw))
        drive_event(o, LC_EV_DRIVE_LOST);
    drive_summary(o);
    offer_feedback(o);
    d->was_enabled = d->all_enabled;
}

/* A heartbeat or boot-up of axis a's node. */
static void drive_heartbeat(can_drive_t *o, unsigned a, const canproto_frame_t *f)
{
    uint8_t n, st;
    if (cia402_decode_heartbeat(f, &n, &st) < 0)
        return;
    int back = o->hb_lost[a], known = o->drive.state[a] != CIA402_STATE_UNKNOWN;
    o->hb_last_ns[a] = o->now_ns;
    o->hb_lost[a] = 0;
    o->hb_armed[a] = o->hb_watch[a] && st != CIA402_HB_BOOTUP;
    o->drive.nmt[a] = st;
    o->drive.hb_lost &= ~(1u << a);
    if (st == CIA402_HB_BOOTUP) {
        /* this drive (re)booted: it alone is brought up again from NMT
         * on; it is no longer enabled (a loss if it was), and is not
         * heard until its next TPDO */
        o->nmt_done &= ~(1u << a);
        o->sdo_next[a] = 0;
        o->sdo_wait[a] = 0;
        o->cw_known[a] = 0;
        o->sdo_failed[a] = 0;
        o->hb_read[a] = o->hb_watch[a] = 0;
        (void)axis_state(o, a, CIA402_STATE_UNKNOWN, 0);
        o->drive.seen &= ~(1u << a);
        drive_summary(o);
        if (known) /* a drive trajd commanded lost its state */
            drive_event(o, LC_EV_DRIVE_BOOTUP);
    }
    if (back)
        drive_event(o, LC_EV_HEARTBEAT_BACK);
}

/* Frames of the bring-up: SDO replies, heartbeats, EMCY of o's nodes; 1 if taken. */
static int drive_frame(can_drive_t *o, const canproto_frame_t *f)
{
    if (o->ids.cia402 != CANPROTO_CIA402_MANAGED)
        return 0;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        unsigned node = canproto_cia402_node(&o->ids, a);
        if (!node)
            continue;
        if (f->id == 0x580u + node) {
            cia402_sdo_reply_t r;
            if (cia402_decode_sdo_reply((uint8_t)node, f, &r) < 0 || !o->sdo_wait[a] ||
                r.index != (uint16_t)(o->sdo_frame[a].data[1] | o->sdo_frame[a].data[2] << 8) ||
                r.sub != o->sdo_frame[a].data[3]) {
                /* not the answer to the request in flight (e.g. a late answer to one
                 * that was resent and answered already): ignored */
                o->st.sdo_stale++;
                return 1;
            }
            if (r.index == 0x1017 && r.sub == 0) { /* the producer time, set or read back */
                uint32_t v = o->sdo_wait[a] == 3 ? r.value
                                                 : (uint32_t)(o->sdo_frame[a].data[4] |
                                                              o->sdo_frame[a].data[5] << 8);
                o->hb_read[a] = 1;
                o->hb_watch[a] = r.kind != CIA402_SDO_ABORT && v > 0;
            }
            if (r.kind == CIA402_SDO_ABORT && o->sdo_wait[a] == 3) {
                o->sdo_wait[a] = 0; /* no 0x1017 to read: no heartbeat to watch */
                return 1;
            }
            if (r.kind == CIA402_SDO_ABORT) {
                o->st.sdo_aborts++;
                o->st.last_abort = r.abort_code;
                o->st.last_abort_index = r.index;
                status_event(o, CANPROTO_STERR_DRIVE);
                if (o->sdo_wait[a] == 1)
                    o->sdo_failed[a] = 1; /* not configured as asked: never enabled */
            }
            if (o->sdo_wait[a] == 1)
                o->sdo_next[a]++;
            o->sdo_wait[a] = 0;
            return 1;
        }
        if (f->id == 0x700u + node) {
            drive_heartbeat(o, a, f);
            return 1;
        }
        if (f->id == 0x080u + node) {
            uint8_t n, reg;
            uint16_t code;
            if (cia402_decode_emcy(f, &n, &code, &reg) == 0) {
                o->st.emcy++;
                o->st.last_emcy = code;
                if (code)
                    status_event(o, CANPROTO_STERR_DRIVE);
            }
            return 1;
        }
    }
    return 0;
}

/* Feedbacks in a row with 0x6064 unchanged that tell a quick-stopped drive
 * at rest. */
#define CAN_DRIVE_STILL_FEEDBACKS 3

/* The controlword axis a's drive needs now (bring-up). */
static uint16_t wanted_cw(const can_drive_t *o, unsigned a)
{
    cia402_state_t st = o->drive.state[a];
    /* a drive in quick stop brakes by its own ramp: kept in it (Quick stop)
     * until its 0x6064 stands still, then Disable voltage (transition 12);
     * Disable voltage at once cut its ramp and the axis coasted, 0.05-0.09 m */
    if (st == CIA402_QUICK_STOP_ACTIVE && o->still[a] < CAN_DRIVE_STILL_FEEDBACKS)
        return CIA402_CW_QUICK_STOP;
    if (o->sdo_failed[a] || o->sdo_next[a] < o->ids.cia402_nsdo ||
        (o->axis_held[a] && !o->reset_req))
        return CIA402_CW_DISABLE_VOLTAGE;
    if (st == CIA402_FAULT)
        /* fault reset acts on the rising edge of bit 7: 0x0000 first, then 0x0080 */
        return o->cw_known[a] && o->cw_sent[a] == CIA402_CW_DISABLE_VOLTAGE
                   ? CIA402_CW_FAULT_RESET
                   : CIA402_CW_DISABLE_VOLTAGE;
    return cia402_controlword_towards_enabled(st, 0);
}

/* Axis a's heartbeat (consumer, cia402_heartbeat_ms): watched only once its
 * producer time is known to be set (0x1017 written by the list or read back
 * > 0) and a heartbeat was heard since; a loss holds the object. */
static void watch_heartbeat(can_drive_t *o, unsigned a, int64_t now_ns)
{
    if (!o->ids.cia402_heartbeat_ms || !o->hb_armed[a] || o->hb_lost[a] ||
        now_ns - o->hb_last_ns[a] <= (int64_t)o->ids.cia402_heartbeat_ms * 1000000)
        return;
    o->hb_lost[a] = 1;
    o->drive.hb_lost |= 1u << a;
    o->st.heartbeat_lost++;
    status_event(o, CANPROTO_STERR_DRIVE);
    if (!o->hb_hold) {
        /* a drive that went silent may not follow: feed hold (override
         * 0), a controlled stop along the path by the time scaling,
         * every axis together; held until a CLEAR command */
        o->hb_hold = 1;
        drive_event(o, LC_EV_HEARTBEAT_LOST);
    }
}

/* The next SDO request of axis a (into o->sdo_frame[a]): 1 configuration, 2
 * controlword, 3 read of 0x1017; 0 none now. */
static int next_sdo(can_drive_t *o, unsigned a, uint8_t node)
{
    if (o->sdo_next[a] < o->ids.cia402_nsdo) {
        unsigned k = o->sdo_next[a];
        cia402_encode_sdo_download(node, o->ids.cia402_sdo[k].index, o->ids.cia402_sdo[k].sub,
                                   o->ids.cia402_sdo[k].value, o->ids.cia402_sdo[k].size,
                                   &o->sdo_frame[a]);
        return 1;
    }
    if (o->ids.cia402_heartbeat_ms && !o->hb_read[a] && !can_axis_list_writes(&o->ids, 0x1017, 0)) {
        o->hb_read[a] = 1; /* once per bring-up: is there a heartbeat to watch? */
        cia402_encode_sdo_upload(node, 0x1017, 0, &o->sdo_frame[a]);
        return 3;
    }
    if (!(o->drive.seen & (1u << a)))
        return 0; /* no statusword yet: nothing to decide */
    uint16_t cw = wanted_cw(o, a);
    if (o->cw_known[a] && cw == o->cw_sent[a])
        return 0;
    cia402_encode_sdo_download(node, CIA402_OBJ_CONTROLWORD, 0, cw, 2, &o->sdo_frame[a]);
    o->cw_sent[a] = cw;
    o->cw_known[a] = 1;
    return 2;
}

/* One step of object o's bring-up: NMT start (per node, again after its
 * boot-up), configuration SDOs, controlword. */
static void bring_up(can_drive_t *o, int64_t now_ns, int64_t period_ns)
{
    canproto_frame_t f;
    o->now_ns = now_ns;
    /* trajd's own stall is not a drive's silence: the time the loop could not
     * look is excused (heartbeats queued meanwhile are read with later stamps) */
    int64_t gap = o->look_ns ? now_ns - o->look_ns : 0;
    if (period_ns > 0 && gap > 2 * period_ns)
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
            o->hb_last_ns[a] += gap - period_ns;
    o->look_ns = now_ns;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        uint8_t node = (uint8_t)canproto_cia402_node(&o->ids, a);
        if (!node)
            continue;
        if (!(o->nmt_done & (1u << a))) {
            cia402_encode_nmt(CIA402_NMT_START, node, &f);
            if (o->ops.send(o->ctx, &f) < 0)
                continue; /* try again next cycle */
            o->nmt_done |= 1u << a;
            o->hb_last_ns[a] = now_ns;
        }
        watch_heartbeat(o, a, now_ns);
        if (o->sdo_wait[a]) {
            if (now_ns - o->sdo_sent_ns[a] < CAN_DRIVE_SDO_TIMEOUT_NS)
                continue;
            o->st.sdo_timeouts++;
            if (o->ops.send(o->ctx, &o->sdo_frame[a]) == 0)
                o->sdo_sent_ns[a] = now_ns;
            continue;
        }
        int kind = next_sdo(o, a, node);
        if (!kind)
            continue;
        if (o->ops.send(o->ctx, &o->sdo_frame[a]) == 0) {
            o->sdo_wait[a] = kind;
            o->sdo_sent_ns[a] = now_ns;
        } else if (kind == 2) {
            o->cw_known[a] = 0; /* not sent: decide again next cycle */
        } else if (kind == 3) {
            o->hb_read[a] = 0;
        }
    }
}

/* The controlword of axis a's RPDO: with the bring-up, the command it last
 * wrote (Disable voltage before any), so that the RPDO never enables a drive
 * the bring-up does not (a quick-stopped drive would take Enable operation as
 * transition 16); without it, the configured value. */
static uint16_t rpdo_cw(const can_drive_t *o, unsigned a)
{
    if (o->ids.cia402 != CANPROTO_CIA402_MANAGED)
        return o->ids.cia402_controlword_value;
    /* before it wrote any (a drive found running by a restarted trajd): the
     * one that keeps the drive where it is, never Disable voltage to a
     * drive in Operation Enabled */
    return o->cw_known[a] ? o->cw_sent[a] : cia402_controlword_hold(o->drive.state[a]);
}

/* Axis a's target this cycle (can_axis.h): 1 with *inc, 0 = no RPDO. */
static int axis_target(can_drive_t *o, const engine_setpoint_t *sp, unsigned a, int32_t *inc,
                       int *clamped)
{
    int eng_ok = !(sp->flags & ENGINE_SP_NO_POSITION);
    can_axis_in_t in = {o->ids.cia402 >= CANPROTO_CIA402_FEEDBACK,
                        (o->drive.seen >> a) & 1u,
                        o->drive.state[a],
                        o->pos_inc[a],
                        eng_ok,
                        eng_ok ? canproto_cia402_counts(&o->ids, a, sp->pos_m[a], clamped) : 0,
                        o->eng_rest,
                        !(o->lost && o->eng_rest)};
    return can_axis_target(&o->ax[a], &in, inc);
}

void can_drive_init(can_drive_t *d)
{
    memset(d, 0, sizeof *d);
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        d->drive.state[a] = CIA402_STATE_UNKNOWN;
        d->drive.nmt[a] = CANPROTO_S2_NMT_NONE;
    }
}

void can_drive_setup(can_drive_t *d, const canproto_ids_t *ids, const can_drive_ops_t *ops,
                     void *ctx)
{
    d->ids = *ids;
    d->ops = *ops;
    d->ctx = ctx;
}

int can_drive_adopt(can_drive_t *d, const can_drive_t *old)
{
    if (memcmp(&d->ids, &old->ids, sizeof d->ids) != 0)
        return 0;
    can_drive_ops_t ops = d->ops;
    void *ctx = d->ctx;
    *d = *old;
    d->ops = ops;
    d->ctx = ctx;
    return 1;
}

int can_drive_rx(can_drive_t *o, const canproto_frame_t *f, int64_t now_ns)
{
    o->now_ns = now_ns; /* stamps of heartbeats and state changes */
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (f->id == canproto_cia402_tpdo(&o->ids, a)) {
            drive_feedback(o, a, f);
            return 1;
        }
    return drive_frame(o, f);
}

void can_drive_clear_asked(can_drive_t *o)
{
    if (o->ids.cia402 == CANPROTO_CIA402_MANAGED && o->drive.held)
        o->reset_req = 1; /* fault reset, then the drives are enabled again */
}

void can_drive_cleared(can_drive_t *o)
{
    o->hb_hold = 0; /* the clear released the object's hold: a new loss holds again */
    if (o->drv_hold)
        o->refresh = 1; /* at rest (can_drive_rpdos): a moving axis keeps following */
    o->drv_hold = 0;
}

void can_drive_cycle(can_drive_t *o, int64_t now_ns, int64_t period_ns)
{
    if (o->ids.cia402 == CANPROTO_CIA402_MANAGED)
        bring_up(o, now_ns, period_ns);
}

unsigned can_drive_rpdos(can_drive_t *o, const engine_setpoint_t *sp, canproto_frame_t *f,
                         int *clamped)
{
    unsigned n = 0;
    /* each drive its own target (can_axis.h): none before a position or
     * before the drive is heard; a drive not in Operation Enabled its own
     * 0x6064; the first after an enable its 0x6064 */
    o->eng_rest = 1;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        if (!(sp->flags & ENGINE_SP_NO_POSITION) && fabs(sp->vel_m_s[a]) > 1e-9)
            o->eng_rest = 0;
    if (o->refresh && o->eng_rest)
        reanchor_at_drives(o);
    if (!o->ids.cia402)
        return 0;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        int32_t inc;
        if (o->ids.cia402_cob_id[a] && axis_target(o, sp, a, &inc, clamped))
            cia402_encode_rpdo(o->ids.cia402_cob_id[a], o->ids.cia402_controlword, rpdo_cw(o, a),
                               inc, &f[n++]);
    }
    return n;
}

int can_drive_summary(const can_drive_t *o, canproto_status2_drive_t *out)
{
    memset(out, 0, sizeof *out);
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        out->state[a] = CANPROTO_S2_NO_DRIVE;
    out->nmt = CANPROTO_S2_NMT_NONE;
    if (o->ids.cia402 < CANPROTO_CIA402_FEEDBACK)
        return 0;
    int pick = -1;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        if (!o->ids.cia402_cob_id[a])
            continue;
        out->state[a] = (uint8_t)o->drive.state[a];
        if (pick < 0 || (o->drive.state[pick] == CIA402_OPERATION_ENABLED &&
                         o->drive.state[a] != CIA402_OPERATION_ENABLED))
            pick = (int)a;
    }
    if (pick >= 0) {
        out->statusword = o->drive.statusword[pick];
        out->nmt = o->drive.nmt[pick];
    }
    out->held = o->drive.held;
    out->hb_lost = o->drive.hb_lost != 0;
    out->emcy = o->st.last_emcy;
    return 1;
}

int can_drive_change(can_drive_t *o, can_axis_change_t *c, uint64_t *dropped)
{
    if (dropped) {
        *dropped = o->chg.dropped;
        o->chg.dropped = 0;
    }
    return can_axis_log_take(&o->chg, c);
}

/* trajd's own heartbeat as CANopen master: the drives' consumers (0x1016) see
 * trajd alive, and stop by themselves when it is not. */
void can_drive_master_heartbeat(can_drive_master_t *m, int64_t now_ns,
                                int (*send)(void *ctx, const canproto_frame_t *f), void *ctx)
{
    if (!m->node || (m->any && now_ns - m->sent_ns < m->period_ns))
        return;
    canproto_frame_t f;
    cia402_encode_heartbeat(m->node, &f);
    if (send(ctx, &f) == 0) {
        m->any = 1;
        m->sent_ns = now_ns;
    }
}
