/* can_port.c - the CAN side of trajd (see can_port.h). */
#include "can_port.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "can_axis.h"

#define CAN_PORT_RX_BATCH 256 /* frames handled per can_port_rx call: do not starve the loop */

typedef struct {
    int set;
    canproto_ids_t ids;
    can_port_hooks_t hooks;
    void *ctx;
    canproto_slot_t slots[CAN_PORT_RX_SLOTS];
    canproto_rx_t rx;
    engine_setpoint_t sp;
    int have_sp;
    int status_due;
    int64_t last_status_ns;
    int sent_status;
    uint8_t flags_since;    /* CANPROTO_ST_BUS_DOWN | _TX_DROP | _OUT_FAULT since last STATUS */
    uint64_t out_lost_seen; /* can_port_output_fault: lines lost as of the last call */
    int out_fault_seen;
    uint8_t last_err;
    int last_state; /* engine state in the last STATUS (-1: none yet) */
    can_port_drive_t drive;
    /* bring-up (ids.cia402 managed) */
    unsigned nmt_done; /* bit per axis: NMT start sent (since its last boot-up) */
    unsigned sdo_next[CANPROTO_CIA402_AXES]; /* next configuration SDO */
    int sdo_wait[CANPROTO_CIA402_AXES];      /* 1 config SDO, 2 controlword, in flight */
    int64_t sdo_sent_ns[CANPROTO_CIA402_AXES];
    canproto_frame_t sdo_frame[CANPROTO_CIA402_AXES];
    int sdo_failed[CANPROTO_CIA402_AXES]; /* a configuration SDO was aborted */
    int cw_known[CANPROTO_CIA402_AXES];
    uint16_t cw_sent[CANPROTO_CIA402_AXES];
    int reset_req; /* CLEAR: fault reset and re-enable */
    int hb_hold;   /* a drive's heartbeat was lost: feed hold until CLEAR */
    int drv_hold;  /* a drive was lost or booted: the object held until CLEAR */
    int64_t hb_last_ns[CANPROTO_CIA402_AXES];
    int hb_lost[CANPROTO_CIA402_AXES];
    int hb_watch[CANPROTO_CIA402_AXES]; /* its producer time is known > 0: set or read back */
    int hb_armed[CANPROTO_CIA402_AXES]; /* and a heartbeat was heard since */
    int hb_read[CANPROTO_CIA402_AXES];  /* 0x1017 read back (or set by the list) */
    int64_t look_ns;                    /* when the bring-up last looked at the heartbeats */
    /* issue 23: each axis' target, and the drives' losses */
    can_axis_t ax[CANPROTO_CIA402_AXES];
    int32_t pos_inc[CANPROTO_CIA402_AXES]; /* 0x6064 as last heard, in increments */
    int axis_oe[CANPROTO_CIA402_AXES];     /* in Operation Enabled as last heard */
    int axis_held[CANPROTO_CIA402_AXES];   /* left Operation Enabled: disabled until CLEAR */
    int lost;           /* a drive of the object left Operation Enabled: the others brake with
                       * the object (hold), then every axis holds until all are re-anchored */
    int eng_rest;       /* the last setpoint was at rest (or had no position) */
    can_axis_log_t chg; /* every state change, until logged */
    int64_t now_ns;
    uint32_t cmd_allow;                       /* can_port_allow_commands */
    canproto_frame_t st2[CANPROTO_ST2_PAGES]; /* STATUS2 pages as last given */
    uint32_t st2_have;                        /* bit per page given */
    uint32_t st2_changed;                     /* bit per page changed since last sent */
    unsigned st2_next;                        /* round robin: the page after the last sent */
    can_port_obj_stats_t st;
} can_port_obj_t;

struct can_port {
    can_port_config_t cfg;
    can_port_io_t io;
    void *io_ctx;
    unsigned nobj;
    can_port_obj_t *obj;
    canproto_ids_t *ids; /* copy of each object's ids, contiguous (bus load) */
    uint8_t sync_counter;
    can_port_stats_t st;
    canerr_bus_t err;   /* bus state and counters from error frames */
    int64_t hb_sent_ns; /* trajd's own heartbeat (cfg.hb_node), last sent */
    int hb_any;
};

void can_port_config_default(can_port_config_t *c)
{
    memset(c, 0, sizeof *c);
    c->sync = 0;
    c->sync_id = CANPROTO_ID_SYNC_DEFAULT;
    c->sync_overflow = 0;
    c->status_period_ns = 100000000LL;
    c->max_late_ns = 0;
    c->hb_period_ns = 100000000LL;
}

