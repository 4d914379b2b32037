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

#define CSV_TRANSPORT_LINE_MAX 1024 /* one csv_format line: 16 numbers at most ~25 chars + name */

typedef struct {
    int fd;
    int own;           /* close at the end */
    int restore_flags; /* fcntl flags to put back (stdout), or -1 */
    int regular;       /* a regular file: a torn line can be cut off again */
    int is_stdout;
    int geo;    /* csv.geo: lat_deg,lon_deg,alt_m,heading_deg appended to every line */
    int age;    /* lines carry the age_s column */
    obj_t *obj; /* csv: the one object writing here; stdout: NULL (all of them) */
    size_t len;
    char *buf;                               /* CSV_TRANSPORT_BUF_BYTES */
    char what[PATH_MAX + CFG_NAME_MAX + 32]; /* for the log: "object 'boat' csv.path /x" */
    int last_errno;                          /* of the last failed write */
    uint64_t errors;                         /* failed write calls */
    uint64_t lost;                           /* lines lost */
    uint64_t errors_logged, lost_logged;
    int64_t logged_ns; /* CLOCK_MONOTONIC of the last warning, 0: none yet */
} stream_t;

/* This transport's row of stats_t.tcount (survives reloads). */
enum { TCOUNT_DROPPED = 0 }; /* lines dropped: the buffer was full */

typedef struct {
    core_t *core;
    uint64_t *dropped; /* &stats->tcount[its index][TCOUNT_DROPPED] */
    unsigned n;
    stream_t *s;  /* csv: one per object index (fd -1 if unused); stdout: one */
    int timer_fd; /* the 1 s housekeeping timer that logs faults, or -1 */
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
        return cfg_get_bool(kv, &c->truncate, why, wl);
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

/* A write failed with err (not EAGAIN): count it, flag the objects writing
 * here; EPIPE on stdout ends the daemon (the tick sees stats.exit_code). */
static void fault(csv_transport_t *st, stream_t *s, int err)
{
    s->errors++;
    s->last_errno = err;
    stats_t *stats = st->core->stats;
    stats->out_errors++;
    stats->out_errno = err;
    stats->out_fault = 1;
    if (s->obj) {
        s->obj->out_fault = 1;
        s->obj->out_errors++;
    } else {
        for (unsigned i = 0; i < st->core->nobj; i++)
            if (cfg_obj_uses(st->core->obj[i].cfg, &stdout_transport) & 2) {
                st->core->obj[i].out_fault = 1;
                st->core->obj[i].out_errors++;
            }
    }
    if (err == EPIPE && s->is_stdout)
        stats->exit_code = CORE_EXIT_EPIPE;
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

/* Queue one line of object o (NULL: the header); a line that does not fit
 * is lost, counted for the stream, the object and the daemon. */
static void put(csv_transport_t *st, stream_t *s, obj_t *o, const char *line, int n)
{
    if (n < 0 || (size_t)n > CSV_TRANSPORT_BUF_BYTES - s->len) {
        (*st->dropped)++;
        st->core->stats->out_lost++;
        s->lost++;
        if (o)
            o->out_lost++;
        return;
    }
    memcpy(s->buf + s->len, line, (size_t)n);
    s->len += (size_t)n;
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
                s->what, strerror(s->last_errno), (unsigned long long)s->errors,
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

/* At close: write what is left, waiting at most CSV_TRANSPORT_DRAIN_MS for a slow
 * reader (a reader that never reads must not keep trajd from exiting).  Lines
 * left over are lost and counted (not per object: the objects are going). */
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
    s->lost += left;
    *st->dropped += left;
    st->core->stats->out_lost += left;
    s->len = 0;
    report(s, 1);
    if (s->restore_flags >= 0)
        fcntl(s->fd, F_SETFL, s->restore_flags);
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

static void stream_fini(csv_transport_t *st, stream_t *s)
{
    drain(st, s);
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
    put(st, s, NULL, line, n);
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
    put(st, s, NULL, line, n < (int)sizeof line ? n : -1);
}

static void close_(void *state, core_t *c)
{
    csv_transport_t *st = state;
    if (!st)
        return;
    if (st->timer_fd >= 0)
        loop_timer_del(c->loop, st->timer_fd);
    for (unsigned i = 0; i < st->n; i++)
        stream_fini(st, &st->s[i]);
    free(st->s);
    free(st);
}

static csv_transport_t *alloc_state(core_t *c, const transport_t *t, unsigned n)
{
    csv_transport_t *st = calloc(1, sizeof *st);
    if (!st)
        return NULL;
    st->core = c;
    st->dropped = &c->stats->tcount[transport_index(t)][TCOUNT_DROPPED];
    st->n = n;
    st->timer_fd = -1;
    st->s = calloc(n, sizeof *st->s);
    if (!st->s) {
        free(st);
        return NULL;
    }
    for (unsigned i = 0; i < n; i++)
        st->s[i].fd = -1;
    return st;
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
        int fd = open(
            oc->path,
            O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC | O_NONBLOCK | (trunc ? O_TRUNC : 0), 0644);
        if (fd < 0) {
            rc = -errno;
            snprintf(why, wl, "object '%s': csv.path %s: %s", o->name, oc->path, strerror(errno));
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
    rc = loop_timer_add(c->loop, 1000000000, on_timer, st);
    if (rc < 0) {
        snprintf(why, wl, "csv: timer: %s", strerror(-rc));
        goto fail;
    }
    st->timer_fd = rc;
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
    int rc = loop_timer_add(c->loop, 1000000000, on_timer, st);
    if (rc < 0) {
        snprintf(why, wl, "stdout: timer: %s", strerror(-rc));
        close_(st, c);
        return rc;
    }
    st->timer_fd = rc;
    *state = st;
    return 0;
}

static void csv_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    csv_transport_t *st = state;
    char line[CSV_TRANSPORT_LINE_MAX];
    int n = csv_format_format(line, sizeof line, o->name, sp);
    if (n > 0 && st->s[o->index].geo) {
        /* the same number form as the other columns (csv_shortest.h) */
        char extra[4 * (CSV_SHORTEST_MAX + 1) + 1];
        const double *geo = core_obj_geo(st->core, o);
        const double v[4] = {geo[0], geo[1], geo[2], o->heading_deg};
        size_t m = 0;
        for (int k = 0; k < 4; k++) {
            extra[m++] = ',';
            m += (size_t)csv_shortest(extra + m, v[k]);
        }
        extra[m] = '\0';
        n = csv_format_append(line, sizeof line, n, extra);
    }
    if (st->s[o->index].age && n > 0)
        n = csv_format_add_age(line, sizeof line, n, sp);
    put(st, &st->s[o->index], o, line, n);
}

static void stdout_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    csv_transport_t *st = state;
    char line[CSV_TRANSPORT_LINE_MAX];
    int n = csv_format_format(line, sizeof line, o->name, sp);
    if (st->s[0].age && n > 0)
        n = csv_format_add_age(line, sizeof line, n, sp);
    put(st, &st->s[0], o, line, n);
}

static void cycle(void *state, core_t *c, int64_t now_ns)
{
    csv_transport_t *st = state;
    (void)c;
    (void)now_ns;
    for (unsigned i = 0; i < st->n; i++)
        if (st->s[i].fd >= 0 && st->s[i].len)
            flush(st, &st->s[i]);
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
