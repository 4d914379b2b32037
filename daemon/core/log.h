/*
 * log.h - log lines, one write() per line so lines from one process never
 * interleave.  Priorities are syslog.h's LOG_ERR .. LOG_DEBUG.  Where they go
 * (chosen at the first line, or set by log_set_mode):
 *   LOG_MODE_TTY      stderr is a terminal (and not journald's stream):
 *                     plain text, "warning: " / "error: " before those levels;
 *   LOG_MODE_PREFIX   otherwise (journald's stream: JOURNAL_STREAM names
 *                     stderr's device:inode, systemd.exec(5); or a pipe or
 *                     file): the "<N>" priority prefix journald reads
 *                     (sd-daemon(3): SD_ERR is "<3>", SD_INFO "<6>" ...);
 *   LOG_MODE_SYSLOG   detached (trajd without -f, once it is ready):
 *                     syslog(3), ident "trajd", facility LOG_DAEMON.
 *
 * Not for the tick: the tick counts events; a housekeeping timer logs them.
 * Once log_async_start() ran (trajd, once detached), lines are formatted by
 * the caller and queued (a bounded ring, daemon/core/spsc.h) for a log thread
 * (SCHED_OTHER) that writes them, so a slow journald or a stderr nobody
 * reads never holds the loop up; a full queue drops the line, counted, and
 * the log thread says how many once it can write again.  log_async_stop()
 * writes every line queued and ends the thread (at exit).
 */
#ifndef TRAJD_LOG_H
#define TRAJD_LOG_H

#include <syslog.h>

/* Lines with a priority above (less urgent than) level are dropped.  Default LOG_INFO. */
void log_set_level(int level);

typedef enum { LOG_MODE_AUTO = 0, LOG_MODE_TTY, LOG_MODE_PREFIX, LOG_MODE_SYSLOG } log_mode_t;

/* Choose the destination; LOG_MODE_AUTO: decide again from stderr and
 * JOURNAL_STREAM at the next line.  LOG_MODE_SYSLOG opens syslog. */
void log_set_mode(log_mode_t mode);

/*
 * One line (printf format; a trailing '\n' is not needed), with where it was
 * logged from.  On journald's stream (JOURNAL_STREAM names stderr) the line
 * goes to the journal natively (sd_journal_sendv) with the fields MESSAGE,
 * PRIORITY, SYSLOG_IDENTIFIER=trajd, CODE_FILE, CODE_LINE, CODE_FUNC, and
 * OBJECT= (the [object] name) / PEER= (a client's address) when given;
 * if the journal socket cannot be written, as "<prio>message" on stderr.
 */
void log_at(const char *file, int line, const char *func, const char *object, const char *peer,
            int prio, const char *fmt, ...) __attribute__((format(printf, 7, 8)));
/* Start / stop the log thread (above).  0 or -errno (lines are then written
 * by the caller, as before). */
int log_async_start(void);
void log_async_stop(void);
/* Lines dropped because the queue was full, since start. */
unsigned long long log_dropped_count(void);

#define log_msg(prio, ...) log_at(__FILE__, __LINE__, __func__, NULL, NULL, prio, __VA_ARGS__)
/* A line about one object (OBJECT=name), or one peer (PEER=address). */
#define log_obj(prio, object, ...)                                                                 \
    log_at(__FILE__, __LINE__, __func__, object, NULL, prio, __VA_ARGS__)
#define log_peer(prio, peer, ...)                                                                  \
    log_at(__FILE__, __LINE__, __func__, NULL, peer, prio, __VA_ARGS__)

#endif
