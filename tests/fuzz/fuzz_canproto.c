/* fuzz_canproto.c - libFuzzer target: the frame decoder and the waypoint
 * reassembly state machine, and the candump line parser.
 *
 * Input: byte 0 selects the slot count (1..4); then a sequence of records
 * [flags, id_lo, len, data...]: each becomes one frame offered to the
 * reassembler (classic or FD id), and the same bytes as text go to
 * candump_parse_line.  Invariants checked (abort on violation):
 *  - a completed waypoint has finite values within the field ranges;
 *  - the counters add up: every frame is counted once as malformed, or
 *    reaches the sequence logic;
 *  - extended sequence numbers of consumed waypoints strictly increase: by
 *    lost_before + 1, or for a resync (a sender that restarted its numbering)
 *    by 128..255 with nothing lost and a time later than the last consumed
 *    one's, counted once when consumed;
 *  - encode(sp) sends the code nearest to the position / LSB, checked in exact
 *    integer arithmetic (a double tolerance of half an LSB was wrong: at
 *    -130927.96875 m, an exact tie, the decoded double differs by half an LSB
 *    plus its own rounding; tests/fuzz/regress/fuzz_canproto/), and decode
 *    gives that code x LSB up to the rounding to a double;
 *  - the STATUS and STATUS2 decoders (every page; what a CAN tool reads back from the
 *    daemon) on every frame: a page decoder answers exactly when
 *    canproto_status2_page names its page, and what a decoder accepts,
 *    encoded again and decoded, gives the same fields (check_status).
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "candump.h"
#include "canproto.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* |code - x * per_unit| <= 1/2, exactly: x = m 2^ex with m a 53-bit integer,
 * compared as 2 m per_unit 2^ex against (2 code +- 1) in 128-bit integers. */
static int nearest_code(double x, int64_t per_unit, int64_t code)
{
    int ex;
    double fr = frexp(x, &ex);            /* x = fr 2^ex, 1/2 <= |fr| < 1 */
    __int128 m = (__int128)ldexp(fr, 53); /* exact */
    ex -= 53;
    __int128 lhs = 2 * m * per_unit, lo = 2 * (__int128)code - 1, hi = 2 * (__int128)code + 1;
    if (ex >= 0) {
        if (ex > 40)
            return 0; /* |x| >= 2^93: never in range */
        lhs *= (__int128)1 << ex;
    } else if (-ex <= 80) {
        lo *= (__int128)1 << -ex;
        hi *= (__int128)1 << -ex;
    } else {
        return code == 0; /* |x| < 2^-27: the nearest code is 0 */
    }
    return lo <= lhs && lhs <= hi;
}

/* decode(encode(decode(f))) == decode(f), field by field (the structs are
 * zeroed by the decoders, so memcmp compares padding as zero). */
#define ROUND_TRIP(T, dec, enc, id, f)                                                             \
    do {                                                                                           \
        T a_, b_;                                                                                  \
        canproto_frame_t g_;                                                                       \
        if (dec(f, &a_) == 0) {                                                                    \
            enc(id, &a_, &g_);                                                                     \
            if (dec(&g_, &b_) != 0 || memcmp(&a_, &b_, sizeof a_))                                 \
                abort();                                                                           \
            found++;                                                                               \
        }                                                                                          \
    } while (0)

