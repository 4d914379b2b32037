/* log.c - log lines to a terminal, journald's stream or syslog (see log.h). */
#include "log.h"

#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/uio.h>
#define SD_JOURNAL_SUPPRESS_LOCATION
#include <systemd/sd-journal.h>
#include <unistd.h>

#include "outworker.h"
#include "spsc.h"

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

/* The mode the next line would use (LOG_MODE_AUTO resolved). */
static log_mode_t log_get_mode(void)
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

/* One "NAME=value" field into iov[*n] from buf (truncated to buf's size). */
static void field(struct iovec *iov, int *n, char *buf, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void field(struct iovec *iov, int *n, char *buf, size_t size, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(buf, size, fmt, ap);
    va_end(ap);
    iov[*n].iov_base = buf;
    iov[(*n)++].iov_len = k < 0 ? 0 : (size_t)k < size ? (size_t)k : size - 1;
}

/* The line to the journal with its fields; 0, or < 0 if it could not be sent. */
static int journal_send(const char *file, int line, const char *func, const char *object,
                        const char *peer, int prio, const char *msg)
{
    char f_msg[1100], f_prio[16], f_id[32], f_file[256], f_line[32], f_func[128], f_obj[160],
        f_peer[160];
    struct iovec iov[8];
    int n = 0;
    field(iov, &n, f_msg, sizeof f_msg, "MESSAGE=%s", msg);
    field(iov, &n, f_prio, sizeof f_prio, "PRIORITY=%d", prio & 7);
    field(iov, &n, f_id, sizeof f_id, "SYSLOG_IDENTIFIER=trajd");
    field(iov, &n, f_file, sizeof f_file, "CODE_FILE=%s", file);
    field(iov, &n, f_line, sizeof f_line, "CODE_LINE=%d", line);
    field(iov, &n, f_func, sizeof f_func, "CODE_FUNC=%s", func);
    if (object)
        field(iov, &n, f_obj, sizeof f_obj, "OBJECT=%s", object);
    if (peer)
        field(iov, &n, f_peer, sizeof f_peer, "PEER=%s", peer);
    return sd_journal_sendv(iov, n);
}

/* One line, its text formatted, to where mode says. */
static void emit(log_mode_t mode, const char *file, int line, const char *func, const char *object,
                 const char *peer, int prio, const char *msg)
{
    char buf[1024];
    /* sd_journal_sendv drops lines silently when journald is not running:
     * only when its socket is there (else the "<N>" line below) */
    if (mode == LOG_MODE_PREFIX && stderr_is_journal() &&
        access("/run/systemd/journal/socket", W_OK) == 0) {
        size_t len = strnlen(msg, sizeof buf - 1);
        memcpy(buf, msg, len);
        while (len && buf[len - 1] == '\n')
            len--;
        buf[len] = '\0';
        if (journal_send(file, line, func, object, peer, prio, buf) >= 0)
            return;
    }
    if (mode == LOG_MODE_SYSLOG) {
        syslog(prio & 7, "%s", msg);
        return;
    }
    int n = mode == LOG_MODE_PREFIX     ? snprintf(buf, sizeof buf, "<%d>", prio & 7)
            : (prio & 7) <= LOG_ERR     ? snprintf(buf, sizeof buf, "error: ")
            : (prio & 7) == LOG_WARNING ? snprintf(buf, sizeof buf, "warning: ")
                                        : 0;
    int m = snprintf(buf + n, sizeof buf - (size_t)n - 1, "%s", msg);
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

/* ---- the log thread (log_async_start) ---------------------------------- */

#define LOG_QUEUE 256 /* lines waiting for the log thread */

typedef struct {
    log_mode_t mode;
    const char *file, *func; /* string literals (__FILE__, __func__) */
    int line, prio, has_object, has_peer;
    char object[64], peer[96];
    char msg[1024];
} log_rec_t;

static spsc_t log_q;
static outworker_t log_w;
static pthread_mutex_t log_mu = PTHREAD_MUTEX_INITIALIZER; /* producers (never the tick) */
static int log_async;
static _Atomic unsigned long long log_dropped;

static int log_idle(void *arg)
{
    (void)arg;
    return spsc_avail(&log_q) == 0;
}

static void *log_thread(void *arg)
{
    unsigned long long told = 0;
    (void)arg;
    for (;;) {
        int stop = outworker_stopping(&log_w);
        size_t n = spsc_avail(&log_q);
        for (size_t i = 0; i < n; i++) {
            const log_rec_t *r = spsc_at(&log_q, i);
            emit(r->mode, r->file, r->line, r->func, r->has_object ? r->object : NULL,
                 r->has_peer ? r->peer : NULL, r->prio, r->msg);
        }
        spsc_release(&log_q, n);
        unsigned long long d = atomic_load(&log_dropped);
        if (d != told) {
            char msg[160];
            snprintf(msg, sizeof msg,
                     "%llu log lines dropped: the log's reader (stderr, the journal) was too slow "
                     "(%llu so far)",
                     d - told, d);
            emit(log_get_mode(), __FILE__, __LINE__, __func__, NULL, NULL, LOG_WARNING, msg);
            told = d;
        }
        if (stop)
            break;
        if (!n)
            outworker_wait(&log_w, log_idle, NULL);
    }
    return NULL;
}

int log_async_start(void)
{
    if (log_async)
        return 0;
    int rc = spsc_init(&log_q, sizeof(log_rec_t), LOG_QUEUE);
    if (rc == 0)
        rc = outworker_start(&log_w, log_thread, NULL, "trajd-log");
    if (rc < 0) {
        spsc_fini(&log_q);
        return rc;
    }
    log_async = 1;
    return 0;
}

void log_async_stop(void)
{
    if (!log_async)
        return;
    pthread_mutex_lock(&log_mu);
    log_async = 0;
    pthread_mutex_unlock(&log_mu);
    outworker_stop(&log_w); /* it writes every line queued first */
    spsc_fini(&log_q);
}

unsigned long long log_dropped_count(void)
{
    return atomic_load(&log_dropped);
}

void log_at(const char *file, int line, const char *func, const char *object, const char *peer,
            int prio, const char *fmt, ...)
{
    if (prio > log_level)
        return;
    va_list ap;
    pthread_mutex_lock(&log_mu);
    if (log_async) {
        log_rec_t *r = spsc_slot(&log_q);
        if (!r) {
            atomic_fetch_add(&log_dropped, 1);
        } else {
            r->mode = log_get_mode();
            r->file = file;
            r->func = func;
            r->line = line;
            r->prio = prio;
            r->has_object = object != NULL;
            r->has_peer = peer != NULL;
            snprintf(r->object, sizeof r->object, "%s", object ? object : "");
            snprintf(r->peer, sizeof r->peer, "%s", peer ? peer : "");
            va_start(ap, fmt);
            vsnprintf(r->msg, sizeof r->msg, fmt, ap);
            va_end(ap);
            spsc_push(&log_q);
            spsc_publish(&log_q);
            outworker_wake(&log_w);
        }
        pthread_mutex_unlock(&log_mu);
        return;
    }
    pthread_mutex_unlock(&log_mu);
    char msg[1024];
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    emit(log_get_mode(), file, line, func, object, peer, prio, msg);
}
