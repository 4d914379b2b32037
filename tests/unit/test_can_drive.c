/* test_can_drive.c - what trajd sends CiA 402 drives at their events (issue 23),
 * on a fake transport and a fake engine (daemon/can/can_port.h,
 * daemon/can/can_axis.h): a drive that faults mid-motion gets its own
 * position, never a moving target; after it is enabled again its first target
 * is its 0x6064 and the engine is re-anchored there; a restarted trajd adopts
 * running drives (Enable operation, target = 0x6064); one drive's boot-up
 * re-initialises that drive only; the drive events go to the object's owner
 * (lost, boot-up, heartbeat lost and back); after a clear each axis
 * re-anchors at its 0x6064; the heartbeat watch arms only for a
 * producer time set or read back, from the first heartbeat, and excuses
 * trajd's own stall; trajd's own heartbeat; every state change kept. */
#include "test.h"

#include <errno.h>
#include <math.h>
#include <string.h>

#include "can_port.h"
#include "fake_can_io.h"

static fake_can_io_t io; /* tests/helpers/fake_can_io.h */
static can_port_t *port;

/* The fake object: the drive events counted (nhold: those that hold it), and
 * a re-anchor done at once when asked (as the owner adopting the drives'
 * position at rest), its position recorded. */
static struct {
    unsigned ev[LC_EV_COUNT];
    unsigned nhold;
    unsigned nanchor;
    double anchor_m[3];
    unsigned enabled_n, lost_n; /* the drives' episodes, as the feedback gave them */
} obj;

static int fo_push(void *ctx, const engine_waypoint_t *wp)
{
    (void)ctx;
    (void)wp;
    return 0;
}

static void fo_status(void *ctx, engine_status_t *st)
{
    (void)ctx;
    st->state = ENGINE_STATE_STREAMING;
}

static int fo_feedback(void *ctx, const can_port_drive_t *d)
{
    (void)ctx;
    obj.enabled_n = d->enabled_n;
    obj.lost_n = d->lost_n;
    if (!d->need_anchor)
        return 0;
    obj.nanchor++;
    memcpy(obj.anchor_m, d->anchor_m, sizeof obj.anchor_m);
    return 1;
}

static void fo_drive_event(void *ctx, lc_event_t ev)
{
    (void)ctx;
    assert_true(ev == LC_EV_DRIVE_LOST || ev == LC_EV_DRIVE_BOOTUP || ev == LC_EV_HEARTBEAT_LOST ||
                ev == LC_EV_HEARTBEAT_BACK);
    obj.ev[ev]++;
    obj.nhold += ev != LC_EV_HEARTBEAT_BACK;
}

static const can_port_hooks_t hooks = {fo_push, NULL, fo_status, fo_feedback, fo_drive_event};

#define OE 0x0237
#define FAULT 0x0218
#define SOD 0x0250

static void new_port(int64_t period_ns, uint8_t hb_node)
{
    can_port_config_t cfg;
    fake_can_reset(&io);
    memset(&obj, 0, sizeof obj);
    can_port_config_default(&cfg);
    cfg.sync = 1;
    cfg.status_period_ns = 0;
    cfg.period_ns = period_ns;
    cfg.hb_node = hb_node;
    port = can_port_new(&cfg, &fake_can_ops, &io, 1);
    assert_non_null(port);
}

static int free_port(void **state)
{
    (void)state;
    can_port_free(port);
    port = NULL;
    return 0;
}

/* Three axes, nodes 1..3, 10000 counts/m, y inverted; feedback only, or the
 * bring-up with the controlword in the RPDO. */
static void three_axes(int enable, uint32_t hb_ms)
{
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = enable ? CANPROTO_CIA402_MANAGED : CANPROTO_CIA402_FEEDBACK;
    ids.cia402_controlword = enable;
    ids.cia402_cob_id[0] = 0x201;
    ids.cia402_cob_id[1] = 0x202;
    ids.cia402_cob_id[2] = 0x203;
    ids.cia402_invert[1] = 1;
    ids.cia402_heartbeat_ms = hb_ms;
    assert_int_equal(can_port_set_object(port, 0, &ids, &hooks, NULL), 0);
}

static void queue(uint32_t id, unsigned len, const uint8_t *data)
{
    canproto_frame_t *f = &io.in[io.nin++];
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = (uint8_t)len;
    memcpy(f->data, data, len);
}

