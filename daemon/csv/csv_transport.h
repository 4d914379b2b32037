/*
 * csv_transport.h - the "csv" and "stdout" output transports: each tick's setpoint
 * as one line of daemon/csv/csv_format.h text (the format trajreplay writes, so the
 * two can be compared byte for byte), header line first.
 *
 *   csv     one file per object.  Object keys:
 *             csv.path   = FILE   output file, relative to the config's directory (required;
 *                                 truncated at start and at each reload)
 *             csv.header = yes    write the header line first
 *   stdout  every object using it writes to standard output, lines of one
 *           tick grouped in config order; the header once.  Object keys:
 *             stdout.header = yes (the header is written if any object asks)
 *
 * Never stalls the tick: lines go into a fixed buffer per stream
 * (CSV_TRANSPORT_BUF_BYTES); the buffer is written once per tick (cycle hook) with
 * non-blocking writes (O_NONBLOCK is set on a pipe/tty stdout and restored at
 * close).  If the reader is slow and the buffer is full, the line is dropped
 * and counted ("out dropped" on the status line; a gap in the cycle column
 * shows where).
 * Limit: a regular file on a slow disk can still block in write(); that is
 * the kernel's page cache's call, not ours.
 */
#ifndef TRAJD_CSVOUT_H
#define TRAJD_CSVOUT_H

#include <limits.h>

#include "transport.h"

#define CSV_TRANSPORT_BUF_BYTES (256u * 1024u)

typedef struct {
    char path[PATH_MAX];
    int header;
} csv_transport_obj_cfg_t;

extern const transport_t csv_transport;
extern const transport_t stdout_transport;

#endif
