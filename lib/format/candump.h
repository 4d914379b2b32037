/*
 * candump.h - text <-> frame for candump log lines, the way can-utils' lib.c
 * does it (parse_canframe / sprint_canframe), pure and tested apart from any
 * socket.
 *
 *   (1502984866.421964) slcan0 09F112CC#FF725AFF7FFF7FFD     candump -l / -L
 *   123#DEADBEEF        classic, 3 hex digits = 11-bit id, 8 digits = 29-bit
 *   123#R  123#R3       remote request (optionally with a DLC)
 *   123##1112233        CAN FD: '##', one hex digit of flags (1 = BRS, 2 = ESI,
 *                       4 = FDF as newer kernels log it), then the data
 *   20000080#...        error frame (bit 29 of an 8-digit id: CAN_ERR_FLAG)
 * Lines starting with '#' (after blanks) and empty lines are skipped: real
 * captures carry comments at the top.
 */
#ifndef TRAJD_CANDUMP_H
#define TRAJD_CANDUMP_H
/* trajd public API: installed as <trajd/candump.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>
#include "canproto.h"

enum candump_error {
    CANDUMP_OK = 0,
    CANDUMP_ESKIP = 1,   /* comment or blank line: no frame (not an error for a reader) */
    CANDUMP_ESYNTAX = 2, /* not a candump line / frame */
    CANDUMP_ELEN = 3,    /* too many data bytes, or an invalid CAN FD length */
    CANDUMP_ESPACE = 4,  /* output buffer too small */
    CANDUMP_ERROR_COUNT
};

/* Text for a candump_error (positive or negated). */
const char *candump_strerror(int err);

/* Longest interface name kept (IFNAMSIZ - 1 on Linux). */
#define CANDUMP_IFNAME_MAX 15

typedef struct {
    int64_t ts_us;                       /* timestamp, microseconds (0 if none) */
    char ifname[CANDUMP_IFNAME_MAX + 1]; /* "" if none */
    canproto_frame_t frame;
} candump_line_t;

/*
 * Parse one frame in cansend syntax ("123#DEADBEEF", "123##1AABB", ...), the
 * whole string (no trailing characters except '\n' / '\r').
 * Returns 0, -CANDUMP_ESYNTAX, -CANDUMP_ELEN.
 */
int candump_parse_frame(const char *s, canproto_frame_t *f);

/*
 * Parse one log line "(sec.usec) ifname frame".  Also accepts a bare frame
 * (cansend syntax) with no timestamp or interface.
 * Returns 0, -CANDUMP_ESKIP (comment/blank), -CANDUMP_ESYNTAX, -CANDUMP_ELEN.
 */
int candump_parse_line(const char *s, candump_line_t *out);

/*
 * Format f in cansend syntax as candump prints it (uppercase hex, 3 or 8 id
 * digits, FD flags as one hex digit after '##').  Returns the length written
 * (without the NUL), or -CANDUMP_ESPACE.
 */
int candump_format_frame(char *buf, size_t len, const canproto_frame_t *f);

/*
 * Format "(sec.usec) ifname frame\n" as candump -L writes it.
 * Returns the length written, or -CANDUMP_ESPACE.
 */
int candump_format_line(char *buf, size_t len, int64_t ts_us, const char *ifname,
                        const canproto_frame_t *f);

#endif
