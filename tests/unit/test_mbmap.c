/*
 * test_mbmap.c - the register map codec against independent references:
 * libmodbus's own float and int32 decoders (modbus_get_float_abcd,
 * MODBUS_GET_INT32_FROM_INT16), IEEE-754 bit patterns from the standard,
 * the CRC-16/MODBUS check value from the CRC catalogue, the request rules of
 * the Modbus Application Protocol spec.
 *
 * Run with --markdown to print the register table of config/PROTOCOL.md (generated from
 * mbmap_fields(); tests/e2e/test_mbmap_readme.sh compares it with config/PROTOCOL.md).
 */
#include "test.h"

#include <math.h>
#include <modbus.h>
#include <stdio.h>
#include <string.h>

#include "mbmap.h"

#define NOBJ 3

/* Bit-exact equality: the values under test are chosen exactly representable,
 * so any difference is a wrong word order or a wrong offset, not rounding. */
static int exact(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Given values with exact IEEE-754 patterns, when encoded, then libmodbus's
 * ABCD decoder and the standard's bit patterns agree with the registers. */
static void test_word_order(void **state)
{
    (void)state;
    uint16_t r[4];
    mbmap_put_f32(r, -2.5f); /* binary32 0xC0200000 */
    assert_int_equal(r[0], 0xC020);
    assert_int_equal(r[1], 0x0000);
    mbmap_put_f32(r, 1234.5678f);
    assert_true(exact(modbus_get_float_abcd(r), 1234.5678f)); /* exact: same bits */
    mbmap_put_u32(r, 0x12345678u);
    assert_int_equal(r[0], 0x1234);
    uint32_t w[2] = {r[0], r[1]}; /* widened: see read_field */
    assert_int_equal((uint32_t)MODBUS_GET_INT32_FROM_INT16(w, 0), 0x12345678u);
    mbmap_put_f64(r, 1.0); /* binary64 0x3FF0000000000000 */
    assert_int_equal(r[0], 0x3FF0);
    assert_int_equal(r[1] | r[2] | r[3], 0);
    mbmap_put_f64(r, -0.1); /* 0xBFB999999999999A */
    assert_int_equal(r[0], 0xBFB9);
    assert_int_equal(r[1], 0x9999);
    assert_int_equal(r[2], 0x9999);
    assert_int_equal(r[3], 0x999A);
    assert_true(exact(mbmap_get_f64(r), -0.1));
}

static const mbmap_field_t *field(const char *table, const char *name)
{
    size_t n;
    const mbmap_field_t *f = mbmap_fields(&n);
    for (size_t i = 0; i < n; i++)
        if (!strcmp(f[i].table, table) && !strcmp(f[i].name, name))
            return &f[i];
    fail_msg("no field %s/%s", table, name);
    return NULL;
}

/* Read a field through the documentation table, the way a client following
 * the README would (libmodbus decoders for u32/f32). */
static double read_field(const uint16_t *block, const mbmap_field_t *f)
{
    const uint16_t *r = block + f->offset;
    switch (f->type) {
    case MBMAP_T_U16: return r[0];
    case MBMAP_T_U32: {
        /* libmodbus's macro shifts its element type: widen first, or a
         * uint16_t promoted to int overflows (UBSan). */
        uint32_t w[2] = {r[0], r[1]};
        return (uint32_t)MODBUS_GET_INT32_FROM_INT16(w, 0);
    }
    case MBMAP_T_F32: return modbus_get_float_abcd(r);
    case MBMAP_T_F64: return mbmap_get_f64(r);
    }
    return NAN;
}

/* Given a snapshot with a distinct value in every field, when encoded, then
 * each value is found where the README table says, with its type. */
static void test_encode_matches_table(void **state)
{
    (void)state;
    static uint16_t regs[MBMAP_REGS(NOBJ)];
    mbmap_object_t o;
    memset(&o, 0, sizeof o);
    o.sp.state = ENGINE_STATE_UNDERRUN;
    o.sp.flags = ENGINE_SP_HOLD | ENGINE_SP_SKIPPED;
    o.sp.cycle = 70001;
    o.sp.track = 7;
    o.sp.t_s = 1234.000125;
    for (int a = 0; a < 3; a++) {
        o.sp.pos_m[a] = 10.5 + a;
        o.sp.vel_m_s[a] = -1.25 - a;
        o.sp.acc_m_s2[a] = 0.125 * (a + 1);
    }
    o.st.buffered = 11;
    o.st.free = 12;
    o.st.lookahead = 13;
    o.st.ahead_s = 2.5;
    o.st.last_seq = 99999;
    o.st.accepted = 0x100000005ull; /* wraps to 5 */
    o.st.rejected = 21;
    o.st.underruns = 22;
    o.st.skipped_ticks = 23;
    o.st.duplicates = 24;
    o.lost = 25;
    o.mb_rejected = 26;
    o.late_p99_us = 27;
    o.late_max_us = 28;
    o.can_state = MBMAP_CAN_PASSIVE;
    o.can_load_permille = 345;
    o.uptime_s = 3600;

    assert_int_equal(mbmap_encode_object(regs, 2, 0xABCD1234u, &o), 0);
    assert_int_equal(mbmap_encode_object(regs, MBMAP_MAX_OBJECTS, 1, &o), -MBMAP_EADDRESS);
    const uint16_t *b = regs + MBMAP_OBJ_BASE(2);
    struct {
        const char *name;
        double v;
    } want[] = {
        {"generation", 0xABCD1234u},
        {"generation_tail", 0xABCD1234u},
        {"state", 2},
        {"flags", 5},
        {"cycle", 70001},
        {"track", 7},
        {"buffered", 11},
        {"free", 12},
        {"lookahead_needed", 13},
        {"lookahead_available", 2.5},
        {"last_seq", 99999},
        {"t", 1234.000125},
        {"x", 10.5},
        {"y", 11.5},
        {"z", 12.5},
        {"vx", -1.25},
        {"vy", -2.25},
        {"vz", -3.25},
        {"ax", 0.125},
        {"ay", 0.25},
        {"az", 0.375},
        {"accepted", 5},
        {"rejected", 21},
        {"lost", 25},
        {"underruns", 22},
        {"missed_ticks", 23},
        {"duplicates", 24},
        {"mb_rejected", 26},
        {"lateness_p99", 27},
        {"lateness_max", 28},
        {"can_state", 3},
        {"can_load", 345},
        {"uptime", 3600},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        double got = read_field(b, field("input object", want[i].name));
        if (!exact(got, want[i].v)) /* values chosen exact in f32/f64 */
            fail_msg("%s: got %.17g want %.17g", want[i].name, got, want[i].v);
    }
    /* Other objects' blocks untouched. */
    for (unsigned i = 0; i < MBMAP_BLOCK; i++)
        assert_int_equal(regs[MBMAP_OBJ_BASE(1) + i], 0);

    mbmap_daemon_t d = {.generation = 77,
                        .objects = 3,
                        .writes_enabled = 1,
                        .uptime_s = 5,
                        .period_us = 1000,
                        .late_p50_us = 8,
                        .late_p99_us = 9,
                        .late_max_us = 10,
                        .missed_ticks = 11,
                        .can_state = 1,
                        .can_load_permille = 12,
                        .mb_requests = 13,
                        .mb_exceptions = 14,
                        .mb_refused = 15,
                        .mb_clients = 16};
    mbmap_encode_daemon(regs, &d);
    struct {
        const char *name;
        double v;
    } dw[] = {
        {"magic", 0x7444},     {"version", MBMAP_VERSION}, {"objects", 3},
        {"writes_enabled", 1}, {"generation", 77},         {"uptime", 5},
        {"period", 1000},      {"lateness_p50", 8},        {"lateness_p99", 9},
        {"lateness_max", 10},  {"missed_ticks", 11},       {"can_state", 1},
        {"can_load", 12},      {"mb_requests", 13},        {"mb_exceptions", 14},
        {"mb_refused", 15},    {"mb_clients", 16},         {"generation_tail", 77},
    };
    for (size_t i = 0; i < sizeof dw / sizeof dw[0]; i++) {
        double got = read_field(regs, field("input daemon", dw[i].name));
        if (!exact(got, dw[i].v))
            fail_msg("daemon %s: got %.17g want %.17g", dw[i].name, got, dw[i].v);
    }
}

/* Given a status with a distinct count for every reason a waypoint is
 * refused, when object 2's diagnostics block is encoded, then each count is
 * where the documentation table puts "rejected_" + the reason's name (the
 * names trajreplay --summary prints), the block is stamped, the codes that
 * are no reason for data read 0, and no other register is touched. */
static void test_encode_diag(void **state)
{
    (void)state;
    static uint16_t regs[MBMAP_TABLE_REGS(NOBJ)];
    mbmap_object_t o;
    memset(&o, 0, sizeof o);
    for (int c = 1; c < ENGINE_ERROR_COUNT; c++)
        o.st.rejected_by[c] = 0x100000000ull * (unsigned)c + 1000u + (unsigned)c; /* low 32 bits */
    o.st.transfers_moving = 77; /* issue 32: moving joins; issue 26: D grown */
    o.st.delay_grown = 0x100000000ull + 99;
    o.st.axis_lag_stops = 3; /* issue 32: the per-axis stops */
    o.st.axis_beyond = 4;
    o.st.reserve_slowed = 0x100000000ull + 5; /* issue 26: slowed for D's reserve */
    assert_int_equal(mbmap_encode_diag(regs, 2, 0xABCD1234u, &o), 0);
    assert_int_equal(mbmap_encode_diag(regs, MBMAP_MAX_OBJECTS, 1, &o), -MBMAP_EADDRESS);
    const uint16_t *b = regs + MBMAP_X_BASE(2);
    assert_int_equal(read_field(b, field("input diagnostics", "generation")), 0xABCD1234u);
    assert_int_equal(read_field(b, field("input diagnostics", "generation_tail")), 0xABCD1234u);
    unsigned reasons = 0;
    for (int c = 1; c < ENGINE_ERROR_COUNT; c++) {
        unsigned off = MBMAP_X_REJECTED_BY + 2 * (unsigned)(c - 1);
        if (!engine_reason_name(c)) {
            assert_int_equal(b[off] | b[off + 1], 0);
            continue;
        }
        char name[64];
        snprintf(name, sizeof name, "rejected_%s", engine_reason_name(c));
        const mbmap_field_t *f = field("input diagnostics", name);
        assert_int_equal(f->offset, off);
        assert_int_equal(read_field(b, f), 1000 + c);
        reasons++;
    }
    assert_int_equal(reasons, 9);
    assert_int_equal(read_field(b, field("input diagnostics", "transfers_moving")), 77);
    assert_int_equal(read_field(b, field("input diagnostics", "delay_grown")), 99);
    assert_int_equal(read_field(b, field("input diagnostics", "axis_lag_stops")), 3);
    assert_int_equal(read_field(b, field("input diagnostics", "axis_beyond")), 4);
    assert_int_equal(read_field(b, field("input diagnostics", "reserve_slowed")), 5);
    /* everything before it (object 2's is the last block of the table) */
    for (unsigned i = 0; i < MBMAP_X_BASE(2); i++)
        assert_int_equal(regs[i], 0);
}

/* Given the worst client's address as 8 groups, when the diagnostics block
 * is encoded and put in every word order, then group i is at
 * mb_worst_addr<i> unchanged (one u16 each: no order applies). */
static void test_encode_diag_worst_addr(void **state)
{
    (void)state;
    static uint16_t regs[MBMAP_TABLE_REGS(NOBJ)];
    mbmap_object_t o;
    memset(&o, 0, sizeof o);
    static const uint16_t a[MBMAP_X_MB_WORST_ADDR_GROUPS] = {0x2001, 0x0db8, 0, 0, 0, 0, 0x12, 7};
    memcpy(o.mb_worst_addr, a, sizeof a);
    for (int ord = MBMAP_ORDER_ABCD; ord <= MBMAP_ORDER_DCBA; ord++) {
        assert_int_equal(mbmap_encode_diag(regs, 1, 5, &o), 0);
        mbmap_order_diag(regs, NOBJ, (mbmap_order_t)ord);
        for (unsigned i = 0; i < MBMAP_X_MB_WORST_ADDR_GROUPS; i++) {
            char name[32];
            snprintf(name, sizeof name, "mb_worst_addr%u", i);
            const mbmap_field_t *f = field("input diagnostics", name);
            assert_int_equal(f->offset, MBMAP_X_MB_WORST_ADDR + i);
            assert_int_equal(regs[MBMAP_X_BASE(1) + f->offset], a[i]);
        }
    }
}

static size_t read_pdu(uint8_t *p, int fc, unsigned addr, unsigned count);
static size_t write_pdu(uint8_t *p, unsigned addr, unsigned count, const uint16_t *v);

/* Given n objects, then reads of the diagnostics blocks 0..n-1 are served
 * (input table and FC 03 mirror), and a read spanning the object blocks and
 * the unserved object slots, or past the last diagnostics block, is 02;
 * writes there are 02 too. */
static void test_diag_requests(void **state)
{
    (void)state;
    uint8_t p[260];
    uint16_t v[1] = {1};
    mbmap_write_t w;
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_X_BASE(0), 125)), 0);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_X_BASE(NOBJ) - 1, 1)), 0);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_X_BASE(NOBJ) - 1, 2)),
                     -MBMAP_EADDRESS);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_X_BASE(0) - 1, 2)),
                     -MBMAP_EADDRESS);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_REGS(NOBJ), 1)),
                     -MBMAP_EADDRESS);
    assert_int_equal(
        mbmap_check_request(NOBJ, 0, p, read_pdu(p, 3, MBMAP_MIRROR_BASE + MBMAP_X_BASE(1), 100)),
        0);
    assert_int_equal(mbmap_check_request(MBMAP_MAX_OBJECTS, 0, p,
                                         read_pdu(p, 4, MBMAP_X_BASE(MBMAP_MAX_OBJECTS) - 2, 2)),
                     0);
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, p,
                                              write_pdu(p, MBMAP_X_BASE(0), 1, v), &w),
                     -MBMAP_EADDRESS);
}