static void tpdo(unsigned node, uint16_t sw, int32_t pos)
{
    uint8_t d[6] = {(uint8_t)sw, (uint8_t)(sw >> 8)};
    for (int i = 0; i < 4; i++)
        d[2 + i] = (uint8_t)((uint32_t)pos >> (8 * i));
    queue(0x180 + node, 6, d);
}

static void heartbeat(unsigned node, uint8_t state)
{
    queue(0x700 + node, 1, &state);
}

static void sdo_reply(unsigned node, uint8_t cs, uint16_t index, uint8_t sub, uint32_t v)
{
    uint8_t d[8] = {cs, (uint8_t)index, (uint8_t)(index >> 8), sub};
    for (int i = 0; i < 4; i++)
        d[4 + i] = (uint8_t)(v >> (8 * i));
    queue(0x580 + node, 8, d);
}

/* One cycle at k ms with the engine at p (metres), moving at v (m/s). */
static void cycle(uint32_t k, const double p[3], double v)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    memcpy(sp.pos_m, p, sizeof sp.pos_m);
    sp.vel_m_s[0] = v;
    sp.state = ENGINE_STATE_STREAMING;
    can_port_rx(port, (int64_t)k * 1000000);
    can_port_setpoint(port, 0, &sp);
    can_port_cycle(port, (int64_t)k * 1000000, 0);
}

/* The target of the last RPDO to node since mark (*cw its controlword), or
 * INT32_MIN if none. */
static int32_t rpdo(unsigned node, unsigned mark, int *cw)
{
    int32_t t = INT32_MIN;
    for (unsigned i = mark; i < io.nout; i++)
        if (io.out[i].id == 0x200 + node) {
            const uint8_t *d = io.out[i].data + (io.out[i].len == 6 ? 2 : 0);
            t = (int32_t)((uint32_t)d[0] | (uint32_t)d[1] << 8 | (uint32_t)d[2] << 16 |
                          (uint32_t)d[3] << 24);
            if (cw)
                *cw = io.out[i].len == 6 ? io.out[i].data[0] | io.out[i].data[1] << 8 : -1;
        }
    return t;
}

/* Given three drives found in Operation Enabled at 1.2 m, -0.8 m (inverted:
 * 8000 counts) and 0.3 m, and the object moving along x: when node 1 faults
 * mid-motion, then from the next cycle its targets are its own 0x6064 (never
 * the moving track), the object is held once, y and z follow the braking
 * engine while it moves and hold when it rests; after node 1 is enabled again
 * its first target is its 0x6064, the engine is re-anchored there (with the
 * others' held targets), and the engine's targets pass again. */