can_port_t *can_port_new(const can_port_config_t *cfg, const can_port_io_t *io, void *io_ctx,
                         unsigned nobj)
{
    if (!cfg || !io || !io->send || !io->recv || !io->is_up || nobj == 0 ||
        cfg->sync_id > CANPROTO_SFF_MASK || cfg->sync_overflow == 1 || cfg->sync_overflow > 240 ||
        cfg->hb_node > CIA402_NODE_MAX)
        return NULL;
    can_port_t *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    canerr_bus_init(&p->err);
    p->obj = calloc(nobj, sizeof *p->obj);
    p->ids = calloc(nobj, sizeof *p->ids);
    if (!p->obj || !p->ids) {
        can_port_free(p);
        return NULL;
    }
    p->cfg = *cfg;
    p->io = *io;
    p->io_ctx = io_ctx;
    p->nobj = nobj;
    for (unsigned i = 0; i < nobj; i++) {
        canproto_rx_init(&p->obj[i].rx, p->obj[i].slots, CAN_PORT_RX_SLOTS);
        p->obj[i].last_state = -1;
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
            p->obj[i].drive.state[a] = CIA402_STATE_UNKNOWN;
            p->obj[i].drive.nmt[a] = CANPROTO_S2_NMT_NONE;
        }
    }
    return p;
}

void can_port_free(can_port_t *p)
{
    if (!p)
        return;
    free(p->obj);
    free(p->ids);
    free(p);
}

int can_port_set_object(can_port_t *p, unsigned i, const canproto_ids_t *ids,
                        const can_port_hooks_t *hooks, void *ctx)
{
    uint32_t mine[CANPROTO_IDS_MAX], other[CANPROTO_IDS_MAX];
    if (i >= p->nobj || !hooks || !hooks->push || !hooks->status)
        return -CANPROTO_EID;
    if (canproto_ids_check(ids, NULL) < 0)
        return -CANPROTO_ECONFIG;
    unsigned n = canproto_ids_in_use(ids, mine);
    for (unsigned k = 0; k < n; k++)
        if (p->cfg.sync && mine[k] == p->cfg.sync_id)
            return -CANPROTO_ECONFIG;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) /* trajd's heartbeat is not a drive's */
        if (p->cfg.hb_node && canproto_cia402_node(ids, a) == p->cfg.hb_node)
            return -CANPROTO_ECONFIG;
    for (unsigned j = 0; j < p->nobj; j++) {
        if (j == i || !p->obj[j].set)
            continue;
        unsigned m = canproto_ids_in_use(&p->obj[j].ids, other);
        for (unsigned k = 0; k < n; k++)
            for (unsigned l = 0; l < m; l++)
                if (mine[k] == other[l])
                    return -CANPROTO_ECONFIG;
    }
    can_port_obj_t *o = &p->obj[i];
    o->set = 1;
    o->cmd_allow = CAN_PORT_CMD_ALL;
    o->ids = *ids;
    o->hooks = *hooks;
    o->ctx = ctx;
    p->ids[i] = *ids;
    return 0;
}

unsigned can_port_rx_ids(const can_port_t *p, uint32_t *out, unsigned max)
{
    unsigned n = 0;
    for (unsigned i = 0; i < p->nobj; i++) {
        uint32_t ids[24];
        if (!p->obj[i].set)
            continue;
        unsigned k = canproto_ids_rx(&p->obj[i].ids, ids, 24);
        for (unsigned j = 0; j < k; j++, n++)
            if (n < max)
                out[n] = ids[j];
    }
    return n;
}

static void event(can_port_obj_t *o, uint8_t err)
{
    o->last_err = err;
    o->status_due = 1;
}

static void handle_waypoint(can_port_obj_t *o, canproto_rx_out_t *out)
{
    int rc = o->hooks.push(o->ctx, &out->wp);
    if (rc == -ENGINE_EFULL) {
        /* not consumed: the sender sees last_seq stay and repeats it */
        o->st.waypoints_full++;
        event(o, ENGINE_EFULL);
        return;
    }
    canproto_rx_consume(&o->rx, out);
    if (out->lost_before)
        event(o, CANPROTO_STERR_LOST);
    if (rc == 0) {
        o->st.waypoints_accepted++;
    } else if (rc == ENGINE_DUPLICATE) {
        o->st.engine_duplicates++;
    } else {
        o->st.waypoints_rejected++;
        event(o, (uint8_t)(rc < 0 ? -rc : rc));
    }
}

