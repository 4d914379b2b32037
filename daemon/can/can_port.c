/* can_port.c - the CAN side of trajd (see can_port.h). */
#include "can_port.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "can_axis.h"
#include "can_drive.h"

#define CAN_PORT_RX_BATCH 256 /* frames handled per can_port_rx call: do not starve the loop */
/* A STATUS that has found no room in the transmit queue for this long (or for
 * one status period, if longer) goes first in the next cycle, ahead of SYNC;
 * one such STATUS at most in this time, the objects in turn (SYNC keeps the
 * other slots). */
#define CAN_PORT_STATUS_STARVED_NS 100000000LL

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
    int64_t status_failing_ns; /* when a due STATUS first found no room (0: it went out) */
    uint64_t status_ahead;     /* the port's cycle in which it last went ahead of SYNC */
    int sent_status;
    uint8_t flags_since;    /* CANPROTO_ST_BUS_DOWN | _TX_DROP | _OUT_FAULT since last STATUS */
    uint64_t out_lost_seen; /* can_port_output_fault: lines lost as of the last call */
    int out_fault_seen;
    uint8_t last_err;
    int last_state; /* engine state in the last STATUS (-1: none yet) */
    struct can_port *port;
    can_drive_t drv;                          /* its CiA 402 drives (can_drive.h) */
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
    unsigned status_rr;    /* the object whose starved STATUS is looked at first */
    int64_t last_ahead_ns; /* when a starved STATUS last went out ahead of SYNC */
    int ahead_once;        /* ... if one ever did */
    can_port_stats_t st;
    canerr_bus_t err;          /* bus state and counters from error frames */
    can_drive_master_t master; /* trajd's own heartbeat (cfg.hb_node) */
};

/* ---- what the drives (can_drive.c) need from the port: can_drive_ops_t ---- */

static void event(can_port_obj_t *o, uint8_t err);

static int drv_send(void *ctx, const canproto_frame_t *f)
{
    const can_port_obj_t *o = ctx;
    return o->port->io.send(o->port->io_ctx, f);
}

static void drv_status_event(void *ctx, uint8_t err)
{
    event(ctx, err);
}

static int drv_feedback(void *ctx, const can_port_drive_t *d)
{
    can_port_obj_t *o = ctx;
    return o->hooks.feedback ? o->hooks.feedback(o->ctx, d) : 0;
}

static void drv_drive_event(void *ctx, lc_event_t ev)
{
    can_port_obj_t *o = ctx;
    if (o->hooks.drive_event)
        o->hooks.drive_event(o->ctx, ev);
}

static const can_drive_ops_t drv_ops = {drv_send, drv_status_event, drv_feedback, drv_drive_event};

static int port_send(void *ctx, const canproto_frame_t *f)
{
    const can_port_t *p = ctx;
    return p->io.send(p->io_ctx, f);
}

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
        p->obj[i].port = p;
        can_drive_init(&p->obj[i].drv);
    }
    p->master.node = cfg->hb_node;
    p->master.period_ns = cfg->hb_period_ns;
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
    can_drive_setup(&o->drv, ids, &drv_ops, o);
    p->ids[i] = *ids;
    return 0;
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

/* Object o's counters to zero: the reassembly's, the drives', the port's. */
static void reset_counters(can_port_obj_t *o)
{
    memset(&o->st, 0, sizeof o->st);
    memset(&o->drv.st, 0, sizeof o->drv.st);
    memset(&o->rx.st, 0, sizeof o->rx.st);
    o->last_err = CANPROTO_STERR_OK;
}

static void refuse_command(can_port_obj_t *o, canproto_cmd_t cmd, uint32_t id, int err)
{
    o->st.cmd_refused++;
    o->st.last_refused = (uint8_t)cmd;
    o->st.last_refused_id = id;
    o->st.last_refused_err = err;
    event(o, CANPROTO_STERR_REFUSED);
}

static void handle_command(can_port_obj_t *o, canproto_cmd_t cmd, unsigned arg, uint32_t id)
{
    int err;

    if (!((o->cmd_allow >> cmd) & 1u)) {
        refuse_command(o, cmd, id, 0);
        return;
    }
    if (cmd == CANPROTO_CMD_CLEAR)
        can_drive_clear_asked(&o->drv); /* a held drive: fault reset, enabled again */
    if (o->hooks.command && (err = o->hooks.command(o->ctx, cmd, arg)) < 0) {
        refuse_command(o, cmd, id, err); /* e.g. an override while held (obj_command) */
        return;
    }
    if (cmd == CANPROTO_CMD_CLEAR) {
        can_drive_cleared(&o->drv); /* the holds released; after a drive's, re-anchored */
        canproto_rx_restart(&o->rx);
    }
    if (cmd == CANPROTO_CMD_RESET_COUNTERS)
        reset_counters(o);
    o->status_due = 1;
}

