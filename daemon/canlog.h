/*
 * canlog.h - candump-log transport: waypoint frames are read from a candump
 * log (`candump -l` / `-L` text, '#' comment lines skipped) and replayed on
 * the engine's clock; frames sent are written as a candump -L log whose
 * timestamps are engine time.  The same codec as on a socket is exercised
 * without a kernel, and logged bus traffic can be replayed.
 *
 * Input timing: frame k is due at engine time start_ns + (ts_k - ts_0); the
 * whole file is read at canlog_open (never in the tick).  Frames with ids
 * that are not ours are delivered too: canport counts them as foreign.
 */
#ifndef TRAJD_CANLOG_H
#define TRAJD_CANLOG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "canproto.h"

typedef struct {
    uint64_t lines;           /* lines read */
    uint64_t comments;        /* '#' and blank lines skipped */
    uint64_t bad_lines;       /* lines that are not candump frames (skipped) */
    int first_bad_line;       /* line number of the first, 0 if none */
    uint64_t frames_in;       /* frames loaded */
    uint64_t frames_out;      /* frames written */
    uint64_t write_errors;
} canlog_stats_t;

typedef struct canlog canlog_t;

/*
 * Open.  in_path: candump log to replay (NULL: no input); out_path: file to
 * write (NULL: no output; "-" = stdout).  ifname: interface name written in
 * output lines.  start_ns: engine time at which the first input frame is due.
 * Returns NULL with a message in err on failure (file missing, unreadable).
 */
canlog_t *canlog_open(const char *in_path, const char *out_path, const char *ifname,
                      int64_t start_ns, char *err, size_t errlen);

/* Flush and close; NULL is a no-op. */
void canlog_close(canlog_t *l);

/* Next input frame due at or before now_ns: 1 (in f), 0 (none yet or no more). */
int canlog_recv(canlog_t *l, int64_t now_ns, canproto_frame_t *f);

/* Write f as a log line stamped with the last now_ns given to canlog_recv /
 * canlog_set_time.  Returns 0 or -EIO. */
int canlog_send(canlog_t *l, const canproto_frame_t *f);

/* Set the time stamped on output lines (engine time, ns). */
void canlog_set_time(canlog_t *l, int64_t now_ns);

/* 1 once every input frame was delivered (or there is no input). */
int canlog_done(const canlog_t *l);

/* Flush the output (once per cycle). */
void canlog_flush(canlog_t *l);

void canlog_stats(const canlog_t *l, canlog_stats_t *st);

#endif