/* Given the documentation table, then fields fit their block, do not
 * overlap, and their register count matches their type. */
static void test_table_consistent(void **state)
{
    (void)state;
    size_t n;
    const mbmap_field_t *f = mbmap_fields(&n);
    for (size_t i = 0; i < n; i++) {
        unsigned want = f[i].type == MBMAP_T_U16 ? 1 : f[i].type == MBMAP_T_F64 ? 4 : 2;
        assert_int_equal(f[i].count, want);
        assert_true(f[i].offset + f[i].count <= MBMAP_BLOCK);
        for (size_t j = 0; j < i; j++)
            if (!strcmp(f[i].table, f[j].table))
                assert_true(f[i].offset >= f[j].offset + f[j].count ||
                            f[j].offset >= f[i].offset + f[i].count);
    }
    /* The waypoint block in the table is the block the decoder takes. */
    const mbmap_field_t *a = field("holding object", "wp_seq"),
                        *z = field("holding object", "wp_z");
    assert_int_equal(a->offset, MBMAP_H_WP);
    assert_int_equal(z->offset + z->count - a->offset, MBMAP_H_WP_COUNT);
}

static size_t read_pdu(uint8_t *p, int fc, unsigned addr, unsigned count)
{
    p[0] = (uint8_t)fc;
    p[1] = (uint8_t)(addr >> 8);
    p[2] = (uint8_t)addr;
    p[3] = (uint8_t)(count >> 8);
    p[4] = (uint8_t)count;
    return 5;
}

