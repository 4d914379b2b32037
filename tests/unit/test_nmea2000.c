/* test_nmea2000.c - NMEA 2000 identifier, fast-packet reassembly and the
 * position PGNs 129025 / 129029 (lib/proto/nmea2000.h), against a test
 * vector published with canboat's JavaScript decoder (canboat/canboatjs,
 * its PGN 129029 test data: the bytes below decode there to 2017-04-15
 * 14:57:56.89500, latitude 39.0700875, longitude -76.4640319, altitude not
 * available, method "DGNSS fix"). */
#include "test.h"

#include <math.h>
#include <string.h>

#include "nmea2000.h"

static const uint8_t canboatjs_129029[43] = {
    0x9b, 0x77, 0x43, 0x36, 0xf6, 0x1c, 0x20, 0x00, 0x2e, 0xcf, 0x33, 0x60, 0x0c, 0x6c, 0x05,
    0xff, 0x49, 0x10, 0x5d, 0xae, 0x73, 0x63, 0xf5, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff,
    0x7f, 0x23, 0xfc, 0x12, 0x41, 0x00, 0xff, 0x7f, 0xff, 0xff, 0xff, 0x7f, 0x00,
};

/* Frame msg into fast packets (frame 0: counter, length, 6 bytes; then 7). */
static size_t frames_of(const uint8_t *msg, size_t len, uint8_t seq, uint8_t fr[][8])
{
    size_t n = 0, off = 0;
    fr[n][0] = (uint8_t)(seq << 5);
    fr[n][1] = (uint8_t)len;
    memcpy(fr[n] + 2, msg, 6);
    off = 6;
    n++;
    while (off < len) {
        size_t k = len - off < 7 ? len - off : 7;
        memset(fr[n], 0xff, 8);
        fr[n][0] = (uint8_t)(seq << 5 | n);
        memcpy(fr[n] + 1, msg + off, k);
        off += k;
        n++;
    }
    return n;
}

/* Given canboatjs's 129029 bytes sent as 7 fast-packet frames, when
 * reassembled and decoded, then date, time, latitude and longitude are
 * canboatjs's and the altitude is not available. */
static void test_gnss_position_canboatjs_vector(void **state)
{
    (void)state;
    uint8_t fr[8][8];
    size_t n = frames_of(canboatjs_129029, sizeof canboatjs_129029, 5, fr);
    assert_int_equal(n, 7);
    n2k_fast_t f;
    memset(&f, 0, sizeof f);
    for (size_t i = 0; i + 1 < n; i++)
        assert_int_equal(n2k_fast_push(&f, fr[i], 8), 0);
    assert_int_equal(n2k_fast_push(&f, fr[n - 1], 8), 1);
    assert_int_equal(f.len, 43);
    n2k_position_t p;
    assert_int_equal(n2k_decode_gnss_position(f.data, f.len, &p), 0);
    assert_true(fabs(p.lat_deg - 39.0700875) < 1e-7);
    assert_true(fabs(p.lon_deg - -76.4640319) < 1e-7);
    assert_true(isnan(p.alt_m));
    assert_true(p.has_time);
    assert_int_equal(p.days, 17271); /* 2017-04-15 */
    assert_true(fabs(p.tod_s - (14 * 3600 + 57 * 60 + 56.895)) < 1e-9);
    assert_int_equal(p.method, 2); /* DGNSS fix */
}

/* Given a frame missing from a message, then that message is dropped
 * (-N2K_ESEQ once), and the next message still decodes; a continuation
 * frame with no message in progress is ignored. */
static void test_fast_packet_missing_frame(void **state)
{
    (void)state;
    uint8_t fr[8][8];
    size_t n = frames_of(canboatjs_129029, sizeof canboatjs_129029, 1, fr);
    n2k_fast_t f;
    memset(&f, 0, sizeof f);
    assert_int_equal(n2k_fast_push(&f, fr[3], 8), 0); /* stray: no start seen */
    assert_int_equal(n2k_fast_push(&f, fr[0], 8), 0);
    assert_int_equal(n2k_fast_push(&f, fr[1], 8), 0);
    assert_int_equal(n2k_fast_push(&f, fr[3], 8), -N2K_ESEQ);
    assert_int_equal(n2k_fast_push(&f, fr[4], 8), 0); /* the rest: stray now */
    int rc = 0;
    for (size_t i = 0; i < n; i++)
        rc = n2k_fast_push(&f, fr[i], 8);
    assert_int_equal(rc, 1);
    uint8_t big[8] = {0x20, 224, 0, 0, 0, 0, 0, 0};
    assert_int_equal(n2k_fast_push(&f, big, 8), -N2K_ELEN);
}

/* Given identifiers of the real capture (tests/data/canboat_candumpSample3.log),
 * then PGN, priority and source follow ISO 11783; a PDU1 PGN keeps its
 * destination out of the PGN; encode inverts decode. */
