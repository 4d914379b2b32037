/* test_mbrtu.c - Modbus RTU request framing on a byte stream (lib/proto/mbrtu.h).
 * Frames are built here with a bitwise CRC-16/MODBUS (not mbmap_crc16). */
#include <string.h>

#include "mbrtu.h"
#include "test.h"

typedef struct {
    unsigned n;
    size_t len[8];
} got_t;

static void deliver(void *ctx, const uint8_t *f, size_t len)
{
    got_t *g = ctx;
    (void)f;
    if (g->n < 8)
        g->len[g->n] = len;
    g->n++;
}

static void put_crc(uint8_t *f, size_t len)
{
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < len - 2; i++) {
        crc ^= f[i];
        for (int k = 0; k < 8; k++)
            crc = (crc & 1) ? (uint16_t)((crc >> 1) ^ 0xA001) : (uint16_t)(crc >> 1);
    }
    f[len - 2] = (uint8_t)(crc & 0xff);
    f[len - 1] = (uint8_t)(crc >> 8);
}

/* A frame of a function whose length the header does not give, len bytes,
 * right CRC, fed in reads of 32 then ended by a line silence. */
static got_t unsized_frame(size_t len, uint64_t *crc_errors)
{
    uint8_t f[400];
    got_t g = {0};
    mbrtu_rx_t r;
    memset(f, 0x55, sizeof f);
    f[0] = 1;
    f[1] = 0x41; /* user-defined function: delimited by silence */
    put_crc(f, len);
    mbrtu_init(&r);
    for (size_t i = 0; i < len; i += 32)
        mbrtu_bytes(&r, f + i, len - i < 32 ? len - i : 32, deliver, &g);
    mbrtu_silence(&r, deliver, &g);
    *crc_errors = r.crc_errors;
    return g;
}

/* Given an unsized frame of 200 bytes with a right CRC, when the line goes
 * silent, then it is delivered (it gets its exception 01). */
static void test_unsized_frame_within_adu_max_delivered(void **state)
{
    (void)state;
    uint64_t e;
    got_t g = unsized_frame(200, &e);
    assert_int_equal(g.n, 1);
    assert_int_equal(g.len[0], 200);
    assert_int_equal(e, 0);
}

/* Given an unsized frame of 319 bytes (beyond the 256-byte RTU ADU) with a
 * right CRC, when the line goes silent, then it is refused and counted
 * (fuzz_modbus_rtu finding: it was delivered to modbus_reply). */
static void test_unsized_frame_beyond_adu_max_refused(void **state)
{
    (void)state;
    uint64_t e;
    got_t g = unsized_frame(319, &e);
    assert_int_equal(g.n, 0);
    assert_int_equal(e, 1);
    g = unsized_frame(MBMAP_RTU_ADU_MAX + 1, &e);
    assert_int_equal(g.n, 0);
    assert_int_equal(e, 1);
    g = unsized_frame(MBMAP_RTU_ADU_MAX, &e);
    assert_int_equal(g.n, 1);
}

/* Given two read-holding-registers requests in one read, then both are
 * delivered, in order, with no silence needed. */
static void test_two_requests_one_read(void **state)
{
    (void)state;
    uint8_t b[16] = {1, 3, 0, 0, 0, 1, 0, 0, 1, 3, 0, 8, 0, 2, 0, 0};
    got_t g = {0};
    mbrtu_rx_t r;
    put_crc(b, 8);
    put_crc(b + 8, 8);
    mbrtu_init(&r);
    mbrtu_bytes(&r, b, sizeof b, deliver, &g);
    assert_int_equal(g.n, 2);
    assert_int_equal(g.len[0], 8);
    assert_int_equal(g.len[1], 8);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_unsized_frame_within_adu_max_delivered),
        cmocka_unit_test(test_unsized_frame_beyond_adu_max_refused),
        cmocka_unit_test(test_two_requests_one_read),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
