/* csv_transport.c - csv and stdout output transports (see csv_transport.h). */
#include "csv_transport.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core.h"
#include "csv_format.h"

#define CSV_TRANSPORT_LINE_MAX 1024 /* one csv_format line: 16 numbers at most ~25 chars + name */

typedef struct {
    int fd;
    int own;               /* close at the end */
    int restore_flags;     /* fcntl flags to put back (stdout), or -1 */
    size_t len;
    char *buf;             /* CSV_TRANSPORT_BUF_BYTES */
} stream_t;

/* This transport's row of stats_t.tcount (survives reloads). */
enum { TCOUNT_DROPPED = 0 };  /* lines dropped: the buffer was full */

typedef struct {
    uint64_t *dropped;     /* &stats->tcount[its index][TCOUNT_DROPPED] */
    unsigned n;
    stream_t *s;           /* csv: one per object index (fd -1 if unused); stdout: one */
} csv_transport_t;

static void obj_default(void *ocfg)
{
    csv_transport_obj_cfg_t *c = ocfg;
    c->header = 1;
}

static int csv_obj_key(void *ocfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    csv_transport_obj_cfg_t *c = ocfg;
    if (strcmp(kv->key, "path") == 0)
        return cfg_get_path(kv, c->path, sizeof c->path, why, wl);
    if (strcmp(kv->key, "header") == 0)
        return cfg_get_bool(kv, &c->header, why, wl);
    return -CFG_EUNKNOWN;
}

static int stdout_obj_key(void *ocfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    csv_transport_obj_cfg_t *c = ocfg;
    if (strcmp(kv->key, "header") == 0)
        return cfg_get_bool(kv, &c->header, why, wl);
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

/* Write what the buffer holds without blocking; keep the rest. */
static void flush(stream_t *s)
{
    size_t off = 0;
    while (off < s->len) {
        ssize_t w = write(s->fd, s->buf + off, s->len - off);
        if (w > 0) {
            off += (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        break; /* EAGAIN: later; other errors: the buffer fills and lines are dropped */
    }
    if (off) {
        memmove(s->buf, s->buf + off, s->len - off);
        s->len -= off;
    }
}

static void put(csv_transport_t *st, stream_t *s, const char *line, int n)
{
    if (n < 0 || (size_t)n > CSV_TRANSPORT_BUF_BYTES - s->len) {
        (*st->dropped)++;
        return;
    }
    memcpy(s->buf + s->len, line, (size_t)n);
    s->len += (size_t)n;
}

/* At close: write what is left, waiting at most CSV_TRANSPORT_DRAIN_MS for a slow
 * reader (a reader that never reads must not keep trajd from exiting). */
#define CSV_TRANSPORT_DRAIN_MS 1000
static void drain(stream_t *s)
{
    if (s->fd < 0)
        return;
    int64_t end_ms = core_mono_ns() / 1000000 + CSV_TRANSPORT_DRAIN_MS;
    for (;;) {
        flush(s);
        int64_t left_ms = end_ms - core_mono_ns() / 1000000;
        if (!s->len || left_ms <= 0)
            break;
        struct pollfd pfd = {.fd = s->fd, .events = POLLOUT};
        if (poll(&pfd, 1, (int)left_ms) <= 0 || (pfd.revents & (POLLERR | POLLHUP)))
            break;
    }
    if (s->restore_flags >= 0)
        fcntl(s->fd, F_SETFL, s->restore_flags);
}

static int stream_init(stream_t *s, int fd, int own)
{
    s->fd = fd;
    s->own = own;
    s->restore_flags = -1;
    s->len = 0;
    s->buf = malloc(CSV_TRANSPORT_BUF_BYTES);
    return s->buf ? 0 : -ENOMEM;
}

static void stream_fini(stream_t *s)
{
    drain(s);
    if (s->own && s->fd >= 0)
        close(s->fd);
    free(s->buf);
    s->buf = NULL;
    s->fd = -1;
}

static void header(csv_transport_t *st, stream_t *s)
{
    char line[CSV_TRANSPORT_LINE_MAX];
    put(st, s, line, csv_format_header(line, sizeof line));
}

static void close_(void *state, core_t *c)
{
    csv_transport_t *st = state;
    (void)c;
    if (!st)
        return;
    for (unsigned i = 0; i < st->n; i++)
        stream_fini(&st->s[i]);
    free(st->s);
    free(st);
}

static csv_transport_t *alloc_state(core_t *c, const transport_t *t, unsigned n)
{
    csv_transport_t *st = calloc(1, sizeof *st);
    if (!st)
        return NULL;
    st->dropped = &c->stats->tcount[transport_index(t)][TCOUNT_DROPPED];
    st->n = n;
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
        /* O_NONBLOCK matters for a FIFO; a regular file ignores it. */
        int fd = open(oc->path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NONBLOCK, 0644);
        if (fd < 0) {
            rc = -errno;
            snprintf(why, wl, "object '%s': csv.path %s: %s", o->name, oc->path,
                     strerror(errno));
            goto fail;
        }
        if (stream_init(&st->s[i], fd, 1) < 0) {
            close(fd);
            rc = -ENOMEM;
            snprintf(why, wl, "out of memory");
            goto fail;
        }
        if (oc->header)
            header(st, &st->s[i]);
    }
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
        }
    if (want_header)
        header(st, &st->s[0]);
    *state = st;
    return 0;
}

static void csv_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    csv_transport_t *st = state;
    char line[CSV_TRANSPORT_LINE_MAX];
    put(st, &st->s[o->index], line, csv_format_format(line, sizeof line, o->name, sp));
}

static void stdout_setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    csv_transport_t *st = state;
    char line[CSV_TRANSPORT_LINE_MAX];
    put(st, &st->s[0], line, csv_format_format(line, sizeof line, o->name, sp));
}

static void cycle(void *state, core_t *c, int64_t now_ns)
{
    csv_transport_t *st = state;
    (void)c;
    (void)now_ns;
    for (unsigned i = 0; i < st->n; i++)
        if (st->s[i].fd >= 0 && st->s[i].len)
            flush(&st->s[i]);
}

/* Lines dropped by csv and stdout together, as one status item. */
static int summary(const core_t *c, char *buf, size_t len)
{
    uint64_t n = c->stats->tcount[transport_index(&csv_transport)][TCOUNT_DROPPED] +
                 c->stats->tcount[transport_index(&stdout_transport)][TCOUNT_DROPPED];
    return n ? snprintf(buf, len, ", out dropped %llu", (unsigned long long)n) : 0;
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
    .summary = summary,         /* stdout's count too */
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
