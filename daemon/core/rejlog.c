/* rejlog.c - sources of waypoints and the rate-limited rejection log (see rejlog.h). */
#include "rejlog.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

void rejlog_init(rejlog_t *l)
{
    memset(l, 0, sizeof *l);
}

size_t rejlog_src_file(char *buf, const char *path, int has_line, uint32_t line)
{
    size_t len = strlen(path), n = 0;
    if (len > REJLOG_SRC_PATH_MAX) {
        memcpy(buf, "...", 3);
        n = 3;
        path += len - REJLOG_SRC_PATH_MAX;
        len = REJLOG_SRC_PATH_MAX;
    }
    memcpy(buf + n, path, len);
    n += len;
    if (has_line) {
        char d[10]; /* UINT32_MAX has 10 digits */
        int k = 0;
        do {
            d[k++] = (char)('0' + line % 10);
            line /= 10;
        } while (line);
        buf[n++] = ':';
        while (k)
            buf[n++] = d[--k];
    }
    buf[n] = '\0';
    return n;
}

void rejlog_offered(rejlog_t *l, const engine_waypoint_t *wp, const char *src)
{
    rejlog_src_t *s = &l->ring[l->ring_next];
    s->seq = wp->seq;
    s->t_s = wp->t_s;
    /* on every push: a copy, not a printf */
    const char *from = src && src[0] ? src : "unknown source";
    size_t n = strnlen(from, sizeof s->src - 1);
    memcpy(s->src, from, n);
    s->src[n] = '\0';
    l->ring_next = (l->ring_next + 1) % REJLOG_RING;
    if (l->ring_len < REJLOG_RING)
        l->ring_len++;
}

/* The same time as offered: the engine reports it bit for bit (NaN too). */
static int same_time(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0 || (isnan(a) && isnan(b));
}

/* The source of a refused waypoint: the newest offer with its seq and time. */
static const char *source_of(const rejlog_t *l, const engine_rejection_t *r)
{
    for (unsigned k = 1; k <= l->ring_len; k++) {
        const rejlog_src_t *s = &l->ring[(l->ring_next + REJLOG_RING - k) % REJLOG_RING];
        if (s->seq == r->seq && same_time(s->t_s, r->t_s))
            return s->src;
    }
    return "unknown source";
}

void rejlog_drain(rejlog_t *l, engine_t *e)
{
    engine_rejection_t r;
    while (engine_rejection_next(e, &r)) {
        l->seen++;
        if (l->npend < REJLOG_LINES) {
            rejlog_line_t *p = &l->pend[l->npend++];
            p->rej = r;
            snprintf(p->src, sizeof p->src, "%s", source_of(l, &r));
        } else if (r.reason > 0 && r.reason < ENGINE_ERROR_COUNT) {
            l->more_by[r.reason]++;
        } else {
            l->more_by[0]++;
        }
    }
}

static const char *name_of(int reason)
{
    const char *n = engine_reason_name(reason);
    return n ? n : engine_strerror(reason);
}

/* x as "%.3f" (the usual metres and seconds), or "%.6g" from 1e12 up (and NaN,
 * infinities): a hostile 1e300 takes 12 characters, not 300, and never cuts
 * the line (issue 24). */
static const char *num(char buf[32], double x)
{
    if (fabs(x) < 1e12)
        snprintf(buf, 32, "%.3f", x);
    else
        snprintf(buf, 32, "%.6g", x);
    return buf;
}

unsigned rejlog_flush(rejlog_t *l, const char *name, void (*emit)(void *ctx, const char *line),
                      void *ctx)
{
    char line[REJLOG_LINE_MAX];
    unsigned n = 0;
    for (unsigned i = 0; i < l->npend; i++, n++) {
        const engine_rejection_t *r = &l->pend[i].rej;
        char t[32], x[32], y[32], z[32];
        snprintf(line, sizeof line,
                 "object '%s': %s: rejected (%s) seq %" PRIu32 " t=%s s at (%s, %s, %s)", name,
                 l->pend[i].src, name_of(r->reason), r->seq, num(t, r->t_s), num(x, r->pos_m[0]),
                 num(y, r->pos_m[1]), num(z, r->pos_m[2]));
        emit(ctx, line);
    }
    l->shown += l->npend;
    l->npend = 0;
    uint64_t more = 0;
    for (int e = 0; e < ENGINE_ERROR_COUNT; e++)
        more += l->more_by[e];
    if (more) {
        int m = snprintf(line, sizeof line,
                         "object '%s': %" PRIu64 " more rejected waypoints not shown (", name,
                         more);
        for (int e = 0; e < ENGINE_ERROR_COUNT && m > 0 && (size_t)m < sizeof line; e++)
            if (l->more_by[e])
                m += snprintf(line + m, sizeof line - (size_t)m, "%s%s %" PRIu64,
                              line[m - 1] == '(' ? "" : ", ", e ? name_of(e) : "other",
                              l->more_by[e]);
        if (m > 0 && (size_t)m < sizeof line)
            snprintf(line + m, sizeof line - (size_t)m, ")");
        emit(ctx, line);
        memset(l->more_by, 0, sizeof l->more_by);
        n++;
    }
    return n;
}
