/* test_can_port.c - the CAN side's behaviour under faults, on a fake transport
 * and a fake engine: queue full, interface down and back, late cycles,
 * flow control (EFULL), malformed/foreign frames, SYNC, status events; and
 * the candump-log transport on the real capture in tests/data. */
#include "test.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "candump.h"
#include "can_logfile.h"
#include "can_port.h"
#include "fake_can_io.h"

/* ---- fake transport: tests/helpers/fake_can_io.h ---- */

/* ---- fake engine ---- */
typedef struct {
    engine_waypoint_t got[256];
    unsigned n;
    int answer; /* what push returns */
    unsigned cmds[8];
    unsigned args[8];
    unsigned ncmd;
    int cmd_answer; /* what command returns (< 0: refused, as obj_command) */
    unsigned nhold; /* hold requests */
    uint32_t free_slots;
} fake_engine_t;

static int fe_push(void *ctx, const engine_waypoint_t *wp)
{
    fake_engine_t *e = ctx;
    if (e->answer == 0 && e->n < 256)
        e->got[e->n++] = *wp;
    return e->answer;
}

static int fe_command(void *ctx, canproto_cmd_t cmd, unsigned arg)
{
    fake_engine_t *e = ctx;
    if (e->ncmd < 8) {
        e->args[e->ncmd] = arg;
        e->cmds[e->ncmd++] = cmd;
    }
    return e->cmd_answer;
}

static void fe_drive_event(void *ctx, lc_event_t ev)
{
    if (ev != LC_EV_HEARTBEAT_BACK)
        ((fake_engine_t *)ctx)->nhold++;
}

static void fe_status(void *ctx, engine_status_t *st)
{
    fake_engine_t *e = ctx;
    st->state = ENGINE_STATE_STREAMING;
    st->last_seq = e->n ? e->got[e->n - 1].seq : 0;
    st->free = e->free_slots;
}

static can_port_drive_t fe_drive;
static unsigned fe_feedbacks;

static int fe_feedback(void *ctx, const can_port_drive_t *d)
{
    (void)ctx;
    fe_drive = *d;
    fe_feedbacks++;
    return 0;
}

static const can_port_hooks_t fe_hooks = {fe_push, fe_command, fe_status, fe_feedback,
                                          fe_drive_event};

static fake_can_io_t io;
static fake_engine_t eng;
static can_port_t *port;

static int setup(void **state)
{
    (void)state;
    can_port_config_t cfg;
    canproto_ids_t ids;
    fake_can_reset(&io);
    memset(&eng, 0, sizeof eng);
    eng.free_slots = 40;
    can_port_config_default(&cfg);
    cfg.sync = 1;
    cfg.sync_overflow = 3;
    cfg.status_period_ns = 0; /* status only on events (and the first) */
    cfg.max_late_ns = 500000;
    port = can_port_new(&cfg, &fake_can_ops, &io, 1);
    assert_non_null(port);
    canproto_ids_default(&ids, 0);
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    can_port_free(port);
    return 0;
}

static engine_setpoint_t sp_at(uint32_t cycle, double x)
{
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    sp.cycle = cycle;
    sp.pos_m[0] = x;
    sp.state = ENGINE_STATE_STREAMING;
    return sp;
}

static void run_cycle(uint32_t k, int64_t late_ns)
{
    engine_setpoint_t sp = sp_at(k, k * 0.001);
    can_port_setpoint(port, 0, &sp);
    can_port_cycle(port, (int64_t)k * 1000000, late_ns);
}

static unsigned count_id(uint32_t id)
{
    unsigned n = 0;
    for (unsigned i = 0; i < io.nout; i++)
        n += io.out[i].id == id;
    return n;
}

static void queue_waypoint(uint32_t seq, double t)
{
    engine_waypoint_t w = {.t_s = t, .pos_m = {t, -t, 0.5}, .seq = seq};
    assert_true(canproto_encode_waypoint(0x680, &w, &io.in[io.nin]) >= 0);
    io.nin += 4;
}

/* Given cycles with SYNC (overflow 3), then each cycle is SYNC then 3
 * setpoint frames, and the SYNC counter runs 1,2,3,1,... */
static void test_cycle_frames_and_sync(void **state)
{
    (void)state;
    for (uint32_t k = 0; k < 5; k++)
        run_cycle(k, 0);
    assert_int_equal(count_id(0x080), 5);
    assert_int_equal(count_id(0x6A0), 15);
    unsigned sync_seen = 0;
    const uint8_t expect[5] = {1, 2, 3, 1, 2};
    for (unsigned i = 0; i < io.nout; i++)
        if (io.out[i].id == 0x080) {
            assert_int_equal(io.out[i].len, 1);
            assert_int_equal(io.out[i].data[0], expect[sync_seen]);
            /* the three setpoint frames of this cycle follow the SYNC */
            for (unsigned a = 0; a < 3; a++)
                assert_int_equal(io.out[i + 1 + a].id, 0x6A0);
            sync_seen++;
        }
    assert_int_equal(count_id(0x6C0), 1); /* first status only (period 0) */
}

/* Given the TX queue full (ENOBUFS) for 3 cycles, then those setpoints are
 * dropped and counted, and the next cycle sends only its own frames (no burst). */
static void test_queue_full_drops_no_burst(void **state)
{
    (void)state;
    run_cycle(0, 0);
    unsigned before = count_id(0x6A0);
    io.fail_with = -ENOBUFS;
    for (uint32_t k = 1; k <= 3; k++)
        run_cycle(k, 0);
    io.fail_with = 0;
    run_cycle(4, 0);
    assert_int_equal(count_id(0x6A0) - before, 3);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.dropped_full, 3);
    assert_int_equal(st.setpoints_sent, 2);
    /* the frames after the gap carry cycle 4 (not 1) */
    canproto_setpoint_t d;
    for (unsigned i = 0; i < io.nout; i++)
        if (io.out[i].id == 0x6A0) {
            assert_int_equal(canproto_decode_setpoint(&io.out[i], &d), 0);
            assert_true(d.cycle == 0 || d.cycle == 4);
        }
    /* the STATUS after recovery reports the drops */
    canproto_status_t s;
    unsigned last = 0;
    for (unsigned i = 0; i < io.nout; i++)
        if (io.out[i].id == 0x6C0)
            last = i;
    assert_int_equal(canproto_decode_status(&io.out[last], &s), 0);
    (void)s;
}

/* Given a transmit queue that stays full, one slot freed between 10 ms cycles
 * (a slow qdisc: tests/uml/daemon.sh phase D), then the SYNC written first in
 * each cycle would take every slot; a STATUS starved for its period (100 ms)
 * goes first instead, so the operator sees the drops at least every 200 ms,
 * and SYNC keeps the other slots. */
