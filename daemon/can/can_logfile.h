/*
 * can_logfile.h - candump-log transport: waypoint frames are read from a candump
 * log (`candump -l` / `-L` text, '#' comment lines skipped) and replayed on
 * the engine's clock; frames sent are written as a candump -L log whose
 * timestamps are engine time, or epoch times (can_logfile_set_epoch).  The same codec as on a socket is exercised
 * without a kernel, and logged bus traffic can be replayed.
 *
 * Input timing: frame k is due at engine time start_ns + (ts_k - ts_0); the
 * whole file is read before (never in the tick): by can_logfile_input_read,
 * which the daemon's config check calls on the configuration's worker
 * (daemon/core/cfgload.h), the frames then adopted by can_logfile_open_input
 * at the swap; or at can_logfile_open_mode.  Frames with ids that are not
 * ours are delivered too: can_port counts them as foreign.
 *
 * Lines are read whole, of any length (getline).  A line that is not a
 * candump frame, holds a NUL byte or is longer than CAN_LOGFILE_LINE_MAX is
 * refused as a whole (never cut: the tail of a long comment must not become
 * a frame), counted in bad_lines and logged as a warning "can: file:line:
 * why", the first CAN_LOGFILE_REPORT_MAX of them, then one summary line.
 */
#ifndef TRAJD_CANLOG_H
#define TRAJD_CANLOG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "canproto.h"

typedef struct {
    uint64_t lines;          /* lines read */
    uint64_t comments;       /* '#' and blank lines skipped */
    uint64_t bad_lines;      /* lines refused (skipped): not a frame, too long, NUL byte */
    uint64_t first_bad_line; /* line number of the first, 0 if none */
    uint64_t frames_in;      /* frames loaded */
    uint64_t frames_out;     /* frames queued for the output */
    uint64_t frames_lost;    /* of those, never written: a failed write or a full buffer */
    uint64_t write_errors;   /* failed write calls (not EAGAIN) */
    int last_errno;          /* of the last failed write */
} can_logfile_stats_t;

typedef struct can_logfile can_logfile_t;
/* A candump log read whole into memory (can_logfile_input_read). */
typedef struct can_logfile_input can_logfile_input_t;

/* Longest candump line accepted, bytes: a CAN FD frame with a 29-bit id,
 * 64 data bytes, a 20-digit stamp and a 15-character interface is ~190. */
#define CAN_LOGFILE_LINE_MAX 1024
/* Output buffer: whole lines, written by the writer thread after each batch
 * with write(2), so a failed write is seen and its frames counted as lost. */
#define CAN_LOGFILE_OUT_BUF 65536
/* Largest log_in accepted (it is read whole into memory), as for a replayed
 * track (TRACK_FILE_MAX_BYTES); a FIFO or a device is refused (regfile.h). */
#define CAN_LOGFILE_MAX_BYTES (1024LL * 1024LL * 1024LL)
/* Bad lines logged one by one per load (then one summary line). */
#define CAN_LOGFILE_REPORT_MAX 5

/*
 * Read the candump log at path whole: its frames, and the counts of its
 * lines, comments and bad lines (logged as they are met, see above).  NULL
 * with why if it cannot be opened, is a directory, a FIFO or a device, is
 * larger than CAN_LOGFILE_MAX_BYTES (regfile.h: refused before anything is
 * read), cannot be read, is empty or has no frame line (the count of lines,
 * comments and bad lines, and the first bad line with its reason), or if the
 * read was cancelled (cfgload_cancelled: a SIGTERM while a configuration is
 * read; polled every 65536 lines) or ran out of memory.  For the config
 * check, on the configuration's worker: never in the loop.
 */
can_logfile_input_t *can_logfile_input_read(const char *path, char *why, size_t wl);

/* Free it (NULL: no-op), after every logfile opened on it was closed. */
void can_logfile_input_free(can_logfile_input_t *in);

