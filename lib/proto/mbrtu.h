/*
 * mbrtu.h - Modbus RTU request framing on a serial byte stream (pure: bytes
 * and line silences in, whole frames out), used by daemon/modbus/modbus_framing.c.
 *
 * A frame's end is known from its function code (mbmap_rtu_frame_len) and
 * checked by its CRC.  A frame that fails its CRC, or cannot fit, makes every
 * byte until the next line silence unusable (the boundary is lost): they are
 * discarded.  A function whose request length cannot be known from its header
 * is delimited by the silence itself (then delivered if its CRC is right, so
 * that it gets its exception 01).  Frames refused for their CRC or cut by a
 * silence are counted in crc_errors (bytes dropped after a frame too long for
 * the buffer are not).
 */
#ifndef TRAJD_MBRTU_H
#define TRAJD_MBRTU_H
/* trajd public API: installed as <trajd/mbrtu.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>

#include "mbmap.h"

typedef void (*mbrtu_deliver_fn)(void *ctx, const uint8_t *frame, size_t len);

typedef struct {
    uint8_t buf[2 * MBMAP_RTU_ADU_MAX];
    size_t len;
    int discard;         /* drop bytes until the line is silent */
    uint64_t crc_errors; /* frames refused: bad CRC, or cut by a silence */
} mbrtu_rx_t;

void mbrtu_init(mbrtu_rx_t *r);

/* Bytes the buffer can take now (read at most this many from the line). */
size_t mbrtu_space(const mbrtu_rx_t *r);

/* n bytes arrived (n <= mbrtu_space): every whole frame with a right CRC
 * goes to deliver, in order. */
void mbrtu_bytes(mbrtu_rx_t *r, const uint8_t *b, size_t n, mbrtu_deliver_fn deliver, void *ctx);

/* The line was silent (at least 3.5 characters): what is buffered ends here. */
void mbrtu_silence(mbrtu_rx_t *r, mbrtu_deliver_fn deliver, void *ctx);

#endif
