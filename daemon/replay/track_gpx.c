/* track_gpx.c - GPX 1.0/1.1 tracks (every <trkpt> of every <trk>, parsed
 * with expat).  See track.h for what is read. */
#include "track_loader.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <expat.h>

#include "geo.h"

#define GPX_TEXT_MAX 128

typedef struct {
    track_loader_t *L;
    XML_Parser p;
    int trk_depth; /* >0 inside <trk> */
    int in_trkpt;
    int depth_in_trkpt; /* element depth below <trkpt> */
    int text_kind;      /* 0 none, 1 ele, 2 time */
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
        if (track_loader_bad(g->L, g->pt_line, "trkpt without lat or lon attribute"))
            gpx_stop(g);
        return;
    }
    if (track_field_num(slat, &g->lat, NULL) || track_field_num(slon, &g->lon, NULL)) {
        g->bad_pt = 1;
        if (track_loader_bad(g->L, g->pt_line, "trkpt lat '%s' or lon '%s' is not a number",
                             track_field_show(slat).s, track_field_show(slon).s))
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
                if (track_loader_bad(g->L, line, "<%s> longer than %d characters", n, GPX_TEXT_MAX))
                    gpx_stop(g);
            } else if (kind == 1) {
                int empty;
                if (track_field_num(g->text, &g->ele, &empty) || isinf(g->ele)) {
                    g->bad_pt = 1;
                    if (track_loader_bad(g->L, line, "<ele> '%s' is not a number",
                                         track_field_show(g->text).s))
                        gpx_stop(g);
                }
            } else {
                if (track_parse_iso8601(g->text, &g->sec, &g->frac)) {
                    g->bad_pt = 1;
                    if (track_loader_bad(g->L, line, "<time> '%s' is not an ISO 8601 date-time",
                                         track_field_show(g->text).s))
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
            if (track_loader_bad(g->L, g->pt_line, "trkpt without <time>"))
                gpx_stop(g);
            return;
        }
        int rc = geo_check(g->lat, g->lon, isnan(g->ele) ? 0.0 : g->ele);
        if (rc) {
            if (track_loader_bad(g->L, g->pt_line, "%s", geo_strerror(rc)))
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
        if (track_loader_add_row(g->L, t, g->lat, g->lon, g->ele, g->pt_line))
            gpx_stop(g);
        return;
    }
    if (strcmp(n, "trk") == 0 && g->trk_depth > 0)
        g->trk_depth--;
}

int track_gpx_parse(track_loader_t *L, const char *buf, size_t len, size_t *segments)
{
    gpx_t g;
    memset(&g, 0, sizeof g);
    g.L = L;
    g.p = XML_ParserCreate(NULL);
    if (!g.p) {
        track_loader_fatal(L, 0, "out of memory (XML parser)");
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
            /* with skip_bad, a file cut off (a logger killed mid-write) or
             * broken keeps the whole points before the error: the rest is
             * skipped, said and counted (it kept none) */
            if (!L->failed && (L->flags & TRACK_SKIP_BAD) && L->n > 0) {
                track_loader_bad(L, XML_GetCurrentLineNumber(g.p),
                                 "XML error: %s: the rest of the file is skipped (%zu whole "
                                 "points kept before it)",
                                 XML_ErrorString(XML_GetErrorCode(g.p)), L->n);
                break;
            }
            char keep[80] = ""; /* what skip_bad would keep */
            if (L->n > 0)
                snprintf(keep, sizeof keep, " (skip_bad keeps the %zu whole points before it)",
                         L->n);
            if (!L->failed)
                track_loader_fatal(L, XML_GetCurrentLineNumber(g.p), "XML error: %s%s",
                                   XML_ErrorString(XML_GetErrorCode(g.p)), keep);
            rc = -1;
            break;
        }
        off += n;
    } while (off < len);
    if (len == 0) {
        track_loader_fatal(L, 0, "empty file");
        rc = -1;
    }
    XML_ParserFree(g.p);
    *segments = g.segments;
    return L->failed ? -1 : rc;
}