void can_port_output_fault(can_port_t *p, unsigned i, uint64_t lost, int fault)
{
    if (i >= p->nobj)
        return;
    can_port_obj_t *o = &p->obj[i];
    if (lost > o->out_lost_seen || (fault && !o->out_fault_seen)) {
        o->flags_since |= CANPROTO_ST_OUT_FAULT;
        event(o, CANPROTO_STERR_OUTPUT);
    }
    o->out_lost_seen = lost;
    o->out_fault_seen = fault;
}

void can_port_allow_commands(can_port_t *p, unsigned i, uint32_t mask)
{
    if (i < p->nobj)
        p->obj[i].cmd_allow = mask;
}

static void status2_put(can_port_t *p, unsigned i, const canproto_frame_t *f, int value)
{
    unsigned page = f->data[0];
    if (i >= p->nobj || page == 0 || page >= CANPROTO_ST2_PAGES)
        return;
    can_port_obj_t *o = &p->obj[i];
    canproto_frame_t *k = &o->st2[page];
    if (!(o->st2_have & (1u << page)) ||
        (!value && (k->len != f->len || memcmp(k->data, f->data, f->len))))
        o->st2_changed |= 1u << page;
    *k = *f;
    k->id = o->ids.status2_id;
    o->st2_have |= 1u << page;
}

void can_port_status2(can_port_t *p, unsigned i, const canproto_frame_t *f)
{
    status2_put(p, i, f, 0);
}

void can_port_status2_value(can_port_t *p, unsigned i, const canproto_frame_t *f)
{
    status2_put(p, i, f, 1);
}

static void refuse_command(can_port_obj_t *o, canproto_cmd_t cmd, uint32_t id, int err)
{
    o->st.cmd_refused++;
    o->st.last_refused = (uint8_t)cmd;
    o->st.last_refused_id = id;
    o->st.last_refused_err = err;
    event(o, CANPROTO_STERR_REFUSED);
}

static void reanchor_at_drives(can_port_obj_t *o);

static void handle_command(can_port_obj_t *o, canproto_cmd_t cmd, unsigned arg, uint32_t id)
{
    int err;

    if (!((o->cmd_allow >> cmd) & 1u)) {
        refuse_command(o, cmd, id, 0);
        return;
    }
    if (cmd == CANPROTO_CMD_CLEAR && o->ids.cia402 == CANPROTO_CIA402_MANAGED && o->drive.held)
        o->reset_req = 1; /* fault reset, then the drives are enabled again */
    if (o->hooks.command && (err = o->hooks.command(o->ctx, cmd, arg)) < 0) {
        refuse_command(o, cmd, id, err); /* e.g. an override while held (obj_set_override) */
        return;
    }
    if (cmd == CANPROTO_CMD_CLEAR) {
        o->hb_hold = 0; /* the clear released the object's hold: a new loss holds again */
        if (o->drv_hold)
            reanchor_at_drives(o);
        canproto_rx_restart(&o->rx);
    }
    if (cmd == CANPROTO_CMD_RESET_COUNTERS) {
        memset(&o->st, 0, sizeof o->st);
        memset(&o->rx.st, 0, sizeof o->rx.st);
        o->last_err = CANPROTO_STERR_OK;
    }
    o->status_due = 1;
}

/* Axis a of object o changed state (from its TPDO, or to CIA402_STATE_UNKNOWN
 * at its boot-up): the change is kept for the log; leaving Operation Enabled
 * is a loss (returns 1): that drive is disabled until CLEAR (with the
 * bring-up); the caller tells the owner, which holds the object (its other
 * axes brake along the path, then every axis holds). */
static int axis_state(can_port_obj_t *o, unsigned a, cia402_state_t to, uint16_t sw)
{
    can_port_drive_t *d = &o->drive;
    if (to == d->state[a] && to != CIA402_STATE_UNKNOWN)
        return 0;
    can_axis_change_t c = {
        o->now_ns,   (uint8_t)a, (uint8_t)canproto_cia402_node(&o->ids, a), (uint8_t)d->state[a],
        (uint8_t)to, sw};
    can_axis_log_put(&o->chg, &c);
    d->state[a] = to;
    if (to == CIA402_OPERATION_ENABLED) {
        o->axis_oe[a] = 1;
        o->axis_held[a] = 0;
        return 0;
    }
    if (!o->axis_oe[a])
        return 0;
    o->axis_oe[a] = 0;
    o->st.drive_lost++;
    event(o, CANPROTO_STERR_DRIVE);
    if (o->ids.cia402 == CANPROTO_CIA402_MANAGED)
        o->axis_held[a] = 1; /* re-enabling is the operator's decision: CLEAR */
    o->lost = 1;
    return 1;
}

