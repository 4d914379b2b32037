/* csv_transport.c - csv and stdout output transports (see csv_transport.h). */
#include "csv_transport.h"
#include "cfg_files.h"
#include "csv_tail.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "core.h"
#include "csv_format.h"
#include "csv_shortest.h"
#include "log.h"
#include "outworker.h"
#include "regfile.h"
#include "spsc.h"

#define CSV_TRANSPORT_LINE_MAX 1024 /* one csv_format line: 16 numbers at most ~25 chars + name */

/*
 * Two threads (issue 28).  The tick only copies each setpoint into a record
 * of a ring (spsc.h) and publishes the ring once per tick; the writer thread
 * (outworker.h, SCHED_OTHER) formats the records into each stream's buffer
 * and writes it.  The writer's counters are atomics the tick folds into the
 * daemon's (stats_t, obj_t) in its cycle hook: those keep one writer, the
 * loop thread.
 */
typedef struct {
    /* the writer's (the loop thread's before the writer starts and after it is joined) */
    int fd;
    int own;           /* close at the end */
    int restore_flags; /* fcntl flags to put back (stdout), or -1 */
    int regular;       /* a regular file: a torn line can be cut off again */
    int is_stdout;
    int geo; /* csv.geo: lat_deg,lon_deg,alt_m,heading_deg appended to every line */
    int age; /* lines carry the age_s column */
    size_t len;
    char *buf;   /* CSV_TRANSPORT_BUF_BYTES */
    int stalled; /* the last write did not take everything (EAGAIN, an error) */
    /* written by the writer, read by the loop thread */
    _Atomic uint64_t w_errors;  /* failed write calls */
    _Atomic uint64_t w_dropped; /* lines dropped: the buffer was full */
    _Atomic uint64_t w_left;    /* lines left in the buffer at the end */
    _Atomic int w_errno;        /* of the last failed write */
    _Atomic int w_epipe;        /* stdout's reader left */
    /* the loop thread's */
    obj_t *obj;                              /* csv: the one object writing here; stdout: NULL */
    char what[PATH_MAX + CFG_NAME_MAX + 32]; /* for the log: "object 'boat' csv.path /x" */
    uint64_t seen_errors, seen_dropped, seen_left; /* writer counts folded so far */
    uint64_t errors;                               /* failed write calls (folded) */
    uint64_t lost;                                 /* lines lost (folded, and queue full) */
    uint64_t errors_logged, lost_logged;
    int64_t logged_ns; /* CLOCK_MONOTONIC of the last warning, 0: none yet */
} stream_t;

/* This transport's row of stats_t.tcount (survives reloads). */
enum { TCOUNT_DROPPED = 0 }; /* lines dropped: the buffer or the queue was full */

/* One setpoint on its way to the writer. */
typedef struct {
    unsigned stream, obj; /* indices: st->s, st->names */
    double geo[4];        /* lat, lon, alt, heading (streams with geo) */
    engine_setpoint_t sp;
} rec_t;

/* The queue holds this many ticks of every object's lines (at least CSV_QUEUE_MIN). */
#define CSV_QUEUE_TICKS 16
#define CSV_QUEUE_MIN 4096

typedef struct {
    core_t *core;
    uint64_t *dropped; /* &stats->tcount[its index][TCOUNT_DROPPED] */
    unsigned n;
    stream_t *s;  /* csv: one per object index (fd -1 if unused); stdout: one */
    int timer_fd; /* the 1 s housekeeping timer that logs faults, or -1 */
    unsigned nobj;
    char (*names)[CFG_NAME_MAX];   /* object names by index (the writer's copy) */
    _Atomic uint64_t *obj_dropped; /* per object: lines the writer dropped */
    uint64_t *obj_seen;            /* the same, folded into obj_t.out_lost */
    _Atomic uint64_t events;       /* bumped by the writer at every count */
    uint64_t events_seen;
    spsc_t q;
    outworker_t w;
} csv_transport_t;