static void test_fault_mid_motion(void **state)
{
    (void)state;
    new_port(0, 0);
    three_axes(0, 0);
    tpdo(1, OE, 12000);
    tpdo(2, OE, 8000);
    tpdo(3, OE, 3000);
    double p[3] = {1.2, -0.8, 0.3};
    unsigned mark = io.nout;
    cycle(0, p, 0);
    assert_int_equal(rpdo(1, mark, NULL), 12000); /* adopted where they stand */
    assert_int_equal(rpdo(2, mark, NULL), 8000);
    assert_int_equal(obj.nanchor, 1);
    assert_true(fabs(obj.anchor_m[1] + 0.8) < 1e-9);
    assert_int_equal(obj.enabled_n, 1); /* one episode each, whenever the log polls it */
    assert_int_equal(obj.lost_n, 0);
    for (uint32_t k = 1; k <= 10; k++) { /* moving in x at 1 m/s, 50 ms cycles */
        p[0] = 1.2 + 0.05 * k;
        mark = io.nout;
        cycle(50 * k, p, 1.0);
        assert_int_equal(rpdo(1, mark, NULL), 12000 + 500 * (int)k);
    }
    tpdo(1, FAULT, 17100); /* the drive faults 400 counts behind the track */
    p[0] += 0.05;
    mark = io.nout;
    cycle(550, p, 0.8); /* the engine brakes (the hold) */
    assert_int_equal(rpdo(1, mark, NULL), 17100);
    assert_int_equal(rpdo(2, mark, NULL), 8000); /* y, z follow the engine */
    assert_int_equal(obj.nhold, 1);
    assert_int_equal(obj.ev[LC_EV_DRIVE_LOST], 1); /* the owner's drive hold: it brakes */
    p[0] += 0.02;
    mark = io.nout;
    cycle(600, p, 0); /* at rest */
    assert_int_equal(rpdo(1, mark, NULL), 17100);
    p[1] = -0.9; /* the engine somewhere else (a new trajectory): nobody follows */
    p[0] += 0.5;
    mark = io.nout;
    cycle(650, p, 1.0);
    assert_int_equal(rpdo(1, mark, NULL), 17100);
    assert_int_equal(rpdo(2, mark, NULL), 8000);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.drive_lost, 1);
    /* enabled again (the operator's clear and another master): its 0x6064 first */
    tpdo(1, OE, 17100);
    can_port_rx(port, 700000000); /* read before the tick: re-anchored at once */
    assert_int_equal(obj.nanchor, 2);
    /* lost once, enabled again once: counted, so that a log that polls only
     * now still tells both (can_transport.c; before, it compared the level) */
    assert_int_equal(obj.lost_n, 1);
    assert_int_equal(obj.enabled_n, 2);
    assert_true(fabs(obj.anchor_m[0] - 1.71) < 1e-9); /* where node 1 stands */
    assert_true(fabs(obj.anchor_m[1] + 0.8) < 1e-9);  /* the target y held */
    assert_true(fabs(obj.anchor_m[2] - 0.3) < 1e-9);
    double q[3] = {1.71, -0.8, 0.3}; /* the engine's setpoint there, then moving */
    mark = io.nout;
    cycle(700, q, 0);
    assert_int_equal(rpdo(1, mark, NULL), 17100); /* its 0x6064 first */
    assert_int_equal(rpdo(2, mark, NULL), 8000);
    q[0] += 0.001;
    q[1] += 0.002;
    mark = io.nout;
    cycle(750, q, 0.1); /* the engine's targets pass again */
    assert_int_equal(rpdo(1, mark, NULL), 17110);
    assert_int_equal(rpdo(2, mark, NULL), 7980);
}

/* Three drives in Operation Enabled at 12000, 8000 and 3000 counts following
 * the object for four cycles of 50 ms: x at +0.05 m a cycle, y at -vy m a
 * cycle; p is left at the last setpoint sent. */
static void three_following(double *p, double vy)
{
    new_port(0, 0);
    three_axes(0, 0);
    tpdo(1, OE, 12000);
    tpdo(2, OE, 8000);
    tpdo(3, OE, 3000);
    p[0] = 1.2;
    p[1] = -0.8;
    p[2] = 0.3;
    cycle(0, p, 0);
    for (uint32_t k = 1; k <= 4; k++) {
        p[0] = 1.2 + 0.05 * k;
        p[1] = -0.8 - vy * k;
        cycle(50 * k, p, 1.0);
    }
}

/* Given three drives following the object (y's 0x6064 3 counts off the target
 * it holds), when node 1 faults mid-motion, the object is cleared (CLEAR
 * command) and node 1 is enabled again, then each axis re-anchors at its own
 * 0x6064 (issue 23: "After clear, each axis re-anchors at its 0x6064"), not at
 * the target it held: the engine is given y's 0x6064 and y's first target
 * after the clear is its 0x6064. */
static void test_clear_reanchors_each_axis_at_its_0x6064(void **state)
{
    (void)state;
    double p[3];
    three_following(p, 0.0);
    tpdo(2, OE, 8003); /* y stands 3 counts off its target */
    tpdo(1, FAULT, 13900);
    cycle(250, p, 0.5); /* the object brakes */
    cycle(300, p, 0);   /* at rest, held */
    unsigned mark = io.nout;
    cycle(350, p, 0);
    assert_int_equal(rpdo(2, mark, NULL), 8000); /* held where it was sent */
    canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &io.in[io.nin++]);
    cycle(400, p, 0);
    tpdo(1, OE, 13900); /* enabled again */
    can_port_rx(port, 450000000);
    assert_int_equal(obj.nanchor, 2);
    assert_true(fabs(obj.anchor_m[0] - 1.39) < 1e-9);
    assert_true(fabs(obj.anchor_m[1] + 0.8003) < 1e-9); /* y's 0x6064, not its held target */
    assert_true(fabs(obj.anchor_m[2] - 0.3) < 1e-9);
    double q[3] = {1.39, -0.8003, 0.3};
    mark = io.nout;
    cycle(450, q, 0);
    assert_int_equal(rpdo(1, mark, NULL), 13900);
    assert_int_equal(rpdo(2, mark, NULL), 8003);
    assert_int_equal(rpdo(3, mark, NULL), 3000);
}