static size_t write_pdu(uint8_t *p, unsigned addr, unsigned count, const uint16_t *v)
{
    p[0] = 0x10;
    p[1] = (uint8_t)(addr >> 8);
    p[2] = (uint8_t)addr;
    p[3] = (uint8_t)(count >> 8);
    p[4] = (uint8_t)count;
    p[5] = (uint8_t)(2 * count);
    for (unsigned i = 0; i < count; i++) {
        p[6 + 2 * i] = (uint8_t)(v[i] >> 8);
        p[7 + 2 * i] = (uint8_t)v[i];
    }
    return 6 + 2 * count;
}

/* Given the spec's rules (function, then quantity, then address), when
 * requests break each one, then the exception code is the spec's. */
/* Given an image with a known f32 position and u32 counter, when reordered
 * to each word order, then libmodbus's decoder of that name (independent:
 * modbus_get_float_cdab etc.) reads the value, the ABCD one does not (except
 * ABCD), and reordering twice restores the image.  f64: the order is the
 * same rule over 8 bytes (CDAB reverses the words, BADC swaps bytes). */
static float dec_order(int o, const uint16_t *r)
{
    switch (o) {
    case MBMAP_ORDER_CDAB: return modbus_get_float_cdab(r);
    case MBMAP_ORDER_BADC: return modbus_get_float_badc(r);
    case MBMAP_ORDER_DCBA: return modbus_get_float_dcba(r);
    default: return modbus_get_float_abcd(r);
    }
}

