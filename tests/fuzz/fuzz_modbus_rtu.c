/*
 * fuzz_modbus_rtu.c - libFuzzer target for Modbus RTU request framing on a
 * serial byte stream (lib/proto/mbrtu.c, the RTU read path of
 * daemon/modbus/modbus_framing.c).  The input is a sequence of records
 * [ctl, bytes...]: ctl & 31 bytes arrive in one read, then (ctl & 0x80) the
 * line is silent.
 *
 * Oracle:
 *  - every frame delivered has 4..MBMAP_RTU_ADU_MAX bytes and a right
 *    CRC-16/MODBUS (computed here bitwise, not with mbmap_crc16);
 *  - frames are the bytes received, in order, never invented, reordered or
 *    overlapping: each one is the next stretch of the bytes received since the
 *    last silence (after bytes dropped, at most);
 *  - it always resynchronises: after the input, a silence and then a valid
 *    request (read holding registers), arriving in pieces, is delivered exactly.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mbrtu.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define STREAM_MAX 8192

typedef struct {
    uint8_t stream[STREAM_MAX]; /* bytes received since the last silence */
    size_t n, used;             /* received; up to the end of the last frame */
    unsigned frames;
    uint8_t last[MBMAP_RTU_ADU_MAX];
    size_t last_len;
} model_t;

static uint16_t crc16(const uint8_t *b, size_t n)
{
    uint16_t crc = 0xFFFF;
    for (size_t i = 0; i < n; i++) {
        crc ^= b[i];
        for (int k = 0; k < 8; k++)
            crc = (crc & 1) ? (uint16_t)((crc >> 1) ^ 0xA001) : (uint16_t)(crc >> 1);
    }
    return crc;
}

static void deliver(void *ctx, const uint8_t *f, size_t len)
{
    model_t *m = ctx;
    if (len < 4 || len > MBMAP_RTU_ADU_MAX)
        abort();
    uint16_t crc = crc16(f, len - 2);
    if (f[len - 2] != (crc & 0xff) || f[len - 1] != (crc >> 8))
        abort();
    /* the next stretch of the stream, at or after the end of the last frame */
    size_t at = m->used;
    while (at + len <= m->n && memcmp(m->stream + at, f, len))
        at++;
    if (at + len > m->n)
        abort();
    m->used = at + len;
    m->frames++;
    memcpy(m->last, f, len);
    m->last_len = len;
}

static void feed(mbrtu_rx_t *r, model_t *m, const uint8_t *b, size_t n)
{
    while (n) {
        size_t k = mbrtu_space(r);
        if (k > n)
            k = n;
        if (k == 0)
            abort(); /* the buffer never stays full */
        if (m->n + k > STREAM_MAX)
            abort();
        memcpy(m->stream + m->n, b, k);
        m->n += k;
        mbrtu_bytes(r, b, k, deliver, m);
        b += k;
        n -= k;
    }
}

static void silence(mbrtu_rx_t *r, model_t *m)
{
    mbrtu_silence(r, deliver, m);
    m->n = m->used = 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static model_t m;
    mbrtu_rx_t r;
    size_t i = 0;

    memset(&m, 0, sizeof m);
    mbrtu_init(&r);
    if (size > STREAM_MAX / 2)
        return 0;
    while (i < size) {
        uint8_t ctl = data[i++];
        size_t n = ctl & 31;
        if (n > size - i)
            n = size - i;
        feed(&r, &m, data + i, n);
        i += n;
        if (ctl & 0x80)
            silence(&r, &m);
    }

    /* resynchronisation */
    uint8_t req[8] = {1, 3, 0, 0, 0, 1, 0, 0};
    uint16_t crc = crc16(req, 6);
    req[6] = (uint8_t)(crc & 0xff);
    req[7] = (uint8_t)(crc >> 8);
    silence(&r, &m);
    unsigned before = m.frames;
    size_t cut = size ? data[0] % 8 : 3;
    feed(&r, &m, req, cut);
    feed(&r, &m, req + cut, sizeof req - cut);
    silence(&r, &m);
    if (m.frames != before + 1 || m.last_len != sizeof req || memcmp(m.last, req, sizeof req))
        abort();
    return 0;
}