int can_port_adopt(can_port_t *p, unsigned i, const can_drive_t *old, uint8_t sync_counter)
{
    if (i >= p->nobj || !p->obj[i].set || !can_drive_adopt(&p->obj[i].drv, old))
        return 0;
    p->sync_counter = sync_counter;
    return 1;
}

void can_port_keep(const can_port_t *p, unsigned i, can_port_kept_t *k)
{
    memset(k, 0, sizeof *k);
    if (i >= p->nobj)
        return;
    k->st = p->obj[i].st;
    k->rx = p->obj[i].rx;
    k->rx.slots = NULL;
    memcpy(k->slots, p->obj[i].slots, sizeof k->slots);
}

void can_port_restore(can_port_t *p, unsigned i, const can_port_kept_t *k)
{
    if (i >= p->nobj || !p->obj[i].set)
        return;
    can_port_obj_t *o = &p->obj[i];
    canproto_slot_t *slots = o->rx.slots;
    unsigned n = o->rx.nslots;
    o->st = k->st;
    o->rx = k->rx;
    o->rx.slots = slots;
    o->rx.nslots = n;
    memcpy(o->slots, k->slots, sizeof o->slots);
}

const can_drive_t *can_port_drive_state(const can_port_t *p, unsigned i)
{
    return i < p->nobj ? &p->obj[i].drv : NULL;
}

uint8_t can_port_sync_counter(const can_port_t *p)
{
    return p->sync_counter;
}

void can_port_reset_counters(can_port_t *p, unsigned i)
{
    if (i >= p->nobj)
        return;
    reset_counters(&p->obj[i]);
    p->obj[i].status_due = 1;
}

void can_port_cleared(can_port_t *p, unsigned i)
{
    if (i >= p->nobj)
        return;
    can_drive_clear_asked(&p->obj[i].drv);
    can_drive_cleared(&p->obj[i].drv);
    p->obj[i].status_due = 1;
}

static void dispatch(can_port_t *p, const canproto_frame_t *f, int64_t now_ns)
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
            if (can_drive_rx(&o->drv, f, now_ns)) /* its drives' TPDO, SDO, heartbeat, EMCY */
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
    if (p->st.rx_foreign++ == 0) {
        p->st.rx_foreign_first = f->id;
        p->st.rx_foreign_first_flags = f->flags;
    }
}