/* Warnings about one output: the first at once (within a second), then at
 * most one per CSV_TRANSPORT_LOG_EVERY_S while lines keep being lost. */
#define CSV_TRANSPORT_LOG_EVERY_S 10

static void obj_default(void *ocfg)
{
    csv_transport_obj_cfg_t *c = ocfg;
    c->header = 1;
    c->truncate = 0;
}

static int csv_obj_key(void *ocfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    csv_transport_obj_cfg_t *c = ocfg;
    if (strcmp(kv->key, "path") == 0)
        return cfg_get_path(kv, c->path, sizeof c->path, why, wl);
    if (strcmp(kv->key, "header") == 0)
        return cfg_get_bool(kv, &c->header, why, wl);
    if (strcmp(kv->key, "truncate") == 0) { /* no | yes (at start) | always (and at reloads) */
        static const char *const always[] = {"always", NULL};
        int k;
        if (cfg_get_enum(kv, always, &k, why, wl) == 0) {
            c->truncate = CSV_TRUNCATE_ALWAYS;
            return 0;
        }
        int rc = cfg_get_bool(kv, &c->truncate, why, wl);
        if (rc < 0) /* the three values, not the boolean's two */
            snprintf(why, wl, "expected no, yes or always, got '%s'", kv->value);
        return rc;
    }
    if (strcmp(kv->key, "geo") == 0)
        return cfg_get_bool(kv, &c->geo, why, wl);
    if (strcmp(kv->key, "age") == 0)
        return cfg_get_bool(kv, &c->age, why, wl);
    return -CFG_EUNKNOWN;
}

static int stdout_obj_key(void *ocfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    csv_transport_obj_cfg_t *c = ocfg;
    if (strcmp(kv->key, "header") == 0)
        return cfg_get_bool(kv, &c->header, why, wl);
    if (strcmp(kv->key, "age") == 0)
        return cfg_get_bool(kv, &c->age, why, wl);
    return -CFG_EUNKNOWN;
}

/* A csv.path whose directory is not there (yet) is said at check time: the
 * start fails on it unless it is made first (a RuntimeDirectory is made by
 * systemd before the unit's check runs), as the start's error then says. */
static void dir_said(const cfg_t *cfg, const cfg_obj_t *o, const char *path)
{
    char d[PATH_MAX];
    struct stat sb;
    snprintf(d, sizeof d, "%s", path);
    char *slash = strrchr(d, '/');
    if (!slash)
        return; /* the working directory */
    if (slash == d)
        slash[1] = 0;
    else
        *slash = 0;
    if (stat(d, &sb) == 0 && S_ISDIR(sb.st_mode))
        return;
    log_msg(LOG_WARNING,
            "%s:%d: [object.%s] csv.path %s: its directory %s is not a directory that exists: "
            "the start fails unless it is made first",
            cfg->path, o->line, o->name, path, d);
}

static int csv_check(cfg_t *cfg, int *line, char *why, size_t wl)
{
    int ti = transport_index(&csv_transport);
    for (unsigned i = 0; i < cfg->nobj; i++) {
        if (!(cfg_obj_uses(&cfg->obj[i], &csv_transport) & 2))
            continue;
        const csv_transport_obj_cfg_t *a = cfg->obj[i].tcfg[ti];
        if (!a->path[0]) {
            *line = cfg->obj[i].line;
            snprintf(why, wl, "object '%s': csv.path is missing", cfg->obj[i].name);
            return -CFG_EMISSING;
        }
        dir_said(cfg, &cfg->obj[i], a->path);
        for (unsigned j = 0; j < i; j++) {
            if (!(cfg_obj_uses(&cfg->obj[j], &csv_transport) & 2))
                continue;
            const csv_transport_obj_cfg_t *b = cfg->obj[j].tcfg[ti];
            if (strcmp(a->path, b->path) == 0) {
                *line = cfg->obj[i].line;
                snprintf(why, wl, "objects '%s' and '%s' write the same csv.path %s",
                         cfg->obj[j].name, cfg->obj[i].name, a->path);
                return -CFG_EVALUE;
            }
        }
    }
    return 0;
}