static void test_queue_full_status_not_starved(void **state)
{
    (void)state;
    can_port_config_t cfg;
    canproto_ids_t ids;
    can_port_free(port);
    can_port_config_default(&cfg);
    cfg.sync = 1;
    cfg.status_period_ns = 100000000LL;
    port = can_port_new(&cfg, &fake_can_ops, &io, 1);
    assert_non_null(port);
    canproto_ids_default(&ids, 0);
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    io.room_limited = 1;
    for (uint32_t k = 0; k < 100; k++) { /* 1 s */
        io.room = 1;
        engine_setpoint_t sp = sp_at(k, k * 0.001);
        can_port_setpoint(port, 0, &sp);
        can_port_cycle(port, (int64_t)k * 10000000, 0);
    }
    unsigned last = 0, nst = 0, with_drop = 0;
    for (unsigned i = 0; i < io.nout; i++) {
        if (io.out[i].id != 0x6C0)
            continue;
        canproto_status_t s;
        assert_int_equal(canproto_decode_status(&io.out[i], &s), 0);
        with_drop += (s.flags & CANPROTO_ST_TX_DROP) != 0;
        if (nst)
            assert_true(i - last <= 20); /* frames are one a cycle here */
        last = i;
        nst++;
    }
    assert_int_equal(io.nout, 100);
    assert_true(nst >= 5);
    assert_true(with_drop >= nst - 1); /* all but maybe the first report the drops */
    assert_true(count_id(0x080) >= 100 - nst);
}

/* The same queue with 40 objects on the port: one starved STATUS at most
 * goes ahead of SYNC each 100 ms, the objects in turn, so each reports within
 * 5 s (the last ones too) and SYNC keeps 9 slots of 10. */
static void test_queue_full_status_not_starved_many(void **state)
{
    (void)state;
    enum { NOBJ = 40 };
    can_port_config_t cfg;
    can_port_free(port);
    can_port_config_default(&cfg);
    cfg.sync = 1;
    port = can_port_new(&cfg, &fake_can_ops, &io, NOBJ);
    assert_non_null(port);
    for (unsigned i = 0; i < NOBJ; i++) { /* (the default ids clash from 16 objects on) */
        canproto_ids_t ids;
        canproto_ids_default(&ids, 0);
        ids.waypoint_id = 0x100 + i, ids.waypoint_fd_id = 0x140 + i;
        ids.setpoint_id = 0x200 + i, ids.setpoint_fd_id = 0x240 + i;
        ids.status_id = 0x300 + i, ids.status2_id = 0x400 + i;
        memset(ids.cia402_cob_id, 0, sizeof ids.cia402_cob_id);
        assert_int_equal(can_port_set_object(port, i, &ids, &fe_hooks, &eng), 0);
    }
    io.room_limited = 1;
    for (uint32_t k = 0; k < 500; k++) {
        io.room = 1;
        for (unsigned i = 0; i < NOBJ; i++) {
            engine_setpoint_t sp = sp_at(k, k * 0.001);
            can_port_setpoint(port, i, &sp);
        }
        can_port_cycle(port, (int64_t)k * 10000000, 0);
    }
    for (unsigned i = 0; i < NOBJ; i++)
        assert_true(count_id(0x300 + i) >= 1);
    assert_true(count_id(0x080) >= 450 - 1);
}

/* Given the interface down for 5 cycles and then back (maintain reopens),
 * then nothing is sent while down, drops are counted as down, and the first
 * cycle after has exactly one setpoint and a STATUS flagging the outage. */
static void test_down_and_back(void **state)
{
    (void)state;
    run_cycle(0, 0);
    io.up = 0;
    unsigned n0 = io.nout;
    for (uint32_t k = 1; k <= 5; k++) {
        assert_int_equal(can_port_maintain(port, (int64_t)k * 1000000), 0);
        run_cycle(k, 0);
    }
    assert_int_equal(io.nout, n0);
    io.reopen_ok = 1;
    assert_int_equal(can_port_maintain(port, 6000000), 1);
    run_cycle(6, 0);
    assert_int_equal(count_id(0x6A0), 6);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.dropped_down, 5);
    assert_int_equal(st.dropped_pos, 5); /* each carried a position: trajd exits 74 */
    can_port_stats_t ps;
    can_port_stats(port, &ps);
    assert_int_equal(ps.down_cycles, 5);
    assert_int_equal(ps.reopens, 1);
    assert_int_equal(ps.dropped_pos, 5); /* the port's sum, for the exit status */
    can_port_reset_counters(port, 0);    /* an operator's reset leaves the port's sum */
    can_port_stats(port, &ps);
    assert_int_equal(ps.dropped_pos, 5);
    /* the status right after recovery says: bus was down, setpoints dropped */
    canproto_status_t s;
    assert_int_equal(io.out[io.nout - 1].id, 0x6C0);
    assert_int_equal(canproto_decode_status(&io.out[io.nout - 1], &s), 0);
    assert_true(s.flags & CANPROTO_ST_BUS_DOWN);
    assert_true(s.flags & CANPROTO_ST_TX_DROP);
    assert_int_equal(s.dropped, 5);
    assert_int_equal(s.last_err, CANPROTO_STERR_BUS_DOWN);
}

/* Given a cycle run later than max_late_ns, then its own frames are not sent
 * (counted), its SYNC is. */
static void test_late_cycle_dropped(void **state)
{
    (void)state;
    run_cycle(0, 0);
    run_cycle(1, 2000000);
    run_cycle(2, 100000);
    assert_int_equal(count_id(0x6A0), 6);
    /* the late cycle still has its SYNC: a drive faults on missing ones */
    assert_int_equal(count_id(0x080), 3);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.dropped_late, 1);
}

/* Given a CiA 402 object, when setpoints have no position yet, then no RPDO
 * is sent (a drive would follow it) and the own frames carry the n/a marker;
 * when a late cycle comes, SYNC and the RPDOs still go out, the own frames
 * do not (counted). */
