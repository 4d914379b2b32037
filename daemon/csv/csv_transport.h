/*
 * csv_transport.h - the "csv" and "stdout" output transports: each tick's setpoint
 * as one line of daemon/csv/csv_format.h text (the format trajreplay writes, so the
 * two can be compared byte for byte), header line first.
 *
 *   csv     one file per object.  Object keys:
 *             csv.path   = FILE   output file, relative to the config's directory (required)
 *             csv.header = yes    write the header line first (into an empty file)
 *             csv.truncate = no   at start and at each reload, append to the file, after a
 *                                 marker line "# trajd: appended at <UTC time> (start or
 *                                 reload)" if it was not empty, and a new header line if
 *                                 its last line has other columns (csv.geo or csv.age
 *                                 changed: csv_tail.h); yes: empty it at start only;
 *                                 always: at start and at each reload
 *             csv.age = no        yes: one more column at the end, age_s, the data age
 *                                 of the setpoint (lib/engine/CLOCK.md; nan for relative
 *                                 time), so readers of the 16 columns are not broken
 *   stdout  every object using it writes to standard output, lines of one
 *           tick grouped in config order; the header once.  Object keys:
 *             stdout.header = yes (the header is written if any object asks)
 *             stdout.age = no     (the age_s column, for every line if any object asks)
 *
 * Never stalls the tick: the tick only copies each setpoint into a bounded ring
 * (daemon/core/spsc.h, CSV_QUEUE_TICKS ticks of every object's lines, allocated
 * at open) and wakes the output's writer thread once per tick
 * (daemon/core/outworker.h, SCHED_OTHER).  The writer formats the lines into a
 * fixed buffer per stream (CSV_TRANSPORT_BUF_BYTES) and writes each buffer once
 * per batch with non-blocking writes (O_NONBLOCK is set on a pipe/tty stdout and
 * restored at close).  A full ring, or a full buffer (a slow reader), loses the
 * line, counted ("out dropped" on the status line, the object's out_lost and
 * the daemon's stats.out_lost; a gap in the cycle column shows where).  The
 * writer's counts are folded into the daemon's by the tick (cycle), so those
 * keep one writer.  At close the writer takes every line published before
 * it, drains, and is joined.
 *
 * Faults: a write that fails (ENOSPC, EIO, EPIPE on a FIFO, ...) sets the
 * fault flag of the objects writing there and stats.out_fault, is counted
 * (stats.out_errors), and is logged at warning level from a 1 s timer, at
 * most once per CSV_TRANSPORT_LOG_EVERY_S while lines keep being lost.  A line
 * reaches a regular file whole or not at all (a torn tail is cut off again
 * and retried).  The lines are kept and retried until the buffer is full;
 * then new lines are lost and counted.  EPIPE on stdout ends the daemon with
 * CORE_EXIT_EPIPE, as a Unix filter whose reader left; any line lost makes
 * trajd exit with CORE_EXIT_OUTPUT_LOST at the end (core.h).
 * A regular file on a slow disk can still block in write(): the writer
 * thread waits then, not the tick; the ring fills and lines are lost, counted.
 */
#ifndef TRAJD_CSVOUT_H
#define TRAJD_CSVOUT_H

#include <limits.h>

#include "transport.h"

#define CSV_TRANSPORT_BUF_BYTES (256u * 1024u)
#define CSV_TRUNCATE_ALWAYS 2

typedef struct {
    char path[PATH_MAX];
    int header;
    int truncate; /* 0 no, 1 yes (at start), CSV_TRUNCATE_ALWAYS (at reloads too) */
    int geo;      /* csv.geo = yes: columns lat_deg,lon_deg,alt_m,heading_deg appended */
    int age;      /* append the column age_s (csv_format_add_age) */
} csv_transport_obj_cfg_t;

extern const transport_t csv_transport;
extern const transport_t stdout_transport;

#endif