/* Bytes after the last newline in buf[0..n): the written part of a torn line. */
static size_t torn_tail(const char *buf, size_t n)
{
    size_t i = n;
    while (i > 0 && buf[i - 1] != '\n')
        i--;
    return n - i;
}

/* Cut the last tail bytes off a regular file (opened O_APPEND, so the next
 * write lands right after).  0 or -errno. */
static int cut_tail(int fd, size_t tail)
{
    struct stat sb;
    if (fstat(fd, &sb) < 0)
        return -errno;
    if ((uintmax_t)sb.st_size < tail)
        return -EINVAL;
    return ftruncate(fd, sb.st_size - (off_t)tail) < 0 ? -errno : 0;
}

/* ---- the writer thread ------------------------------------------------ */

/* A write failed with err (not EAGAIN): counted; the loop thread folds it
 * into the daemon's counters and flags (fold), and EPIPE on stdout ends the
 * daemon (CORE_EXIT_EPIPE). */
static void fault(csv_transport_t *st, stream_t *s, int err)
{
    atomic_store_explicit(&s->w_errno, err, memory_order_relaxed);
    if (err == EPIPE && s->is_stdout)
        atomic_store_explicit(&s->w_epipe, 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&s->w_errors, 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&st->events, 1, memory_order_release);
}

/*
 * Write what the buffer holds without blocking; keep the rest.  The buffer
 * holds whole lines, and a line reaches a regular file whole or not at all:
 * if a write stops inside a line and the next one fails (ENOSPC, EIO, a
 * quota), the part written is cut off the file again and the line stays in
 * the buffer for the next try.  Returns 0 or the errno of a failed write.
 */