static void test_cia402_no_position_and_late(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_TARGETS;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    engine_setpoint_t sp = sp_at(0, NAN);
    sp.pos_m[1] = sp.pos_m[2] = NAN;
    sp.state = ENGINE_STATE_WAITING;
    sp.flags = ENGINE_SP_NO_POSITION;
    can_port_setpoint(port, 0, &sp);
    can_port_cycle(port, 0, 0);
    assert_int_equal(count_id(0x080), 1);
    assert_int_equal(count_id(0x201) + count_id(0x202) + count_id(0x203), 0);
    assert_int_equal(count_id(0x6A0), 3);
    for (unsigned i = 0; i < io.nout; i++)
        if (io.out[i].id == 0x6A0) {
            canproto_setpoint_t d;
            assert_int_equal(canproto_decode_setpoint(&io.out[i], &d), 0);
            assert_true(d.flags & ENGINE_SP_NO_POSITION);
            assert_true(d.flags & ENGINE_SP_HOLD);
            assert_true(isnan(d.pos_m[d.axis]));
            /* raw field: int32 0x80000000 */
            assert_int_equal(io.out[i].data[2] | io.out[i].data[3] | io.out[i].data[4], 0);
            assert_int_equal(io.out[i].data[5], 0x80);
        }
    run_cycle(1, 0);
    assert_int_equal(count_id(0x201), 1);
    run_cycle(2, 2000000); /* later than max_late_ns (0.5 ms) */
    assert_int_equal(count_id(0x080), 3);
    assert_int_equal(count_id(0x201), 2);
    assert_int_equal(count_id(0x6A0), 6);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.dropped_late, 1);
    assert_int_equal(st.dropped_pos, 1);
    /* a cycle not sent while the object has no position (the n/a marker)
     * lost no motion: counted as not sent, not as motion missed */
    sp.flags = ENGINE_SP_NO_POSITION;
    can_port_setpoint(port, 0, &sp);
    can_port_cycle(port, 3000000, 2000000);
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.dropped_late, 2);
    assert_int_equal(st.dropped_pos, 1);
}

static void queue_tpdo(uint32_t id, uint16_t sw, int32_t pos)
{
    canproto_frame_t *f = &io.in[io.nin++];
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = 6;
    f->data[0] = (uint8_t)sw;
    f->data[1] = (uint8_t)(sw >> 8);
    for (int i = 0; i < 4; i++)
        f->data[2 + i] = (uint8_t)((uint32_t)pos >> (8 * i));
}

/* Given a drive on axis x with feedback (TPDO 0x180 + node 1), inverted, then
 * its statusword gives the state (CiA 402 patterns), its position actual
 * value the position in metres, Operation Enabled is reported once seen, and
 * leaving it (fault) is counted and reported in STATUS (0x47); with another
 * TPDO COB-ID configured, feedback is read there and no longer on 0x181. */
static void test_cia402_feedback(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_FEEDBACK;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_invert[0] = 1;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    uint32_t rx[8]; /* the ids the transport lets through (can_transport.c set_objects) */
    unsigned n = canproto_ids_rx(&ids, rx, 8);
    assert_int_equal(n, 2);
    assert_int_equal(rx[1], 0x181);
    fe_feedbacks = 0;
    queue_tpdo(0x181, 0x0250, 12345);  /* switch on disabled */
    queue_tpdo(0x181, 0x0637, -20000); /* operation enabled, at +2 m (inverted) */
    assert_int_equal(can_port_rx(port, 0), 2);
    assert_int_equal(fe_feedbacks, 2);
    assert_int_equal(fe_drive.state[0], CIA402_OPERATION_ENABLED);
    assert_true(fe_drive.all_seen && fe_drive.all_enabled && !fe_drive.was_enabled);
    assert_true(fabs(fe_drive.pos_m[0] - 2.0) < 1e-12);
    queue_tpdo(0x181, 0x0218, -20000); /* fault */
    queue_tpdo(0x181, 0x02, 0);        /* too short: 1 byte */
    io.in[io.nin - 1].len = 1;
    assert_int_equal(can_port_rx(port, 0), 2);
    assert_int_equal(fe_drive.state[0], CIA402_FAULT);
    assert_true(fe_drive.was_enabled && !fe_drive.all_enabled);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.drive_frames, 3);
    assert_int_equal(st.drive_lost, 1);
    assert_int_equal(st.drive_bad, 1);

    /* a TPDO COB-ID other than 0x180 + node (can.cia402_tpdo_x): listened to
     * there, and 0x181 is no longer the drive's */
    ids.cia402_tpdo_id[0] = 0x285;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    n = canproto_ids_rx(&ids, rx, 8);
    assert_int_equal(n, 2);
    assert_int_equal(rx[1], 0x285);
    fe_feedbacks = 0;
    queue_tpdo(0x181, 0x0637, -30000);
    can_port_rx(port, 0);
    assert_int_equal(fe_feedbacks, 0);
    queue_tpdo(0x285, 0x0637, -30000); /* operation enabled, at +3 m (inverted) */
    can_port_rx(port, 0);
    assert_int_equal(fe_feedbacks, 1);
    assert_int_equal(fe_drive.state[0], CIA402_OPERATION_ENABLED);
    assert_true(fabs(fe_drive.pos_m[0] - 3.0) < 1e-12);
}

static void queue_sdo_reply(uint8_t node, uint8_t cs, uint16_t index, uint32_t abort_code)
{
    canproto_frame_t *f = &io.in[io.nin++];
    memset(f, 0, sizeof *f);
    f->id = 0x580u + node;
    f->len = 8;
    f->data[0] = cs;
    f->data[1] = (uint8_t)index;
    f->data[2] = (uint8_t)(index >> 8);
    for (int i = 0; i < 4; i++)
        f->data[4 + i] = (uint8_t)(abort_code >> (8 * i));
}

/* The last SDO download sent to node: index and value, or -1 if none since mark. */
static long last_sdo(uint8_t node, unsigned mark, uint16_t *index)
{
    long v = -1;
    for (unsigned i = mark; i < io.nout; i++)
        if (io.out[i].id == 0x600u + node) {
            *index = (uint16_t)(io.out[i].data[1] | io.out[i].data[2] << 8);
            v = (long)(io.out[i].data[4] | io.out[i].data[5] << 8);
        }
    return v;
}

/* One step: the drive reports statusword sw and 0x6064 = inc; trajd's next
 * cycle writes the controlword it answers with (returned; -1: none), and the
 * drive acknowledges it. */
static long step_drive_at(uint16_t sw, int32_t inc, uint32_t k)
{
    uint16_t index = 0;
    queue_tpdo(0x181, sw, inc);
    can_port_rx(port, 0);
    unsigned mark = io.nout;
    run_cycle(k, 0);
    long cw = last_sdo(1, mark, &index);
    if (cw >= 0) {
        assert_int_equal(index, 0x6040);
        queue_sdo_reply(1, 0x60, 0x6040, 0);
        can_port_rx(port, 0);
    }
    return cw;
}

/* step_drive_at with the drive at 0x6064 = 0. */
static long step_drive(uint16_t sw, uint32_t k)
{
    return step_drive_at(sw, 0, k);
}

/* Node 1's heartbeat (operational), then the drive through Switch on disabled,
 * Ready to switch on and Switched on (steps 1..3). */