static void test_word_orders(void **state)
{
    (void)state;
    assert_int_equal(mbmap_order_parse("cdab"), MBMAP_ORDER_CDAB);
    assert_int_equal(mbmap_order_parse("ABDC"), -1);
    for (int o = 0; o < 4; o++) {
        assert_int_equal(mbmap_order_parse(mbmap_order_name((mbmap_order_t)o)), o);
        static uint16_t img[MBMAP_REGS(NOBJ)], ref[MBMAP_REGS(NOBJ)];
        mbmap_object_t ob;
        memset(&ob, 0, sizeof ob);
        ob.sp.pos_m[1] = -1234.5678f;
        ob.sp.t_s = 0x1.23456789abcdep+3;
        ob.st.accepted = 0x11223344u;
        mbmap_daemon_t d = {.period_us = 0xA1B2C3D4u};
        mbmap_encode_daemon(img, &d);
        for (unsigned k = 0; k < NOBJ; k++)
            mbmap_encode_object(img, k, 7, &ob);
        memcpy(ref, img, sizeof img);
        mbmap_order_image(img, NOBJ, (mbmap_order_t)o);
        const uint16_t *b = img + MBMAP_OBJ_BASE(NOBJ - 1);
        assert_true(exact(dec_order(o, b + MBMAP_O_POS + 2), -1234.5678f));
        if (o)
            assert_false(exact(modbus_get_float_abcd(b + MBMAP_O_POS + 2), -1234.5678f));
        uint32_t u;
        float f = dec_order(o, b + MBMAP_O_ACCEPTED);
        memcpy(&u, &f, sizeof u);
        assert_int_equal(u, 0x11223344u);
        f = dec_order(o, img + MBMAP_D_PERIOD_US);
        memcpy(&u, &f, sizeof u);
        assert_int_equal(u, 0xA1B2C3D4u);
        /* f64 bytes on the wire, from the value's big-endian bytes B0..B7. */
        uint64_t bits;
        memcpy(&bits, &ob.sp.t_s, sizeof bits);
        uint8_t want[8], got[8];
        for (int i = 0; i < 8; i++)
            want[i] = (uint8_t)(bits >> (56 - 8 * i));
        for (int i = 0; i < 4; i++) {
            got[2 * i] = (uint8_t)(b[MBMAP_O_T_S + i] >> 8);
            got[2 * i + 1] = (uint8_t)b[MBMAP_O_T_S + i];
        }
        for (int i = 0; i < 8; i++) {
            int w = i / 2, byte = i % 2;
            if (o == MBMAP_ORDER_CDAB || o == MBMAP_ORDER_DCBA)
                w = 3 - w;
            if (o == MBMAP_ORDER_BADC || o == MBMAP_ORDER_DCBA)
                byte = 1 - byte;
            assert_int_equal(got[i], want[2 * w + byte]);
        }
        assert_int_equal(img[MBMAP_D_MAGIC], MBMAP_MAGIC); /* u16: never reordered */
        mbmap_order_image(img, NOBJ, (mbmap_order_t)o);
        assert_memory_equal(img, ref, sizeof img);
    }
}

