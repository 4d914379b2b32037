/* fuzz_canerr.c - libFuzzer target: SocketCAN error frames (lib/proto/canerr.h)
 * as the daemon gets them, from a socket or from a candump log line.
 *
 * Input: records [class (4 bytes, little-endian), len, data (8 bytes)], each
 * given to canerr_bus_frame; the same frame is also formatted as a candump
 * line ("2000xxxx#...") and parsed back, and the parsed frame given to a
 * second accumulator.
 * Invariants (abort on violation):
 *  - the state is always error-active, warning, passive or bus-off, and has a name;
 *  - frames + malformed = records given; each entry counter <= frames;
 *  - a frame refused by canerr_decode changes nothing but malformed;
 *  - the state changes exactly when canerr_bus_frame says so;
 *  - the candump round trip keeps the error flag, class and payload, so both
 *    accumulators end equal.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "candump.h"
#include "canerr.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REC 13

static void check_bus(const canerr_bus_t *b, uint64_t given)
{
    if (b->state < CANERR_STATE_ACTIVE || b->state > CANERR_STATE_BUS_OFF ||
        canerr_state_name(b->state)[0] == '?')
        abort();
    if (b->frames + b->malformed != given)
        abort();
    if (b->warnings > b->frames || b->passives > b->frames || b->bus_offs > b->frames ||
        b->restarts > b->frames || b->bus_errors > b->frames || b->overflows > b->frames)
        abort();
}

/* Field by field (the struct has padding). */
static int same(const canerr_bus_t *x, const canerr_bus_t *y)
{
    return x->state == y->state && x->tx_err == y->tx_err && x->rx_err == y->rx_err &&
           x->frames == y->frames && x->malformed == y->malformed && x->warnings == y->warnings &&
           x->passives == y->passives && x->bus_offs == y->bus_offs && x->restarts == y->restarts &&
           x->bus_errors == y->bus_errors && x->overflows == y->overflows;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    canerr_bus_t a, b;
    canerr_bus_init(&a);
    canerr_bus_init(&b);
    uint64_t n = 0;
    for (size_t off = 0; off + REC <= size; off += REC, n++) {
        const uint8_t *r = data + off;
        uint32_t cls = (uint32_t)r[0] | (uint32_t)r[1] << 8 | (uint32_t)r[2] << 16 |
                       (uint32_t)r[3] << 24;
        size_t len = r[4] % 9;
        canerr_bus_t before = a;
        int rc = canerr_bus_frame(&a, cls, r + 5, len);
        if (rc < 0) {
            before.malformed++;
            if (!same(&before, &a))
                abort();
        } else if ((rc == 1) != (before.state != a.state)) {
            abort();
        }
        check_bus(&a, n + 1);

        canproto_frame_t f, g;
        memset(&f, 0, sizeof f);
        f.flags = CANPROTO_F_ERR;
        f.id = cls & CANERR_MASK;
        f.len = (uint8_t)len;
        memcpy(f.data, r + 5, len);
        char line[64];
        if (candump_format_frame(line, sizeof line, &f) < 0)
            abort();
        if (candump_parse_frame(line, &g) < 0 || !(g.flags & CANPROTO_F_ERR) || g.id != f.id ||
            g.len != f.len || memcmp(g.data, f.data, f.len))
            abort();
        canerr_bus_frame(&b, g.id, g.data, g.len);
    }
    check_bus(&b, n);
    if (!same(&a, &b))
        abort();
    return 0;
}
