/* log.c - log lines to a terminal, journald's stream or syslog (see log.h). */
#include "log.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int log_level = LOG_INFO;
static log_mode_t log_mode = LOG_MODE_AUTO;

/* JOURNAL_STREAM is "DEVICE:INODE" of the stream systemd connected; it is
 * inherited by children whose stderr may be elsewhere, so compare. */
static int stderr_is_journal(void)
{
    const char *js = getenv("JOURNAL_STREAM");
    unsigned long long dev, ino;
    struct stat st;
    if (!js || sscanf(js, "%llu:%llu", &dev, &ino) != 2 || fstat(STDERR_FILENO, &st) < 0)
        return 0;
    return (unsigned long long)st.st_dev == dev && (unsigned long long)st.st_ino == ino;
}

void log_set_mode(log_mode_t mode)
{
    if (log_mode == LOG_MODE_SYSLOG && mode != LOG_MODE_SYSLOG)
        closelog();
    if (mode == LOG_MODE_SYSLOG && log_mode != LOG_MODE_SYSLOG)
        openlog("trajd", LOG_PID | LOG_NDELAY, LOG_DAEMON);
    log_mode = mode;
}

log_mode_t log_get_mode(void)
{
    if (log_mode != LOG_MODE_AUTO)
        return log_mode;
    if (!stderr_is_journal() && isatty(STDERR_FILENO))
        return LOG_MODE_TTY;
    return LOG_MODE_PREFIX;
}

void log_set_level(int level)
{
    log_level = level;
}

int log_get_level(void)
{
    return log_level;
}

int log_level_parse(const char *s)
{
    static const struct {
        const char *name;
        int level;
    } t[] = {{"err", LOG_ERR},       {"error", LOG_ERR}, {"warning", LOG_WARNING},
             {"notice", LOG_NOTICE}, {"info", LOG_INFO}, {"debug", LOG_DEBUG}};
    for (size_t i = 0; i < sizeof t / sizeof t[0]; i++)
        if (strcmp(s, t[i].name) == 0)
            return t[i].level;
    return -1;
}

void log_msg(int prio, const char *fmt, ...)
{
    if (prio > log_level)
        return;
    char buf[1024];
    log_mode_t mode = log_get_mode();
    va_list ap;
    if (mode == LOG_MODE_SYSLOG) {
        va_start(ap, fmt);
        vsyslog(prio & 7, fmt, ap);
        va_end(ap);
        return;
    }
    int n = mode == LOG_MODE_PREFIX     ? snprintf(buf, sizeof buf, "<%d>", prio & 7)
            : (prio & 7) <= LOG_ERR     ? snprintf(buf, sizeof buf, "error: ")
            : (prio & 7) == LOG_WARNING ? snprintf(buf, sizeof buf, "warning: ")
                                        : 0;
    va_start(ap, fmt);
    int m = vsnprintf(buf + n, sizeof buf - (size_t)n - 1, fmt, ap);
    va_end(ap);
    if (m < 0)
        m = 0;
    size_t len = (size_t)n +
                 ((size_t)m < sizeof buf - (size_t)n - 1 ? (size_t)m : sizeof buf - (size_t)n - 2);
    if (len == 0 || buf[len - 1] != '\n')
        buf[len++] = '\n';
    /* One write: a line is never interleaved with another process's line. */
    ssize_t w = write(STDERR_FILENO, buf, len);
    (void)w;
}