static void heartbeat_to_switched_on(void)
{
    io.in[io.nin] = (canproto_frame_t){.id = 0x701, .len = 1, .data = {0x05}};
    io.nin++;
    can_port_rx(port, 0);
    step_drive(0x0250, 1);
    step_drive(0x0231, 2);
    step_drive(0x0233, 3);
}

/* Given CiA 402 managed with one configuration SDO (0x6060 = 8), then trajd
 * starts the node (NMT), writes the SDO, and drives the controlword from the
 * statusword: Shutdown, Switch on, Enable operation (CiA 402 patterns); a
 * drive fault gets Disable voltage and stays so until CLEAR, which resets it
 * on a rising edge of bit 7. */
static void test_cia402_bring_up(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_sdo[0].index = 0x6060;
    ids.cia402_sdo[0].sub = 0;
    ids.cia402_sdo[0].size = 1;
    ids.cia402_sdo[0].value = 8;
    ids.cia402_nsdo = 1;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    run_cycle(0, 0);
    assert_int_equal(count_id(0x000), 1); /* NMT start node 1 */
    for (unsigned i = 0; i < io.nout; i++)
        if (io.out[i].id == 0)
            assert_true(io.out[i].len == 2 && io.out[i].data[0] == 0x01 && io.out[i].data[1] == 1);
    uint16_t index = 0;
    assert_int_equal(last_sdo(1, 0, &index), 8);
    assert_int_equal(index, 0x6060);
    queue_sdo_reply(1, 0x60, 0x6060, 0);
    can_port_rx(port, 0);
    assert_int_equal(step_drive(0x0250, 1), 0x0006); /* switch on disabled -> shutdown */
    assert_int_equal(step_drive(0x0231, 2), 0x0007); /* ready -> switch on */
    assert_int_equal(step_drive(0x0233, 3), 0x000F); /* switched on -> enable operation */
    assert_int_equal(step_drive(0x0237, 4), -1);     /* enabled: nothing more to write */
    assert_true(fe_drive.all_enabled);
    assert_int_equal(step_drive(0x0218, 5), 0x0000); /* fault: disable voltage, held */
    assert_true(fe_drive.held);
    assert_int_equal(step_drive(0x0218, 6), -1); /* no reset without the operator */
    canproto_frame_t clr;
    assert_int_equal(canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &clr), 0);
    io.in[io.nin++] = clr;
    assert_int_equal(step_drive(0x0218, 7), 0x0080); /* rising edge of bit 7 */
    assert_int_equal(step_drive(0x0250, 8), 0x0006); /* and the sequence again */
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.drive_lost, 1);
    assert_int_equal(st.sdo_aborts, 0);
}

/* The controlword of the last RPDO (6 bytes: controlword, target) to node 1, -1 if none since mark. */
static long last_rpdo_cw(unsigned mark)
{
    long v = -1;
    for (unsigned i = mark; i < io.nout; i++)
        if (io.out[i].id == 0x201 && io.out[i].len == 6)
            v = (long)(io.out[i].data[0] | io.out[i].data[1] << 8);
    return v;
}

static void enable_with_controlword_rpdo(void)
{
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_controlword = 1;
    ids.cia402_heartbeat_ms = 100;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_sdo[0].index = 0x1017;
    ids.cia402_sdo[0].size = 2;
    ids.cia402_sdo[0].value = 20;
    ids.cia402_nsdo = 1; /* the producer time set: its heartbeat is watched */
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    unsigned mark = io.nout;
    run_cycle(0, 0);
    uint16_t index = 0;
    assert_int_equal(last_sdo(1, mark, &index), 20);
    assert_int_equal(index, 0x1017);
    queue_sdo_reply(1, 0x60, 0x1017, 0);
    can_port_rx(port, 0);
}

/* Given CiA 402 managed with the controlword in the RPDO, then the RPDO carries
 * the command the bring-up last wrote by SDO, never a fixed Enable operation:
 * Disable voltage before the drive is enabled, Enable operation once it is,
 * Disable voltage again after a fault and for a drive in quick stop (which
 * would take Enable operation as transition 16 and move again). */
static void test_cia402_rpdo_controlword_follows_bring_up(void **state)
{
    (void)state;
    enable_with_controlword_rpdo();
    unsigned mark = io.nout;
    run_cycle(0, 0);
    assert_int_equal(last_rpdo_cw(mark), -1); /* the drive not heard yet: no RPDO */
    mark = io.nout;
    assert_int_equal(step_drive(0x0250, 1), 0x0006);
    assert_int_equal(last_rpdo_cw(mark), 0x0006);
    assert_int_equal(step_drive(0x0231, 2), 0x0007);
    mark = io.nout;
    assert_int_equal(step_drive(0x0233, 3), 0x000F);
    assert_int_equal(last_rpdo_cw(mark), 0x000F);
    mark = io.nout;
    assert_int_equal(step_drive(0x0207, 4), 0x0000); /* quick stop active: disable voltage */
    assert_int_equal(last_rpdo_cw(mark), 0x0000);
    mark = io.nout;
    run_cycle(5, 0);
    assert_int_equal(last_rpdo_cw(mark), 0x0000); /* held until clear */
}

/* Given a drive that quick-stops while it moves (a local input: it brakes by
 * its own ramp), then trajd keeps it in quick stop (controlword Quick stop,
 * 0x0002, in the SDO and the RPDO) while its 0x6064 still moves, and sends
 * Disable voltage (transition 12) only once it stands still (3 feedbacks
 * unchanged); Disable voltage at once cut the ramp and the axis coasted
 * (0.05-0.09 m, probe N). */
static void test_cia402_quick_stop_ramp_kept(void **state)
{
    (void)state;
    enable_with_controlword_rpdo();
    run_cycle(0, 0);
    assert_int_equal(step_drive_at(0x0250, 0, 1), 0x0006);
    assert_int_equal(step_drive_at(0x0231, 0, 2), 0x0007);
    assert_int_equal(step_drive_at(0x0233, 0, 3), 0x000F);
    assert_int_equal(step_drive_at(0x0237, 100, 4), -1); /* moving, enabled */
    assert_int_equal(step_drive_at(0x0237, 300, 5), -1);
    unsigned mark = io.nout;
    assert_int_equal(step_drive_at(0x0207, 450, 6), 0x0002); /* quick stop, still moving */
    assert_int_equal(last_rpdo_cw(mark), 0x0002);
    assert_int_equal(step_drive_at(0x0207, 540, 7), -1); /* kept in it while it brakes */
    assert_int_equal(step_drive_at(0x0207, 570, 8), -1);
    assert_int_equal(step_drive_at(0x0207, 570, 9), -1);
    assert_int_equal(step_drive_at(0x0207, 570, 10), -1);
    mark = io.nout;
    assert_int_equal(step_drive_at(0x0207, 570, 11), 0x0000); /* at rest: transition 12 */
    assert_int_equal(last_rpdo_cw(mark), 0x0000);
}