int can_port_rx(can_port_t *p, int64_t now_ns)
{
    canproto_frame_t f;
    int n = 0;
    while (n < CAN_PORT_RX_BATCH) {
        int rc = p->io.recv(p->io_ctx, now_ns, &f);
        if (rc == 0)
            break;
        if (rc < 0) {
            p->st.rx_errors++;
            return n ? n : rc;
        }
        p->st.rx_frames++;
        dispatch(p, &f, now_ns);
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
    /* each drive its own target (can_drive.h; own frames carry the n/a
     * marker without a position) */
    n += can_drive_rpdos(&o->drv, &o->sp, &f[n], &clamped);
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

/* A cycle of o not sent whose setpoint carried a position: motion missed. */
static void count_missed(can_port_t *p, can_port_obj_t *o)
{
    unsigned pos = !(o->sp.flags & ENGINE_SP_NO_POSITION);
    o->st.dropped_pos += pos;
    p->st.dropped_pos += pos;
}

static void count_drop(can_port_t *p, can_port_obj_t *o, int rc)
{
    o->flags_since |= CANPROTO_ST_TX_DROP;
    count_missed(p, o);
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
    } else {
        o->st.status_dropped++;
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
        o->status_failing_ns = 0;
        o->last_state = (int)es.state;
        send_status2(p, o);
    } else {
        o->st.status_dropped++; /* due again next cycle */
        if (!o->status_failing_ns)
            o->status_failing_ns = now_ns ? now_ns : 1;
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

/* Object i's STATUS, if one is due (or, with starved_only, only if a due one
 * has found no room in the transmit queue for CAN_PORT_STATUS_STARVED_NS or
 * one status period; without, not if it went so in this cycle). */
static void status_step(can_port_t *p, unsigned i, int64_t now_ns, int starved_only)
{
    can_port_obj_t *o = &p->obj[i];
    if (starved_only) {
        int64_t starve = p->cfg.status_period_ns > CAN_PORT_STATUS_STARVED_NS
                             ? p->cfg.status_period_ns
                             : CAN_PORT_STATUS_STARVED_NS;
        if (!o->status_failing_ns || now_ns - o->status_failing_ns < starve)
            return;
        o->status_ahead = p->st.cycles;
    } else if (o->status_ahead == p->st.cycles) {
        return; /* it went ahead of SYNC in this cycle already */
    }
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

void can_port_cycle(can_port_t *p, int64_t now_ns, int64_t late_ns)
{
    p->st.cycles++;
    if (!p->io.is_up(p->io_ctx)) {
        p->st.down_cycles++;
        for (unsigned i = 0; i < p->nobj; i++)
            if (p->obj[i].set && p->obj[i].have_sp)
                count_drop(p, &p->obj[i], -ENETDOWN);
        goto out;
    }
    /* With the transmit queue full, the first frame written after a slot frees
     * is the one that gets it: each cycle's SYNC, every time.  A STATUS that has
     * been starved so (the operator's only word of the drops) goes first. */
    int may = !p->ahead_once || now_ns - p->last_ahead_ns >= CAN_PORT_STATUS_STARVED_NS;
    for (unsigned n = 0, start = p->status_rr; may && n < p->nobj; n++) {
        unsigned i = (start + n) % p->nobj; /* in turn: none starves the others */
        can_port_obj_t *o = &p->obj[i];
        if (!o->set)
            continue;
        status_step(p, i, now_ns, 1);
        if (o->status_ahead == p->st.cycles && !o->status_failing_ns) { /* it went out */
            p->status_rr = (i + 1) % p->nobj;
            p->last_ahead_ns = now_ns;
            p->ahead_once = 1;
            break;
        }
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
    can_drive_master_heartbeat(&p->master, now_ns, port_send, p);
    for (unsigned i = 0; i < p->nobj; i++)
        if (p->obj[i].set)
            can_drive_cycle(&p->obj[i].drv, now_ns, p->cfg.period_ns); /* the bring-up */
    for (unsigned i = 0; i < p->nobj; i++) {
        can_port_obj_t *o = &p->obj[i];
        if (!o->set || !o->have_sp)
            continue;
        int rc = send_setpoint(p, o, !late);
        if (rc < 0) {
            count_drop(p, o, rc);
        } else if (late && o->ids.own) {
            o->st.dropped_late++;
            count_missed(p, o);
            o->flags_since |= CANPROTO_ST_TX_DROP;
            event(o, CANPROTO_STERR_TX_DROPPED);
        } else {
            o->st.setpoints_sent++;
        }
    }
    for (unsigned i = 0; i < p->nobj; i++)
        if (p->obj[i].set)
            status_step(p, i, now_ns, 0);
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
    return can_drive_change(&p->obj[i].drv, c, dropped);
}

const can_port_drive_t *can_port_drive(const can_port_t *p, unsigned i)
{
    return i < p->nobj ? &p->obj[i].drv.drive : NULL;
}

int can_port_drive_summary(const can_port_t *p, unsigned i, canproto_status2_drive_t *out)
{
    if (!p || i >= p->nobj || !p->obj[i].set) {
        memset(out, 0, sizeof *out);
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
            out->state[a] = CANPROTO_S2_NO_DRIVE;
        out->nmt = CANPROTO_S2_NMT_NONE;
        return 0;
    }
    return can_drive_summary(&p->obj[i].drv, out);
}

void can_port_obj_stats(const can_port_t *p, unsigned i, can_port_obj_stats_t *st)
{
    memset(st, 0, sizeof *st);
    if (i >= p->nobj)
        return;
    const can_drive_stats_t *d = &p->obj[i].drv.st;
    *st = p->obj[i].st;
    st->rx = p->obj[i].rx.st;
    st->drive_frames = d->drive_frames;
    st->drive_lost = d->drive_lost;
    st->drive_bad = d->drive_bad;
    st->sdo_aborts = d->sdo_aborts;
    st->sdo_timeouts = d->sdo_timeouts;
    st->sdo_stale = d->sdo_stale;
    st->emcy = d->emcy;
    st->heartbeat_lost = d->heartbeat_lost;
    st->last_abort = d->last_abort;
    st->last_abort_index = d->last_abort_index;
    st->last_emcy = d->last_emcy;
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