/* Given three drives following the object, y's 0x6064 30 counts behind its
 * moving target, when node 1 faults and the CLEAR comes while the object
 * still brakes, then y and z go on following the braking engine (no step to
 * their 0x6064 mid-motion: that is for the rest), and once the engine's
 * setpoint is at rest each re-anchors at its 0x6064. */
static void test_clear_while_braking_keeps_axes_following(void **state)
{
    (void)state;
    double p[3];
    three_following(p, 0.01); /* y moves too: 8000 + 100 k counts */
    tpdo(2, OE, 8370);        /* 30 counts behind its target */
    tpdo(1, FAULT, 13900);
    canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &io.in[io.nin++]);
    p[1] = -0.845;
    unsigned mark = io.nout;
    cycle(250, p, 0.5);                          /* still braking */
    assert_int_equal(rpdo(2, mark, NULL), 8450); /* the engine's, not its 0x6064 */
    p[1] = -0.846;
    mark = io.nout;
    cycle(300, p, 0);                            /* at rest */
    assert_int_equal(rpdo(2, mark, NULL), 8370); /* now its 0x6064 */
    assert_int_equal(rpdo(1, mark, NULL), 13900);
}

/* Given the bring-up with the controlword in the RPDO and drives already in
 * Operation Enabled (trajd restarted while they run), then trajd never sends
 * them Disable voltage: the first RPDO carries Enable operation and target =
 * 0x6064, the controlword written by SDO after the list is Enable operation. */
static void test_restart_adopts_running_drives(void **state)
{
    (void)state;
    new_port(0, 0);
    three_axes(1, 0);
    for (unsigned n = 1; n <= 3; n++) {
        heartbeat(n, 0x05);
        tpdo(n, OE, 1000 * (int32_t)n);
    }
    double p[3] = {0.5, 0.5, 0.5}; /* whatever the engine says before the anchor */
    unsigned mark = io.nout;
    cycle(0, p, 0);
    for (unsigned n = 1; n <= 3; n++) {
        int cw = -1;
        assert_int_equal(rpdo(n, mark, &cw), 1000 * (int32_t)n);
        assert_int_equal(cw, 0x000F);
    }
    for (uint32_t k = 1; k < 5; k++) {
        for (unsigned n = 1; n <= 3; n++)
            if (io.out[io.nout - 1].id == 0x600 + n)
                sdo_reply(n, 0x60, 0x6040, 0, 0);
        cycle(50 * k, p, 0);
    }
    for (unsigned i = 0; i < io.nout; i++) {
        const canproto_frame_t *f = &io.out[i];
        if (f->id > 0x600 && f->id <= 0x603 && f->data[1] == 0x40 && f->data[2] == 0x60)
            assert_int_equal(f->data[4] | f->data[5] << 8, 0x000F);
        if (f->id > 0x200 && f->id <= 0x203)
            assert_int_equal(f->data[0] | f->data[1] << 8, 0x000F);
    }
}

/* Given three enabled drives with a configuration list, when node 2 sends its
 * boot-up, then NMT start and the list go to node 2 only; nodes 1 and 3 get
 * no SDO and keep Enable operation; the object is held once; node 2 gets its
 * own position as target while not enabled. */