/* Tell the object's owner (lib/engine/LIFECYCLE.md's drive events). */
static void drive_event(can_port_obj_t *o, lc_event_t ev)
{
    if (ev == LC_EV_DRIVE_LOST || ev == LC_EV_DRIVE_BOOTUP)
        o->drv_hold = 1;
    if (o->hooks.drive_event)
        o->hooks.drive_event(o->ctx, ev);
}

/* The summary flags of o's drives, and what the engine must re-anchor at. */
static void drive_summary(can_port_obj_t *o)
{
    can_port_drive_t *d = &o->drive;
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
    d->need_anchor = d->all_enabled && !live;
    if (d->all_enabled) {
        o->reset_req = 0;
        o->lost = 0;
    }
}

/* What o's drives report to the owner; with need_anchor, the drives enabled
 * again at anchor_m: the axes take the engine's targets once it stands there. */
static void offer_feedback(can_port_obj_t *o)
{
    can_port_drive_t *d = &o->drive;
    if (o->hooks.feedback && o->hooks.feedback(o->ctx, d) > 0 && d->need_anchor) {
        for (unsigned k = 0; k < CANPROTO_CIA402_AXES; k++)
            if (o->ids.cia402_cob_id[k])
                can_axis_anchored(&o->ax[k]);
        d->need_anchor = 0;
    }
}

/* A CLEAR after a drive hold: every axis re-anchors at its drive's 0x6064
 * (issue 23), not at a target it held: its next target in Operation Enabled
 * is its 0x6064 again, and the engine is given those positions as soon as
 * every drive is enabled (now, if they are). */
static void reanchor_at_drives(can_port_obj_t *o)
{
    o->drv_hold = 0;
    for (unsigned k = 0; k < CANPROTO_CIA402_AXES; k++)
        if (o->ids.cia402_cob_id[k])
            can_axis_refresh(&o->ax[k]);
    drive_summary(o);
    if (o->drive.need_anchor)
        offer_feedback(o);
}

/* A feedback TPDO of axis a of object o. */
static void drive_feedback(can_port_obj_t *o, unsigned a, const canproto_frame_t *f)
{
    can_port_drive_t *d = &o->drive;
    uint16_t sw;
    int32_t inc;
    if (cia402_decode_feedback(f, &sw, &inc) < 0) {
        o->st.drive_bad++;
        event(o, CANPROTO_STERR_MALFORMED);
        return;
    }
    o->st.drive_frames++;
    d->statusword[a] = sw;
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
static void drive_heartbeat(can_port_obj_t *o, unsigned a, const canproto_frame_t *f)
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
static int drive_frame(can_port_obj_t *o, const canproto_frame_t *f)
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
                event(o, CANPROTO_STERR_DRIVE);
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
                    event(o, CANPROTO_STERR_DRIVE);
            }
            return 1;
        }
    }
    return 0;
}

static void dispatch(can_port_t *p, const canproto_frame_t *f)
{
    if (f->flags & CANPROTO_F_ERR) {
        canerr_bus_frame(&p->err, f->id, f->data, f->len);
        return;
    }
    if (!(f->flags & CANPROTO_F_EFF)) {
        for (unsigned i = 0; i < p->nobj; i++) {
            can_port_obj_t *o = &p->obj[i];
            int is_fd;
            if (!o->set)
                continue;
            for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
                if (f->id == canproto_cia402_tpdo(&o->ids, a)) {
                    drive_feedback(o, a, f);
                    return;
                }
            if (drive_frame(o, f))
                return;
            if (f->id == o->ids.waypoint_id)
                is_fd = 0;
            else if (o->ids.fd && f->id == o->ids.waypoint_fd_id)
                is_fd = 1;
            else
                continue;
            canproto_rx_out_t out;
            uint64_t ooo = o->rx.st.out_of_order;
            int rc = canproto_rx_frame(&o->rx, f, is_fd, &out);
            if (rc < 0)
                event(o, CANPROTO_STERR_MALFORMED);
            else if (rc == CANPROTO_RX_WAYPOINT)
                handle_waypoint(o, &out);
            else if (rc == CANPROTO_RX_COMMAND)
                handle_command(o, out.cmd, out.cmd_arg, f->id);
            if (o->rx.st.out_of_order != ooo)
                event(o, CANPROTO_STERR_OUT_OF_ORDER);
            return;
        }
    }
    p->st.rx_foreign++;
}

