/* nmea2000.c - NMEA 2000 identifier, fast packets, position PGNs; see nmea2000.h. */
#include "nmea2000.h"

#include <math.h>
#include <string.h>

const char *n2k_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case N2K_OK: return "ok";
    case N2K_ENA: return "position not available";
    case N2K_ELEN: return "message too short";
    case N2K_ERANGE: return "latitude, longitude, date or time out of range";
    case N2K_ESEQ: return "fast packet frame out of sequence";
    case N2K_ENOFIX: return "no GNSS fix (method 0)";
    default: return "unknown NMEA 2000 error";
    }
}

void n2k_id_decode(uint32_t can_id, n2k_id_t *out)
{
    uint32_t pf = (can_id >> 16) & 0xffu;
    out->priority = (uint8_t)((can_id >> 26) & 0x7u);
    out->source = (uint8_t)(can_id & 0xffu);
    if (pf < 240) {
        out->dest = (uint8_t)((can_id >> 8) & 0xffu);
        out->pgn = (can_id >> 8) & 0x3ff00u;
    } else {
        out->dest = 255;
        out->pgn = (can_id >> 8) & 0x3ffffu;
    }
}

uint32_t n2k_id_encode(const n2k_id_t *id)
{
    uint32_t pgn = id->pgn & 0x3ffffu;
    if (((pgn >> 8) & 0xffu) < 240)
        pgn = (pgn & 0x3ff00u) | id->dest;
    return ((uint32_t)(id->priority & 7u) << 26) | (pgn << 8) | id->source;
}

int n2k_fast_push(n2k_fast_t *f, const uint8_t *data, size_t len)
{
    if (len < 2)
        return -N2K_ELEN;
    uint8_t seq = data[0] >> 5, frame = data[0] & 0x1f;
    if (frame == 0) {
        f->active = 0; /* a message in progress, if any, is abandoned */
        if (data[1] > N2K_FAST_MAX)
            return -N2K_ELEN;
        f->len = data[1];
        f->seq = seq;
        f->next = 1;
        f->got = 0;
        size_t n = len - 2 < f->len ? len - 2 : f->len;
        memcpy(f->data, data + 2, n);
        f->got = (uint8_t)n;
        if (f->got >= f->len)
            return 1;
        f->active = 1;
        return 0;
    }
    if (!f->active)
        return 0; /* the rest of a message whose start we never saw */
    if (seq != f->seq || frame != f->next) {
        f->active = 0;
        return -N2K_ESEQ;
    }
    size_t want = (size_t)(f->len - f->got), n = len - 1 < want ? len - 1 : want;
    memcpy(f->data + f->got, data + 1, n);
    f->got = (uint8_t)(f->got + n);
    f->next++;
    if (f->got >= f->len) {
        f->active = 0;
        return 1;
    }
    return 0;
}

static uint32_t le_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static uint64_t le_u64(const uint8_t *p)
{
    return (uint64_t)le_u32(p) | (uint64_t)le_u32(p + 4) << 32;
}

static int check_ll(const n2k_position_t *p)
{
    return fabs(p->lat_deg) <= 90.0 && fabs(p->lon_deg) <= 180.0 ? 0 : -N2K_ERANGE;
}

int n2k_decode_position_rapid(const uint8_t *data, size_t len, n2k_position_t *out)
{
    memset(out, 0, sizeof *out);
    out->alt_m = NAN;
    if (len < 8)
        return -N2K_ELEN;
    int32_t lat = (int32_t)le_u32(data), lon = (int32_t)le_u32(data + 4);
    if (lat == INT32_MAX || lon == INT32_MAX)
        return -N2K_ENA;
    out->lat_deg = lat * 1e-7;
    out->lon_deg = lon * 1e-7;
    return check_ll(out);
}

int n2k_decode_gnss_position(const uint8_t *data, size_t len, n2k_position_t *out)
{
    memset(out, 0, sizeof *out);
    out->alt_m = NAN;
    if (len < N2K_GNSS_POSITION_MIN_LEN)
        return -N2K_ELEN;
    uint16_t days = (uint16_t)(data[1] | data[2] << 8);
    uint32_t tod = le_u32(data + 3);
    int64_t lat = (int64_t)le_u64(data + 7), lon = (int64_t)le_u64(data + 15);
    int64_t alt = (int64_t)le_u64(data + 23);
    out->method = data[31] >> 4;
    out->sid = data[0];
    if (lat == INT64_MAX || lon == INT64_MAX)
        return -N2K_ENA;
    if (out->method == 0)
        return -N2K_ENOFIX;
    /* 1e-16 deg per bit: split so the integer part stays exact in double */
    out->lat_deg = (double)(lat / 10000000000LL) * 1e-6 + (double)(lat % 10000000000LL) * 1e-16;
    out->lon_deg = (double)(lon / 10000000000LL) * 1e-6 + (double)(lon % 10000000000LL) * 1e-16;
    if (alt != INT64_MAX)
        out->alt_m = (double)(alt / 1000000) + (double)(alt % 1000000) * 1e-6;
    if (days != 0xffffu && tod != 0xffffffffu) {
        if (tod >= 864000000u)
            return -N2K_ERANGE;
        out->has_time = 1;
        out->days = days;
        out->tod_s = tod * 1e-4;
    }
    return check_ll(out);
}

int n2k_decode_cog_sog(const uint8_t *data, size_t len, n2k_cog_sog_t *out)
{
    memset(out, 0, sizeof *out);
    if (len < 8)
        return -N2K_ELEN;
    uint16_t cog = (uint16_t)(data[2] | data[3] << 8), sog = (uint16_t)(data[4] | data[5] << 8);
    out->sid = data[0];
    out->ref = data[1] & 3u;
    if (cog == 0xffffu || sog == 0xffffu)
        return -N2K_ENA;
    if (cog > 62832u) /* 2 pi in 1e-4 rad, rounded up */
        return -N2K_ERANGE;
    out->cog_deg = cog * 1e-4 * (180.0 / M_PI);
    out->sog_m_s = sog * 1e-2;
    return 0;
}