static void test_bootup_of_one_drive(void **state)
{
    (void)state;
    new_port(0, 0);
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_controlword = 1;
    ids.cia402_cob_id[0] = 0x201;
    ids.cia402_cob_id[1] = 0x202;
    ids.cia402_cob_id[2] = 0x203;
    ids.cia402_sdo[0].index = 0x6060;
    ids.cia402_sdo[0].size = 1;
    ids.cia402_sdo[0].value = 8;
    ids.cia402_nsdo = 1;
    assert_int_equal(can_port_set_object(port, 0, &ids, &hooks, NULL), 0);
    double p[3] = {0.1, -0.2, 0.3};
    cycle(0, p, 0);
    for (unsigned n = 1; n <= 3; n++)
        sdo_reply(n, 0x60, 0x6060, 0, 0);
    for (unsigned n = 1; n <= 3; n++)
        tpdo(n, OE, 1000);
    cycle(50, p, 0);
    for (unsigned n = 1; n <= 3; n++)
        sdo_reply(n, 0x60, 0x6040, 0, 0);
    cycle(100, p, 0);
    assert_int_equal(obj.nhold, 0);
    heartbeat(2, 0x00); /* node 2 reset */
    unsigned mark = io.nout;
    cycle(150, p, 1.0);
    assert_int_equal(obj.nhold, 1);
    assert_int_equal(obj.ev[LC_EV_DRIVE_BOOTUP], 1); /* a boot-up, not a loss */
    assert_int_equal(obj.ev[LC_EV_DRIVE_LOST], 0);
    unsigned nmt = 0, sdo[4] = {0};
    for (unsigned i = mark; i < io.nout; i++) {
        if (io.out[i].id == 0x000) {
            assert_int_equal(io.out[i].data[1], 2);
            nmt++;
        }
        if (io.out[i].id > 0x600 && io.out[i].id <= 0x603)
            sdo[io.out[i].id - 0x600]++;
    }
    assert_int_equal(nmt, 1);
    assert_int_equal(sdo[1] + sdo[3], 0);
    assert_int_equal(sdo[2], 1);                      /* its list again, from the first entry */
    assert_int_equal(rpdo(2, mark, NULL), INT32_MIN); /* not heard since: no target */
    tpdo(2, SOD, 1000);
    mark = io.nout;
    cycle(200, p, 1.0);
    int cw = -1;
    assert_int_equal(rpdo(2, mark, &cw), 1000);
    assert_int_equal(cw, 0x0000);
    cw = -1;
    rpdo(1, mark, &cw);
    assert_int_equal(cw, 0x000F);
}

/* Given a heartbeat consumer time of 100 ms and no 0x1017 in the list, then
 * trajd reads 0x1017 back; a drive at the CiA 301 default (0: no heartbeat)
 * is never watched; one that produces is watched from its first heartbeat. */
static void test_heartbeat_watch_armed(void **state)
{
    (void)state;
    for (int produces = 0; produces < 2; produces++) {
        new_port(0, 0);
        three_axes(1, 100);
        double p[3] = {0, 0, 0};
        unsigned mark = io.nout;
        cycle(0, p, 0);
        unsigned reads = 0;
        for (unsigned i = mark; i < io.nout; i++)
            if (io.out[i].id == 0x601 && io.out[i].data[0] == 0x40 && io.out[i].data[1] == 0x17 &&
                io.out[i].data[2] == 0x10)
                reads++;
        assert_int_equal(reads, 1);
        for (unsigned n = 1; n <= 3; n++)
            sdo_reply(n, 0x4B, 0x1017, 0, produces ? 20 : 0);
        cycle(50, p, 0);
        cycle(1000, p, 0); /* no heartbeat heard yet: not armed */
        assert_int_equal(obj.nhold, 0);
        heartbeat(1, 0x7F);
        cycle(1050, p, 0);
        cycle(1100, p, 0);
        cycle(1250, p, 0);
        assert_int_equal(obj.nhold, (unsigned)produces);
        assert_int_equal(obj.ev[LC_EV_HEARTBEAT_LOST], (unsigned)produces);
        heartbeat(1, 0x7F); /* heard again */
        cycle(1300, p, 0);
        assert_int_equal(obj.ev[LC_EV_HEARTBEAT_BACK], (unsigned)produces);
        free_port(NULL);
    }
}

/* Given a watched heartbeat (0x1017 in the list, 100 ms consumer) and 50 ms
 * cycles, when trajd itself stalls for 1 s (no cycle), then the heartbeats
 * are not judged lost; a drive that is really silent is, after the stall. */