int can_port_rx(can_port_t *p, int64_t now_ns)
{
    canproto_frame_t f;
    int n = 0;
    for (unsigned i = 0; i < p->nobj; i++)
        p->obj[i].now_ns = now_ns; /* stamps of heartbeats and state changes */
    while (n < CAN_PORT_RX_BATCH) {
        int rc = p->io.recv(p->io_ctx, now_ns, &f);
        if (rc == 0)
            break;
        if (rc < 0) {
            p->st.rx_errors++;
            return n ? n : rc;
        }
        p->st.rx_frames++;
        dispatch(p, &f);
        n++;
    }
    return n;
}

void can_port_setpoint(can_port_t *p, unsigned i, const engine_setpoint_t *sp)
{
    if (i >= p->nobj)
        return;
    if ((sp->flags & ENGINE_SP_FAULT) && !(p->obj[i].sp.flags & ENGINE_SP_FAULT))
        event(&p->obj[i], CANPROTO_STERR_SAFETY); /* reported at once */
    p->obj[i].sp = *sp;
    p->obj[i].have_sp = 1;
}

static int is_full(int rc)
{
    return rc == -ENOBUFS || rc == -EAGAIN;
}

/* The controlword of axis a's RPDO: with the bring-up, the command it last
 * wrote (Disable voltage before any), so that the RPDO never enables a drive
 * the bring-up does not (a quick-stopped drive would take Enable operation as
 * transition 16); without it, the configured value. */
static uint16_t rpdo_cw(const can_port_obj_t *o, unsigned a)
{
    if (o->ids.cia402 != CANPROTO_CIA402_MANAGED)
        return o->ids.cia402_controlword_value;
    /* before it wrote any (a drive found running by a restarted trajd): the
     * one that keeps the drive where it is, never Disable voltage to a
     * drive in Operation Enabled */
    return o->cw_known[a] ? o->cw_sent[a] : cia402_controlword_hold(o->drive.state[a]);
}

/* Axis a's target this cycle (can_axis.h): 1 with *inc, 0 = no RPDO. */
static int axis_target(can_port_obj_t *o, unsigned a, int32_t *inc, int *clamped)
{
    int eng_ok = !(o->sp.flags & ENGINE_SP_NO_POSITION);
    can_axis_in_t in = {o->ids.cia402 >= CANPROTO_CIA402_FEEDBACK,
                        (o->drive.seen >> a) & 1u,
                        o->drive.state[a],
                        o->pos_inc[a],
                        eng_ok,
                        eng_ok ? canproto_cia402_counts(&o->ids, a, o->sp.pos_m[a], clamped) : 0,
                        o->eng_rest,
                        !(o->lost && o->eng_rest)};
    return can_axis_target(&o->ax[a], &in, inc);
}

/* Send object o's frames for this cycle (own frames only if own); 0 or the
 * first failure. */
static int send_setpoint(can_port_t *p, can_port_obj_t *o, int own)
{
    canproto_frame_t f[ENGINE_AXES + CANPROTO_CIA402_AXES];
    unsigned n = 0;
    int clamped = 0, rc;

    if (o->ids.own && own) {
        if (o->ids.fd)
            rc = canproto_encode_setpoint_fd(o->ids.setpoint_fd_id, o->ids.brs, &o->sp, &f[n++]);
        else {
            rc = canproto_encode_setpoint(o->ids.setpoint_id, &o->sp, &f[n]);
            n += ENGINE_AXES;
        }
        clamped |= rc == CANPROTO_CLAMPED;
    }
    /* each drive its own target (can_axis.h): none before a position or
     * before the drive is heard; a drive not in Operation Enabled its own
     * 0x6064; the first after an enable its 0x6064 (own frames carry the n/a
     * marker without a position) */
    o->eng_rest = 1;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        if (!(o->sp.flags & ENGINE_SP_NO_POSITION) && fabs(o->sp.vel_m_s[a]) > 1e-9)
            o->eng_rest = 0;
    if (o->ids.cia402)
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
            int32_t inc;
            if (o->ids.cia402_cob_id[a] && axis_target(o, a, &inc, &clamped))
                cia402_encode_rpdo(o->ids.cia402_cob_id[a], o->ids.cia402_controlword,
                                   rpdo_cw(o, a), inc, &f[n++]);
        }
    if (clamped) { /* counted, flagged (STATUS bit 3), logged by can_transport */
        o->st.tx_clamped++;
        o->flags_since |= CANPROTO_ST_CLAMPED;
    }
    for (unsigned k = 0; k < n; k++)
        if ((rc = p->io.send(p->io_ctx, &f[k])) < 0)
            return rc;
    return 0;
}