/* Given the FC 03 mirror, when reading holding registers at MBMAP_MIRROR_BASE
 * + a, then the range rules of the input table apply; writes there are 02. */
static void test_mirror_request(void **state)
{
    (void)state;
    uint8_t p[260];
    uint16_t v[2] = {0};
    unsigned end = MBMAP_REGS(NOBJ);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 3, MBMAP_MIRROR_BASE, 125)), 0);
    assert_int_equal(
        mbmap_check_request(NOBJ, 0, p, read_pdu(p, 3, MBMAP_MIRROR_BASE + end - 1, 1)), 0);
    assert_int_equal(
        mbmap_check_request(NOBJ, 0, p, read_pdu(p, 3, MBMAP_MIRROR_BASE + end - 1, 2)),
        -MBMAP_EADDRESS);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 3, MBMAP_MIRROR_BASE - 1, 2)),
                     -MBMAP_EADDRESS);
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, 4, MBMAP_MIRROR_BASE, 1)),
                     -MBMAP_EADDRESS);
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, write_pdu(p, MBMAP_MIRROR_BASE + 100, 1, v)),
                     -MBMAP_EADDRESS);
    assert_true(MBMAP_REGS(1 + 2 * MBMAP_MAX_OBJECTS) <= MBMAP_MIRROR_BASE);
    assert_true(MBMAP_MIRROR_BASE + MBMAP_REGS(1 + 2 * MBMAP_MAX_OBJECTS) <= 65536);
}

static void test_check_request(void **state)
{
    (void)state;
    uint8_t p[260];
    unsigned end = MBMAP_REGS(NOBJ);
    for (int fc = 0; fc < 256; fc++) {
        memset(p, 0, sizeof p);
        p[0] = (uint8_t)fc;
        if (fc == 3 || fc == 4 || fc == 6 || fc == 16)
            continue;
        assert_int_equal(mbmap_check_request(NOBJ, 1, p, 5), -MBMAP_EFUNCTION);
    }
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, 0), -MBMAP_EVALUE);
    for (int fc = 3; fc <= 4; fc++) {
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, 0, 125)), 0);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, 0, 0)), -MBMAP_EVALUE);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, 0, 126)), -MBMAP_EVALUE);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, end - 1, 1)), 0);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, end - 1, 2)),
                         -MBMAP_EADDRESS);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, read_pdu(p, fc, 65535, 125)),
                         -MBMAP_EADDRESS);
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, 4), -MBMAP_EVALUE); /* truncated */
        assert_int_equal(mbmap_check_request(NOBJ, 0, p, 6), -MBMAP_EVALUE); /* trailing byte */
    }
    uint16_t v[124] = {0};
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, write_pdu(p, 100, 1, v)), -MBMAP_EFUNCTION);
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, write_pdu(p, 100, 1, v)), 0);
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, write_pdu(p, 100, 124, v)), -MBMAP_EVALUE);
    size_t l = write_pdu(p, 100, 2, v);
    p[5] = 3; /* byte count lies */
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, l), -MBMAP_EVALUE);
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, write_pdu(p, end - 1, 2, v)), -MBMAP_EADDRESS);
    p[0] = 6;
    assert_int_equal(mbmap_check_request(NOBJ, 0, p, 5), -MBMAP_EFUNCTION);
    assert_int_equal(mbmap_check_request(NOBJ, 1, p, 5), 0);
}

static void wp_regs(uint16_t *r, uint32_t seq, double t, double x, double y, double z)
{
    mbmap_put_u32(r + MBMAP_H_WP_SEQ - MBMAP_H_WP, seq);
    mbmap_put_f64(r + MBMAP_H_WP_T_S - MBMAP_H_WP, t);
    mbmap_put_f64(r + MBMAP_H_WP_POS - MBMAP_H_WP, x);
    mbmap_put_f64(r + MBMAP_H_WP_POS - MBMAP_H_WP + 4, y);
    mbmap_put_f64(r + MBMAP_H_WP_POS - MBMAP_H_WP + 8, z);
}