static int flush(csv_transport_t *st, stream_t *s)
{
    size_t off = 0;
    int err = 0;
    while (off < s->len) {
        ssize_t w = write(s->fd, s->buf + off, s->len - off);
        if (w > 0) {
            off += (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK)
            err = errno;
        else if (w == 0)
            err = EIO;
        break; /* EAGAIN: later (the buffer fills and new lines are dropped, counted) */
    }
    s->stalled = off < s->len;
    if (err) {
        size_t tail = torn_tail(s->buf, off);
        if (tail && s->regular && cut_tail(s->fd, tail) == 0)
            off -= tail;
        fault(st, s, err);
    }
    if (off) {
        memmove(s->buf, s->buf + off, s->len - off);
        s->len -= off;
    }
    return err;
}

/* Queue one line of object index oi (-1: the header or a marker) in the
 * stream's buffer; a line that does not fit is lost, counted.  From the
 * writer (may_write): a full buffer is written first unless the last write
 * stalled (a slow reader, a failing disk: then the line is lost, as at the
 * tick before, and the failed writes are not multiplied by the lines). */
static void put(csv_transport_t *st, stream_t *s, int oi, const char *line, int n, int may_write)
{
    if (n >= 0 && (size_t)n > CSV_TRANSPORT_BUF_BYTES - s->len && may_write && !s->stalled)
        flush(st, s);
    if (n < 0 || (size_t)n > CSV_TRANSPORT_BUF_BYTES - s->len) {
        atomic_fetch_add_explicit(&s->w_dropped, 1, memory_order_relaxed);
        if (oi >= 0)
            atomic_fetch_add_explicit(&st->obj_dropped[oi], 1, memory_order_relaxed);
        atomic_fetch_add_explicit(&st->events, 1, memory_order_release);
        return;
    }
    memcpy(s->buf + s->len, line, (size_t)n);
    s->len += (size_t)n;
}

/* One record as a line into its stream's buffer: the csv_format line, then
 * the geo columns (csv.geo) in the same number form, then age_s. */
static void format_rec(csv_transport_t *st, const rec_t *r)
{
    stream_t *s = &st->s[r->stream];
    char line[CSV_TRANSPORT_LINE_MAX];
    int n = csv_format_format(line, sizeof line, st->names[r->obj], &r->sp);
    if (n > 0 && s->geo) {
        char extra[4 * (CSV_SHORTEST_MAX + 1) + 1];
        size_t m = 0;
        for (int k = 0; k < 4; k++) {
            extra[m++] = ',';
            m += (size_t)csv_shortest(extra + m, r->geo[k]);
        }
        extra[m] = '\0';
        n = csv_format_append(line, sizeof line, n, extra);
    }
    if (s->age && n > 0)
        n = csv_format_add_age(line, sizeof line, n, &r->sp);
    put(st, s, (int)r->obj, line, n, 1);
}

/* At the end: write what is left, waiting at most CSV_TRANSPORT_DRAIN_MS for a
 * slow reader (a reader that never reads must not keep trajd from exiting).
 * Lines left over are lost and counted (not per object: the objects are going). */
#define CSV_TRANSPORT_DRAIN_MS 1000
static void drain(csv_transport_t *st, stream_t *s)
{
    if (s->fd < 0)
        return;
    int64_t end_ms = core_mono_ns() / 1000000 + CSV_TRANSPORT_DRAIN_MS;
    for (;;) {
        if (flush(st, s))
            break;
        int64_t left_ms = end_ms - core_mono_ns() / 1000000;
        if (!s->len || left_ms <= 0)
            break;
        struct pollfd pfd = {.fd = s->fd, .events = POLLOUT};
        if (poll(&pfd, 1, (int)left_ms) <= 0 || (pfd.revents & (POLLERR | POLLHUP)))
            break;
    }
    uint64_t left = 0;
    for (size_t i = 0; i < s->len; i++)
        left += s->buf[i] == '\n';
    s->len = 0;
    if (left) {
        atomic_fetch_add_explicit(&s->w_left, left, memory_order_relaxed);
        atomic_fetch_add_explicit(&st->events, 1, memory_order_release);
    }
}

static int queue_idle(void *arg)
{
    csv_transport_t *st = arg;
    return spsc_avail(&st->q) == 0;
}

/* The writer: format what the tick published, write each stream once per
 * batch (as the tick did once per tick), sleep when there is nothing; at the
 * stop, take what was published before it, then drain every stream. */
static void *writer(void *arg)
{
    csv_transport_t *st = arg;
    for (;;) {
        int stop = outworker_stopping(&st->w);
        size_t n = spsc_avail(&st->q);
        for (size_t i = 0; i < n; i++)
            format_rec(st, spsc_at(&st->q, i));
        spsc_release(&st->q, n);
        if (n)
            for (unsigned i = 0; i < st->n; i++)
                if (st->s[i].fd >= 0 && st->s[i].len)
                    flush(st, &st->s[i]);
        if (stop)
            break;
        if (!n)
            outworker_wait(&st->w, queue_idle, st);
    }
    for (unsigned i = 0; i < st->n; i++)
        drain(st, &st->s[i]);
    return NULL;
}

/* ---- the loop thread ---------------------------------------------------- */

/*
 * The writer's counts since the last call into the daemon's: failed writes
 * set the fault flag of the objects writing there and stats.out_fault;
 * dropped lines count for the stream, the object and the daemon (the lines
 * left at a close for the object whose file it is, not those of stdout); EPIPE on stdout ends the daemon (the tick
 * sees stats.exit_code).  In the tick (cycle) and at close: no blocking, no
 * allocation; a scan only when the writer counted something.
 */
static void fold(csv_transport_t *st)
{
    uint64_t ev = atomic_load_explicit(&st->events, memory_order_acquire);
    if (ev == st->events_seen)
        return;
    st->events_seen = ev;
    stats_t *stats = st->core->stats;
    for (unsigned i = 0; i < st->n; i++) {
        stream_t *s = &st->s[i];
        uint64_t e = atomic_load_explicit(&s->w_errors, memory_order_relaxed);
        uint64_t d = atomic_load_explicit(&s->w_dropped, memory_order_relaxed);
        uint64_t l = atomic_load_explicit(&s->w_left, memory_order_relaxed);
        uint64_t de = e - s->seen_errors, dleft = l - s->seen_left,
                 dl = d - s->seen_dropped + dleft;
        s->seen_errors = e;
        s->seen_dropped = d;
        s->seen_left = l;
        if (de) {
            s->errors += de;
            stats->out_errors += de;
            stats->out_errno = atomic_load_explicit(&s->w_errno, memory_order_relaxed);
            stats->out_fault = 1;
            if (s->obj) {
                s->obj->out_fault = 1;
                s->obj->out_errors += de;
            }
            for (unsigned k = 0; !s->obj && k < st->core->nobj; k++) {
                obj_t *o = &st->core->obj[k];
                if (cfg_obj_uses(o->cfg, &stdout_transport) & 2) {
                    o->out_fault = 1;
                    o->out_errors += de;
                }
            }
        }
        if (dl) {
            s->lost += dl;
            *st->dropped += dl;
            stats->out_lost += dl;
            /* the lines left at a close (a reload, the end) are its object's
             * too where the stream is one object's (the dropped ones are
             * counted per object by the writer: obj_dropped) */
            if (s->obj)
                s->obj->out_lost += dleft;
        }
        if (s->is_stdout && atomic_load_explicit(&s->w_epipe, memory_order_relaxed))
            stats->exit_code = CORE_EXIT_EPIPE;
    }
    for (unsigned k = 0; k < st->nobj && k < st->core->nobj; k++) {
        uint64_t d = atomic_load_explicit(&st->obj_dropped[k], memory_order_relaxed);
        st->core->obj[k].out_lost += d - st->obj_seen[k];
        st->obj_seen[k] = d;
    }
}

/* Warn about new losses or errors of s, rate-limited (not from the tick). */
static void report(stream_t *s, int final)
{
    if (s->lost == s->lost_logged && s->errors == s->errors_logged)
        return;
    int64_t now = core_mono_ns();
    if (!final && s->logged_ns && now - s->logged_ns < CSV_TRANSPORT_LOG_EVERY_S * 1000000000LL)
        return;
    if (s->errors != s->errors_logged)
        log_msg(LOG_WARNING, "%s: write failed: %s (%llu failed writes, %llu lines lost so far)",
                s->what, strerror(atomic_load(&s->w_errno)), (unsigned long long)s->errors,
                (unsigned long long)s->lost);
    else
        log_msg(LOG_WARNING, "%s: reader too slow, buffer full: %llu lines lost so far", s->what,
                (unsigned long long)s->lost);
    s->lost_logged = s->lost;
    s->errors_logged = s->errors;
    s->logged_ns = now;
}

static void on_timer(loop_t *l, uint64_t exp, void *ctx)
{
    csv_transport_t *st = ctx;
    (void)l;
    (void)exp;
    for (unsigned i = 0; i < st->n; i++)
        if (st->s[i].fd >= 0)
            report(&st->s[i], 0);
}

static int stream_init(stream_t *s, int fd, int own)
{
    s->fd = fd;
    s->own = own;
    s->restore_flags = -1;
    s->len = 0;
    struct stat sb;
    s->regular = fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode);
    s->buf = malloc(CSV_TRANSPORT_BUF_BYTES);
    return s->buf ? 0 : -ENOMEM;
}

