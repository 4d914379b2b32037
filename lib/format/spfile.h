/*
 * spfile.h - the binary setpoint file (trajreplay --binary, trajd
 * csv.binary where offered): public, installed as <trajd/spfile.h>.
 *
 * A 64-byte header, then one 112-byte record per setpoint.  Every field is
 * little-endian, with no padding; the doubles are the engine's, bit for bit.
 * On a little-endian machine (x86-64, arm64) the structs below are the bytes
 * of the file; elsewhere read the fields at their offsets.
 *
 * numpy (the same layout; trajreplay(1) "BINARY FORMAT"):
 *   dt = np.dtype([("now_ns", "<i8"), ("t_s", "<f8"), ("pos_m", "<f8", 3),
 *                  ("vel_m_s", "<f8", 3), ("acc_m_s2", "<f8", 3), ("state", "<u4"),
 *                  ("flags", "<u4"), ("cycle", "<u4"), ("track", "<u4"), ("reserved", "<u8")])
 *   rows = np.fromfile(path, dtype=dt, offset=64)
 */
#ifndef TRAJD_SPFILE_H
#define TRAJD_SPFILE_H
/* trajd public API: installed as <trajd/spfile.h> (make install; pkg-config trajd). */

#include <stdint.h>

#define SPFILE_MAGIC "TRAJDSP1" /* 8 bytes, no NUL */
#define SPFILE_HEADER 64        /* header size, bytes */
#define SPFILE_RECORD 112       /* record size, bytes */
#define SPFILE_OBJECT_MAX 47    /* object name characters kept (NUL padded to 48) */

typedef struct {
    char magic[8];        /* SPFILE_MAGIC */
    uint32_t header_size; /* SPFILE_HEADER */
    uint32_t record_size; /* SPFILE_RECORD */
    char object[48];      /* object name, NUL padded, cut at SPFILE_OBJECT_MAX */
} spfile_header_t;

typedef struct {
    int64_t now_ns;     /* the tick's time, ns (engine time; epoch time for clocked objects) */
    double t_s;         /* track time the setpoint stands at, s */
    double pos_m[3];    /* x, y, z, m */
    double vel_m_s[3];  /* vx, vy, vz, m/s */
    double acc_m_s2[3]; /* ax, ay, az, m/s^2 */
    uint32_t state;     /* 0 waiting, 1 streaming, 2 underrun, 3 finished (engine_state_t) */
    uint32_t flags;     /* ENGINE_SP_* (motion.h) */
    uint32_t cycle;     /* tick counter, low 32 bits */
    uint32_t track;     /* trajectory counter */
    uint64_t reserved;  /* 0 */
} spfile_record_t;

_Static_assert(sizeof(spfile_header_t) == SPFILE_HEADER, "spfile header layout");
_Static_assert(sizeof(spfile_record_t) == SPFILE_RECORD, "spfile record layout");

#endif
