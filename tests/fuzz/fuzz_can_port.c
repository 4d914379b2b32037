/*
 * fuzz_can_port.c - libFuzzer target for the daemon's CAN port on the
 * receiving side (daemon/can/can_port.c, can_port_rx): everything a bus can
 * send to trajd's CANopen master and waypoint input, handled by the same
 * dispatch as in the daemon, between the port's own cycles (setpoints, RPDOs,
 * SYNC, STATUS, the drives' bring-up by NMT and SDO, heartbeat watch).
 *
 * Input: byte 0 picks the object's configuration (CiA 402 drives on 1..3
 * axes, feedback, bring-up with configuration SDOs, controlword RPDO,
 * heartbeat watch, FD).  Then records [sel, len, data...]: sel & 15 picks the
 * id among those the port listens to (waypoint, FD waypoint, and per axis
 * (sel >> 4) & 3 its SDO reply 0x580 + node, heartbeat 0x700 + node, EMCY
 * 0x80 + node, feedback TPDO) or a foreign or error frame; len & 0x3F bytes
 * follow (any length: the port must check).  sel 15 instead runs one cycle
 * (1 + (len & 7) periods later): receive what was queued, hand over a
 * setpoint, send, maintain.
 *
 * Oracle: no crash, no leak, no undefined behaviour (sanitizers); every frame
 * delivered is counted once (rx_frames); every frame the port sends is one a
 * bus can carry (classic at most 8 bytes, FD of a valid FD length, an 11-bit
 * id unless extended); the drives' summary (STATUS2 page 4) holds valid
 * states, and encodes to a frame that decodes to the same summary.
 */
#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "can_port.h"
#include "canproto.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define QMAX 64
#define PERIOD_NS 10000000LL

typedef struct {
    canproto_frame_t q[QMAX];
    unsigned head, n;
    int up;
} bus_t;

static int bus_send(void *io, const canproto_frame_t *f)
{
    const bus_t *b = io;
    if (f->flags & CANPROTO_F_FD) {
        if (!canproto_fd_len_valid(f->len))
            abort();
    } else if (f->len > 8) {
        abort();
    }
    if (!(f->flags & CANPROTO_F_EFF) && f->id > 0x7FF)
        abort();
    return b->up ? 0 : -ENETDOWN;
}

static int bus_recv(void *io, int64_t now_ns, canproto_frame_t *f)
{
    bus_t *b = io;
    (void)now_ns;
    if (!b->n)
        return 0;
    *f = b->q[b->head];
    b->head = (b->head + 1) % QMAX;
    b->n--;
    return 1;
}

static int bus_maintain(void *io, int64_t now_ns)
{
    (void)io;
    (void)now_ns;
    return 0;
}

static int bus_is_up(const void *io)
{
    return ((const bus_t *)io)->up;
}

static const can_port_io_t bus_ops = {bus_send, bus_recv, bus_maintain, bus_is_up};

typedef struct {
    engine_status_t st;
    int answer;
} obj_t;

static int obj_push(void *ctx, const engine_waypoint_t *wp)
{
    obj_t *o = ctx;
    if (o->answer == 0)
        o->st.last_seq = wp->seq;
    return o->answer;
}

static int obj_command(void *ctx, canproto_cmd_t cmd, unsigned arg)
{
    obj_t *o = ctx;
    (void)arg;
    o->st.state = (cmd & 1) ? ENGINE_STATE_FINISHED : ENGINE_STATE_STREAMING;
    return 0;
}

static void obj_status(void *ctx, engine_status_t *st)
{
    *st = ((obj_t *)ctx)->st;
}

static int obj_feedback(void *ctx, const can_port_drive_t *d)
{
    (void)ctx;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (d->state[a] > CIA402_STATE_UNKNOWN)
            abort();
    return d->need_anchor; /* the engine re-anchored at once */
}

static const can_port_hooks_t obj_hooks = {obj_push, obj_command, obj_status, obj_feedback, NULL};

static void configure(canproto_ids_t *ids, uint8_t b)
{
    canproto_ids_default(ids, 0);
    ids->fd = (b >> 7) & 1;
    if (!(b & 3))
        return; /* no drives: waypoints and commands only */
    for (unsigned a = b & 3; a < CANPROTO_CIA402_AXES; a++)
        ids->cia402_cob_id[a] = 0;
    ids->cia402 = (b >> 3) & 1   ? CANPROTO_CIA402_MANAGED
                  : (b >> 2) & 1 ? CANPROTO_CIA402_FEEDBACK
                                 : CANPROTO_CIA402_TARGETS;
    ids->cia402_controlword = (b >> 4) & 1;
    ids->cia402_heartbeat_ms = (b & 0x20) ? 50 : 0;
    if (b & 0x40) {
        ids->cia402_sdo[0].index = 0x6060;
        ids->cia402_sdo[0].size = 1;
        ids->cia402_sdo[0].value = 8;
        ids->cia402_sdo[1].index = 0x60C2;
        ids->cia402_sdo[1].sub = 1;
        ids->cia402_sdo[1].size = 4;
        ids->cia402_sdo[1].value = 10;
        ids->cia402_nsdo = 2;
    }
}

