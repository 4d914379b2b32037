/* track.c - load a logged track into waypoints: the common API, the choice
 * of format, and rows to waypoints.  One parser per format in
 * track_<format>.c.  See track.h. */
#include "track.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "angle.h"
#include "geo.h"
#include "regfile.h"
#include "track_loader.h"

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

/* Every format: its name, what it reads, the extension and the content test
 * that pick it under TRACK_FMT_AUTO (extensions first, then content in this
 * order; CSV when nothing matches). */
typedef struct {
    const char *help;
    const char *ext;
    int (*sniff)(const char *buf, size_t len);
} format_info_t;

static const format_info_t formats[TRACK_FMT_COUNT] = {
    [TRACK_FMT_AUTO] = {"from the extension, else the content, else the CSV header", NULL, NULL},
    [TRACK_FMT_XYZ] = {"CSV t,x,y[,z]: seconds, metres", NULL, NULL},
    [TRACK_FMT_LATLON] = {"CSV t,lat,lon[,alt]: seconds, degrees, metres", NULL, NULL},
    [TRACK_FMT_GPX] = {"GPX 1.0/1.1 <trkpt> with <time> (*.gpx, or starts with '<')", ".gpx",
                       looks_like_xml},
    [TRACK_FMT_PATH] = {"lines and arcs, lib/spline/path.h (*.path)", ".path", NULL},
    [TRACK_FMT_N2K] = {"candump log of NMEA 2000 PGN 129029 or 129025 positions", NULL,
                       track_n2k_sniff},
    [TRACK_FMT_NMEA0183] = {"NMEA 0183 GGA/RMC sentences, checksummed (*.nmea)", ".nmea",
                            track_nmea0183_sniff},
    [TRACK_FMT_IGC] = {"IGC flight log: B records, date from HFDTE (*.igc)", ".igc",
                       track_igc_sniff},
};

const char *const track_format_names[TRACK_FMT_COUNT + 1] = {
    "auto", "xyz", "latlon", "gpx", "path", "n2k", "nmea", "igc", NULL,
};

static int ends_with(const char *name, const char *ext)
{
    size_t n = strlen(name), e = strlen(ext);
    return n >= e && strcasecmp(name + n - e, ext) == 0;
}

/* The format AUTO picks for name and content; XYZ stands for "CSV, the
 * header decides". */
static track_format_t detect(const char *name, const char *buf, size_t len)
{
    for (int f = 0; f < TRACK_FMT_COUNT; f++)
        if (formats[f].ext && ends_with(name, formats[f].ext))
            return (track_format_t)f;
    for (int f = 0; f < TRACK_FMT_COUNT; f++)
        if (formats[f].sniff && formats[f].sniff(buf, len))
            return (track_format_t)f;
    return TRACK_FMT_AUTO;
}

void track_free(track_t *trk)
{
    if (!trk)
        return;
    free(trk->wp);
    free(trk->line);
    free(trk->geo);
    free(trk->geo_vel);
    free(trk->heading_t);
    free(trk->heading);
    free(trk->reports);
    memset(trk, 0, sizeof *trk);
}

/* A velocity east, north, up at the fix (lat, lon) in the axes of frame
 * (lib/util/geo.h): through ECEF. */
static void vel_to_frame(double lat, double lon, const double *v, const geo_enu_t *frame,
                         double *out)
{
    geo_enu_t at;
    double ecef[3];
    (void)geo_enu_init(lat, lon, 0.0, &at); /* checked as the rows were read */
    geo_vec_from_enu(&at, v, ecef);
    geo_vec_to_enu(frame, ecef, out);
}

int track_reframe(track_t *trk, double lat0_deg, double lon0_deg, double alt0_m)
{
    geo_enu_t frame;
    if (!trk->geo || geo_enu_init(lat0_deg, lon0_deg, alt0_m, &frame) < 0)
        return -1;
    trk->lat0_deg = lat0_deg;
    trk->lon0_deg = lon0_deg;
    trk->alt0_m = alt0_m;
    for (size_t i = 0; i < trk->n; i++) {
        const double *g = trk->geo[i];
        double enu[3];
        int no_alt = isnan(g[2]);
        (void)geo_to_enu(&frame, g[0], g[1], no_alt ? alt0_m : g[2], enu);
        trk->wp[i].pos_m[0] = enu[0];
        trk->wp[i].pos_m[1] = enu[1];
        trk->wp[i].pos_m[2] = no_alt ? 0.0 : enu[2];
        if (trk->geo_vel && !isnan(trk->geo_vel[i][0])) {
            vel_to_frame(g[0], g[1], trk->geo_vel[i], &frame, trk->wp[i].vel_m_s);
            trk->wp[i].has_vel = 1;
        }
    }
    return 0;
}

/* The heading axis of the rows that have one (time strictly increasing),
 * unwrapped (lib/util/angle.h).  Returns 0 or -1 (out of memory). */