/*
 * Open.  in: the frames to replay, read before (NULL: no input), only read
 * from (several logfiles may replay one input, one after the other: a reload
 * rolled back reopens the running configuration's); it must outlive the
 * logfile.  The open reads no input file: no more than the output's open
 * (below) and a thread start, at a configuration's swap.  out_path: file to
 * write (NULL: no output; "-" = stdout).  ifname: interface name written in
 * output lines.  start_ns: engine time at which the first input frame is due.
 * append: 1 appends to the output file (O_APPEND) instead of truncating it; a
 * torn last line (no newline at its end, a full disk) is cut off first, with
 * a warning, so every line stays whole.
 * Returns NULL with a message in err on failure (the output cannot be opened,
 * out of memory, no writer thread).
 */
can_logfile_t *can_logfile_open_input(const can_logfile_input_t *in, const char *out_path,
                                      const char *ifname, int64_t start_ns, int append, char *err,
                                      size_t errlen);

/* can_logfile_open_input on the candump log at in_path (NULL: no input), read
 * whole now (can_logfile_input_read; its message in err as "in_path: why"). */
can_logfile_t *can_logfile_open_mode(const char *in_path, const char *out_path, const char *ifname,
                                     int64_t start_ns, int append, char *err, size_t errlen);

/* Bytes the output file held after opening it (0 if it was truncated or
 * empty), -1 if it is not a regular file (stdout, a FIFO, /dev/null). */
long long can_logfile_out_kept(const can_logfile_t *l);

/* The stamp (us) of the last line kept in an appended output file, if a
 * stamped frame; INT64_MIN if none. */
int64_t can_logfile_out_last_us(const can_logfile_t *l);

/* The output's writer thread (below) takes every frame queued, writes them,
 * counts what is left unwritten as lost, and ends; read the stats after it.
 * A no-op without output, or once done.  NULL is a no-op. */
void can_logfile_finish(can_logfile_t *l);

/* Finish and close; NULL is a no-op. */
void can_logfile_close(can_logfile_t *l);

/* Next input frame due at or before now_ns: 1 (in f), 0 (none yet or no more). */
int can_logfile_recv(can_logfile_t *l, int64_t now_ns, canproto_frame_t *f);

/* A reload (issue 24): keep where l's input, read from path, stopped (the
 * frames delivered so far), before l is closed. */
void can_logfile_keep_pos(const can_logfile_t *l, const char *path);

/* If the position kept last is of path: l goes on from there, so nothing
 * already played is played again; returns the frames skipped (0: none).
 * path NULL (the reload carried no object over): start afresh.  Forgets the
 * kept position either way. */
size_t can_logfile_resume(can_logfile_t *l, const char *path);

/* Queue f for the output as a log line stamped with the last now_ns given to
 * can_logfile_recv / can_logfile_set_time.  In the tick: a copy into a
 * bounded ring (daemon/core/spsc.h), no formatting, no write, no allocation.
 * Returns 0, or -EIO if the ring is full (the writer is behind: counted in
 * frames_lost). */
int can_logfile_send(can_logfile_t *l, const canproto_frame_t *f);

/* Set the time stamped on output lines (engine time, ns). */
void can_logfile_set_time(can_logfile_t *l, int64_t now_ns);

/* Output stamps are engine time + epoch_ns (0 by default: engine time; the
 * daemon's [can] log_time = wall sets the wall clock at engine time 0, so
 * stamps are epoch times whose differences are exactly engine time). */
void can_logfile_set_epoch(can_logfile_t *l, int64_t epoch_ns);

/* 1 once every input frame was delivered (or there is no input). */
int can_logfile_done(const can_logfile_t *l);

/* Once per cycle: hand the frames queued to the output's writer thread
 * (daemon/core/outworker.h, SCHED_OTHER, started at open with an output),
 * which formats them into a buffer of whole lines and writes it; a failed
 * write (not EAGAIN) counts in write_errors and its frames in frames_lost,
 * as does a frame that finds the buffer full behind a slow reader. */
void can_logfile_flush(can_logfile_t *l);

void can_logfile_stats(const can_logfile_t *l, can_logfile_stats_t *st);

#endif