/* Given an SDO request resent after no answer, when the late answer to the
 * first and then the answer to the resent one arrive, then only the one for
 * the request in flight counts: the second does not acknowledge the next
 * request (a different object) before its own answer came. */
static void test_cia402_sdo_stale_reply_ignored(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_sdo[0].index = 0x6060;
    ids.cia402_sdo[0].size = 1;
    ids.cia402_sdo[0].value = 8;
    ids.cia402_sdo[1].index = 0x60C2;
    ids.cia402_sdo[1].sub = 1;
    ids.cia402_sdo[1].size = 1;
    ids.cia402_sdo[1].value = 10;
    ids.cia402_nsdo = 2;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    uint16_t index = 0;
    run_cycle(0, 0);
    assert_int_equal(last_sdo(1, 0, &index), 8);
    run_cycle(1000, 0); /* 1 s later: resent */
    queue_sdo_reply(1, 0x60, 0x6060, 0);
    can_port_rx(port, 0);
    unsigned mark = io.nout;
    run_cycle(1001, 0);
    assert_int_equal(last_sdo(1, mark, &index), 10);
    assert_int_equal(index, 0x60C2);
    queue_sdo_reply(1, 0x60, 0x6060, 0); /* the answer to the resent 0x6060 */
    can_port_rx(port, 0);
    queue_tpdo(0x181, 0x0250, 0);
    can_port_rx(port, 0);
    mark = io.nout;
    run_cycle(1002, 0);
    assert_int_equal(last_sdo(1, mark, &index), -1); /* still waiting for 0x60C2 */
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.sdo_stale, 1);
    assert_int_equal(st.sdo_timeouts, 1);
}

/* Given a drive going through bring-up, fault and heartbeat loss, then STATUS2
 * page 4 (decoded by canproto_decode_status2_drive) says its state, the
 * statusword, the NMT state of its heartbeat, held, heartbeat lost and the
 * last EMCY code; it is sent at once when it changes. */
static void test_cia402_status2_drive_page(void **state)
{
    (void)state;
    enable_with_controlword_rpdo();
    canproto_status2_drive_t d;
    heartbeat_to_switched_on();
    step_drive(0x0237, 4);
    unsigned mark = io.nout;
    io.in[io.nin] = (canproto_frame_t){.id = 0x081, .len = 8, .data = {0x11, 0x86, 0x01}};
    io.nin++;
    step_drive(0x0218, 5);
    int found = 0;
    for (unsigned i = mark; i < io.nout; i++)
        if (io.out[i].id == 0x6D0) {
            assert_int_equal(canproto_decode_status2_drive(&io.out[i], &d), 0);
            found = 1;
        }
    assert_true(found);
    assert_int_equal(d.state[0], CIA402_FAULT);
    assert_int_equal(d.state[1], CANPROTO_S2_NO_DRIVE);
    assert_int_equal(d.state[2], CANPROTO_S2_NO_DRIVE);
    assert_int_equal(d.statusword, 0x0218);
    assert_int_equal(d.nmt, 0x05);
    assert_int_equal(d.emcy, 0x8611);
    assert_true(d.held);
    assert_false(d.hb_lost);
    /* no heartbeat for longer than cia402_heartbeat_ms (100 ms): lost */
    mark = io.nout;
    run_cycle(500, 0);
    found = 0;
    for (unsigned i = mark; i < io.nout; i++)
        if (io.out[i].id == 0x6D0 && canproto_decode_status2_drive(&io.out[i], &d) == 0)
            found = 1;
    assert_true(found && d.hb_lost);
    canproto_status2_drive_t s;
    assert_int_equal(can_port_drive_summary(port, 0, &s), 1);
    assert_memory_equal(&s, &d, sizeof s);
    /* another page is not page 4 */
    canproto_frame_t other = io.out[io.nout - 1];
    other.data[0] = CANPROTO_ST2_BUS;
    assert_int_equal(canproto_decode_status2_drive(&other, &d), -CANPROTO_EMUX);
}

/* Given a drive with a heartbeat consumer (100 ms) whose heartbeat stops,
 * then the object is asked once to hold (obj_hold: feed override 0, a
 * controlled stop along the path by the time scaling); a command the object
 * refuses (an override while held) is counted as refused, and a CLEAR
 * (which releases the object's hold) passes. */
static void test_cia402_heartbeat_lost_holds(void **state)
{
    (void)state;
    enable_with_controlword_rpdo();
    heartbeat_to_switched_on();
    eng.ncmd = 0;
    run_cycle(50, 0);
    assert_int_equal(eng.nhold, 0); /* heard 50 ms ago: fine */
    run_cycle(500, 0);
    assert_int_equal(eng.nhold, 1);
    run_cycle(600, 0);
    assert_int_equal(eng.nhold, 1); /* once */
    assert_int_equal(eng.ncmd, 0);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.heartbeat_lost, 1);
    canproto_frame_t f;
    assert_int_equal(canproto_encode_override(0x680, 100, &f), 0);
    io.in[io.nin++] = f;
    eng.cmd_answer = -ENGINE_ESTATE; /* the held object refuses it */
    can_port_rx(port, 0);
    assert_int_equal(eng.ncmd, 1);
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.cmd_refused, 1);
    assert_int_equal(st.last_refused, CANPROTO_CMD_OVERRIDE);
    eng.cmd_answer = 0;
    assert_int_equal(canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &f), 0);
    io.in[io.nin++] = f;
    can_port_rx(port, 0);
    assert_int_equal(eng.ncmd, 2);
    assert_int_equal(eng.cmds[1], CANPROTO_CMD_CLEAR);
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.cmd_refused, 1);
}

/* Given the drive refuses the configuration SDO, then the abort is counted
 * with its code and the drive is never enabled. */
static void test_cia402_sdo_abort(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_MANAGED;
    ids.cia402_cob_id[1] = ids.cia402_cob_id[2] = 0;
    ids.cia402_sdo[0].index = 0x6060;
    ids.cia402_sdo[0].size = 1;
    ids.cia402_sdo[0].value = 8;
    ids.cia402_nsdo = 1;
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    run_cycle(0, 0);
    queue_sdo_reply(1, 0x80, 0x6060, 0x06020000);
    can_port_rx(port, 0);
    assert_int_equal(step_drive(0x0250, 1), 0x0000); /* stays disabled */
    assert_int_equal(step_drive(0x0250, 2), -1);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.sdo_aborts, 1);
    assert_int_equal(st.last_abort, 0x06020000);
    assert_int_equal(st.last_abort_index, 0x6060);
}