static int rows_heading(track_loader_t *L, track_t *trk)
{
    size_t m = 0;
    for (size_t i = 0; i < L->n; i++)
        m += !isnan(L->rows[i].h);
    if (!m)
        return 0;
    trk->heading_t = calloc(m, sizeof *trk->heading_t);
    trk->heading = calloc(m, sizeof *trk->heading);
    if (!trk->heading_t || !trk->heading)
        return -1;
    for (size_t i = 0; i < L->n; i++) {
        const track_row_t *r = &L->rows[i];
        if (isnan(r->h) || (trk->nheading && r->t_s <= trk->heading_t[trk->nheading - 1]))
            continue; /* a repeated or backward time: the engine drops that row too */
        trk->heading_t[trk->nheading] = r->t_s;
        trk->heading[trk->nheading++] = r->h;
    }
    angle_unwrap_deg(trk->heading, trk->nheading);
    return 0;
}

/* A track with no waypoint: why.  Well formed, none with a fix: said so (it
 * said only "no waypoints"). */
static void no_waypoints(track_loader_t *L)
{
    if (L->ignored)
        track_loader_fatal(L, 0,
                           "no waypoints: %zu record%s without a usable fix (no fix, position not "
                           "available%s)",
                           L->ignored, L->ignored == 1 ? "" : "s",
                           L->skipped ? ", and every other data line bad" : "");
    else
        track_loader_fatal(L, 0,
                           L->skipped ? "no waypoints (every data line was bad)" : "no waypoints");
}

/* Rows read by a parser into trk's waypoints (lat/lon to local metres about
 * the first row when geographic).  Returns 0 or -1 (message in L). */
static int rows_to_track(track_loader_t *L, int geographic, track_t *trk)
{
    if (L->n == 0) {
        no_waypoints(L);
        return -1;
    }
    if (L->n > UINT32_MAX) {
        track_loader_fatal(L, 0, "more than %lu waypoints", (unsigned long)UINT32_MAX);
        return -1;
    }
    trk->wp = calloc(L->n, sizeof *trk->wp);
    trk->line = calloc(L->n, sizeof *trk->line);
    if (!trk->wp || !trk->line) {
        track_loader_fatal(L, 0, "out of memory");
        return -1;
    }
    if (geographic) {
        trk->geo = calloc(L->n, sizeof *trk->geo);
        if (!trk->geo) {
            track_loader_fatal(L, 0, "out of memory");
            return -1;
        }
        size_t nv = 0;
        for (size_t i = 0; i < L->n; i++)
            nv += L->rows[i].has_v != 0;
        if (nv && !(trk->geo_vel = calloc(L->n, sizeof *trk->geo_vel))) {
            track_loader_fatal(L, 0, "out of memory");
            return -1;
        }
    }
    for (size_t i = 0; i < L->n; i++) {
        const track_row_t *r = &L->rows[i];
        engine_waypoint_t *w = &trk->wp[i];
        w->t_s = r->t_s;
        w->seq = (uint32_t)(i + 1);
        trk->line[i] = r->line;
        if (geographic) {
            trk->geo[i][0] = r->a;
            trk->geo[i][1] = r->b;
            trk->geo[i][2] = r->c; /* NaN: no altitude */
            if (trk->geo_vel) {
                for (int k = 0; k < 3; k++)
                    trk->geo_vel[i][k] = r->has_v ? r->v[k] : NAN;
            }
        } else {
            if (r->has_v) {
                w->has_vel = 1;
                memcpy(w->vel_m_s, r->v, sizeof w->vel_m_s);
            }
            w->pos_m[0] = r->a;
            w->pos_m[1] = r->b;
            w->pos_m[2] = isnan(r->c) ? 0.0 : r->c;
        }
    }
    trk->n = L->n;
    if (rows_heading(L, trk) < 0) {
        track_loader_fatal(L, 0, "out of memory");
        return -1;
    }
    if (geographic) {
        double alt0 = isnan(L->rows[0].c) ? 0.0 : L->rows[0].c;
        /* Rows were checked with geo_check as they were read. */
        (void)track_reframe(trk, L->rows[0].a, L->rows[0].b, alt0);
    }
    trk->n = L->n;
    trk->geographic = geographic;
    trk->skipped = L->skipped;
    trk->ignored = L->ignored;
    trk->reports = L->reports;
    trk->nreports = L->nreports;
    L->reports = NULL;
    return 0;
}

/* Parse the track of len bytes at buf (need not be NUL-terminated; NUL bytes
 * are an error); name is used in messages and, with TRACK_FMT_AUTO, for the
 * .gpx extension.  Results as track_load_opts. */
