/* test_canproto.c - CAN codec: reassembly state machine, malformed frames,
 * clamping, bus-load arithmetic against published worst-case frame lengths.
 * (Bit-level layouts are cross-checked against canmatrix in test_canproto.py.) */
#include "test.h"

#include <math.h>
#include <string.h>

#include "canproto.h"
#include "canproto_dbc.h"

#define ID 0x680u
#define FDID 0x690u
/* Waypoint fields are 1 us / 1 um per bit: a decoded value is within half a bit. */
#define WP_T_TOL 0.5e-6
#define WP_POS_TOL 0.5e-6

static canproto_slot_t slots[2];
static canproto_rx_t rx;

static int setup(void **state)
{
    (void)state;
    canproto_rx_init(&rx, slots, 2);
    return 0;
}

static engine_waypoint_t wpt(uint32_t seq, double t, double x, double y, double z)
{
    engine_waypoint_t w = {.t_s = t, .pos_m = {x, y, z}, .seq = seq};
    return w;
}

/* Feed all four frames of w (in the given order); return the last result. */
static int feed(const engine_waypoint_t *w, const int order[4], canproto_rx_out_t *out)
{
    canproto_frame_t f[4];
    int rc = 0;
    assert_true(canproto_encode_waypoint(ID, w, f) >= 0);
    for (int k = 0; k < 4; k++)
        rc = canproto_rx_frame(&rx, &f[order ? order[k] : k], 0, out);
    return rc;
}

/* Given a waypoint sent as four frames in scrambled order, when reassembled,
 * then it comes out once, on the fourth frame, with its values. */
static void test_reassembly_any_order(void **state)
{
    (void)state;
    engine_waypoint_t w = wpt(7, 12.345678, -1234.567891, 0.000001, 98765.4321);
    canproto_frame_t f[4];
    canproto_rx_out_t out;
    const int order[4] = {2, 0, 3, 1};
    assert_int_equal(canproto_encode_waypoint(ID, &w, f), 0);
    for (int k = 0; k < 3; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f[order[k]], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f[order[3]], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_true(fabs(out.wp.t_s - w.t_s) <= WP_T_TOL);
    for (int a = 0; a < 3; a++)
        assert_true(fabs(out.wp.pos_m[a] - w.pos_m[a]) <= WP_POS_TOL);
    assert_int_equal(out.wp.seq, 7);
    assert_int_equal(out.lost_before, 0);
}

/* Given waypoints 1,2 consumed, when 5 arrives, then 2 are counted lost; and
 * when 5 comes again it is a duplicate, and 4 (late) is out of order. */
static void test_gaps_duplicates_out_of_order(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    for (uint32_t s = 1; s <= 2; s++) {
        engine_waypoint_t w = wpt(s, s, 0, 0, 0);
        assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_WAYPOINT);
        canproto_rx_consume(&rx, &out);
    }
    engine_waypoint_t w5 = wpt(5, 5, 1, 2, 3);
    assert_int_equal(feed(&w5, NULL, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.lost_before, 2);
    canproto_rx_consume(&rx, &out);
    assert_int_equal(rx.st.lost, 2);
    assert_int_equal(feed(&w5, NULL, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.duplicates, 4); /* four frames, each a duplicate */
    engine_waypoint_t w4 = wpt(4, 4, 0, 0, 0);
    assert_int_equal(feed(&w4, NULL, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.out_of_order, 4);
    assert_int_equal(rx.st.completed, 3);
}

/* Given a waypoint not consumed (the engine said EFULL), when the sender
 * repeats it, then it is reassembled again (flow control can retry). */
static void test_not_consumed_can_be_repeated(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    engine_waypoint_t w = wpt(9, 1, 0, 0, 0);
    assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_WAYPOINT);
    canproto_rx_consume(&rx, &out);
    assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_NONE);
}

/* Given the 8-bit sequence wrapping 255 -> 0, when waypoints continue, then the
 * extended sequence keeps counting and nothing is lost. */
static void test_sequence_wraps(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    uint32_t expect = 250;
    for (uint32_t s = 250; s < 262; s++) {
        engine_waypoint_t w = wpt(s & 0xFF, s, 0, 0, 0);
        assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_WAYPOINT);
        assert_int_equal(out.wp.seq, expect++);
        canproto_rx_consume(&rx, &out);
    }
    assert_int_equal(rx.st.lost, 0);
}

/* Given two slots, when the frames of three waypoints interleave, then the
 * oldest partial one is abandoned (incomplete) and later counted lost. */