/* Given waypoints with a gap, a duplicate, a malformed and a foreign frame,
 * then the engine gets each good waypoint once, and STATUS reports the loss
 * and the malformed frame. */
static void test_rx_paths(void **state)
{
    (void)state;
    queue_waypoint(1, 1.0);
    queue_waypoint(2, 2.0);
    queue_waypoint(2, 2.0); /* duplicate */
    queue_waypoint(5, 5.0); /* 3 and 4 lost */
    canproto_frame_t *bad = &io.in[io.nin++];
    memset(bad, 0, sizeof *bad);
    bad->id = 0x680;
    bad->len = 3; /* malformed */
    canproto_frame_t *foreign = &io.in[io.nin++];
    memset(foreign, 0, sizeof *foreign);
    foreign->id = 0x123;
    foreign->len = 1;
    assert_int_equal(can_port_rx(port, 0), (int)io.nin);
    assert_int_equal(eng.n, 3);
    assert_int_equal(eng.got[2].seq, 5);
    assert_true(fabs(eng.got[1].pos_m[1] + 2.0) < 1e-9);
    can_port_stats_t ps;
    can_port_stats(port, &ps);
    assert_int_equal(ps.rx_foreign, 1);
    run_cycle(0, 0);
    canproto_status_t s;
    assert_int_equal(io.out[io.nout - 1].id, 0x6C0);
    canproto_decode_status(&io.out[io.nout - 1], &s);
    assert_int_equal(s.lost, 2);
    assert_int_equal(s.malformed, 1);
    assert_int_equal(s.last_seq, 5);
    assert_int_equal(s.free, 40);
    assert_int_equal(s.last_err, CANPROTO_STERR_MALFORMED);
}

/* Given the engine full (EFULL), then the waypoint is not consumed, STATUS
 * says error EFULL without counting it as rejected (flow control, not bad
 * data: issue 11), and the sender's repeat is accepted. */
static void test_flow_control_efull(void **state)
{
    (void)state;
    queue_waypoint(1, 1.0);
    eng.answer = -ENGINE_EFULL;
    can_port_rx(port, 0);
    assert_int_equal(eng.n, 0);
    run_cycle(0, 0);
    canproto_status_t s;
    canproto_decode_status(&io.out[io.nout - 1], &s);
    assert_int_equal(s.rejected, 0);
    assert_int_equal(s.last_err, ENGINE_EFULL);
    eng.answer = 0;
    queue_waypoint(1, 1.0); /* the sender repeats */
    can_port_rx(port, 0);
    assert_int_equal(eng.n, 1);
    can_port_obj_stats_t st;
    can_port_obj_stats(port, 0, &st);
    assert_int_equal(st.rx.lost, 0);
}

/* Given a sender that restarted its numbering (seq 1 after 10, its time
 * later), over a reload (can_port_keep into a new port, can_port_restore),
 * then the history went over: seq 0 older than the last is still out of
 * order, seq 1 later is taken as a resync and seq 2 follows it, nothing lost;
 * the engine sees the extended number go on forward (low 8 bits the wire's),
 * and STATUS shows the sender its own number. */
static void test_resync_kept_over_reload(void **state)
{
    (void)state;
    queue_waypoint(9, 0.9);
    queue_waypoint(10, 1.0);
    can_port_rx(port, 0);
    assert_int_equal(eng.n, 2);
    can_port_kept_t k;
    can_port_keep(port, 0, &k);
    can_port_free(port);
    can_port_config_t cfg;
    canproto_ids_t ids;
    can_port_config_default(&cfg);
    cfg.status_period_ns = 0;
    port = can_port_new(&cfg, &fake_can_ops, &io, 1);
    assert_non_null(port);
    canproto_ids_default(&ids, 0);
    assert_int_equal(can_port_set_object(port, 0, &ids, &fe_hooks, &eng), 0);
    can_port_restore(port, 0, &k);
    queue_waypoint(0, 0.5); /* behind and older: a late one */
    queue_waypoint(1, 2.0); /* behind and later: the sender restarted */
    queue_waypoint(2, 2.1);
    can_port_rx(port, 0);
    assert_int_equal(eng.n, 4);
    assert_int_equal(eng.got[2].seq & 0xFF, 1);
    assert_true(eng.got[2].seq > 10);
    assert_int_equal(eng.got[3].seq, eng.got[2].seq + 1);
    can_port_obj_stats_t os;
    can_port_obj_stats(port, 0, &os);
    assert_int_equal(os.rx.resyncs, 1);
    assert_int_equal(os.rx.resync_seq, 1);
    assert_int_equal(os.rx.resync_after, 10);
    assert_int_equal(os.rx.out_of_order, CANPROTO_WP_PARTS);
    assert_int_equal(os.rx.lost, 0);
    assert_int_equal(os.waypoints_accepted, 4);
    run_cycle(0, 0);
    canproto_status_t s;
    assert_int_equal(io.out[io.nout - 1].id, 0x6C0);
    canproto_decode_status(&io.out[io.nout - 1], &s);
    assert_int_equal(s.last_seq, 2);
    assert_int_equal(s.lost, 0);
}

/* Given the object's csv/stdout output losing lines (disk full), then the
 * next STATUS goes out at once with the OUT_FAULT flag and error OUTPUT; a
 * later STATUS with nothing new lost has the flag clear again. */
static void test_output_fault_in_status(void **state)
{
    (void)state;
    canproto_status_t s;
    run_cycle(0, 0); /* the first STATUS */
    unsigned before = count_id(0x6C0);
    can_port_output_fault(port, 0, 3, 1);
    run_cycle(1, 0);
    assert_int_equal(count_id(0x6C0), before + 1);
    canproto_decode_status(&io.out[io.nout - 1], &s);
    assert_true(s.flags & CANPROTO_ST_OUT_FAULT);
    assert_int_equal(s.last_err, CANPROTO_STERR_OUTPUT);
    can_port_output_fault(port, 0, 3, 1); /* nothing new */
    run_cycle(2, 0);
    assert_int_equal(count_id(0x6C0), before + 1);
    can_port_output_fault(port, 0, 4, 1); /* one more line lost */
    run_cycle(3, 0);
    assert_int_equal(count_id(0x6C0), before + 2);
    canproto_decode_status(&io.out[io.nout - 1], &s);
    assert_true(s.flags & CANPROTO_ST_OUT_FAULT);
}

/* Given commands, then the hook sees them with their argument (OVERRIDE's
 * percent); CLEAR restarts sequence numbering. */