static uint32_t pick_id(const canproto_ids_t *ids, uint8_t sel, uint8_t *flags)
{
    unsigned a = (sel >> 4) & 3, node = canproto_cia402_node(ids, a % CANPROTO_CIA402_AXES);
    *flags = 0;
    switch (sel & 15) {
    case 0: return ids->waypoint_id;
    case 1: *flags = CANPROTO_F_FD; return ids->waypoint_fd_id;
    case 2: return 0x580u + node;
    case 3: return 0x700u + node;
    case 4: return 0x080u + node;
    case 5: return canproto_cia402_tpdo(ids, a % CANPROTO_CIA402_AXES);
    case 6: *flags = CANPROTO_F_ERR; return sel >> 4;
    case 7: *flags = CANPROTO_F_EFF; return ids->waypoint_id;
    case 8: *flags = CANPROTO_F_RTR; return 0x580u + node;
    default: return 0x600u + (sel & 0x7F);
    }
}

/* The summary's states are valid and it survives the STATUS2 round trip.  The
 * round trip is a pure function of the summary: it is checked again only when
 * the summary changed since the last check (*last, *have_last), not every
 * cycle (most cycles leave the drives as they were). */
static void check_summary(const can_port_t *p, canproto_status2_drive_t *last, int *have_last)
{
    canproto_status2_drive_t s, back;
    canproto_frame_t f;
    (void)can_port_drive_summary(p, 0, &s);
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (s.state[a] > CIA402_STATE_UNKNOWN && s.state[a] != CANPROTO_S2_NO_DRIVE)
            abort();
    if (*have_last && !memcmp(&s, last, sizeof s))
        return;
    canproto_encode_status2_drive(0x6D0, &s, &f);
    if (canproto_decode_status2_drive(&f, &back) != 0 || memcmp(&s, &back, sizeof s))
        abort();
    *last = s;
    *have_last = 1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static bus_t bus;
    obj_t obj;
    canproto_ids_t ids;
    can_port_config_t cfg;
    canproto_status2_drive_t summary;
    int have_summary = 0;
    if (size < 1)
        return 0;
    memset(&bus, 0, sizeof bus);
    memset(&obj, 0, sizeof obj);
    bus.up = 1;
    obj.st.free = 40;
    configure(&ids, data[0]);
    can_port_config_default(&cfg);
    cfg.sync = data[0] & 1;
    can_port_t *p = can_port_new(&cfg, &bus_ops, &bus, 1);
    if (!p)
        abort();
    if (can_port_set_object(p, 0, &ids, &obj_hooks, &obj) != 0)
        abort();
    int64_t now = 0;
    uint64_t delivered = 0;
    size_t i = 1;
    while (i + 2 <= size) {
        uint8_t sel = data[i], len = data[i + 1];
        i += 2;
        if ((sel & 15) == 15) { /* one cycle */
            can_port_stats_t st;
            now += PERIOD_NS * (1 + (len & 7));
            obj.answer = (len & 0x18) ? 0 : -ENGINE_ESPEED;
            bus.up = !(len & 0x20);
            delivered += bus.n;
            while (can_port_rx(p, now) > 0)
                ;
            can_port_stats(p, &st);
            if (st.rx_frames != delivered)
                abort();
            engine_setpoint_t sp = {0};
            sp.now_ns = now;
            sp.state = obj.st.state;
            sp.pos_m[0] = 0.001 * (double)(int8_t)len;
            can_port_setpoint(p, 0, &sp);
            can_port_cycle(p, now, 0);
            (void)can_port_maintain(p, now);
            check_summary(p, &summary, &have_summary);
            continue;
        }
        canproto_frame_t f;
        memset(&f, 0, sizeof f);
        f.id = pick_id(&ids, sel, &f.flags);
        unsigned n = len & 0x3F;
        f.len = (uint8_t)n;
        if (n > size - i)
            n = (unsigned)(size - i);
        memcpy(f.data, data + i, n);
        i += n;
        if (bus.n < QMAX) {
            bus.q[(bus.head + bus.n) % QMAX] = f;
            bus.n++;
        }
    }
    delivered += bus.n;
    while (can_port_rx(p, now + PERIOD_NS) > 0)
        ;
    can_port_stats_t st;
    can_port_stats(p, &st);
    if (st.rx_frames != delivered)
        abort();
    check_summary(p, &summary, &have_summary);
    can_port_free(p);
    return 0;
}