static void test_slot_eviction(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    canproto_frame_t a[4], b[4], c[4];
    engine_waypoint_t wa = wpt(1, 1, 0, 0, 0), wb = wpt(2, 2, 0, 0, 0), wc = wpt(3, 3, 0, 0, 0);
    canproto_encode_waypoint(ID, &wa, a);
    canproto_encode_waypoint(ID, &wb, b);
    canproto_encode_waypoint(ID, &wc, c);
    /* seed history: consume a waypoint 0 */
    engine_waypoint_t w0 = wpt(0, 0, 0, 0, 0);
    assert_int_equal(feed(&w0, NULL, &out), CANPROTO_RX_WAYPOINT);
    canproto_rx_consume(&rx, &out);
    canproto_rx_frame(&rx, &a[0], 0, &out);
    canproto_rx_frame(&rx, &b[0], 0, &out);
    canproto_rx_frame(&rx, &c[0], 0, &out); /* evicts a */
    assert_int_equal(rx.st.incomplete, 1);
    for (int k = 1; k < 3; k++)
        canproto_rx_frame(&rx, &b[k], 0, &out);
    assert_int_equal(canproto_rx_frame(&rx, &b[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.lost_before, 1);
    canproto_rx_consume(&rx, &out);
    for (int k = 1; k < 3; k++)
        canproto_rx_frame(&rx, &c[k], 0, &out);
    assert_int_equal(canproto_rx_frame(&rx, &c[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.lost_before, 0);
}

/* Given malformed frames (wrong DLC, FD on the classic id, unknown mux, n/a
 * marker, bad command, RTR, EFF), when offered, then each is refused with its
 * error, counted, and no state changes. */
static void test_malformed(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    canproto_frame_t f[4], g;
    engine_waypoint_t w = wpt(3, 1, 2, 3, 4);
    canproto_encode_waypoint(ID, &w, f);

    g = f[0];
    g.len = 7;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_ELEN);
    g = f[0];
    g.flags |= CANPROTO_F_FD;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_ELEN);
    g = f[0];
    g.flags |= CANPROTO_F_RTR;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_ELEN);
    g = f[0];
    g.flags |= CANPROTO_F_EFF;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_ELEN);
    g = f[0];
    g.data[0] = 9;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_EMUX);
    g = f[1];
    memset(&g.data[2], 0, 6);
    g.data[7] = 0x80; /* int48 min: n/a */
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_EVALUE);
    canproto_encode_command(ID, CANPROTO_CMD_STOP, &g);
    g.data[2] = 77;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_EVALUE);
    canproto_encode_command(ID, CANPROTO_CMD_STOP, &g);
    g.data[5] = 1;
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_EVALUE);
    canproto_encode_command(ID, CANPROTO_CMD_STOP, &g);
    g.data[3] = 1; /* no argument */
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), -CANPROTO_EVALUE);
    assert_int_equal(canproto_encode_override(ID, 201, &g), -CANPROTO_EVALUE);
    canproto_encode_override(ID, 200, &g);
    g.data[3] = 201; /* above 200 %: a well-formed command the receiver refuses (issue 24) */
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), CANPROTO_RX_COMMAND);
    assert_int_equal(out.cmd, CANPROTO_CMD_OVERRIDE);
    assert_int_equal(out.cmd_arg, 201);
    /* classic frame on the FD id */
    assert_int_equal(canproto_rx_frame(&rx, &f[0], 1, &out), -CANPROTO_ELEN);
    assert_int_equal(rx.st.malformed, 10);
    assert_int_equal(rx.st.malformed_by[CANPROTO_ELEN], 5);
    assert_int_equal(rx.st.malformed_by[CANPROTO_EMUX], 1);
    assert_int_equal(rx.st.malformed_by[CANPROTO_EVALUE], 4);
    /* nothing was half-assembled by the bad frames */
    assert_int_equal(feed(&w, NULL, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(rx.st.duplicates, 0);
}

/* Given a command frame, then it decodes as that command. */
static void test_command(void **state)
{
    (void)state;
    canproto_frame_t g;
    canproto_rx_out_t out;
    assert_int_equal(canproto_encode_command(ID, CANPROTO_CMD_CLEAR, &g), 0);
    assert_int_equal(canproto_rx_frame(&rx, &g, 0, &out), CANPROTO_RX_COMMAND);
    assert_int_equal(out.cmd, CANPROTO_CMD_CLEAR);
    assert_int_equal(canproto_encode_command(ID, (canproto_cmd_t)0, &g), -CANPROTO_EVALUE);
}

/* Given an FD waypoint, then one frame gives the whole waypoint; reserved bytes
 * and a wrong length are refused. */
static void test_fd_waypoint(void **state)
{
    (void)state;
    canproto_frame_t g, h;
    canproto_rx_out_t out;
    engine_waypoint_t w = wpt(200, 3600.5, 5300.25, -7.125, 1e-6);
    assert_int_equal(canproto_encode_waypoint_fd(FDID, &w, &g), 0);
    assert_int_equal(g.len, 32);
    assert_true(g.flags & CANPROTO_F_FD);
    assert_int_equal(canproto_rx_frame(&rx, &g, 1, &out), CANPROTO_RX_WAYPOINT);
    for (int a = 0; a < 3; a++)
        assert_true(fabs(out.wp.pos_m[a] - w.pos_m[a]) <= WP_POS_TOL);
    assert_true(fabs(out.wp.t_s - w.t_s) <= WP_T_TOL);
    h = g;
    h.data[30] = 1;
    assert_int_equal(canproto_rx_frame(&rx, &h, 1, &out), -CANPROTO_EVALUE);
    h = g;
    h.len = 24;
    assert_int_equal(canproto_rx_frame(&rx, &h, 1, &out), -CANPROTO_ELEN);
    h = g;
    h.data[0] = 4;
    assert_int_equal(canproto_rx_frame(&rx, &h, 1, &out), -CANPROTO_EMUX);
    /* the int48 n/a marker (0x800000000000, little-endian) in any axis is
     * refused, as in the classic frames, never decoded as -140737 km */
    for (int a = 0; a < 3; a++) {
        h = g;
        memset(&h.data[8 + 6 * a], 0, 6);
        h.data[8 + 6 * a + 5] = 0x80;
        assert_int_equal(canproto_rx_frame(&rx, &h, 1, &out), -CANPROTO_EVALUE);
    }
    assert_int_equal(rx.st.malformed_by[CANPROTO_EVALUE], 4);
}

/* Given a waypoint with the source's velocity (issue 31): its VELOCITY frame
 * sent first, then its four frames in any order, then it comes out with the
 * velocity (1 cm/s per bit); a VELOCITY after the fourth frame is a frame of a
 * waypoint already handed out (a duplicate), never merged into the next; the
 * int16 n/a code is refused; as one FD frame, mux 7 carries it, mux 5 none. */
static void test_velocity(void **state)
{
    (void)state;
    canproto_frame_t f[4], v, g;
    canproto_rx_out_t out;
    engine_waypoint_t w = wpt(9, 1.5, 10, 20, 30);
    w.has_vel = 1;
    w.vel_m_s[0] = 12.345;
    w.vel_m_s[1] = -250.0;
    w.vel_m_s[2] = 0.004;
    assert_int_equal(canproto_encode_waypoint_vel(ID, &w, &v), 0);
    assert_int_equal(v.data[0], CANPROTO_MUX_VELOCITY);
    assert_int_equal(canproto_rx_frame(&rx, &v, 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_encode_waypoint(ID, &w, f), 0);
    const int order[4] = {3, 1, 0, 2};
    for (int k = 0; k < 3; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f[order[k]], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f[order[3]], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.has_vel, 1);
    assert_true(fabs(out.wp.vel_m_s[0] - 12.35) < 1e-12 || fabs(out.wp.vel_m_s[0] - 12.34) < 1e-12);
    assert_true(fabs(out.wp.vel_m_s[1] + 250.0) < 1e-12);
    assert_true(fabs(out.wp.vel_m_s[2]) < 1e-12);
    canproto_rx_consume(&rx, &out);
    uint64_t dup = rx.st.duplicates;
    assert_int_equal(canproto_rx_frame(&rx, &v, 0, &out), CANPROTO_RX_NONE); /* late */
    assert_int_equal(rx.st.duplicates, dup + 1);
    engine_waypoint_t w2 = wpt(10, 1.6, 11, 21, 31); /* the next: no velocity */
    assert_int_equal(feed(&w2, NULL, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.has_vel, 0);
    canproto_rx_consume(&rx, &out);
    v.data[1] = 11;
    v.data[2] = 0x00; /* vx = INT16_MIN: n/a, refused */
    v.data[3] = 0x80;
    assert_int_equal(canproto_rx_frame(&rx, &v, 0, &out), -CANPROTO_EVALUE);
    w.seq = 11;
    assert_int_equal(canproto_encode_waypoint_fd(FDID, &w, &g), 0);
    assert_int_equal(g.data[0], CANPROTO_MUX_FD_WAYPOINT_VEL);
    assert_int_equal(canproto_rx_frame(&rx, &g, 1, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.has_vel, 1);
    assert_true(fabs(out.wp.vel_m_s[1] + 250.0) < 1e-12);
    g.data[26] = 0x00;
    g.data[27] = 0x80;
    assert_int_equal(canproto_rx_frame(&rx, &g, 1, &out), -CANPROTO_EVALUE);
}

/* Given out-of-range and NaN values, then encoders clamp and say so; a NaN
 * waypoint is refused (a sender must not send it). */
static void test_clamping(void **state)
{
    (void)state;
    engine_setpoint_t sp;
    canproto_frame_t f[3];
    canproto_setpoint_t d;
    memset(&sp, 0, sizeof sp);
    sp.pos_m[0] = 1e6;   /* > 214 km */
    sp.vel_m_s[1] = -40; /* < -32.768 m/s */
    sp.pos_m[2] = NAN;
    assert_int_equal(canproto_encode_setpoint(0x6A0, &sp, f), CANPROTO_CLAMPED);
    assert_int_equal(canproto_decode_setpoint(&f[0], &d), 0);
    assert_true(fabs(d.pos_m[0] - INT32_MAX * CANPROTO_SP_POS_M_PER_BIT) < 1e-9);
    assert_int_equal(canproto_decode_setpoint(&f[1], &d), 0);
    assert_true(fabs(d.vel_m_s[1] - INT16_MIN * CANPROTO_SP_VEL_M_S_PER_BIT) < 1e-12);
    assert_int_equal(canproto_decode_setpoint(&f[2], &d), 0);
    assert_true(fabs(d.pos_m[2]) < 1e-12);
    /* each cause alone says so (together, one missing would be hidden):
     * in range -> 0; NaN -> sent as 0, flagged; +inf -> the maximum, flagged */
    memset(&sp, 0, sizeof sp);
    sp.pos_m[1] = 12.5;
    assert_int_equal(canproto_encode_setpoint(0x6A0, &sp, f), 0);
    sp.pos_m[1] = NAN;
    assert_int_equal(canproto_encode_setpoint(0x6A0, &sp, f), CANPROTO_CLAMPED);
    assert_int_equal(canproto_decode_setpoint(&f[1], &d), 0);
    assert_true(fabs(d.pos_m[1]) <= 0.0);
    memset(&sp, 0, sizeof sp);
    sp.vel_m_s[0] = INFINITY;
    assert_int_equal(canproto_encode_setpoint(0x6A0, &sp, f), CANPROTO_CLAMPED);
    assert_int_equal(canproto_decode_setpoint(&f[0], &d), 0);
    assert_true(fabs(d.vel_m_s[0] - INT16_MAX * CANPROTO_SP_VEL_M_S_PER_BIT) < 1e-12);
    canproto_frame_t fd;
    memset(&sp, 0, sizeof sp);
    assert_int_equal(canproto_encode_setpoint_fd(0x6B0, 0, &sp, &fd), 0);
    sp.vel_m_s[2] = NAN;
    assert_int_equal(canproto_encode_setpoint_fd(0x6B0, 0, &sp, &fd), CANPROTO_CLAMPED);
    canproto_frame_t g[4];
    engine_waypoint_t w = wpt(1, NAN, 0, 0, 0);
    assert_int_equal(canproto_encode_waypoint(ID, &w, g), -CANPROTO_EVALUE);
    w = wpt(1, -1, 0, 0, 0);
    assert_int_equal(canproto_encode_waypoint(ID, &w, g), CANPROTO_CLAMPED);
}

/* Worst-case classic frame lengths, from Davis et al. 2007 (Table / eq. 2):
 * 11-bit ids: 135 bits for 8 data bytes, 55 for 0 (incl. 3-bit IFS);
 * 29-bit ids: 160 bits for 8 bytes, 80 for 0. */
static void test_classic_frame_bits(void **state)
{
    (void)state;
    /* tolerance: exact integers computed in double */
    assert_true(fabs(canproto_frame_bits(8, 0, 0, 0, 500e3, 0) - 135) < 1e-9);
    assert_true(fabs(canproto_frame_bits(0, 0, 0, 0, 500e3, 0) - 55) < 1e-9);
    assert_true(fabs(canproto_frame_bits(8, 0, 0, 1, 500e3, 0) - 160) < 1e-9);
    assert_true(fabs(canproto_frame_bits(0, 0, 0, 1, 500e3, 0) - 80) < 1e-9);
    /* 135 bits at 500 kbit/s = 270 us */
    assert_true(fabs(canproto_frame_time_s(8, 0, 0, 0, 500e3, 0) - 270e-6) < 1e-12);
    assert_true(canproto_frame_time_s(9, 0, 0, 0, 500e3, 0) < 0);
    assert_true(canproto_frame_time_s(33, 1, 0, 0, 500e3, 0) < 0);
}

/* CAN FD: without BRS the whole frame is at the nominal rate; count the fields
 * by hand from ISO 11898-1:2015 for 64 bytes, 11-bit id:
 *  arbitration 17 + 4 stuff, data 5+512 + 129 stuff, stuff count 4 + CRC21 +
 *  7 fixed stuff, tail 13  = 712 bits.  With BRS 500k/2M: (17+4+13)/500k +
 *  (517+129+4+21+7)/2M = 68 us + 339 us. */
static void test_fd_frame_time(void **state)
{
    (void)state;
    assert_true(fabs(canproto_frame_bits(64, 1, 0, 0, 500e3, 0) - 712) < 1e-9);
    assert_true(fabs(canproto_frame_time_s(64, 1, 1, 0, 500e3, 2e6) - (68e-6 + 339e-6)) < 1e-12);
    /* FD with BRS is shorter than FD without, which is longer than classic 8 bytes */
    assert_true(canproto_frame_time_s(8, 1, 1, 0, 500e3, 2e6) <
                canproto_frame_time_s(8, 1, 0, 0, 500e3, 0));
}

/* Given one object at 1 kHz with classic own frames, no SYNC, no status, no
 * input, then the load is 3 frames x 135 bits x 1000 / bitrate. */
static void test_busload(void **state)
{
    (void)state;
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    canproto_traffic_t tr = {.rate_hz = 1000, .status_hz = 0, .waypoint_hz = 0};
    double l = canproto_busload(&ids, 1, 0, 0, &tr, 500e3, 0);
    assert_true(fabs(l - 3 * 135 * 1000 / 500e3) < 1e-12);
    /* SYNC (55 bits) and 10 Hz STATUS + STATUS2 (2 x 135 bits) and 10
     * waypoints/s (4 x 135) */
    tr.status_hz = 10;
    tr.waypoint_hz = 10;
    l = canproto_busload(&ids, 1, 1, 0, &tr, 1e6, 0);
    assert_true(fabs(l - (1000.0 * (3 * 135 + 55) + 10 * 2 * 135 + 10 * 4 * 135) / 1e6) < 1e-12);
    assert_true(canproto_busload(&ids, 1, 0, 0, &tr, 0, 0) < 0);
}

/* Ids: defaults are valid; a clash or a 29-bit id is refused; rx ids listed. */
static void test_ids(void **state)
{
    (void)state;
    canproto_ids_t ids;
    uint32_t rxids[4];
    const char *why = NULL;
    canproto_ids_default(&ids, 3);
    assert_int_equal(canproto_ids_check(&ids, &why), 0);
    assert_int_equal(ids.waypoint_id, 0x683);
    assert_int_equal(canproto_ids_rx(&ids, rxids, 4), 1);
    ids.fd = 1;
    assert_int_equal(canproto_ids_rx(&ids, rxids, 4), 2);
    assert_int_equal(rxids[1], 0x693);
    ids.status_id = ids.waypoint_id;
    assert_int_equal(canproto_ids_check(&ids, &why), -CANPROTO_ECONFIG);
    assert_non_null(why);
    canproto_ids_default(&ids, 0);
    ids.setpoint_id = 0x800;
    assert_int_equal(canproto_ids_check(&ids, &why), -CANPROTO_ECONFIG);
}

/* The DBC writer reports the length it needs and fills a big enough buffer. */
static void test_dbc_length(void **state)
{
    (void)state;
    static char buf[16384];
    int n = canproto_dbc(NULL, 0);
    assert_true(n > 100 && n < (int)sizeof buf);
    assert_int_equal(canproto_dbc(buf, sizeof buf), n);
    assert_int_equal((int)strlen(buf), n);
    assert_int_equal(canproto_dbc(buf, 10), n);
    assert_int_equal((int)strlen(buf), 9);
}

/* Given a waypoint reassembled but not yet consumed (the engine said EFULL),
 * when the sender starts repeating it (a partial slot for the same seq) and
 * the first copy is then consumed, then that partial is dropped at once
 * (counted incomplete: it can never be used), freeing its slot, so the next
 * two waypoints interleaved frame by frame both come through without an
 * eviction. */
static void test_consume_drops_partial_of_same_seq(void **state)
{
    (void)state;
    canproto_rx_out_t out, first;
    canproto_frame_t f9[4], f10[4], f11[4];
    engine_waypoint_t w9 = wpt(9, 9, 1, 2, 3), w10 = wpt(10, 10, 4, 5, 6),
                      w11 = wpt(11, 11, 7, 8, 9);
    assert_int_equal(canproto_encode_waypoint(ID, &w9, f9), 0);
    assert_int_equal(canproto_encode_waypoint(ID, &w10, f10), 0);
    assert_int_equal(canproto_encode_waypoint(ID, &w11, f11), 0);
    for (int k = 0; k < 3; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f9[k], 0, &first), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f9[3], 0, &first), CANPROTO_RX_WAYPOINT);
    /* the repeat has begun: two of its four frames are in */
    assert_int_equal(canproto_rx_frame(&rx, &f9[0], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f9[1], 0, &out), CANPROTO_RX_NONE);
    canproto_rx_consume(&rx, &first);
    assert_int_equal(rx.st.incomplete, 1);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(canproto_rx_frame(&rx, &f10[k], 0, &out), CANPROTO_RX_NONE);
        assert_int_equal(canproto_rx_frame(&rx, &f11[k], 0, &out), CANPROTO_RX_NONE);
    }
    assert_int_equal(canproto_rx_frame(&rx, &f10[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.seq, 10);
    canproto_rx_consume(&rx, &out);
    assert_int_equal(canproto_rx_frame(&rx, &f11[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.seq, 11);
    assert_int_equal(out.lost_before, 0);
    assert_int_equal(rx.st.incomplete, 1);
}

/* ---- a sender that restarted its numbering (K-D3) ---- */

/* The one FD frame of w, offered. */
static int feed_fd(const engine_waypoint_t *w, canproto_rx_out_t *out)
{
    canproto_frame_t g;
    assert_true(canproto_encode_waypoint_fd(FDID, w, &g) >= 0);
    return canproto_rx_frame(&rx, &g, 1, out);
}

static int feed_as(int fd, const engine_waypoint_t *w, canproto_rx_out_t *out)
{
    return fd ? feed_fd(w, out) : feed(w, NULL, out);
}

/* Waypoints seq from..to (8 bits on the wire), 0.1 s apart from t0: each comes
 * out with nothing lost and is consumed. */
static void consume_run(int fd, uint32_t from, uint32_t to, double t0)
{
    canproto_rx_out_t out;
    for (uint32_t s = from; s <= to; s++) {
        engine_waypoint_t w = wpt(s & 0xFF, t0 + 0.1 * (s - from), s, 0, 0);
        assert_int_equal(feed_as(fd, &w, &out), CANPROTO_RX_WAYPOINT);
        assert_int_equal(out.lost_before, 0);
        assert_int_equal(out.wp.seq & 0xFF, s & 0xFF);
        canproto_rx_consume(&rx, &out);
    }
}

/* Given a sender that sent seq 1..60 (0.1 s apart) and restarts at seq 1 with
 * later times, then every waypoint of the restarted numbering is taken: the
 * first is a resync (nothing lost, its extended number goes on forward), the
 * next follow it; a waypoint behind whose time is not later (older, or the
 * same) is still out of order; a resync the engine answered EFULL comes out
 * again when repeated and counts once when consumed. */
static void restart_resyncs_by_time(int fd)
{
    canproto_rx_out_t out;
    unsigned nframes = fd ? 1 : CANPROTO_WP_PARTS;
    consume_run(fd, 1, 60, 0.1); /* t 0.1 .. 6.0 */
    uint32_t prev = rx.last_seq;
    for (uint32_t s = 1; s <= 70; s++) {
        engine_waypoint_t w = wpt(s, 10.0 + 0.1 * (s - 1), s, 1, 2);
        assert_int_equal(feed_as(fd, &w, &out), CANPROTO_RX_WAYPOINT);
        assert_int_equal(out.lost_before, 0);
        assert_int_equal(out.resync, s == 1);
        assert_int_equal(out.wp.seq & 0xFF, s);
        assert_true(out.wp.seq > prev);
        prev = out.wp.seq;
        canproto_rx_consume(&rx, &out);
    }
    assert_int_equal(rx.st.completed, 130);
    assert_int_equal(rx.st.lost, 0);
    assert_int_equal(rx.st.resyncs, 1);
    assert_int_equal(rx.st.resync_seq, 1);
    assert_int_equal(rx.st.resync_after, 60);
    assert_int_equal(rx.st.out_of_order, 0);
    assert_int_equal(rx.st.incomplete, 0);
    /* last: seq 70 at 16.9 s.  Truly late: 5 behind, older */
    engine_waypoint_t late = wpt(65, 16.4, 65, 1, 2);
    assert_int_equal(feed_as(fd, &late, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.out_of_order, nframes);
    /* 1 behind at the very same time: not later, out of order */
    engine_waypoint_t same = wpt(69, 16.9, 69, 1, 2);
    assert_int_equal(feed_as(fd, &same, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.out_of_order, 2 * nframes);
    /* 128 behind (the farthest), later: a restart too */
    engine_waypoint_t far = wpt((70 + 128) & 0xFF, 20.0, 0, 0, 0);
    assert_int_equal(feed_as(fd, &far, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.resync, 1);
    /* not consumed (EFULL): repeated, it comes out again, a resync still */
    assert_int_equal(feed_as(fd, &far, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.resync, 1);
    assert_int_equal(out.lost_before, 0);
    canproto_rx_consume(&rx, &out);
    assert_int_equal(rx.st.resyncs, 2);
    assert_int_equal(rx.st.resync_seq, 198);
    assert_int_equal(rx.st.resync_after, 70);
    assert_int_equal(rx.st.lost, 0);
    /* and the duplicate of it stays a duplicate */
    uint64_t dup = rx.st.duplicates;
    assert_int_equal(feed_as(fd, &far, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.duplicates, dup + nframes);
    assert_int_equal(rx.st.completed, 132);
    assert_int_equal(rx.st.out_of_order, 2 * nframes);
}

static void test_restart_resyncs_by_time(void **state)
{
    (void)state;
    restart_resyncs_by_time(0);
}

static void test_restart_resyncs_by_time_fd(void **state)
{
    (void)state;
    restart_resyncs_by_time(1);
}

/* Given two slots, the last consumed 10 and waypoint 11 partial, when late
 * frames of older waypoints (7, 8) trickle in among those of 11 and 12, then
 * none of them costs a waypoint ahead: a frame behind only takes a free slot
 * or one behind, a frame ahead takes the slot behind first; the late frames
 * are all counted out of order (when dropped, judged or abandoned), and 11
 * and 12 come out whole, nothing lost or incomplete. */
static void test_late_frames_keep_partial_ahead(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    canproto_frame_t f7[4], f8[4], f11[4], f12[4];
    engine_waypoint_t w7 = wpt(7, 1.6, 7, 0, 0), w8 = wpt(8, 1.7, 8, 0, 0),
                      w11 = wpt(11, 2.0, 11, 0, 0), w12 = wpt(12, 2.1, 12, 0, 0);
    canproto_encode_waypoint(ID, &w7, f7);
    canproto_encode_waypoint(ID, &w8, f8);
    canproto_encode_waypoint(ID, &w11, f11);
    canproto_encode_waypoint(ID, &w12, f12);
    consume_run(0, 1, 10, 1.0); /* last: 10 at 1.9 s */
    assert_int_equal(canproto_rx_frame(&rx, &f11[0], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f11[1], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f8[0], 0, &out), CANPROTO_RX_NONE);  /* free slot */
    assert_int_equal(canproto_rx_frame(&rx, &f12[0], 0, &out), CANPROTO_RX_NONE); /* takes 8's */
    assert_int_equal(rx.st.out_of_order, 1);
    assert_int_equal(canproto_rx_frame(&rx, &f7[0], 0, &out), CANPROTO_RX_NONE); /* no room */
    assert_int_equal(rx.st.out_of_order, 2);
    assert_int_equal(canproto_rx_frame(&rx, &f11[2], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f11[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.seq, 11);
    assert_int_equal(out.lost_before, 0);
    canproto_rx_consume(&rx, &out);
    /* a whole late waypoint in the free slot: judged when complete, dropped */
    for (int k = 0; k < 4; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f7[k], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.out_of_order, 6);
    assert_int_equal(canproto_rx_frame(&rx, &f8[1], 0, &out), CANPROTO_RX_NONE);
    for (int k = 1; k < 3; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f12[k], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(canproto_rx_frame(&rx, &f12[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.wp.seq, 12);
    assert_int_equal(out.lost_before, 0);
    canproto_rx_consume(&rx, &out); /* 8's partial, behind it: abandoned, out of order */
    assert_int_equal(rx.st.out_of_order, 7);
    assert_int_equal(rx.st.incomplete, 0);
    assert_int_equal(rx.st.lost, 0);
    assert_int_equal(rx.st.resyncs, 0);
    assert_int_equal(rx.st.completed, 12);
}

/* Given a partial classic waypoint 11 ahead, when an FD waypoint behind and
 * older arrives, then it is out of order (one frame) and leaves the partial
 * waypoint alone: 11 still completes. */
static void test_late_fd_keeps_partial_ahead(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    canproto_frame_t f11[4];
    engine_waypoint_t w11 = wpt(11, 2.0, 11, 0, 0), late = wpt(8, 1.7, 8, 0, 0);
    canproto_encode_waypoint(ID, &w11, f11);
    consume_run(1, 1, 10, 1.0);
    for (int k = 0; k < 3; k++)
        assert_int_equal(canproto_rx_frame(&rx, &f11[k], 0, &out), CANPROTO_RX_NONE);
    assert_int_equal(feed_fd(&late, &out), CANPROTO_RX_NONE);
    assert_int_equal(rx.st.out_of_order, 1);
    assert_int_equal(canproto_rx_frame(&rx, &f11[3], 0, &out), CANPROTO_RX_WAYPOINT);
    assert_int_equal(out.lost_before, 0);
    canproto_rx_consume(&rx, &out);
    assert_int_equal(rx.st.incomplete, 0);
    assert_int_equal(rx.st.lost, 0);
}

/* Given the old sender gone with both slots holding partial waypoints ahead
 * (61, 62), when it restarts at seq 1 with later times, then its first frames
 * find no room, but once the partial ones are stale (no frame for
 * CANPROTO_RX_STALE_FRAMES frames) they are abandoned (incomplete), and from
 * then on every waypoint is taken: one resync, nothing lost. */
static void test_restart_after_stuck_partials(void **state)
{
    (void)state;
    canproto_rx_out_t out;
    canproto_frame_t f61[4], f62[4];
    engine_waypoint_t w61 = wpt(61, 6.1, 0, 0, 0), w62 = wpt(62, 6.2, 0, 0, 0);
    canproto_encode_waypoint(ID, &w61, f61);
    canproto_encode_waypoint(ID, &w62, f62);
    consume_run(0, 1, 60, 0.1);
    for (int k = 0; k < 2; k++) {
        assert_int_equal(canproto_rx_frame(&rx, &f61[k], 0, &out), CANPROTO_RX_NONE);
        assert_int_equal(canproto_rx_frame(&rx, &f62[k], 0, &out), CANPROTO_RX_NONE);
    }
    uint32_t first = 0;
    for (uint32_t s = 1; s <= 20; s++) {
        engine_waypoint_t w = wpt(s, 10.0 + 0.1 * s, s, 0, 0);
        int rc = feed(&w, NULL, &out);
        if (first) {
            assert_int_equal(rc, CANPROTO_RX_WAYPOINT);
            assert_int_equal(out.resync, 0);
        }
        if (rc == CANPROTO_RX_WAYPOINT) {
            if (!first)
                assert_int_equal(out.resync, 1);
            first = first ? first : s;
            assert_int_equal(out.lost_before, 0);
            canproto_rx_consume(&rx, &out);
        }
    }
    assert_true(first >= 1 && first <= CANPROTO_RX_STALE_FRAMES / CANPROTO_WP_PARTS + 2);
    assert_int_equal(rx.st.resyncs, 1);
    assert_int_equal(rx.st.incomplete, 2);
    assert_int_equal(rx.st.lost, 0);
    assert_int_equal(rx.st.completed, 60 + 21 - first);
    /* every frame of the restarted waypoints not taken was counted */
    assert_int_equal(rx.st.out_of_order, (first - 1) * CANPROTO_WP_PARTS);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup(test_reassembly_any_order, setup),
        cmocka_unit_test_setup(test_gaps_duplicates_out_of_order, setup),
        cmocka_unit_test_setup(test_not_consumed_can_be_repeated, setup),
        cmocka_unit_test_setup(test_sequence_wraps, setup),
        cmocka_unit_test_setup(test_slot_eviction, setup),
        cmocka_unit_test_setup(test_consume_drops_partial_of_same_seq, setup),
        cmocka_unit_test_setup(test_restart_resyncs_by_time, setup),
        cmocka_unit_test_setup(test_restart_resyncs_by_time_fd, setup),
        cmocka_unit_test_setup(test_late_frames_keep_partial_ahead, setup),
        cmocka_unit_test_setup(test_late_fd_keeps_partial_ahead, setup),
        cmocka_unit_test_setup(test_restart_after_stuck_partials, setup),
        cmocka_unit_test_setup(test_malformed, setup),
        cmocka_unit_test_setup(test_command, setup),
        cmocka_unit_test_setup(test_fd_waypoint, setup),
        cmocka_unit_test_setup(test_velocity, setup),
        cmocka_unit_test(test_clamping),
        cmocka_unit_test(test_classic_frame_bits),
        cmocka_unit_test(test_fd_frame_time),
        cmocka_unit_test(test_busload),
        cmocka_unit_test(test_ids),
        cmocka_unit_test(test_dbc_length),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