static void test_commands(void **state)
{
    (void)state;
    queue_waypoint(10, 1.0);
    canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &io.in[io.nin++]);
    queue_waypoint(0, 0.5); /* would be "out of order" without the restart */
    assert_int_equal(canproto_encode_override(0x680, 150, &io.in[io.nin++]), 0);
    can_port_rx(port, 0);
    assert_int_equal(eng.ncmd, 2);
    assert_int_equal(eng.cmds[0], CANPROTO_CMD_CLEAR);
    assert_int_equal(eng.args[0], 0);
    assert_int_equal(eng.cmds[1], CANPROTO_CMD_OVERRIDE);
    assert_int_equal(eng.args[1], 150);
    assert_int_equal(eng.n, 2);
}

/* Given an object that obeys only FINISH (a CAN input with writable = no),
 * when CLEAR, STOP, OVERRIDE and FINISH arrive, then only FINISH reaches the
 * hook; the three others are counted with the last one's command and id,
 * STATUS goes out at once with last_err REFUSED, and the refused CLEAR did
 * not restart sequence numbering (seq 0 after 10 is out of order). */
static void test_commands_refused(void **state)
{
    (void)state;
    can_port_obj_stats_t os;
    canproto_status_t s;
    can_port_allow_commands(port, 0, 1u << CANPROTO_CMD_FINISH);
    run_cycle(0, 0); /* the first STATUS */
    unsigned before = count_id(0x6C0);
    queue_waypoint(10, 1.0);
    canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &io.in[io.nin++]);
    canproto_encode_command(0x680, CANPROTO_CMD_STOP, &io.in[io.nin++]);
    assert_int_equal(canproto_encode_override(0x680, 50, &io.in[io.nin++]), 0);
    canproto_encode_command(0x680, CANPROTO_CMD_FINISH, &io.in[io.nin++]);
    queue_waypoint(0, 0.5);
    can_port_rx(port, 0);
    assert_int_equal(eng.ncmd, 1);
    assert_int_equal(eng.cmds[0], CANPROTO_CMD_FINISH);
    can_port_obj_stats(port, 0, &os);
    assert_int_equal(os.cmd_refused, 3);
    assert_int_equal(os.last_refused, CANPROTO_CMD_OVERRIDE);
    assert_int_equal(os.last_refused_id, 0x680);
    assert_int_equal(eng.n, 1); /* seq 0 after 10: out of order, not a restart */
    assert_int_equal(os.rx.out_of_order, CANPROTO_WP_PARTS) /* frames */;
    run_cycle(1, 0);
    assert_int_equal(count_id(0x6C0), before + 1);
    memset(&s, 0, sizeof s);
    for (unsigned i = io.nout; i-- > 0;)
        if (io.out[i].id == 0x6C0) {
            canproto_decode_status(&io.out[i], &s);
            break;
        }
    assert_true(s.last_err == CANPROTO_STERR_REFUSED || s.last_err == CANPROTO_STERR_OUT_OF_ORDER);
    /* all allowed again: CLEAR reaches the hook */
    can_port_allow_commands(port, 0, CAN_PORT_CMD_ALL);
    canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &io.in[io.nin++]);
    can_port_rx(port, 0);
    assert_int_equal(eng.ncmd, 2);
    assert_int_equal(eng.cmds[1], CANPROTO_CMD_CLEAR);
}

/* Given STATUS2 pages, then each STATUS is followed by one STATUS2 on the
 * object's status2_id (0x6D0): a page whose bytes changed first, else the
 * pages in turn; the counters of page 1 read back through the decoder. */
static void test_status2_pages(void **state)
{
    (void)state;
    canproto_frame_t f, g;
    canproto_st2_faults_t pg = {5, 2, 1}, back;
    run_cycle(0, 0); /* a STATUS before any page: no STATUS2 */
    assert_int_equal(count_id(0x6D0), 0);
    canproto_encode_status2_faults(0x123, &pg, &f); /* the id is the object's, not f's */
    can_port_status2(port, 0, &f);
    can_port_output_fault(port, 0, 5, 1); /* an event: STATUS due */
    run_cycle(1, 0);
    assert_int_equal(count_id(0x6D0), 1);
    assert_int_equal(io.out[io.nout - 1].id, 0x6D0);
    assert_int_equal(io.out[io.nout - 2].id, 0x6C0); /* right after its STATUS */
    assert_int_equal(canproto_decode_status2_faults(&io.out[io.nout - 1], &back), 0);
    assert_int_equal(back.out_lost, 5);
    assert_int_equal(back.out_errors, 2);
    assert_int_equal(back.cmd_refused, 1);
    /* a second page (as another module would give it), then page 1 changes:
     * the changed page 1 goes first, then page 2, then 1, 2 in turn */
    memset(&g, 0, sizeof g);
    g.len = 8;
    g.data[0] = 2;
    g.data[1] = 0xAB;
    can_port_status2(port, 0, &g);
    pg.out_lost = 6;
    canproto_encode_status2_faults(0, &pg, &f);
    can_port_status2(port, 0, &f);
    unsigned want[] = {1, 2, 1, 2};
    for (unsigned k = 0; k < 4; k++) {
        can_port_output_fault(port, 0, 6 + k + 1, 1); /* STATUS due */
        run_cycle(2 + k, 0);
        assert_int_equal(io.out[io.nout - 1].id, 0x6D0);
        assert_int_equal(io.out[io.nout - 1].data[0], want[k]);
    }
    assert_int_equal(count_id(0x6D0), 5);
}

/* Given pages 1 and 2 and the clock page 3 as a value page whose age changes
 * every cycle, then each STATUS is followed by the pages in turn: the page
 * that always changes never holds the others back (given as a changed page
 * it would go out after every STATUS), and it carries the latest age. */
static void test_status2_value_page(void **state)
{
    (void)state;
    canproto_frame_t f;
    canproto_st2_faults_t pg = {5, 2, 1};
    canproto_st2_rejected_t rj = {1, 2, 3, 4, 5, 6, 7};
    canproto_encode_status2_faults(0, &pg, &f);
    can_port_status2(port, 0, &f);
    canproto_encode_status2_rejected(0, &rj, &f);
    can_port_status2(port, 0, &f);
    unsigned seen[4] = {0};
    for (unsigned k = 0; k < 9; k++) {
        canproto_st2_clock_t ck = {10.0 + 0.1 * k, 1.5, CANPROTO_ST2_CLOCK_ON}, back;
        canproto_encode_status2_clock(0, &ck, &f);
        can_port_status2_value(port, 0, &f);
        can_port_output_fault(port, 0, k + 1, 1); /* an event: STATUS due */
        run_cycle(k, 0);
        const canproto_frame_t *o = &io.out[io.nout - 1];
        assert_int_equal(o->id, 0x6D0);
        assert_true(o->data[0] >= 1 && o->data[0] <= 3);
        seen[o->data[0]]++;
        if (o->data[0] == CANPROTO_ST2_CLOCK) {
            assert_int_equal(canproto_decode_status2_clock(o, &back), 0);
            assert_float_equal(back.age_s, 10.0 + 0.1 * k, 1e-9);
            assert_float_equal(back.drift_ppm, 1.5, 1e-9);
            assert_int_equal(back.clocked, CANPROTO_ST2_CLOCK_ON);
        }
    }
    assert_int_equal(seen[1], 3);
    assert_int_equal(seen[2], 3);
    assert_int_equal(seen[3], 3);
}

