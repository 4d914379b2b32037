/* fuzz_cia402.c - libFuzzer target: the master side's decoders of frames a
 * CANopen drive (or anything on the bus) sends: SDO replies, heartbeat,
 * EMCY, the feedback TPDO, and the statusword state machine.
 *
 * Input: records [flags, id_lo, id_hi, len, data...] (len taken modulo 9 for
 * classic, any FD length for flags & FD), each offered to every decoder.
 * Invariants (abort on violation):
 *  - a decoder that succeeds reports a node-id in 1..127 that matches the id;
 *  - an SDO reply decodes only from the id of the node asked, 8 bytes;
 *  - every statusword maps to a state whose controlword towards Operation
 *    Enabled is one of the CiA 402 commands, and the state's name exists;
 *  - an SDO download we encode decodes as a request for the same object
 *    (command 0x2F/0x2B/0x23, index and sub where CiA 301 puts them).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cia402.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_frame(const canproto_frame_t *f)
{
    uint8_t node = 0, st = 0, reg = 0;
    uint16_t code = 0, sw = 0;
    int32_t pos = 0;
    cia402_sdo_reply_t r;

    if (cia402_decode_heartbeat(f, &node, &st) == 0)
        if (node < 1 || node > CIA402_NODE_MAX || f->id != CIA402_COB_HEARTBEAT + node ||
            f->len != 1)
            abort();
    if (cia402_decode_emcy(f, &node, &code, &reg) == 0)
        if (node < 1 || node > CIA402_NODE_MAX || f->id != CIA402_COB_EMCY + node || f->len != 8)
            abort();
    /* The node the id names, its neighbours and the ends of the range (all
     * 129 nodes cost 129 decodes a frame and kept the target at 1 k/s; a
     * decoder that answered for the wrong node answers for a neighbour too). */
    unsigned own = f->id - CIA402_COB_SDO_TX, ask[5] = {0, 128, own, own - 1, own + 1};
    for (unsigned k = 0; k < 5; k++) {
        unsigned n = ask[k];
        if (n > 255)
            continue;
        if (cia402_decode_sdo_reply((uint8_t)n, f, &r) == 0) {
            if (n < 1 || n > CIA402_NODE_MAX || f->id != CIA402_COB_SDO_TX + n || f->len != 8)
                abort();
            if (r.kind == CIA402_SDO_ABORT)
                (void)cia402_sdo_abort_text(r.abort_code);
        }
    }
    if (cia402_decode_feedback(f, &sw, &pos) == 0) {
        if (f->len < 6)
            abort();
        cia402_state_t s = cia402_state(sw);
        if ((unsigned)s > CIA402_STATE_UNKNOWN || !cia402_state_name(s))
            abort();
        for (int reset = 0; reset < 2; reset++) {
            uint16_t cw = cia402_controlword_towards_enabled(s, reset);
            if (cw != CIA402_CW_DISABLE_VOLTAGE && cw != CIA402_CW_SHUTDOWN &&
                cw != CIA402_CW_SWITCH_ON && cw != CIA402_CW_ENABLE_OPERATION &&
                cw != CIA402_CW_FAULT_RESET)
                abort();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    size_t i = 0;
    while (i + 4 <= size) {
        canproto_frame_t f;
        memset(&f, 0, sizeof f);
        f.flags = data[i] & 0x3F;
        f.id = (uint32_t)data[i + 1] | ((uint32_t)(data[i + 2] & 0x07) << 8);
        unsigned len = data[i + 3];
        len = (f.flags & CANPROTO_F_FD) ? len % 65 : len % 9;
        i += 4;
        if (len > size - i)
            len = (unsigned)(size - i);
        f.len = (uint8_t)len;
        memcpy(f.data, data + i, len);
        i += len;
        check_frame(&f);
        /* an SDO download we build from the same bytes (d zeroed: checked
         * below also where the encoder refused it and wrote nothing, which
         * valgrind saw read from the stack) */
        canproto_frame_t d;
        memset(&d, 0, sizeof d);
        uint16_t index = (uint16_t)(f.id | (unsigned)f.data[0] << 8);
        unsigned sz = 1u << (f.data[1] % 3); /* 1, 2, 4 */
        uint8_t node = (uint8_t)(f.data[2] % 130);
        if (cia402_encode_sdo_download(node, index, f.data[3], (uint32_t)f.id, sz, &d) == 0) {
            if (node < 1 || node > CIA402_NODE_MAX || d.id != CIA402_COB_SDO_RX + node ||
                d.len != 8 || d.data[0] != (uint8_t)(0x23 | ((4 - sz) << 2)) ||
                (uint16_t)(d.data[1] | d.data[2] << 8) != index || d.data[3] != f.data[3])
                abort();
        } else if (node >= 1 && node <= CIA402_NODE_MAX) {
            abort();
        }
        check_frame(&d);
    }
    return 0;
}
