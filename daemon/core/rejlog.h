/*
 * rejlog.h - where each waypoint came from, and the rate-limited log of the
 * waypoints the engine refused (one per object, owned by obj_t).
 *
 * The engine judges a waypoint with its neighbours (lib/engine/accept.h), so
 * its verdict may come a few pushes after it was offered, or at
 * engine_finish.  Every input offers waypoints through obj_push_from
 * (core.h), which notes the waypoint's source here (replay: "file:line";
 * Modbus: "modbus PEER", the client's address:port or the RTU line; CAN:
 * "can IFACE id 0xID seq N") and then reads the engine's verdicts
 * (engine_rejection_next) into this log; the tick reads them too (a finish
 * judges what was held).  A refused waypoint is matched with its source by
 * seq and time among the last REJLOG_RING offered.
 *
 * Rate limit: the log is flushed once a second (core_stats_roll; the tick
 * never writes, log.h).  The first REJLOG_LINES refusals of each second are
 * logged one line each, "object 'NAME': SOURCE: rejected (REASON) t=... s
 * at (x, y, z)"; the rest are counted per reason and summed up in one line
 * "object 'NAME': N more rejected waypoints not shown (speed 12, stale 3)".
 * The counters (engine_status rejected_by, Modbus, CAN) stay exact.
 */
#ifndef TRAJD_REJLOG_H
#define TRAJD_REJLOG_H

#include <stddef.h>
#include <stdint.h>

#include "engine.h"

#define REJLOG_SRC_LEN 192
#define REJLOG_SRC_PATH_MAX 160 /* of a file's path, its end kept (rejlog_src_file) */
#define REJLOG_RING 32          /* waypoints remembered with their source (judged within 8) */
#define REJLOG_LINES 5          /* refusals logged in full per flush (per second) */
#define REJLOG_LINE_MAX 384

typedef struct {
    uint32_t seq;
    double t_s;
    char src[REJLOG_SRC_LEN];
} rejlog_src_t;

typedef struct {
    engine_rejection_t rej;
    char src[REJLOG_SRC_LEN];
} rejlog_line_t;

typedef struct {
    rejlog_src_t ring[REJLOG_RING];
    unsigned ring_next, ring_len;
    rejlog_line_t pend[REJLOG_LINES];
    unsigned npend;
    uint64_t more_by[ENGINE_ERROR_COUNT]; /* refusals not shown since the last flush */
    uint64_t seen;                        /* refusals read from the engine */
    uint64_t shown;                       /* logged one line each */
} rejlog_t;

void rejlog_init(rejlog_t *l);

/*
 * A file's row as a source, into buf (REJLOG_SRC_LEN): "PATH:LINE", or
 * "PATH" without a line (!has_line); a path longer than REJLOG_SRC_PATH_MAX
 * keeps its end (the file's name) after "...".  Its length.  Made on every
 * push of a replay, for the rare refusal: copies and digits, no printf.
 */
size_t rejlog_src_file(char *buf, const char *path, int has_line, uint32_t line);

/* Note that wp was offered from src (NULL or "": "unknown source"); src is
 * copied (cut at REJLOG_SRC_LEN - 1 bytes). */
void rejlog_offered(rejlog_t *l, const engine_waypoint_t *wp, const char *src);

/* Read every verdict the engine has for us (engine_rejection_next). */
void rejlog_drain(rejlog_t *l, engine_t *e);

/*
 * Hand the pending lines to emit (one call per line, no trailing newline,
 * prefixed "object 'NAME': "), then the "N more" line if any; forget them.
 * Returns the number of lines emitted.
 */
unsigned rejlog_flush(rejlog_t *l, const char *name, void (*emit)(void *ctx, const char *line),
                      void *ctx);

#endif