/* After the writer was joined (or never started) and its counts folded. */
static void stream_fini(stream_t *s)
{
    if (s->fd >= 0) {
        report(s, 1);
        if (s->restore_flags >= 0)
            fcntl(s->fd, F_SETFL, s->restore_flags);
    }
    if (s->own && s->fd >= 0)
        close(s->fd);
    free(s->buf);
    s->buf = NULL;
    s->fd = -1;
}

static void header(csv_transport_t *st, stream_t *s)
{
    char line[CSV_TRANSPORT_LINE_MAX];
    int n = csv_format_header(line, sizeof line);
    if (n > 0 && s->geo)
        n = csv_format_append(line, sizeof line, n, ",lat_deg,lon_deg,alt_m,heading_deg");
    if (s->age && n > 0)
        n = csv_format_add_age(line, sizeof line, n, NULL);
    put(st, s, -1, line, n, 0);
}

/* Fields of s's lines: 16, + 4 with csv.geo, + 1 with age_s (csv_tail.h). */
static int columns(const stream_t *s)
{
    return 16 + (s->geo ? 4 : 0) + (s->age ? 1 : 0);
}

/* The line that marks where a restart or a reload appended to a file that
 * was not empty ("#": not a row; pandas: comment='#'). */
static void marker(csv_transport_t *st, stream_t *s)
{
    char line[160], when[64] = "?";
    struct timespec ts;
    struct tm tm;
    if (clock_gettime(CLOCK_REALTIME, &ts) == 0 && gmtime_r(&ts.tv_sec, &tm))
        strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &tm);
    int n = snprintf(line, sizeof line, "# trajd: appended at %s (start or reload)\n", when);
    put(st, s, -1, line, n < (int)sizeof line ? n : -1, 0);
}