static int parse(const char *name, const char *buf, size_t len, track_format_t fmt, unsigned flags,
                 track_t *trk, char *err, size_t errlen)
{
    track_loader_t L;
    memset(&L, 0, sizeof L);
    memset(trk, 0, sizeof *trk);
    L.name = name ? name : "(track)";
    L.flags = flags;
    L.err = err;
    L.errlen = errlen;
    if (err && errlen)
        err[0] = '\0';

    int rc;
    track_format_t got = fmt == TRACK_FMT_AUTO ? detect(L.name, buf, len) : fmt;
    switch (got) {
    case TRACK_FMT_PATH:
        rc = track_path_parse(&L, buf, len, trk);
        if (rc)
            track_free(trk);
        return rc;
    case TRACK_FMT_GPX: rc = track_gpx_parse(&L, buf, len, &trk->segments); break;
    case TRACK_FMT_N2K: rc = track_n2k_parse(&L, buf, len); break;
    case TRACK_FMT_NMEA0183: rc = track_nmea0183_parse(&L, buf, len); break;
    case TRACK_FMT_IGC: rc = track_igc_parse(&L, buf, len); break;
    case TRACK_FMT_AUTO:
    case TRACK_FMT_XYZ:
    case TRACK_FMT_LATLON: rc = track_csv_parse(&L, buf, len, got, &got); break;
    default:
        track_loader_fatal(&L, 0, "unknown format %d", (int)fmt);
        rc = -1;
        break;
    }
    if (rc == 0)
        rc = rows_to_track(&L, got != TRACK_FMT_XYZ, trk);
    if (rc == 0)
        trk->format = got;
    free(L.rows);
    free(L.reports);
    if (rc) {
        track_free(trk);
        return -1;
    }
    return 0;
}

int track_load_opts(const char *path, track_format_t fmt, unsigned flags, track_t *trk, char *err,
                    size_t errlen)
{
    track_loader_t L; /* only for the message helpers */
    memset(&L, 0, sizeof L);
    memset(trk, 0, sizeof *trk);
    L.name = path;
    L.err = err;
    L.errlen = errlen;
    if (err && errlen)
        err[0] = '\0';

    char why[256];
    int fd = regfile_open(path, TRACK_FILE_MAX_BYTES, why, sizeof why);
    FILE *f = fd < 0 ? NULL : fdopen(fd, "rb");
    if (!f) {
        track_loader_fatal(&L, 0, "%s", fd < 0 ? why : strerror(errno));
        if (fd >= 0)
            close(fd);
        return -1;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0;
    int rc = 0;
    for (;;) {
        if (len == cap) {
            if (cap >= (size_t)TRACK_FILE_MAX_BYTES) {
                track_loader_fatal(&L, 0, "larger than %ld bytes", TRACK_FILE_MAX_BYTES);
                rc = -1;
                break;
            }
            size_t ncap = cap ? cap * 2 : 65536;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                track_loader_fatal(&L, 0, "out of memory");
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
                track_loader_fatal(&L, 0, "read error: %s", strerror(errno));
                rc = -1;
            }
            break;
        }
    }
    fclose(f);
    /* a UTF-8 byte order mark (some Windows editors write one) is no part of
     * any format: an NMEA 0183 or IGC file with one was refused at line 1 */
    if (rc == 0 && len >= 3 && (unsigned char)buf[0] == 0xEF && (unsigned char)buf[1] == 0xBB &&
        (unsigned char)buf[2] == 0xBF) {
        memmove(buf, buf + 3, len - 3);
        len -= 3;
    }
    /* lines that end in CR alone (classic Mac OS, some loggers' exports): read
     * as lines (it was one line: "no waypoints") */
    if (rc == 0 && len && !memchr(buf, '\n', len) && memchr(buf, '\r', len))
        for (char *p = buf; (p = memchr(p, '\r', len - (size_t)(p - buf))) != NULL;)
            *p++ = '\n';
    if (rc == 0)
        rc = parse(path, buf, len, fmt, flags, trk, err, errlen);
    free(buf);
    return rc;
}

int track_format_parse(const char *s, track_format_t *fmt)
{
    if (!s)
        return -1;
    for (int f = 0; f < TRACK_FMT_COUNT; f++)
        if (strcmp(s, track_format_names[f]) == 0) {
            *fmt = (track_format_t)f;
            return 0;
        }
    return -1;
}

const char *track_format_name(track_format_t fmt)
{
    return (unsigned)fmt < TRACK_FMT_COUNT ? track_format_names[fmt] : "unknown";
}

const char *track_format_help(track_format_t fmt)
{
    return (unsigned)fmt < TRACK_FMT_COUNT ? formats[fmt].help : "";
}

int track_no_altitude(const track_t *trk)
{
    if (!trk->geographic || !trk->geo)
        return 0;
    for (size_t k = 0; k < trk->n; k++)
        if (!isnan(trk->geo[k][2]))
            return 0;
    return 1;
}
