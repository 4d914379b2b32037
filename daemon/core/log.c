/* log.c - stderr lines with journald "<N>" priority prefixes (see log.h). */
#include "log.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static int log_level = LOG_INFO;

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
    } t[] = {{"err", LOG_ERR},   {"error", LOG_ERR}, {"warning", LOG_WARNING},
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
    int n = snprintf(buf, sizeof buf, "<%d>", prio & 7);
    va_list ap;
    va_start(ap, fmt);
    int m = vsnprintf(buf + n, sizeof buf - (size_t)n - 1, fmt, ap);
    va_end(ap);
    if (m < 0)
        m = 0;
    size_t len = (size_t)n + ((size_t)m < sizeof buf - (size_t)n - 1
                                   ? (size_t)m : sizeof buf - (size_t)n - 2);
    if (len == 0 || buf[len - 1] != '\n')
        buf[len++] = '\n';
    /* One write: a line is never interleaved with another process's line. */
    ssize_t w = write(STDERR_FILENO, buf, len);
    (void)w;
}
