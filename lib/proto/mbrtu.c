/* mbrtu.c - Modbus RTU request framing on a byte stream (see mbrtu.h). */
#include <string.h>

#include "mbrtu.h"

void mbrtu_init(mbrtu_rx_t *r)
{
    memset(r, 0, sizeof *r);
}

size_t mbrtu_space(const mbrtu_rx_t *r)
{
    return sizeof r->buf - r->len;
}

static int crc_ok(const uint8_t *f, size_t len)
{
    uint16_t crc = mbmap_crc16(f, len - 2);
    return f[len - 2] == (crc & 0xffu) && f[len - 1] == (crc >> 8);
}

void mbrtu_bytes(mbrtu_rx_t *r, const uint8_t *b, size_t n, mbrtu_deliver_fn deliver, void *ctx)
{
    if (r->discard) {
        r->len = 0;
        return;
    }
    if (n > mbrtu_space(r))
        n = mbrtu_space(r);
    memcpy(r->buf + r->len, b, n);
    r->len += n;
    for (;;) {
        int fl = mbmap_rtu_frame_len(r->buf, r->len);
        if (fl == 0 || (fl < 0 && r->len < sizeof r->buf))
            return; /* more bytes, or the silence, will tell */
        if (fl < 0 || fl > MBMAP_RTU_ADU_MAX) {
            r->discard = 1;
            r->len = 0;
            return;
        }
        if (r->len < (size_t)fl)
            return;
        if (crc_ok(r->buf, (size_t)fl)) {
            deliver(ctx, r->buf, (size_t)fl);
        } else {
            /* Frame boundary unknown from here on: resynchronise at silence. */
            r->crc_errors++;
            r->discard = 1;
            r->len = 0;
            return;
        }
        memmove(r->buf, r->buf + fl, r->len - (size_t)fl);
        r->len -= (size_t)fl;
    }
}

void mbrtu_silence(mbrtu_rx_t *r, mbrtu_deliver_fn deliver, void *ctx)
{
    /* A frame of a function we cannot size is delimited by this silence:
     * if it is whole and ours, it gets its exception 01.  No RTU frame is
     * longer than MBMAP_RTU_ADU_MAX (the buffer holds twice that): a longer
     * one is refused and counted, even with a right CRC. */
    if (!r->discard && r->len >= 4 && r->len <= MBMAP_RTU_ADU_MAX &&
        mbmap_rtu_frame_len(r->buf, r->len) < 0 && crc_ok(r->buf, r->len))
        deliver(ctx, r->buf, r->len);
    else if (r->len && !r->discard)
        r->crc_errors++;
    r->len = 0;
    r->discard = 0;
}