static void close_(void *state, core_t *c)
{
    csv_transport_t *st = state;
    if (!st)
        return;
    if (st->timer_fd >= 0)
        loop_timer_del(c->loop, st->timer_fd);
    if (st->w.started) {
        spsc_publish(&st->q);
        outworker_stop(&st->w); /* it takes what was published, then drains */
    } else {
        for (unsigned i = 0; i < st->n; i++)
            drain(st, &st->s[i]); /* lines put at open; the writer never started */
    }
    fold(st);
    for (unsigned i = 0; i < st->n; i++)
        stream_fini(&st->s[i]);
    spsc_fini(&st->q);
    free(st->names);
    free(st->obj_dropped);
    free(st->obj_seen);
    free(st->s);
    free(st);
}

static csv_transport_t *alloc_state(core_t *c, const transport_t *t, unsigned n)
{
    /* its queue's counters are _Alignas(64) (spsc.h): more than malloc gives */
    csv_transport_t *st = aligned_alloc(_Alignof(csv_transport_t), sizeof *st);
    if (st)
        memset(st, 0, sizeof *st);
    if (!st)
        return NULL;
    st->core = c;
    st->dropped = &c->stats->tcount[transport_index(t)][TCOUNT_DROPPED];
    st->n = n;
    st->timer_fd = -1;
    st->nobj = c->nobj;
    st->s = calloc(n, sizeof *st->s);
    st->names = calloc(c->nobj ? c->nobj : 1, sizeof *st->names);
    st->obj_dropped = calloc(c->nobj ? c->nobj : 1, sizeof *st->obj_dropped);
    st->obj_seen = calloc(c->nobj ? c->nobj : 1, sizeof *st->obj_seen);
    size_t cap = (size_t)c->nobj * CSV_QUEUE_TICKS;
    if (!st->s || !st->names || !st->obj_dropped || !st->obj_seen ||
        spsc_init(&st->q, sizeof(rec_t), cap > CSV_QUEUE_MIN ? cap : CSV_QUEUE_MIN) < 0) {
        spsc_fini(&st->q);
        free(st->names);
        free(st->obj_dropped);
        free(st->obj_seen);
        free(st->s);
        free(st);
        return NULL;
    }
    for (unsigned i = 0; i < c->nobj; i++)
        snprintf(st->names[i], sizeof st->names[i], "%s", c->obj[i].name);
    for (unsigned i = 0; i < n; i++)
        st->s[i].fd = -1;
    return st;
}

