/*
 * log.h - log lines to stderr with the "<N>" priority prefix journald reads
 * (sd-daemon(3): SD_ERR is "<3>", SD_INFO "<6>" ...), one write() per line so
 * lines from one process never interleave.  Priorities are syslog.h's
 * LOG_ERR .. LOG_DEBUG.
 *
 * Not for the tick: stderr may block when journald is slow.  The tick counts
 * events; a housekeeping timer logs them.
 */
#ifndef TRAJD_LOG_H
#define TRAJD_LOG_H

#include <syslog.h>

/* Lines with a priority above (less urgent than) level are dropped.  Default LOG_INFO. */
void log_set_level(int level);
int log_get_level(void);

/* Parse "err", "warning", "notice", "info", "debug"; returns the LOG_* value or -1. */
int log_level_parse(const char *s);

/* Write "<prio>message\n" to stderr (printf format; a trailing '\n' is not needed). */
void log_msg(int prio, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