/* Given two objects with clashing ids, then the second is refused. */
static void test_id_clash(void **state)
{
    (void)state;
    can_port_config_t cfg;
    canproto_ids_t a, b;
    can_port_config_default(&cfg);
    can_port_t *p = can_port_new(&cfg, &fake_can_ops, &io, 2);
    canproto_ids_default(&a, 0);
    canproto_ids_default(&b, 1);
    b.status_id = a.setpoint_id;
    assert_int_equal(can_port_set_object(p, 0, &a, &fe_hooks, &eng), 0);
    assert_int_equal(can_port_set_object(p, 1, &b, &fe_hooks, &eng), -CANPROTO_ECONFIG);
    canproto_ids_default(&b, 1);
    b.fd = 1;
    assert_int_equal(can_port_set_object(p, 1, &b, &fe_hooks, &eng), 0);
    /* the ids the transport lets through, object after object (can_transport.c
     * set_objects) */
    uint32_t rx[8];
    unsigned n = canproto_ids_rx(&a, rx, 8);
    n += canproto_ids_rx(&b, rx + n, 8 - n);
    assert_int_equal(n, 3);
    assert_int_equal(rx[0], 0x680);
    assert_int_equal(rx[1], 0x681);
    assert_int_equal(rx[2], 0x691);
    can_port_free(p);
}

/* Given the real candump capture (comments at the top, 29-bit NMEA 2000
 * frames), when replayed through can_logfile into can_port, then every frame is
 * delivered on time and counted as foreign, comments are skipped. */
static void test_can_logfile_real_capture(void **state)
{
    (void)state;
    char err[256];
    can_logfile_t *l = can_logfile_open_mode("tests/data/canboat_candumpSample3.log", NULL, "can0",
                                             0, 0, err, sizeof err);
    assert_non_null(l);
    can_logfile_stats_t ls;
    can_logfile_stats(l, &ls);
    assert_int_equal(ls.frames_in, 2368);
    assert_int_equal(ls.bad_lines, 0);
    assert_true(ls.comments >= 9);
    canproto_frame_t f;
    /* nothing is due before time 0; the first frame is due at 0 */
    assert_int_equal(can_logfile_recv(l, -1, &f), 0);
    assert_int_equal(can_logfile_recv(l, 0, &f), 1);
    assert_int_equal(f.id, 0x09F112CC);
    assert_true(f.flags & CANPROTO_F_EFF);
    /* second frame: 22 us later */
    assert_int_equal(can_logfile_recv(l, 21000, &f), 0);
    assert_int_equal(can_logfile_recv(l, 22000, &f), 1);
    unsigned n = 2;
    while (can_logfile_recv(l, INT64_MAX / 2, &f))
        n++;
    assert_int_equal(n, 2368);
    assert_true(can_logfile_done(l));
    can_logfile_close(l);
}

/* Given a can_logfile output, when setpoints are sent, then the file holds candump
 * -L lines with engine-time stamps that our parser reads back. */
static void test_can_logfile_output(void **state)
{
    (void)state;
    char path[] = "/tmp/trajd-can_logfile-XXXXXX", err[256], line[256];
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    close(fd);
    can_logfile_t *l = can_logfile_open_mode(NULL, path, "vcan0", 0, 0, err, sizeof err);
    assert_non_null(l);
    engine_setpoint_t sp = sp_at(7, 1.5);
    canproto_frame_t f[3];
    canproto_encode_setpoint(0x6A0, &sp, f);
    can_logfile_set_time(l, 1234567000);
    for (int a = 0; a < 3; a++)
        assert_int_equal(can_logfile_send(l, &f[a]), 0);
    can_logfile_close(l);
    FILE *fp = fopen(path, "r");
    assert_non_null(fp);
    int n = 0;
    while (fgets(line, sizeof line, fp)) {
        candump_line_t cl;
        assert_int_equal(candump_parse_line(line, &cl), 0);
        assert_int_equal(cl.ts_us, 1234567);
        assert_string_equal(cl.ifname, "vcan0");
        assert_memory_equal(cl.frame.data, f[n].data, 8);
        n++;
    }
    fclose(fp);
    unlink(path);
    assert_int_equal(n, 3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_cycle_frames_and_sync, setup, teardown),
        cmocka_unit_test_setup_teardown(test_queue_full_drops_no_burst, setup, teardown),
        cmocka_unit_test_setup_teardown(test_queue_full_status_not_starved, setup, teardown),
        cmocka_unit_test_setup_teardown(test_queue_full_status_not_starved_many, setup, teardown),
        cmocka_unit_test_setup_teardown(test_down_and_back, setup, teardown),
        cmocka_unit_test_setup_teardown(test_late_cycle_dropped, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_no_position_and_late, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_feedback, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_bring_up, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_sdo_abort, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_rpdo_controlword_follows_bring_up, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_cia402_quick_stop_ramp_kept, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_sdo_stale_reply_ignored, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_status2_drive_page, setup, teardown),
        cmocka_unit_test_setup_teardown(test_cia402_heartbeat_lost_holds, setup, teardown),
        cmocka_unit_test_setup_teardown(test_rx_paths, setup, teardown),
        cmocka_unit_test_setup_teardown(test_flow_control_efull, setup, teardown),
        cmocka_unit_test_setup_teardown(test_resync_kept_over_reload, setup, teardown),
        cmocka_unit_test_setup_teardown(test_commands, setup, teardown),
        cmocka_unit_test_setup_teardown(test_output_fault_in_status, setup, teardown),
        cmocka_unit_test_setup_teardown(test_commands_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_status2_pages, setup, teardown),
        cmocka_unit_test_setup_teardown(test_status2_value_page, setup, teardown),
        cmocka_unit_test(test_id_clash),
        cmocka_unit_test(test_can_logfile_real_capture),
        cmocka_unit_test(test_can_logfile_output),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