/* The timer that logs faults, and the writer.  0 or -errno with why. */
static int start(csv_transport_t *st, core_t *c, const char *what, char *why, size_t wl)
{
    int rc = loop_timer_add(c->loop, 1000000000, on_timer, st);
    if (rc < 0) {
        snprintf(why, wl, "%s: timer: %s", what, strerror(-rc));
        return rc;
    }
    st->timer_fd = rc;
    rc = outworker_start(&st->w, writer, st, "trajd-out");
    if (rc < 0)
        snprintf(why, wl, "%s: writer thread: %s", what, strerror(-rc));
    return rc;
}

/* In the tick: one setpoint into the queue (copied, formatted by the writer);
 * a full queue loses the line, counted for the stream, the object and the
 * daemon.  Published in cycle. */
static void push(csv_transport_t *st, unsigned si, obj_t *o, const engine_setpoint_t *sp)
{
    rec_t *r = spsc_slot(&st->q);
    if (!r) {
        (*st->dropped)++;
        st->core->stats->out_lost++;
        st->s[si].lost++;
        o->out_lost++;
        return;
    }
    r->stream = si;
    r->obj = o->index;
    r->sp = *sp;
    if (st->s[si].geo) {
        const double *geo = core_obj_geo(st->core, o);
        r->geo[0] = geo[0];
        r->geo[1] = geo[1];
        r->geo[2] = geo[2];
        r->geo[3] = o->heading_deg;
    }
    spsc_push(&st->q);
}

static int csv_open(core_t *c, void **state, char *why, size_t wl)
{
    csv_transport_t *st = alloc_state(c, &csv_transport, c->nobj);
    int rc = 0;
    if (!st) {
        snprintf(why, wl, "out of memory");
        return -ENOMEM;
    }
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        if (!(cfg_obj_uses(o->cfg, &csv_transport) & 2))
            continue;
        const csv_transport_obj_cfg_t *oc = cfg_obj_transport(o->cfg, &csv_transport);
        /* O_NONBLOCK matters for a FIFO; a regular file ignores it.  O_APPEND
         * always: a torn line is cut off the end (flush), and the next write
         * must land there, not at an offset past it. */
        /* a reload (ticks ran) empties the file only with csv.truncate = always */
        int trunc = oc->truncate == CSV_TRUNCATE_ALWAYS || (oc->truncate && !c->stats->ticks);
        int tail = trunc ? 0 : csv_tail_fields(oc->path); /* before anything is written */
        int fd = regfile_create(/* (the [daemon] user's if trajd makes it: regfile.h) */
                                oc->path,
                                O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NONBLOCK |
                                    (trunc ? O_TRUNC : 0),
                                0644);
        if (fd < 0) {
            rc = -errno;
            snprintf(why, wl, "%s:%d: [object.%s] csv.path %s: %s", c->cfg->path, o->cfg->line,
                     o->name, oc->path, strerror(errno));
            goto fail;
        }
        if (stream_init(&st->s[i], fd, 1) < 0) {
            close(fd);
            rc = -ENOMEM;
            snprintf(why, wl, "out of memory");
            goto fail;
        }
        stream_t *sm = &st->s[i];
        sm->obj = o;
        sm->geo = oc->geo;
        sm->age = oc->age;
        snprintf(sm->what, sizeof sm->what, "object '%s' csv.path %s", o->name, oc->path);
        struct stat sb;
        if (sm->regular && fstat(fd, &sb) == 0 && sb.st_size > 0) {
            marker(st, sm); /* appending: no second header, unless the columns change */
            if (oc->header && tail && tail != columns(sm))
                header(st, sm);
        } else if (oc->header) {
            header(st, sm);
        }
    }
    rc = start(st, c, "csv", why, wl);
    if (rc < 0)
        goto fail;
    *state = st;
    return 0;
fail:
    close_(st, c);
    return rc;
}