static void test_heartbeat_stall_excused(void **state)
{
    (void)state;
    new_port(50000000, 0);
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_heartbeat_ms = 100;
    ids.cia402_sdo[0].index = 0x1017;
    ids.cia402_sdo[0].size = 2;
    ids.cia402_sdo[0].value = 20;
    ids.cia402_nsdo = 1;
    assert_int_equal(can_port_set_object(port, 0, &ids, &hooks, NULL), 0);
    double p[3] = {0, 0, 0};
    cycle(0, p, 0);
    sdo_reply(1, 0x60, 0x1017, 0, 0);
    heartbeat(1, 0x05);
    cycle(50, p, 0);
    cycle(1050, p, 0); /* a 1 s stall */
    assert_int_equal(obj.nhold, 0);
    cycle(1100, p, 0);
    cycle(1150, p, 0);
    cycle(1200, p, 0); /* 150 ms of looking without a heartbeat */
    assert_int_equal(obj.nhold, 1);
}

/* Given trajd's heartbeat node 127 at 100 ms, then 0x77F with state 0x05
 * (operational) goes out on the first cycle and every 100 ms. */
static void test_master_heartbeat(void **state)
{
    (void)state;
    new_port(0, 127);
    three_axes(0, 0);
    double p[3] = {0, 0, 0};
    unsigned n = 0;
    for (uint32_t k = 0; k < 10; k++) {
        unsigned mark = io.nout;
        cycle(50 * k, p, 0);
        for (unsigned i = mark; i < io.nout; i++)
            if (io.out[i].id == 0x77F) {
                assert_int_equal(io.out[i].len, 1);
                assert_int_equal(io.out[i].data[0], 0x05);
                n++;
            }
    }
    assert_int_equal(n, 5);
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_TARGETS;
    ids.cia402_cob_id[0] = 0x200 + 127; /* a drive on trajd's own node: refused */
    assert_int_equal(can_port_set_object(port, 0, &ids, &hooks, NULL), -CANPROTO_ECONFIG);
}

/* Given a drive that goes through three states between two looks, then every
 * change is kept, in order, with its statusword; a boot-up too. */
static void test_every_state_change_kept(void **state)
{
    (void)state;
    new_port(0, 0);
    three_axes(1, 0);
    tpdo(1, OE, 0);
    tpdo(1, 0x020F, 0); /* fault reaction active */
    tpdo(1, FAULT, 0);
    heartbeat(1, 0x00);
    can_port_rx(port, 0);
    can_axis_change_t c;
    uint64_t lost = 9;
    static const uint8_t want[][2] = {{CIA402_STATE_UNKNOWN, CIA402_OPERATION_ENABLED},
                                      {CIA402_OPERATION_ENABLED, CIA402_FAULT_REACTION},
                                      {CIA402_FAULT_REACTION, CIA402_FAULT},
                                      {CIA402_FAULT, CIA402_STATE_UNKNOWN}};
    for (unsigned k = 0; k < 4; k++) {
        assert_int_equal(can_port_drive_change(port, 0, &c, &lost), 1);
        assert_int_equal(c.from, want[k][0]);
        assert_int_equal(c.to, want[k][1]);
        assert_int_equal(c.node, 1);
        assert_int_equal(lost, 0);
    }
    assert_int_equal(can_port_drive_change(port, 0, &c, &lost), 0);
    for (unsigned k = 0; k < CAN_AXIS_LOG_MAX + 3; k++)
        tpdo(2, k % 2 ? OE : SOD, 0);
    can_port_rx(port, 0);
    unsigned n = 0;
    uint64_t dropped = 0;
    while (can_port_drive_change(port, 0, &c, &lost) && (dropped += lost, 1))
        n++;
    assert_int_equal(n, CAN_AXIS_LOG_MAX); /* the ring is full: the rest counted */
    assert_int_equal(dropped, 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_fault_mid_motion, free_port),
        cmocka_unit_test_teardown(test_clear_reanchors_each_axis_at_its_0x6064, free_port),
        cmocka_unit_test_teardown(test_clear_while_braking_keeps_axes_following, free_port),
        cmocka_unit_test_teardown(test_restart_adopts_running_drives, free_port),
        cmocka_unit_test_teardown(test_bootup_of_one_drive, free_port),
        cmocka_unit_test(test_heartbeat_watch_armed),
        cmocka_unit_test_teardown(test_heartbeat_stall_excused, free_port),
        cmocka_unit_test_teardown(test_master_heartbeat, free_port),
        cmocka_unit_test_teardown(test_every_state_change_kept, free_port),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
