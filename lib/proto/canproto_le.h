/*
 * canproto_le.h - little-endian fields of CAN frames, for the canproto
 * encoders and decoders (canproto.c, canproto_rx.c, canproto_st2motion.c).  Internal to
 * lib/proto: not installed.
 */
#ifndef TRAJD_CANPROTO_LE_H
#define TRAJD_CANPROTO_LE_H

#include <stdint.h>

/* The low nbytes of v at p, least significant first. */
static inline void put_le(uint8_t *p, unsigned nbytes, uint64_t v)
{
    for (unsigned i = 0; i < nbytes; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

/* nbytes at p, least significant first. */
static inline uint64_t get_le(const uint8_t *p, unsigned nbytes)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < nbytes; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

/* Sign-extend the low nbits of v. */
static inline int64_t sext(uint64_t v, unsigned nbits)
{
    uint64_t m = 1ull << (nbits - 1);
    v &= (m << 1) - 1;
    return (int64_t)((v ^ m) - m);
}

#endif