static void check_status(const canproto_frame_t *f)
{
    int page = canproto_status2_page(f), found = 0;
    ROUND_TRIP(canproto_status_t, canproto_decode_status, canproto_encode_status, 0x6C1, f);
    found = 0;
    ROUND_TRIP(canproto_st2_faults_t, canproto_decode_status2_faults,
               canproto_encode_status2_faults, 0x6D1, f);
    if (found != (page == CANPROTO_ST2_FAULTS))
        abort();
    found = 0;
    ROUND_TRIP(canproto_st2_rejected_t, canproto_decode_status2_rejected,
               canproto_encode_status2_rejected, 0x6D1, f);
    if (found != (page == CANPROTO_ST2_REJECTED))
        abort();
    found = 0;
    ROUND_TRIP(canproto_st2_clock_t, canproto_decode_status2_clock, canproto_encode_status2_clock,
               0x6D1, f);
    if (found != (page == CANPROTO_ST2_CLOCK))
        abort();
    found = 0;
    ROUND_TRIP(canproto_status2_drive_t, canproto_decode_status2_drive,
               canproto_encode_status2_drive, 0x6D1, f);
    if (found != (page == CANPROTO_ST2_DRIVE))
        abort();
    found = 0;
    ROUND_TRIP(canproto_st2_bus_t, canproto_decode_status2_bus, canproto_encode_status2_bus, 0x6D1,
               f);
    if (found != (page == CANPROTO_ST2_BUS))
        abort();
    found = 0;
    ROUND_TRIP(canproto_st2_motion_t, canproto_decode_status2_motion,
               canproto_encode_status2_motion, 0x6D1, f);
    if (found != (page == CANPROTO_ST2_MOTION))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    canproto_slot_t slots[4];
    canproto_rx_t rx;
    if (size < 1)
        return 0;
    unsigned nslots = 1 + (data[0] & 3);
    canproto_rx_init(&rx, slots, nslots);
    size_t i = 1;
    uint64_t frames = 0;
    int have = 0;
    uint32_t last = 0;
    double last_t = 0;
    while (i + 3 <= size) {
        canproto_frame_t f;
        memset(&f, 0, sizeof f);
        uint8_t fl = data[i];
        f.flags = fl & 0x3F;
        int is_fd = (fl >> 6) & 1;
        f.id = is_fd ? 0x690 : 0x680;
        f.len = data[i + 2] % (CANPROTO_MAX_DLEN + 1);
        i += 3;
        size_t n = f.len;
        if (n > size - i)
            n = size - i;
        memcpy(f.data, data + i, n);
        i += n;
        check_status(&f);
        canproto_rx_out_t out;
        int rc = canproto_rx_frame(&rx, &f, is_fd, &out);
        frames++;
        if (rc == CANPROTO_RX_WAYPOINT) {
            if (!isfinite(out.wp.t_s) || out.wp.t_s < 0 || out.wp.t_s > 3e8)
                abort();
            for (int a = 0; a < ENGINE_AXES; a++)
                if (!isfinite(out.wp.pos_m[a]) || fabs(out.wp.pos_m[a]) > 1.5e8)
                    abort();
            if (have && (int32_t)(out.wp.seq - last) <= 0)
                abort();
            /* a resync: behind in numbering (128..255 ahead, modulo 256), later
             * in time, nothing lost; else at most 127 ahead */
            uint32_t step = out.wp.seq - last;
            if (out.resync &&
                (!have || step < 128 || step > 255 || out.lost_before || !(out.wp.t_s > last_t)))
                abort();
            if (!out.resync && have && step != out.lost_before + 1)
                abort();
            /* consume most of them, leave some (as after EFULL) */
            if (!(fl & 0x80)) {
                uint64_t resyncs = rx.st.resyncs;
                canproto_rx_consume(&rx, &out);
                if (rx.st.resyncs != resyncs + out.resync)
                    abort();
                have = 1;
                last = out.wp.seq;
                last_t = out.wp.t_s;
            }
        } else if (rc < 0 && (rc < -CANPROTO_EID)) {
            abort(); /* the reassembler only reports frame errors */
        }
    }
    if (rx.st.frames != frames)
        abort();

    /* the candump parser on the raw bytes as a line */
    char line[300];
    size_t n = size < sizeof line - 1 ? size : sizeof line - 1;
    memcpy(line, data, n);
    line[n] = '\0';
    candump_line_t cl;
    if (candump_parse_line(line, &cl) == 0) {
        char back[256];
        if (candump_format_frame(back, sizeof back, &cl.frame) < 0)
            abort();
        canproto_frame_t g;
        if (candump_parse_frame(back, &g) != 0 || g.id != cl.frame.id || g.len != cl.frame.len ||
            memcmp(g.data, cl.frame.data, g.len))
            abort();
    }

    /* setpoint round trip on bytes read as doubles */
    if (size >= 8 * 6) {
        engine_setpoint_t sp;
        memset(&sp, 0, sizeof sp);
        memcpy(sp.pos_m, data, sizeof sp.pos_m);
        memcpy(sp.vel_m_s, data + 24, sizeof sp.vel_m_s);
        canproto_frame_t f3[3];
        canproto_setpoint_t d;
        int rc = canproto_encode_setpoint(0x6A0, &sp, f3);
        for (int a = 0; a < 3; a++) {
            if (canproto_decode_setpoint(&f3[a], &d) != 0)
                abort();
            int32_t code = (int32_t)((uint32_t)f3[a].data[2] | (uint32_t)f3[a].data[3] << 8 |
                                     (uint32_t)f3[a].data[4] << 16 | (uint32_t)f3[a].data[5] << 24);
            if (rc == 0 && !nearest_code(sp.pos_m[a], 10000, code))
                abort();
            /* decoded: code x 1e-4 up to the rounding to a double */
            double want = (double)code / 1e4;
            if (fabs(d.pos_m[a] - want) > 2 * nextafter(fabs(want), INFINITY) - 2 * fabs(want))
                abort();
        }
    }
    return 0;
}