static int is_down(int rc)
{
    return rc == -ENETDOWN || rc == -ENODEV || rc == -ENXIO || rc == -ENETUNREACH;
}

static void count_drop(can_port_obj_t *o, int rc)
{
    o->flags_since |= CANPROTO_ST_TX_DROP;
    if (is_down(rc)) {
        o->st.dropped_down++;
        o->flags_since |= CANPROTO_ST_BUS_DOWN;
        event(o, CANPROTO_STERR_BUS_DOWN);
        return;
    }
    if (is_full(rc))
        o->st.dropped_full++;
    else
        o->st.dropped_error++; /* e.g. EINVAL: FD frame on a classic-MTU interface */
    event(o, CANPROTO_STERR_TX_DROPPED);
}

/* One STATUS2 page after a STATUS: a changed one first, else the next in turn. */
static void send_status2(can_port_t *p, can_port_obj_t *o)
{
    unsigned page = 0;
    if (!o->st2_have)
        return;
    for (unsigned k = 1; k < CANPROTO_ST2_PAGES && !page; k++)
        if (o->st2_changed & (1u << k))
            page = k;
    for (unsigned j = 0; j < CANPROTO_ST2_PAGES && !page; j++) {
        unsigned k = (o->st2_next + j) % CANPROTO_ST2_PAGES;
        if (o->st2_have & (1u << k))
            page = k;
    }
    if (p->io.send(p->io_ctx, &o->st2[page]) == 0) {
        o->st2_changed &= ~(1u << page);
        o->st2_next = (page + 1) % CANPROTO_ST2_PAGES;
    }
}

static void send_status(can_port_t *p, can_port_obj_t *o, const engine_status_t *es_in,
                        int64_t now_ns)
{
    const engine_status_t es = *es_in;
    canproto_status_t st;
    canproto_frame_t f;

    memset(&st, 0, sizeof st);
    st.state = (uint8_t)es.state;
    st.flags = o->flags_since;
    if (o->sp.flags & ENGINE_SP_FAULT)
        st.flags |= CANPROTO_ST_FAULT;
    st.last_seq = es.last_seq;
    st.free = es.free;
    st.lost = (uint32_t)o->rx.st.lost;
    /* the engine's count: it also holds the waypoints refused once judged with
     * their neighbours, after the push had taken them (EFULL shows as last_err only) */
    st.rejected = (uint32_t)(es.rejected > o->st.waypoints_rejected ? es.rejected
                                                                    : o->st.waypoints_rejected);
    st.malformed = (uint32_t)o->rx.st.malformed;
    st.dropped = (uint32_t)(o->st.dropped_late + o->st.dropped_full + o->st.dropped_down +
                            o->st.dropped_error);
    st.last_err = o->last_err;
    canproto_encode_status(o->ids.status_id, &st, &f);
    if (p->io.send(p->io_ctx, &f) == 0) {
        o->st.status_sent++;
        o->flags_since = 0;
        o->status_due = 0;
        o->last_status_ns = now_ns;
        o->sent_status = 1;
        o->last_state = (int)es.state;
        send_status2(p, o);
    }
}

/* STATUS2 page 4 of object i, if it has drives, given to the page rotation;
 * a change makes a STATUS due at once, and the changed page goes out with it. */
static void update_status2_drive(can_port_t *p, unsigned i)
{
    can_port_obj_t *o = &p->obj[i];
    canproto_status2_drive_t d;
    canproto_frame_t f;
    if (!can_port_drive_summary(p, i, &d))
        return;
    canproto_encode_status2_drive(o->ids.status2_id, &d, &f);
    can_port_status2(p, i, &f);
    if (o->st2_changed & (1u << CANPROTO_ST2_DRIVE))
        o->status_due = 1;
}

#define CAN_PORT_SDO_TIMEOUT_NS 500000000LL /* an SDO request unanswered this long is resent */

