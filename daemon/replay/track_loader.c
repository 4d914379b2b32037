/* track_loader.c - rows, messages and fields shared by the track parsers.
 * See track_loader.h. */
#include "track_loader.h"
#include "cfgload.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void vmsg(char *err, size_t errlen, const char *name, unsigned long line, const char *fmt,
                 va_list ap) __attribute__((format(printf, 5, 0)));

static void vmsg(char *err, size_t errlen, const char *name, unsigned long line, const char *fmt,
                 va_list ap)
{
    if (!err || errlen == 0)
        return;
    int k = line ? snprintf(err, errlen, "%s:%lu: ", name, line)
                 : snprintf(err, errlen, "%s: ", name);
    if (k < 0 || (size_t)k >= errlen)
        return;
    vsnprintf(err + k, errlen - (size_t)k, fmt, ap);
}

void track_loader_fatal(track_loader_t *L, unsigned long line, const char *fmt, ...)
{
    va_list ap;
    if (L->failed)
        return;
    L->failed = 1;
    va_start(ap, fmt);
    vmsg(L->err, L->errlen, L->name, line, fmt, ap);
    va_end(ap);
}

int track_loader_bad(track_loader_t *L, unsigned long line, const char *fmt, ...)
{
    va_list ap;
    if (L->flags & TRACK_SKIP_BAD) {
        if (L->skipped++ == 0) {
            va_start(ap, fmt);
            vmsg(L->err, L->errlen, L->name, line, fmt, ap);
            va_end(ap);
        }
        if (!L->reports)
            L->reports = calloc(TRACK_REPORT_MAX, sizeof *L->reports);
        if (L->reports && L->nreports < TRACK_REPORT_MAX) {
            va_start(ap, fmt);
            vmsg(L->reports[L->nreports++], TRACK_REPORT_LEN, L->name, line, fmt, ap);
            va_end(ap);
        } /* out of memory for a message: the count is still right */
        return 0;
    }
    if (!L->failed) {
        L->failed = 1;
        va_start(ap, fmt);
        vmsg(L->err, L->errlen, L->name, line, fmt, ap);
        va_end(ap);
    }
    return -1;
}

int track_loader_add_row(track_loader_t *L, double t_s, double a, double b, double c,
                         unsigned long line)
{
    if ((L->n & 0xffffu) == 0xffffu && cfgload_cancelled()) { /* SIGTERM: cfgload.h */
        track_loader_fatal(L, line, "cancelled (trajd is stopping)");
        return -1;
    }
    if (L->n == L->cap) {
        size_t cap = L->cap ? L->cap * 2 : 1024;
        track_row_t *r = realloc(L->rows, cap * sizeof *r);
        if (!r) {
            L->oom = 1;
            track_loader_fatal(L, 0, "out of memory");
            return -1;
        }
        L->rows = r;
        L->cap = cap;
    }
    track_row_t *r = &L->rows[L->n++];
    r->t_s = t_s;
    r->a = a;
    r->b = b;
    r->c = c;
    r->h = NAN;
    r->has_v = 0;
    r->line = line > UINT32_MAX ? UINT32_MAX : (uint32_t)line;
    return 0;
}

int track_field_num(const char *s, double *v, int *empty)
{
    char *end;
    while (*s == ' ' || *s == '\t')
        s++;
    if (*s == '\0') {
        *v = NAN;
        if (empty)
            *empty = 1;
        return empty ? 0 : -1;
    }
    if (empty)
        *empty = 0;
    errno = 0;
    *v = strtod(s, &end);
    if (end == s)
        return -1;
    while (*end == ' ' || *end == '\t')
        end++;
    if (*end != '\0')
        return -1;
    /* ERANGE on underflow gives a tiny number: fine; overflow gives inf,
     * caught by the finiteness checks. */
    return 0;
}

track_shown_t track_field_show(const char *f)
{
    track_shown_t o;
    size_t j = 0;
    for (size_t i = 0; f[i]; i++) {
        if (i == TRACK_SHOW_MAX) {
            memcpy(o.s + j, "...", 3);
            j += 3;
            break;
        }
        unsigned char c = (unsigned char)f[i];
        if (c >= 0x20 && c < 0x7f) {
            o.s[j++] = (char)c;
        } else {
            snprintf(o.s + j, 5, "\\x%02x", c);
            j += 4;
        }
    }
    o.s[j] = '\0';
    return o;
}

void track_lines_init(track_lines_t *it, const char *buf, size_t len)
{
    it->buf = buf;
    it->len = len;
    it->pos = 0;
    it->lineno = 0;
    it->line[0] = '\0';
}

int track_lines_next(track_loader_t *L, track_lines_t *it)
{
    for (;;) {
        if (it->pos >= it->len)
            return 0;
        const char *src = it->buf + it->pos;
        const char *nl = memchr(src, '\n', it->len - it->pos);
        size_t ll = nl ? (size_t)(nl - src) : it->len - it->pos;
        it->pos += ll + 1;
        it->lineno++;
        if (ll > 0 && src[ll - 1] == '\r')
            ll--;
        int rc = 0;
        if (ll > TRACK_LINE_MAX)
            rc = track_loader_bad(L, it->lineno, "line longer than %d bytes", TRACK_LINE_MAX);
        else if (memchr(src, '\0', ll))
            rc = track_loader_bad(L, it->lineno, "NUL byte (binary file?)");
        else {
            memcpy(it->line, src, ll);
            it->line[ll] = '\0';
            return 1;
        }
        if (rc)
            return -1;
    }
}

void track_loader_course_speed(track_loader_t *L, double cog_deg, double sog_m_s)
{
    track_row_t *r = &L->rows[L->n - 1];
    double c = cog_deg * (M_PI / 180.0);
    r->has_v = 1;
    r->v[0] = sog_m_s * sin(c);
    r->v[1] = sog_m_s * cos(c);
    r->v[2] = 0.0;
}