static int stdout_open(core_t *c, void **state, char *why, size_t wl)
{
    csv_transport_t *st = alloc_state(c, &stdout_transport, 1);
    if (!st || stream_init(&st->s[0], STDOUT_FILENO, 0) < 0) {
        close_(st, c);
        snprintf(why, wl, "out of memory");
        return -ENOMEM;
    }
    st->s[0].is_stdout = 1;
    snprintf(st->s[0].what, sizeof st->s[0].what, "stdout");
    int fl = fcntl(STDOUT_FILENO, F_GETFL);
    if (fl < 0) {
        int rc = -errno;
        snprintf(why, wl, "stdout: %s", strerror(errno));
        close_(st, c);
        return rc;
    }
    if (!(fl & O_NONBLOCK)) {
        st->s[0].restore_flags = fl;
        fcntl(STDOUT_FILENO, F_SETFL, fl | O_NONBLOCK);
    }
    int want_header = 0;
    for (unsigned i = 0; i < c->nobj; i++)
        if (cfg_obj_uses(c->obj[i].cfg, &stdout_transport) & 2) {
            const csv_transport_obj_cfg_t *oc = cfg_obj_transport(c->obj[i].cfg, &stdout_transport);
            want_header |= oc->header;
            st->s[0].age |= oc->age;
        }
    if (want_header)
        header(st, &st->s[0]);
    int rc = start(st, c, "stdout", why, wl);
    if (rc < 0) {
        close_(st, c);
        return rc;
    }
    *state = st;
    return 0;
}

static void csv_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    push(state, o->index, o, sp);
}

static void stdout_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    push(state, 0, o, sp);
}

/* Once per tick: what the tick queued goes to the writer; its counts come back. */
static void cycle(void *state, core_t *c, int64_t now_ns)
{
    csv_transport_t *st = state;
    (void)c;
    (void)now_ns;
    spsc_publish(&st->q);
    outworker_wake(&st->w);
    fold(st);
}

/* Lines dropped by csv and stdout together, as one status item. */
static int summary(const core_t *c, char *buf, size_t len)
{
    uint64_t n = c->stats->tcount[transport_index(&csv_transport)][TCOUNT_DROPPED] +
                 c->stats->tcount[transport_index(&stdout_transport)][TCOUNT_DROPPED];
    return n ? snprintf(buf, len, ", out dropped %llu", (unsigned long long)n) : 0;
}

/* Each csv.path is written (cfg_files.h). */
static void csv_files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx)
{
    int ti = transport_index(&csv_transport);
    for (unsigned i = 0; i < cfg->nobj; i++)
        if (cfg_obj_uses(&cfg->obj[i], &csv_transport) & 2) {
            char what[64];
            snprintf(what, sizeof what, "[object.%s] csv.path", cfg->obj[i].name);
            const csv_transport_obj_cfg_t *a = cfg->obj[i].tcfg[ti];
            add(ctx, a->path, 1, cfg->obj[i].line, what);
        }
}

/* one file per object written (csv_files: two objects never share one) */
static unsigned csv_fds(const cfg_t *cfg, unsigned *clients)
{
    unsigned n = 0;
    (void)clients;
    for (unsigned i = 0; i < cfg->nobj; i++)
        n += (cfg_obj_uses(&cfg->obj[i], &csv_transport) & 2) != 0;
    return n;
}

const transport_t csv_transport = {
    .name = "csv",
    .roles = TRANSPORT_OUTPUT,
    .obj_cfg_size = sizeof(csv_transport_obj_cfg_t),
    .obj_cfg_default = obj_default,
    .obj_key = csv_obj_key,
    .check = csv_check,
    .open = csv_open,
    .setpoint = csv_setpoint,
    .cycle = cycle,
    .close = close_,
    .summary = summary, /* stdout's count too */
    .files = csv_files,
    .fds = csv_fds,
};

const transport_t stdout_transport = {
    .name = "stdout",
    .roles = TRANSPORT_OUTPUT,
    .obj_cfg_size = sizeof(csv_transport_obj_cfg_t),
    .obj_cfg_default = obj_default,
    .obj_key = stdout_obj_key,
    .open = stdout_open,
    .setpoint = stdout_setpoint,
    .cycle = cycle,
    .close = close_,
};