/* The controlword axis a's drive needs now (bring-up). */
static uint16_t wanted_cw(const can_port_obj_t *o, unsigned a)
{
    cia402_state_t st = o->drive.state[a];
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
static void watch_heartbeat(can_port_obj_t *o, unsigned a, int64_t now_ns)
{
    if (!o->ids.cia402_heartbeat_ms || !o->hb_armed[a] || o->hb_lost[a] ||
        now_ns - o->hb_last_ns[a] <= (int64_t)o->ids.cia402_heartbeat_ms * 1000000)
        return;
    o->hb_lost[a] = 1;
    o->drive.hb_lost |= 1u << a;
    o->st.heartbeat_lost++;
    event(o, CANPROTO_STERR_DRIVE);
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
static int next_sdo(can_port_obj_t *o, unsigned a, uint8_t node)
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
static void bring_up(can_port_t *p, can_port_obj_t *o, int64_t now_ns)
{
    canproto_frame_t f;
    o->now_ns = now_ns;
    /* trajd's own stall is not a drive's silence: the time the loop could not
     * look is excused (heartbeats queued meanwhile are read with later stamps) */
    int64_t gap = o->look_ns ? now_ns - o->look_ns : 0;
    if (p->cfg.period_ns > 0 && gap > 2 * p->cfg.period_ns)
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
            o->hb_last_ns[a] += gap - p->cfg.period_ns;
    o->look_ns = now_ns;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        uint8_t node = (uint8_t)canproto_cia402_node(&o->ids, a);
        if (!node)
            continue;
        if (!(o->nmt_done & (1u << a))) {
            cia402_encode_nmt(CIA402_NMT_START, node, &f);
            if (p->io.send(p->io_ctx, &f) < 0)
                continue; /* try again next cycle */
            o->nmt_done |= 1u << a;
            o->hb_last_ns[a] = now_ns;
        }
        watch_heartbeat(o, a, now_ns);
        if (o->sdo_wait[a]) {
            if (now_ns - o->sdo_sent_ns[a] < CAN_PORT_SDO_TIMEOUT_NS)
                continue;
            o->st.sdo_timeouts++;
            if (p->io.send(p->io_ctx, &o->sdo_frame[a]) == 0)
                o->sdo_sent_ns[a] = now_ns;
            continue;
        }
        int kind = next_sdo(o, a, node);
        if (!kind)
            continue;
        if (p->io.send(p->io_ctx, &o->sdo_frame[a]) == 0) {
            o->sdo_wait[a] = kind;
            o->sdo_sent_ns[a] = now_ns;
        } else if (kind == 2) {
            o->cw_known[a] = 0; /* not sent: decide again next cycle */
        } else if (kind == 3) {
            o->hb_read[a] = 0;
        }
    }
}

/* trajd's own heartbeat as CANopen master (cfg.hb_node): the drives' consumers
 * (0x1016) see trajd alive, and stop by themselves when it is not. */
static void master_heartbeat(can_port_t *p, int64_t now_ns)
{
    if (!p->cfg.hb_node || (p->hb_any && now_ns - p->hb_sent_ns < p->cfg.hb_period_ns))
        return;
    canproto_frame_t f;
    cia402_encode_heartbeat(p->cfg.hb_node, &f);
    if (p->io.send(p->io_ctx, &f) == 0) {
        p->hb_any = 1;
        p->hb_sent_ns = now_ns;
    }
}

void can_port_cycle(can_port_t *p, int64_t now_ns, int64_t late_ns)
{
    p->st.cycles++;
    if (!p->io.is_up(p->io_ctx)) {
        p->st.down_cycles++;
        for (unsigned i = 0; i < p->nobj; i++)
            if (p->obj[i].set && p->obj[i].have_sp)
                count_drop(&p->obj[i], -ENETDOWN);
        goto out;
    }
    /* A late cycle still sends its SYNC and its CiA 402 targets (a drive
     * applies the target at the next SYNC, so a late one is as good as an
     * early one; a missing SYNC is a fault for most drives); only the own
     * frames, stamped for a deadline that has passed, are dropped. */
    int late = p->cfg.max_late_ns > 0 && late_ns > p->cfg.max_late_ns;
    if (p->cfg.sync) {
        canproto_frame_t f;
        uint8_t c = 0;
        if (p->cfg.sync_overflow) {
            /* CiA 301: the counter runs 1..overflow */
            p->sync_counter = p->sync_counter >= p->cfg.sync_overflow ? 1 : p->sync_counter + 1;
            c = p->sync_counter;
        }
        canproto_encode_sync(p->cfg.sync_id, c, &f);
        if (p->io.send(p->io_ctx, &f) == 0)
            p->st.sync_sent++;
        else
            p->st.sync_dropped++;
    }
    master_heartbeat(p, now_ns);
    for (unsigned i = 0; i < p->nobj; i++)
        if (p->obj[i].set && p->obj[i].ids.cia402 == CANPROTO_CIA402_MANAGED)
            bring_up(p, &p->obj[i], now_ns);
    for (unsigned i = 0; i < p->nobj; i++) {
        can_port_obj_t *o = &p->obj[i];
        if (!o->set || !o->have_sp)
            continue;
        int rc = send_setpoint(p, o, !late);
        if (rc < 0) {
            count_drop(o, rc);
        } else if (late && o->ids.own) {
            o->st.dropped_late++;
            o->flags_since |= CANPROTO_ST_TX_DROP;
            event(o, CANPROTO_STERR_TX_DROPPED);
        } else {
            o->st.setpoints_sent++;
        }
    }
    for (unsigned i = 0; i < p->nobj; i++) {
        can_port_obj_t *o = &p->obj[i];
        if (!o->set)
            continue;
        engine_status_t es;
        memset(&es, 0, sizeof es);
        o->hooks.status(o->ctx, &es);
        update_status2_drive(p, i);
        /* a change of state is reported at once (e.g. FINISHED, UNDERRUN) */
        int due = o->status_due || !o->sent_status || (int)es.state != o->last_state ||
                  (p->cfg.status_period_ns > 0 &&
                   now_ns - o->last_status_ns >= p->cfg.status_period_ns);
        if (due && p->io.is_up(p->io_ctx))
            send_status(p, o, &es, now_ns);
    }
out:
    for (unsigned i = 0; i < p->nobj; i++)
        p->obj[i].have_sp = 0;
}

int can_port_maintain(can_port_t *p, int64_t now_ns)
{
    if (!p->io.maintain)
        return 0;
    int up = p->io.maintain(p->io_ctx, now_ns);
    if (up > 0)
        p->st.reopens++;
    return up > 0;
}

void can_port_stats(const can_port_t *p, can_port_stats_t *st)
{
    *st = p->st;
}

const canerr_bus_t *can_port_bus_errors(const can_port_t *p)
{
    return &p->err;
}

int can_port_drive_change(can_port_t *p, unsigned i, can_axis_change_t *c, uint64_t *dropped)
{
    if (i >= p->nobj)
        return 0;
    can_axis_log_t *l = &p->obj[i].chg;
    if (dropped) {
        *dropped = l->dropped;
        l->dropped = 0;
    }
    return can_axis_log_take(l, c);
}

const can_port_drive_t *can_port_drive(const can_port_t *p, unsigned i)
{
    return i < p->nobj ? &p->obj[i].drive : NULL;
}

int can_port_drive_summary(const can_port_t *p, unsigned i, canproto_status2_drive_t *out)
{
    memset(out, 0, sizeof *out);
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        out->state[a] = CANPROTO_S2_NO_DRIVE;
    out->nmt = CANPROTO_S2_NMT_NONE;
    if (!p || i >= p->nobj || !p->obj[i].set)
        return 0;
    const can_port_obj_t *o = &p->obj[i];
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

void can_port_obj_stats(const can_port_t *p, unsigned i, can_port_obj_stats_t *st)
{
    memset(st, 0, sizeof *st);
    if (i >= p->nobj)
        return;
    *st = p->obj[i].st;
    st->rx = p->obj[i].rx.st;
}

void can_port_reset_counters(can_port_t *p)
{
    memset(&p->st, 0, sizeof p->st);
    for (unsigned i = 0; i < p->nobj; i++) {
        memset(&p->obj[i].st, 0, sizeof p->obj[i].st);
        memset(&p->obj[i].rx.st, 0, sizeof p->obj[i].rx.st);
    }
}

double can_port_busload(const can_port_t *p, double rate_hz, double waypoint_hz, double bitrate,
                        double data_bitrate)
{
    canproto_traffic_t tr = {
        .rate_hz = rate_hz,
        .status_hz = p->cfg.status_period_ns > 0 ? 1e9 / (double)p->cfg.status_period_ns : 0,
        .waypoint_hz = waypoint_hz,
    };
    return canproto_busload(p->ids, p->nobj, p->cfg.sync, p->cfg.sync_overflow ? 1 : 0, &tr,
                            bitrate, data_bitrate);
}