static void test_identifier(void **state)
{
    (void)state;
    n2k_id_t id;
    n2k_id_decode(0x09F112CC, &id);
    assert_int_equal(id.pgn, 127250);
    assert_int_equal(id.priority, 2);
    assert_int_equal(id.source, 0xCC);
    assert_int_equal(id.dest, 255);
    assert_int_equal(n2k_id_encode(&id), 0x09F112CC);
    n2k_id_decode(0x18EACCAC, &id);
    assert_int_equal(id.pgn, 59904);
    assert_int_equal(id.dest, 0xCC);
    assert_int_equal(id.source, 0xAC);
    assert_int_equal(n2k_id_encode(&id), 0x18EACCAC);
}

/* Given 129025 frames, then 1e-7 deg per bit; "not available" and a
 * latitude beyond 90 deg are refused; a short frame too. */
static void test_position_rapid(void **state)
{
    (void)state;
    n2k_position_t p;
    /* -33.8688197, 151.2092955 (little-endian int32 of 1e-7 deg) */
    int32_t la = -338688197, lo = 1512092955;
    uint8_t d[8];
    for (int i = 0; i < 4; i++) {
        d[i] = (uint8_t)((uint32_t)la >> (8 * i));
        d[4 + i] = (uint8_t)((uint32_t)lo >> (8 * i));
    }
    assert_int_equal(n2k_decode_position_rapid(d, 8, &p), 0);
    assert_true(fabs(p.lat_deg - -33.8688197) < 1e-12);
    assert_true(fabs(p.lon_deg - 151.2092955) < 1e-12);
    assert_true(isnan(p.alt_m));
    assert_int_equal(n2k_decode_position_rapid(d, 7, &p), -N2K_ELEN);
    uint8_t na[8] = {0xff, 0xff, 0xff, 0x7f, 0, 0, 0, 0};
    assert_int_equal(n2k_decode_position_rapid(na, 8, &p), -N2K_ENA);
    int32_t far = 910000000;
    for (int i = 0; i < 4; i++)
        d[i] = (uint8_t)((uint32_t)far >> (8 * i));
    assert_int_equal(n2k_decode_position_rapid(d, 8, &p), -N2K_ERANGE);
    assert_non_null(n2k_strerror(-N2K_ESEQ));
}

/* Given 129029 with method 0 (no fix), then -N2K_ENOFIX. */
static void test_gnss_no_fix(void **state)
{
    (void)state;
    uint8_t m[43];
    memcpy(m, canboatjs_129029, sizeof m);
    m[31] = 0x03; /* GNSS type 3, method 0 */
    n2k_position_t p;
    assert_int_equal(n2k_decode_gnss_position(m, sizeof m, &p), -N2K_ENOFIX);
    assert_int_equal(n2k_decode_gnss_position(m, 42, &p), -N2K_ELEN);
}

/* Given PGN 129026 frames laid out as canboat defines them (SID, reference
 * in bits 0..1, COG 1e-4 rad, SOG 1e-2 m/s): the real capture's
 * (tests/data/canboat_candumpSample3.log, FF00000001000000: SID 255, true,
 * COG 0, SOG 0.01 m/s), a course of 1.5708 rad magnetic at 12.34 m/s, one
 * without SOG and one beyond 2 pi, then decoded, refused as not available,
 * and out of range. */
static void test_cog_sog(void **state)
{
    (void)state;
    n2k_cog_sog_t v;
    static const uint8_t sample[8] = {0xFF, 0x00, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00};
    assert_int_equal(n2k_decode_cog_sog(sample, 8, &v), 0);
    assert_int_equal(v.sid, 255);
    assert_int_equal(v.ref, 0);
    assert_true(fabs(v.cog_deg) < 1e-12);
    assert_true(fabs(v.sog_m_s - 0.01) < 1e-12);
    /* 15708 = 0x3D5C, 1234 = 0x04D2 */
    static const uint8_t mag[8] = {7, 0xFD, 0x5C, 0x3D, 0xD2, 0x04, 0xFF, 0xFF};
    assert_int_equal(n2k_decode_cog_sog(mag, 8, &v), 0);
    assert_int_equal(v.sid, 7);
    assert_int_equal(v.ref, 1);
    assert_true(fabs(v.cog_deg - 1.5708 * 180.0 / M_PI) < 1e-9);
    assert_true(fabs(v.sog_m_s - 12.34) < 1e-12);
    static const uint8_t na[8] = {7, 0xFC, 0x5C, 0x3D, 0xFF, 0xFF, 0xFF, 0xFF};
    assert_int_equal(n2k_decode_cog_sog(na, 8, &v), -N2K_ENA);
    static const uint8_t big[8] = {7, 0xFC, 0x00, 0xF6, 0x01, 0x00, 0xFF, 0xFF}; /* 62976 */
    assert_int_equal(n2k_decode_cog_sog(big, 8, &v), -N2K_ERANGE);
    assert_int_equal(n2k_decode_cog_sog(sample, 7, &v), -N2K_ELEN);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gnss_position_canboatjs_vector),
        cmocka_unit_test(test_fast_packet_missing_frame),
        cmocka_unit_test(test_identifier),
        cmocka_unit_test(test_position_rapid),
        cmocka_unit_test(test_gnss_no_fix),
        cmocka_unit_test(test_cog_sog),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