/* Given write requests, when decoded, then a whole waypoint block and a
 * known command decode exactly; partial blocks, read-only and unknown
 * values are refused with the documented exception. */
static void test_decode_write(void **state)
{
    (void)state;
    uint8_t p[260];
    uint16_t r[MBMAP_H_WP_COUNT + 1];
    mbmap_write_t w;

    wp_regs(r, 4000000000u, 12.345678901234, -1e5, 0.1, 7);
    assert_int_equal(mbmap_decode_write_order(
                         NOBJ, MBMAP_ORDER_ABCD, p,
                         write_pdu(p, MBMAP_OBJ_BASE(1) + MBMAP_H_WP, MBMAP_H_WP_COUNT, r), &w),
                     0);
    assert_int_equal(w.kind, MBMAP_WRITE_WAYPOINT);
    assert_int_equal(w.object, 1);
    assert_int_equal(w.wp.seq, 4000000000u);
    assert_true(exact(w.wp.t_s, 12.345678901234)); /* f64 carries the double exactly */
    assert_true(exact(w.wp.pos_m[0], -1e5) && exact(w.wp.pos_m[1], 0.1) && exact(w.wp.pos_m[2], 7));

    /* Part of the block, or one register too many: not applied. */
    assert_int_equal(mbmap_decode_write_order(
                         NOBJ, MBMAP_ORDER_ABCD, p,
                         write_pdu(p, MBMAP_OBJ_BASE(1) + MBMAP_H_WP, MBMAP_H_WP_COUNT - 1, r), &w),
                     -MBMAP_EADDRESS);
    assert_int_equal(mbmap_decode_write_order(
                         NOBJ, MBMAP_ORDER_ABCD, p,
                         write_pdu(p, MBMAP_OBJ_BASE(1) + MBMAP_H_WP, MBMAP_H_WP_COUNT + 1, r), &w),
                     -MBMAP_EADDRESS);
    assert_int_equal(
        mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, p,
                                 write_pdu(p, MBMAP_OBJ_BASE(1) + MBMAP_H_WP + 2, 4, r), &w),
        -MBMAP_EADDRESS);
    /* NaN and infinity refused. */
    wp_regs(r, 1, 1, NAN, 0, 0);
    assert_int_equal(mbmap_decode_write_order(
                         NOBJ, MBMAP_ORDER_ABCD, p,
                         write_pdu(p, MBMAP_OBJ_BASE(0) + MBMAP_H_WP, MBMAP_H_WP_COUNT, r), &w),
                     -MBMAP_EVALUE);
    assert_int_equal(w.object, 0);
    wp_regs(r, 1, INFINITY, 0, 0, 0);
    assert_int_equal(mbmap_decode_write_order(
                         NOBJ, MBMAP_ORDER_ABCD, p,
                         write_pdu(p, MBMAP_OBJ_BASE(0) + MBMAP_H_WP, MBMAP_H_WP_COUNT, r), &w),
                     -MBMAP_EVALUE);
    /* Commands by FC 06 and FC 16. */
    uint8_t s6[5] = {6, (uint8_t)(MBMAP_OBJ_BASE(2) >> 8), (uint8_t)MBMAP_OBJ_BASE(2), 0,
                     MBMAP_CMD_CLEAR};
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w), 0);
    assert_int_equal(w.kind, MBMAP_WRITE_COMMAND);
    assert_int_equal(w.object, 2);
    assert_int_equal(w.command, MBMAP_CMD_CLEAR);
    uint16_t c = MBMAP_CMD_RESET_COUNTERS;
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, p,
                                              write_pdu(p, MBMAP_OBJ_BASE(0), 1, &c), &w),
                     0);
    assert_int_equal(w.command, MBMAP_CMD_RESET_COUNTERS);
    for (unsigned bad = 0; bad < 65536; bad += (bad < 10 ? 1 : 997)) {
        if (bad >= MBMAP_CMD_START && bad <= MBMAP_CMD_FINISH)
            continue;
        s6[3] = (uint8_t)(bad >> 8);
        s6[4] = (uint8_t)bad;
        assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w),
                         -MBMAP_EVALUE);
    }
    /* Read-only places: the daemon block, other registers of an object. */
    s6[1] = 0;
    s6[2] = 5;
    s6[3] = 0;
    s6[4] = 1;
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w), -MBMAP_EADDRESS);
    s6[1] = 0;
    s6[2] = 102;
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w), -MBMAP_EADDRESS);
    /* The feed override: 0..200 %, one register. */
    s6[1] = 0;
    s6[2] = 100 + MBMAP_H_OVERRIDE;
    s6[3] = 0;
    s6[4] = 150;
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w), 0);
    assert_int_equal(w.kind, MBMAP_WRITE_OVERRIDE);
    assert_int_equal(w.object, 0);
    assert_int_equal(w.override_pct, 150);
    s6[4] = 201;
    assert_int_equal(mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, s6, 5, &w), -MBMAP_EVALUE);
    /* A read is not a write. */
    assert_int_equal(
        mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, p, read_pdu(p, 3, 100, 1), &w),
        -MBMAP_EFUNCTION);
}

