/*
 * nmea2000.h - the few NMEA 2000 pieces a position log needs, pure (no I/O,
 * no allocation): the 29-bit identifier, fast-packet reassembly, and the
 * two position PGNs.  Field layouts follow the public canboat PGN database
 * (canboat/canboat analyzer/pgn.h; canboat.json), all little-endian:
 *
 *   129025 Position, Rapid Update (single frame, 8 bytes)
 *     0..3  latitude  int32, 1e-7 deg       4..7  longitude int32, 1e-7 deg
 *   129029 GNSS Position Data (fast packet, 43 bytes + 3 per reference station)
 *     0     SID                    1..2   date uint16, days since 1970-01-01
 *     3..6  time uint32, 1e-4 s since midnight (UTC)
 *     7..14 latitude int64, 1e-16 deg      15..22 longitude int64, 1e-16 deg
 *     23..30 altitude int64, 1e-6 m (above WGS84 ellipsoid)
 *     31    GNSS type (bits 0..3), method (bits 4..7: 0 no fix, 1 GNSS fix, 2 DGNSS,
 *           3 precise, 4 RTK fixed, 5 RTK float, 6 estimated, 7 manual, 8 simulated)
 *     32..42 integrity, satellites, HDOP, PDOP, geoidal separation, stations
 *   129026 COG & SOG, Rapid Update (single frame, 8 bytes)
 *     0     SID      1  COG reference (bits 0..1: 0 true, 1 magnetic)
 *     2..3  COG uint16, 1e-4 rad        4..5  SOG uint16, 1e-2 m/s
 *   "Not available" is the largest positive value of a signed field
 *   (0x7FFFFFFF, 0x7FFF...FF) and all ones of an unsigned one.
 *
 * Identifier (ISO 11783 / SAE J1939): priority bits 26..28, data page and
 * PDU format bits 16..25, PDU specific bits 8..15, source bits 0..7.  With
 * PDU format < 240 (PDU1) the PDU specific byte is a destination and not
 * part of the PGN.
 *
 * Fast packet (NMEA 2000 Appendix B, as canboat reassembles it): byte 0 of
 * each frame is a 3-bit sequence counter (bits 5..7) and a 5-bit frame
 * counter (bits 0..4).  Frame 0 carries the total length in byte 1 and the
 * first 6 data bytes; frame k carries the next 7.  At most 223 bytes.
 */
#ifndef TRAJD_NMEA2000_H
#define TRAJD_NMEA2000_H
/* trajd public API: installed as <trajd/nmea2000.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>

#define N2K_PGN_POSITION_RAPID 129025u
#define N2K_PGN_GNSS_POSITION 129029u
#define N2K_PGN_COG_SOG_RAPID 129026u
/* Fast-packet payload limit: 6 + 31 * 7 bytes. */
#define N2K_FAST_MAX 223
/* 129029 without reference stations. */
#define N2K_GNSS_POSITION_MIN_LEN 43

enum n2k_error {
    N2K_OK = 0,
    N2K_ENA = 1,    /* the position field is "not available" */
    N2K_ELEN = 2,   /* message too short */
    N2K_ERANGE = 3, /* latitude or longitude out of range, bad date or time */
    N2K_ESEQ = 4,   /* fast packet: a frame out of sequence (message dropped) */
    N2K_ENOFIX = 5, /* 129029 method 0: no GNSS fix */
};

const char *n2k_strerror(int err);

typedef struct {
    uint32_t pgn;
    uint8_t priority;
    uint8_t source;
    uint8_t dest; /* 255 (global) for PDU2 */
} n2k_id_t;

/* Split a 29-bit identifier. */
void n2k_id_decode(uint32_t can_id, n2k_id_t *out);

/* Encode (the inverse, for tests and tools). */
uint32_t n2k_id_encode(const n2k_id_t *id);

/* One fast-packet message being reassembled (one per source and PGN). */
typedef struct {
    uint8_t data[N2K_FAST_MAX];
    uint8_t len;  /* total length announced by frame 0 */
    uint8_t got;  /* bytes received so far */
    uint8_t seq;  /* sequence counter of the message */
    uint8_t next; /* frame counter expected next */
    uint8_t active;
} n2k_fast_t;

/*
 * Feed one frame (data, len <= 8) of a fast-packet PGN.  Returns 1 when the
 * message is complete (f->data, f->len), 0 when more frames are needed (or
 * for a stray continuation frame with no message in progress, as at the
 * start of a log), -N2K_ESEQ when the frame breaks the message in progress
 * (a frame missing: that message is dropped; a frame 0 starts a new one),
 * -N2K_ELEN for a frame 0 announcing more than N2K_FAST_MAX bytes or a
 * frame shorter than its header.
 */
int n2k_fast_push(n2k_fast_t *f, const uint8_t *data, size_t len);

typedef struct {
    double lat_deg, lon_deg;
    double alt_m;   /* NaN if not available (always for 129025) */
    int has_time;   /* 129029: date and time valid */
    int64_t days;   /* since 1970-01-01 */
    double tod_s;   /* seconds since midnight, [0, 86400) */
    uint8_t method; /* 129029 method (bits 4..7 of byte 31) */
    uint8_t sid;    /* 129029: sequence id (byte 0), ties data of one epoch; 0 for 129025 */
} n2k_position_t;

typedef struct {
    uint8_t sid;    /* sequence id: the 129029 of the same epoch has the same */
    uint8_t ref;    /* COG reference: 0 true north, 1 magnetic */
    double cog_deg; /* course over ground, degrees, [0, 360) */
    double sog_m_s; /* speed over ground, m/s */
} n2k_cog_sog_t;

/* Decode 129025.  Returns 0, -N2K_ELEN, -N2K_ENA, -N2K_ERANGE. */
int n2k_decode_position_rapid(const uint8_t *data, size_t len, n2k_position_t *out);

/* Decode 129029.  Returns 0, -N2K_ELEN, -N2K_ENA, -N2K_ERANGE, -N2K_ENOFIX. */
int n2k_decode_gnss_position(const uint8_t *data, size_t len, n2k_position_t *out);

/* Decode 129026.  Returns 0, -N2K_ELEN, -N2K_ENA (COG or SOG not available),
 * -N2K_ERANGE (COG beyond 2 pi). */
int n2k_decode_cog_sog(const uint8_t *data, size_t len, n2k_cog_sog_t *out);

#endif
