/* track.c - load a logged track (CSV or GPX) into waypoints.  See track.h. */
#include "track.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include <expat.h>

#include "geo.h"
#include "path.h"

/* One row as read, before the geographic conversion. */
typedef struct {
    double t_s;
    double a, b, c;   /* x,y,z or lat,lon,alt */
    uint32_t line;
} row_t;

typedef struct {
    const char *name;
    unsigned flags;
    char *err;
    size_t errlen;
    row_t *rows;
    size_t n, cap;
    size_t skipped;
    int failed;       /* a fatal error was recorded in err */
    int oom;
} loader_t;

static void vmsg(char *err, size_t errlen, const char *name, unsigned long line,
                 const char *fmt, va_list ap)
{
    if (!err || errlen == 0)
        return;
    int k = line ? snprintf(err, errlen, "%s:%lu: ", name, line)
                 : snprintf(err, errlen, "%s: ", name);
    if (k < 0 || (size_t)k >= errlen)
        return;
    vsnprintf(err + k, errlen - (size_t)k, fmt, ap);
}

/* A fatal error (not skippable): I/O, memory, header, XML well-formedness. */
static void fatal(loader_t *L, unsigned long line, const char *fmt, ...)
{
    va_list ap;
    if (L->failed)
        return;
    L->failed = 1;
    va_start(ap, fmt);
    vmsg(L->err, L->errlen, L->name, line, fmt, ap);
    va_end(ap);
}

/* A bad line: fatal unless TRACK_SKIP_BAD, then counted (first message kept).
 * Returns 0 if the caller may go on, -1 if loading must stop. */