/* Engine results map to the documented exceptions. */
static void test_from_engine(void **state)
{
    (void)state;
    assert_int_equal(mbmap_from_engine(0), 0);
    assert_int_equal(mbmap_from_engine(ENGINE_DUPLICATE), 0);
    assert_int_equal(mbmap_from_engine(-ENGINE_EFULL), -MBMAP_EBUSY);
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++)
        if (e != ENGINE_EFULL)
            assert_int_equal(mbmap_from_engine(-e), -MBMAP_EVALUE);
}

/* CRC-16/MODBUS: catalogue check value of "123456789" is 0x4B37; the spec's
 * example request 01 03 00 00 00 0A is sent with CRC bytes C5 CD. */
static void test_crc_and_framing(void **state)
{
    (void)state;
    assert_int_equal(mbmap_crc16((const uint8_t *)"123456789", 9), 0x4B37);
    const uint8_t req[] = {0x01, 0x03, 0x00, 0x00, 0x00, 0x0A};
    uint16_t crc = mbmap_crc16(req, sizeof req);
    assert_int_equal(crc & 0xff, 0xC5);
    assert_int_equal(crc >> 8, 0xCD);

    uint8_t f[16] = {1, 3};
    assert_int_equal(mbmap_rtu_frame_len(f, 1), 0);
    assert_int_equal(mbmap_rtu_frame_len(f, 2), 8);
    f[1] = 0x10;
    assert_int_equal(mbmap_rtu_frame_len(f, 6), 0);
    f[6] = 36;
    assert_int_equal(mbmap_rtu_frame_len(f, 7), 9 + 36);
    f[1] = 0x2B;
    assert_int_equal(mbmap_rtu_frame_len(f, 7), -1);
}

/* Each condition sets its health bit; a safety hold, a drive fault and a
 * feed hold show as state 4 (held), the others keep the engine's state. */
static void test_health(void **state)
{
    (void)state;
    static uint16_t regs[MBMAP_REGS(1)];
    struct {
        const char *what;
        uint16_t bit;
        int held;
    } cases[] = {{"safety", MBMAP_HEALTH_SAFETY, 1},     {"drive fault", MBMAP_HEALTH_DRIVE, 1},
                 {"hb lost", MBMAP_HEALTH_DRIVE, 1},     {"output", MBMAP_HEALTH_OUTPUT, 0},
                 {"underrun", MBMAP_HEALTH_UNDERRUN, 0}, {"stale", MBMAP_HEALTH_STALE, 0},
                 {"clock", MBMAP_HEALTH_CLOCK, 0},       {"feed hold", MBMAP_HEALTH_HELD, 1}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        mbmap_object_t o;
        memset(&o, 0, sizeof o);
        o.sp.state = ENGINE_STATE_STREAMING;
        o.drive_states = 0x0444; /* three drives in Operation Enabled */
        o.delay_s = 2.0;
        o.sp.age_s = 2.0;
        switch (c) {
        case 0: o.sp.flags = ENGINE_SP_FAULT | ENGINE_SP_HOLD; break;
        case 1: o.drive_states = 0x0474; break; /* y in Fault */
        case 2: o.drive_states = 0x4444; break;
        case 3: o.out_fault = 1; break;
        case 4: o.sp.state = ENGINE_STATE_UNDERRUN; break;
        case 5:
            o.clocked = 1;
            o.sp.age_s = 3.5;
            break;
        case 6:
            o.clocked = 1;
            o.clock_unsync = 1;
            break;
        default: o.held = 1; break;
        }
        assert_int_equal(mbmap_health(&o), cases[c].bit);
        assert_int_equal(mbmap_encode_object(regs, 0, 1, &o), 0);
        assert_int_equal(regs[MBMAP_OBJ_BASE(0) + MBMAP_O_HEALTH], cases[c].bit);
        assert_int_equal(regs[MBMAP_OBJ_BASE(0) + MBMAP_O_STATE],
                         cases[c].held ? MBMAP_STATE_HELD : (unsigned)o.sp.state);
    }
    /* well: nothing; not on the clock, an old age and an unsynchronised clock do not count */
    mbmap_object_t o;
    memset(&o, 0, sizeof o);
    o.sp.age_s = 1e9;
    o.clock_unsync = 1;
    o.drive_states = 0x0FFF; /* no drives */
    assert_int_equal(mbmap_health(&o), 0);
}

/* The float32 waypoint block decodes, in every word order, to the float32 values. */
/* The state register tells the lifecycle's states apart (LIFECYCLE.md): a stop
 * latched until start or clear is 5 stopped, not the engine's finished (3) or
 * streaming (1, while it brakes); a fault hold of the lifecycle (a drive's
 * hold braking to rest, with no drive state in 5..7) is 4 held; a hold wins
 * over a latch. */
static void test_state_register_lifecycle(void **state)
{
    (void)state;
    static uint16_t regs[MBMAP_REGS(1)];
    static const struct {
        unsigned eng, latched, fault_held, want;
    } cases[] = {
        {ENGINE_STATE_FINISHED, 0, 0, ENGINE_STATE_FINISHED},
        {ENGINE_STATE_FINISHED, 1, 0, MBMAP_STATE_STOPPED},
        {ENGINE_STATE_STREAMING, 1, 0, MBMAP_STATE_STOPPED},
        {ENGINE_STATE_STREAMING, 0, 1, MBMAP_STATE_HELD},
        {ENGINE_STATE_FINISHED, 1, 1, MBMAP_STATE_HELD},
    };
    for (unsigned c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        mbmap_object_t o;
        memset(&o, 0, sizeof o);
        o.drive_states = 0x0FFF; /* no drives */
        o.sp.state = (engine_state_t)cases[c].eng;
        o.latched = (uint16_t)cases[c].latched;
        o.fault_held = (uint16_t)cases[c].fault_held;
        assert_int_equal(mbmap_encode_object(regs, 0, 1, &o), 0);
        assert_int_equal(regs[MBMAP_OBJ_BASE(0) + MBMAP_O_STATE], cases[c].want);
    }
}

static void test_decode_wpf(void **state)
{
    (void)state;
    const float v[4] = {12.25f, 100.123456f, -7.5f, 0.1f};
    for (int ord = 0; ord < 4; ord++) {
        uint16_t r[MBMAP_H_WPF_COUNT];
        mbmap_put_u32(r, 77);
        for (int k = 0; k < 4; k++)
            mbmap_put_f32(r + 2 + 2 * k, v[k]);
        for (unsigned i = 0; i < MBMAP_H_WPF_COUNT; i += 2)
            mbmap_order_value(r + i, 2, (mbmap_order_t)ord); /* as the client sends it */
        uint8_t pdu[6 + 2 * MBMAP_H_WPF_COUNT];
        unsigned a = MBMAP_OBJ_BASE(0) + MBMAP_H_WPF;
        pdu[0] = MBMAP_FC_WRITE_MULTIPLE;
        pdu[1] = (uint8_t)(a >> 8);
        pdu[2] = (uint8_t)a;
        pdu[3] = 0;
        pdu[4] = MBMAP_H_WPF_COUNT;
        pdu[5] = 2 * MBMAP_H_WPF_COUNT;
        for (unsigned i = 0; i < MBMAP_H_WPF_COUNT; i++) {
            pdu[6 + 2 * i] = (uint8_t)(r[i] >> 8);
            pdu[7 + 2 * i] = (uint8_t)r[i];
        }
        mbmap_write_t w;
        assert_int_equal(mbmap_decode_write_order(1, (mbmap_order_t)ord, pdu, sizeof pdu, &w), 0);
        assert_int_equal(w.kind, MBMAP_WRITE_WAYPOINT);
        assert_int_equal(w.wp.seq, 77);
        assert_memory_equal(&(double){v[0]}, &w.wp.t_s, sizeof(double));
        for (int k = 0; k < 3; k++)
            assert_memory_equal(&(double){v[k + 1]}, &w.wp.pos_m[k], sizeof(double));
    }
}

static int markdown(void)
{
    size_t n;
    const mbmap_field_t *f = mbmap_fields(&n);
    const char *last = "";
    for (size_t i = 0; i < n; i++) {
        if (strcmp(last, f[i].table)) {
            const char *base = !strcmp(f[i].table, "input daemon")        ? "absolute address"
                               : !strcmp(f[i].table, "input diagnostics") ? "offset from 100·(65+k)"
                                                                          : "offset from 100·(k+1)";
            printf("%s| %s (%s) | type | name | unit | meaning |\n|---|---|---|---|---|\n",
                   i ? "\n" : "", f[i].table, base);
            last = f[i].table;
        }
        printf("| %u | %s | %s | %s | %s |\n", f[i].offset, mbmap_type_name(f[i].type), f[i].name,
               f[i].unit, f[i].doc);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "--markdown"))
        return markdown();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_word_order),
        cmocka_unit_test(test_encode_matches_table),
        cmocka_unit_test(test_table_consistent),
        cmocka_unit_test(test_check_request),
        cmocka_unit_test(test_decode_write),
        cmocka_unit_test(test_from_engine),
        cmocka_unit_test(test_crc_and_framing),
        cmocka_unit_test(test_word_orders),
        cmocka_unit_test(test_mirror_request),
        cmocka_unit_test(test_encode_diag),
        cmocka_unit_test(test_encode_diag_worst_addr),
        cmocka_unit_test(test_diag_requests),
        cmocka_unit_test(test_health),
        cmocka_unit_test(test_state_register_lifecycle),
        cmocka_unit_test(test_decode_wpf),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