static int bad(loader_t *L, unsigned long line, const char *fmt, ...)
{
    va_list ap;
    if (L->flags & TRACK_SKIP_BAD) {
        if (L->skipped++ == 0) {
            va_start(ap, fmt);
            vmsg(L->err, L->errlen, L->name, line, fmt, ap);
            va_end(ap);
        }
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

static int add_row(loader_t *L, double t_s, double a, double b, double c,
                   unsigned long line)
{
    if (L->n == L->cap) {
        size_t cap = L->cap ? L->cap * 2 : 1024;
        row_t *r = realloc(L->rows, cap * sizeof *r);
        if (!r) {
            L->oom = 1;
            fatal(L, 0, "out of memory");
            return -1;
        }
        L->rows = r;
        L->cap = cap;
    }
    row_t *r = &L->rows[L->n++];
    r->t_s = t_s;
    r->a = a;
    r->b = b;
    r->c = c;
    r->line = line > UINT32_MAX ? UINT32_MAX : (uint32_t)line;
    return 0;
}

/* Parse a whole field as a double.  Leading/trailing blanks allowed.
 * An empty field gives NaN with *empty set. */
static int parse_num(const char *s, double *v, int *empty)
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

/* A field as it may appear in a message: printable ASCII, other bytes as
 * \xHH, cut at SHOW_MAX characters ("..." appended), so that garbage in a
 * file cannot put control characters or invalid UTF-8 on a terminal. */
#define SHOW_MAX 40
typedef struct {
    char s[SHOW_MAX * 4 + 4];
} shown_t;

static shown_t show(const char *f)
{
    shown_t o;
    size_t j = 0;
    for (size_t i = 0; f[i]; i++) {
        if (i == SHOW_MAX) {
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

/* ---- CSV ----------------------------------------------------------------- */

enum { COL_T, COL_X, COL_Y, COL_Z, COL_LAT, COL_LON, COL_ALT, COL_COUNT };

static const char *const col_names[COL_COUNT][5] = {
    [COL_T] = {"t", "t_s", "time", "time_s", NULL},
    [COL_X] = {"x", "x_m", "east_m", NULL},
    [COL_Y] = {"y", "y_m", "north_m", NULL},
    [COL_Z] = {"z", "z_m", "up_m", NULL},
    [COL_LAT] = {"lat", "lat_deg", "latitude", NULL},
    [COL_LON] = {"lon", "lon_deg", "lng", "longitude", NULL},
    [COL_ALT] = {"alt", "alt_m", "ele", "altitude", NULL},
};

#define MAX_FIELDS 64

/* Split line (modified in place) at commas; trims blanks.  Returns the
 * number of fields, or -1 if more than max. */
static int split(char *line, char **field, int max)
{
    int n = 0;
    char *p = line;
    for (;;) {
        if (n == max)
            return -1;
        while (*p == ' ' || *p == '\t')
            p++;
        field[n++] = p;
        char *c = strchr(p, ',');
        char *e = c ? c : p + strlen(p);
        while (e > p && (e[-1] == ' ' || e[-1] == '\t'))
            e--;
        if (!c) {
            *e = '\0';
            return n;
        }
        *e = '\0';
        p = c + 1;
    }
}

static int col_lookup(const char *f)
{
    for (int c = 0; c < COL_COUNT; c++)
        for (int k = 0; col_names[c][k]; k++)
            if (strcasecmp(f, col_names[c][k]) == 0)
                return c;
    return -1;
}

static int numeric_line(char **field, int nf)
{
    for (int i = 0; i < nf; i++) {
        double v;
        if (parse_num(field[i], &v, NULL) != 0)
            return 0;
    }
    return 1;
}

static int parse_csv(loader_t *L, const char *buf, size_t len,
                     track_format_t fmt, track_format_t *got)
{
    int col[COL_COUNT];
    int have_header = 0, geographic = 0, needed = 0;
    unsigned long lineno = 0;
    size_t pos = 0;
    char line[TRACK_LINE_MAX + 1];
    char *field[MAX_FIELDS];

    for (int c = 0; c < COL_COUNT; c++)
        col[c] = -1;

    while (pos < len) {
        size_t end = pos;
        while (end < len && buf[end] != '\n')
            end++;
        size_t ll = end - pos;
        const char *src = buf + pos;
        pos = end + 1;
        lineno++;
        if (ll > 0 && src[ll - 1] == '\r')
            ll--;
        if (ll > TRACK_LINE_MAX) {
            if (!have_header) {
                fatal(L, lineno, "line longer than %d bytes", TRACK_LINE_MAX);
                return -1;
            }
            if (bad(L, lineno, "line longer than %d bytes", TRACK_LINE_MAX))
                return -1;
            continue;
        }
        if (memchr(src, '\0', ll)) {
            if (!have_header) {
                fatal(L, lineno, "NUL byte (binary file?)");
                return -1;
            }
            if (bad(L, lineno, "NUL byte (binary file?)"))
                return -1;
            continue;
        }
        memcpy(line, src, ll);
        line[ll] = '\0';
        /* Skip a UTF-8 byte order mark on the first line. */
        char *s = line;
        if (lineno == 1 && (unsigned char)s[0] == 0xef &&
            (unsigned char)s[1] == 0xbb && (unsigned char)s[2] == 0xbf)
            s += 3;
        while (*s == ' ' || *s == '\t')
            s++;
        if (*s == '\0' || *s == '#')
            continue;

        int nf = split(s, field, MAX_FIELDS);
        if (nf < 0) {
            if (!have_header) {
                fatal(L, lineno, "more than %d columns", MAX_FIELDS);
                return -1;
            }
            if (bad(L, lineno, "more than %d columns", MAX_FIELDS))
                return -1;
            continue;
        }

        if (!have_header) {
            have_header = 1;
            if (numeric_line(field, nf)) {
                if (fmt != TRACK_FMT_XYZ && fmt != TRACK_FMT_LATLON) {
                    fatal(L, lineno, "no header line: expected one naming the "
                          "columns (t,x,y,z or t,lat,lon,alt), or give the format");
                    return -1;
                }
                /* Positional columns; this line is data, fall through. */
                if (fmt == TRACK_FMT_XYZ) {
                    col[COL_T] = 0; col[COL_X] = 1; col[COL_Y] = 2; col[COL_Z] = 3;
                } else {
                    col[COL_T] = 0; col[COL_LAT] = 1; col[COL_LON] = 2; col[COL_ALT] = 3;
                }
            } else {
                for (int i = 0; i < nf; i++) {
                    int c = col_lookup(field[i]);
                    if (c >= 0 && col[c] < 0)
                        col[c] = i;
                }
                if (col[COL_T] < 0) {
                    fatal(L, lineno, "header has no time column (t or t_s)");
                    return -1;
                }
                int has_ll = col[COL_LAT] >= 0 && col[COL_LON] >= 0;
                int has_xy = col[COL_X] >= 0 && col[COL_Y] >= 0;
                if (fmt == TRACK_FMT_AUTO)
                    fmt = has_ll ? TRACK_FMT_LATLON : TRACK_FMT_XYZ;
                if (fmt == TRACK_FMT_LATLON && !has_ll) {
                    fatal(L, lineno, "header has no lat and lon columns");
                    return -1;
                }
                if (fmt == TRACK_FMT_XYZ && !has_xy) {
                    fatal(L, lineno, has_ll ? "header has no x and y columns"
                          " (it has lat/lon: use format latlon)"
                          : "header names neither t,x,y[,z] nor t,lat,lon[,alt]");
                    return -1;
                }
                continue;
            }
        }
        if (!needed) {
            geographic = fmt == TRACK_FMT_LATLON;
            int a = geographic ? COL_LAT : COL_X, b = geographic ? COL_LON : COL_Y;
            needed = col[COL_T];
            if (col[a] > needed) needed = col[a];
            if (col[b] > needed) needed = col[b];
            needed++;
        }

        /* A data line. */
        if (nf < needed) {
            if (bad(L, lineno, "%d columns, %d needed", nf, needed))
                return -1;
            continue;
        }
        int a = geographic ? COL_LAT : COL_X, b = geographic ? COL_LON : COL_Y;
        int c3 = geographic ? COL_ALT : COL_Z;
        double t, va, vb, vc = NAN;
        int empty;
        if (parse_num(field[col[COL_T]], &t, NULL) || !isfinite(t)) {
            if (bad(L, lineno, "time '%s' is not a finite number",
                    show(field[col[COL_T]]).s))
                return -1;
            continue;
        }
        if (parse_num(field[col[a]], &va, NULL) || !isfinite(va)) {
            if (bad(L, lineno, "%s '%s' is not a finite number",
                    geographic ? "latitude" : "x", show(field[col[a]]).s))
                return -1;
            continue;
        }
        if (parse_num(field[col[b]], &vb, NULL) || !isfinite(vb)) {
            if (bad(L, lineno, "%s '%s' is not a finite number",
                    geographic ? "longitude" : "y", show(field[col[b]]).s))
                return -1;
            continue;
        }
        if (col[c3] >= 0 && col[c3] < nf) {
            if (parse_num(field[col[c3]], &vc, &empty) || isinf(vc)) {
                if (bad(L, lineno, "%s '%s' is not a number",
                        geographic ? "altitude" : "z", show(field[col[c3]]).s))
                    return -1;
                continue;
            }
        }
        if (geographic) {
            int rc = geo_check(va, vb, isnan(vc) ? 0.0 : vc);
            if (rc) {
                if (bad(L, lineno, "%s", geo_strerror(rc)))
                    return -1;
                continue;
            }
        }
        if (add_row(L, t, va, vb, vc, lineno))
            return -1;
    }
    if (!have_header) {
        fatal(L, 0, "no waypoints (empty file)");
        return -1;
    }
    *got = fmt;
    return 0;
}

/* ---- ISO 8601 ------------------------------------------------------------- */

/* Days from 1970-01-01 to y-m-d in the proleptic Gregorian calendar
 * (H. Hinnant's days_from_civil; exact for every year in int range). */
static int64_t days_from_civil(int64_t y, int m, int d)
{
    y -= m <= 2;
    int64_t era = (y >= 0 ? y : y - 399) / 400;
    int64_t yoe = y - era * 400;
    int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + doe - 719468;
}

static int digits(const char **p, int n, int *v)
{
    int x = 0;
    for (int i = 0; i < n; i++) {
        if (!isdigit((unsigned char)(*p)[i]))
            return -1;
        x = x * 10 + ((*p)[i] - '0');
    }
    *p += n;
    *v = x;
    return 0;
}

int track_parse_iso8601(const char *s, int64_t *sec, double *frac)
{
    int y, mo, d, h, mi, se, oh = 0, om = 0, sign = 0;
    double fr = 0.0;
    const char *p = s;
    while (isspace((unsigned char)*p))
        p++;
    if (digits(&p, 4, &y) || *p++ != '-' || digits(&p, 2, &mo) || *p++ != '-' ||
        digits(&p, 2, &d))
        return -1;
    if (*p != 'T' && *p != 't' && *p != ' ')
        return -1;
    p++;
    if (digits(&p, 2, &h) || *p++ != ':' || digits(&p, 2, &mi) || *p++ != ':' ||
        digits(&p, 2, &se))
        return -1;
    if (*p == '.' || *p == ',') {
        double scale = 0.1;
        p++;
        if (!isdigit((unsigned char)*p))
            return -1;
        while (isdigit((unsigned char)*p)) {
            fr += (*p - '0') * scale;
            scale *= 0.1;
            p++;
        }
    }
    if (*p == 'Z' || *p == 'z') {
        p++;
    } else if (*p == '+' || *p == '-') {
        sign = *p == '+' ? 1 : -1;
        p++;
        if (digits(&p, 2, &oh))
            return -1;
        if (*p == ':')
            p++;
        if (digits(&p, 2, &om) || oh > 23 || om > 59)
            return -1;
    }
    while (isspace((unsigned char)*p))
        p++;
    if (*p != '\0')
        return -1;
    static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (mo < 1 || mo > 12 || d < 1 || d > mdays[mo - 1] || h > 24 || mi > 59 ||
        se > 60 || (h == 24 && (mi || se || fr > 0.0)))
        return -1;
    int leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    if (mo == 2 && d == 29 && !leap)
        return -1;
    /* The sum of the digits can reach 1 - 1e-k rounding up to 1.0 only for
     * absurd digit counts; clamp so frac stays in [0,1). */
    if (fr >= 1.0)
        fr = nextafter(1.0, 0.0);
    *sec = days_from_civil(y, mo, d) * 86400 + h * 3600 + mi * 60 + se -
           sign * (oh * 3600 + om * 60);
    *frac = fr;
    return 0;
}

/* ---- GPX ----------------------------------------------------------------- */

#define GPX_TEXT_MAX 128

typedef struct {
    loader_t *L;
    XML_Parser p;
    int trk_depth;          /* >0 inside <trk> */
    int in_trkpt;
    int depth_in_trkpt;     /* element depth below <trkpt> */
    int text_kind;          /* 0 none, 1 ele, 2 time */
    char text[GPX_TEXT_MAX + 1];
    size_t text_len;
    int text_overflow;
    double lat, lon, ele;
    int have_time, bad_pt;
    int64_t sec;
    double frac;
    int64_t sec0;
    double frac0;
    int have_t0;
    unsigned long pt_line;
    size_t segments;
} gpx_t;

static const char *local_name(const char *n)
{
    const char *c = strrchr(n, ':');
    return c ? c + 1 : n;
}

static void gpx_stop(gpx_t *g)
{
    XML_StopParser(g->p, XML_FALSE);
}

static void XMLCALL gpx_start(void *ud, const XML_Char *name, const XML_Char **attr)
{
    gpx_t *g = ud;
    const char *n = local_name(name);
    if (g->in_trkpt) {
        g->depth_in_trkpt++;
        if (g->depth_in_trkpt == 1 && (strcmp(n, "ele") == 0 || strcmp(n, "time") == 0)) {
            g->text_kind = n[0] == 'e' ? 1 : 2;
            g->text_len = 0;
            g->text_overflow = 0;
        }
        return;
    }
    if (strcmp(n, "trk") == 0) {
        g->trk_depth++;
        return;
    }
    if (g->trk_depth == 0)
        return;
    if (strcmp(n, "trkseg") == 0) {
        g->segments++;
        return;
    }
    if (strcmp(n, "trkpt") != 0)
        return;
    g->in_trkpt = 1;
    g->depth_in_trkpt = 0;
    g->have_time = 0;
    g->bad_pt = 0;
    g->ele = NAN;
    g->pt_line = XML_GetCurrentLineNumber(g->p);
    const char *slat = NULL, *slon = NULL;
    for (int i = 0; attr[i]; i += 2) {
        if (strcmp(attr[i], "lat") == 0)
            slat = attr[i + 1];
        else if (strcmp(attr[i], "lon") == 0)
            slon = attr[i + 1];
    }
    if (!slat || !slon) {
        g->bad_pt = 1;
        if (bad(g->L, g->pt_line, "trkpt without lat or lon attribute"))
            gpx_stop(g);
        return;
    }
    if (parse_num(slat, &g->lat, NULL) || parse_num(slon, &g->lon, NULL)) {
        g->bad_pt = 1;
        if (bad(g->L, g->pt_line, "trkpt lat '%s' or lon '%s' is not a number",
                show(slat).s, show(slon).s))
            gpx_stop(g);
        return;
    }
}

static void XMLCALL gpx_text(void *ud, const XML_Char *s, int len)
{
    gpx_t *g = ud;
    if (!g->text_kind)
        return;
    if (g->text_len + (size_t)len > GPX_TEXT_MAX) {
        g->text_overflow = 1;
        return;
    }
    memcpy(g->text + g->text_len, s, (size_t)len);
    g->text_len += (size_t)len;
}

static void XMLCALL gpx_end(void *ud, const XML_Char *name)
{
    gpx_t *g = ud;
    const char *n = local_name(name);
    if (g->in_trkpt && g->depth_in_trkpt > 0) {
        if (g->depth_in_trkpt == 1 && g->text_kind) {
            unsigned long line = XML_GetCurrentLineNumber(g->p);
            g->text[g->text_len] = '\0';
            int kind = g->text_kind;
            g->text_kind = 0;
            if (g->bad_pt) {
                /* already reported */
            } else if (g->text_overflow) {
                g->bad_pt = 1;
                if (bad(g->L, line, "<%s> longer than %d characters", n, GPX_TEXT_MAX))
                    gpx_stop(g);
            } else if (kind == 1) {
                int empty;
                if (parse_num(g->text, &g->ele, &empty) || isinf(g->ele)) {
                    g->bad_pt = 1;
                    if (bad(g->L, line, "<ele> '%s' is not a number", show(g->text).s))
                        gpx_stop(g);
                }
            } else {
                if (track_parse_iso8601(g->text, &g->sec, &g->frac)) {
                    g->bad_pt = 1;
                    if (bad(g->L, line, "<time> '%s' is not an ISO 8601 date-time",
                            show(g->text).s))
                        gpx_stop(g);
                } else {
                    g->have_time = 1;
                }
            }
        }
        g->depth_in_trkpt--;
        return;
    }
    if (g->in_trkpt) { /* </trkpt> */
        g->in_trkpt = 0;
        if (g->bad_pt)
            return;
        if (!g->have_time) {
            if (bad(g->L, g->pt_line, "trkpt without <time>"))
                gpx_stop(g);
            return;
        }
        int rc = geo_check(g->lat, g->lon, isnan(g->ele) ? 0.0 : g->ele);
        if (rc) {
            if (bad(g->L, g->pt_line, "%s", geo_strerror(rc)))
                gpx_stop(g);
            return;
        }
        if (!g->have_t0) {
            g->have_t0 = 1;
            g->sec0 = g->sec;
            g->frac0 = g->frac;
        }
        /* Whole seconds and fractions subtracted apart: exact for any date. */
        double t = (double)(g->sec - g->sec0) + (g->frac - g->frac0);
        if (add_row(g->L, t, g->lat, g->lon, g->ele, g->pt_line))
            gpx_stop(g);
        return;
    }
    if (strcmp(n, "trk") == 0 && g->trk_depth > 0)
        g->trk_depth--;
}

static int parse_gpx(loader_t *L, const char *buf, size_t len, size_t *segments)
{
    gpx_t g;
    memset(&g, 0, sizeof g);
    g.L = L;
    g.p = XML_ParserCreate(NULL);
    if (!g.p) {
        fatal(L, 0, "out of memory (XML parser)");
        return -1;
    }
    XML_SetUserData(g.p, &g);
    XML_SetElementHandler(g.p, gpx_start, gpx_end);
    XML_SetCharacterDataHandler(g.p, gpx_text);

    int rc = 0;
    /* XML_Parse takes an int length: feed in chunks. */
    const size_t chunk = 1 << 20;
    size_t off = 0;
    do {
        size_t n = len - off > chunk ? chunk : len - off;
        int final = off + n == len;
        if (XML_Parse(g.p, buf + off, (int)n, final) == XML_STATUS_ERROR) {
            if (!L->failed)
                fatal(L, XML_GetCurrentLineNumber(g.p), "XML error: %s",
                      XML_ErrorString(XML_GetErrorCode(g.p)));
            rc = -1;
            break;
        }
        off += n;
    } while (off < len);
    if (len == 0) {
        fatal(L, 0, "empty file");
        rc = -1;
    }
    XML_ParserFree(g.p);
    *segments = g.segments;
    return L->failed ? -1 : rc;
}

/* ---- common ------------------------------------------------------------- */

/* ---- path (lib/spline/path.h) --------------------------------------------------- */

static int ends_with_path(const char *name)
{
    size_t n = strlen(name);
    return n >= 5 && strcasecmp(name + n - 5, ".path") == 0;
}

/*
 * Parse a path text and expand it straight into trk (no row_t stage: the
 * waypoints are metric already).  Waypoints of element k are those between
 * the expansions of elements 0..k-1 and 0..k, which gives line[].
 */
static int parse_path_text(loader_t *L, const char *buf, size_t len, track_t *trk)
{
    path_elem_t *el = NULL;
    uint32_t *el_line = NULL;
    size_t nel = 0, cap = 0, pos = 0, nw = 0, k, prev = 0;
    unsigned long lineno = 0;
    int rc = -1;

    while (pos < len) {
        char line[PATH_LINE_MAX + 1];
        size_t e = pos, ll;
        int prc;
        while (e < len && buf[e] != '\n')
            e++;
        ll = e - pos;
        lineno++;
        if (ll > PATH_LINE_MAX) {
            fatal(L, lineno, "line longer than %d characters", PATH_LINE_MAX);
            goto out;
        }
        memcpy(line, buf + pos, ll);
        line[ll] = '\0';
        pos = e + 1;
        if (nel == cap) {
            size_t nc = cap ? 2 * cap : 64;
            path_elem_t *ne = realloc(el, nc * sizeof *el);
            uint32_t *nl = ne ? realloc(el_line, nc * sizeof *el_line) : NULL;
            if (ne)
                el = ne;
            if (!ne || !nl) {
                fatal(L, 0, "out of memory");
                goto out;
            }
            el_line = nl;
            cap = nc;
        }
        prc = path_parse_line(line, &el[nel]);
        if (prc < 0) {
            fatal(L, lineno, "%s", path_strerror(prc));
            goto out;
        }
        if (el[nel].kind != PATH_NONE)
            el_line[nel++] = (uint32_t)lineno;
    }
    if ((rc = path_expand(el, nel, NULL, 0, &nw)) < 0) {
        fatal(L, 0, "%s", path_strerror(rc));
        goto out;
    }
    rc = -1;
    if (nw == 0) {
        fatal(L, 0, "no waypoints");
        goto out;
    }
    trk->wp = calloc(nw, sizeof *trk->wp);
    trk->line = calloc(nw, sizeof *trk->line);
    if (!trk->wp || !trk->line) {
        fatal(L, 0, "out of memory");
        goto out;
    }
    if (path_expand(el, nel, trk->wp, nw, &nw) < 0)
        goto out;
    for (k = 1; k <= nel; k++) {
        size_t upto = 0, i;
        (void)path_expand(el, k, NULL, 0, &upto);
        for (i = prev; i < upto && i < nw; i++)
            trk->line[i] = el_line[k - 1];
        prev = upto;
    }
    trk->n = nw;
    trk->format = TRACK_FMT_PATH;
    rc = 0;
out:
    free(el);
    free(el_line);
    return rc;
}

static int ends_with_gpx(const char *name)
{
    size_t n = strlen(name);
    return n >= 4 && strcasecmp(name + n - 4, ".gpx") == 0;
}

static int looks_like_xml(const char *buf, size_t len)
{
    size_t i = 0;
    if (len >= 3 && (unsigned char)buf[0] == 0xef && (unsigned char)buf[1] == 0xbb &&
        (unsigned char)buf[2] == 0xbf)
        i = 3;
    while (i < len && isspace((unsigned char)buf[i]))
        i++;
    return i < len && buf[i] == '<';
}

void track_free(track_t *trk)
{
    if (!trk)
        return;
    free(trk->wp);
    free(trk->line);
    memset(trk, 0, sizeof *trk);
}

int track_parse(const char *name, const char *buf, size_t len,
                track_format_t fmt, unsigned flags, track_t *trk, char *err,
                size_t errlen)
{
    loader_t L;
    memset(&L, 0, sizeof L);
    memset(trk, 0, sizeof *trk);
    L.name = name ? name : "(track)";
    L.flags = flags;
    L.err = err;
    L.errlen = errlen;
    if (err && errlen)
        err[0] = '\0';

    int rc;
    track_format_t got = fmt;
    if (fmt == TRACK_FMT_PATH || (fmt == TRACK_FMT_AUTO && ends_with_path(L.name))) {
        rc = parse_path_text(&L, buf, len, trk);
        if (rc)
            track_free(trk);
        return rc;
    }
    if (fmt == TRACK_FMT_GPX ||
        (fmt == TRACK_FMT_AUTO && (ends_with_gpx(L.name) || looks_like_xml(buf, len)))) {
        got = TRACK_FMT_GPX;
        rc = parse_gpx(&L, buf, len, &trk->segments);
    } else if (fmt == TRACK_FMT_AUTO || fmt == TRACK_FMT_XYZ || fmt == TRACK_FMT_LATLON) {
        rc = parse_csv(&L, buf, len, fmt, &got);
    } else {
        fatal(&L, 0, "unknown format %d", (int)fmt);
        rc = -1;
    }
    if (rc == 0 && L.n == 0) {
        fatal(&L, 0, L.skipped ? "no waypoints (every data line was bad)" : "no waypoints");
        rc = -1;
    }
    if (rc == 0 && L.n > UINT32_MAX) {
        fatal(&L, 0, "more than %lu waypoints", (unsigned long)UINT32_MAX);
        rc = -1;
    }
    if (rc == 0) {
        trk->wp = calloc(L.n, sizeof *trk->wp);
        trk->line = calloc(L.n, sizeof *trk->line);
        if (!trk->wp || !trk->line) {
            fatal(&L, 0, "out of memory");
            rc = -1;
        }
    }
    if (rc == 0) {
        geo_enu_t frame;
        int geographic = got != TRACK_FMT_XYZ;
        if (geographic) {
            const row_t *r0 = &L.rows[0];
            double alt0 = isnan(r0->c) ? 0.0 : r0->c;
            /* Rows were checked with geo_check as they were read. */
            (void)geo_enu_init(r0->a, r0->b, alt0, &frame);
            trk->lat0_deg = r0->a;
            trk->lon0_deg = r0->b;
            trk->alt0_m = alt0;
        }
        for (size_t i = 0; i < L.n; i++) {
            const row_t *r = &L.rows[i];
            engine_waypoint_t *w = &trk->wp[i];
            w->t_s = r->t_s;
            w->seq = (uint32_t)(i + 1);
            trk->line[i] = r->line;
            if (geographic) {
                double enu[3];
                int no_alt = isnan(r->c);
                (void)geo_to_enu(&frame, r->a, r->b, no_alt ? frame.alt0_m : r->c, enu);
                w->pos_m[0] = enu[0];
                w->pos_m[1] = enu[1];
                w->pos_m[2] = no_alt ? 0.0 : enu[2];
            } else {
                w->pos_m[0] = r->a;
                w->pos_m[1] = r->b;
                w->pos_m[2] = isnan(r->c) ? 0.0 : r->c;
            }
        }
        trk->n = L.n;
        trk->format = got;
        trk->geographic = geographic;
        trk->skipped = L.skipped;
    }
    free(L.rows);
    if (rc) {
        track_free(trk);
        return -1;
    }
    return 0;
}

int track_load_opts(const char *path, track_format_t fmt, unsigned flags,
                    track_t *trk, char *err, size_t errlen)
{
    loader_t L; /* only for the message helpers */
    memset(&L, 0, sizeof L);
    memset(trk, 0, sizeof *trk);
    L.name = path;
    L.err = err;
    L.errlen = errlen;
    if (err && errlen)
        err[0] = '\0';

    FILE *f = fopen(path, "rb");
    if (!f) {
        fatal(&L, 0, "%s", strerror(errno));
        return -1;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int rc = 0;
    for (;;) {
        if (len == cap) {
            if (cap >= (size_t)TRACK_FILE_MAX_BYTES) {
                fatal(&L, 0, "larger than %ld bytes", TRACK_FILE_MAX_BYTES);
                rc = -1;
                break;
            }
            size_t ncap = cap ? cap * 2 : 65536;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                fatal(&L, 0, "out of memory");
                rc = -1;
                break;
            }
            buf = nb;
            cap = ncap;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0) {
            if (ferror(f)) {
                fatal(&L, 0, "read error: %s", strerror(errno));
                rc = -1;
            }
            break;
        }
    }
    fclose(f);
    if (rc == 0)
        rc = track_parse(path, buf, len, fmt, flags, trk, err, errlen);
    free(buf);
    return rc;
}

int track_load(const char *path, track_format_t fmt, track_t *trk, char *err,
               size_t errlen)
{
    return track_load_opts(path, fmt, 0, trk, err, errlen);
}

int track_format_parse(const char *s, track_format_t *fmt)
{
    static const struct { const char *name; track_format_t f; } tab[] = {
        {"auto", TRACK_FMT_AUTO}, {"xyz", TRACK_FMT_XYZ},
        {"latlon", TRACK_FMT_LATLON}, {"gpx", TRACK_FMT_GPX},
        {"path", TRACK_FMT_PATH},
    };
    if (!s)
        return -1;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (strcmp(s, tab[i].name) == 0) {
            *fmt = tab[i].f;
            return 0;
        }
    return -1;
}

const char *track_format_name(track_format_t fmt)
{
    switch (fmt) {
    case TRACK_FMT_AUTO: return "auto";
    case TRACK_FMT_XYZ: return "xyz";
    case TRACK_FMT_LATLON: return "latlon";
    case TRACK_FMT_GPX: return "gpx";
    case TRACK_FMT_PATH: return "path";
    }
    return "unknown";
}
