/* track_nmea0183.c - NMEA 0183 logs: GGA and RMC sentences (decoded by
 * lib/format/nmea0183.h) into fixes, with the velocity of RMC's speed and
 * course, or of a VTG's that follows a time of the epoch (issue 31: a
 * velocity only with the fix of its own epoch).  See track.h for the rules. */
#include "track_loader.h"

#include <math.h>
#include <string.h>

#include "geo.h"
#include "nmea0183.h"

/* Sentences whose times differ by less than this (s) are of one fix: the
 * sentences print the time with at most 3 or 4 decimals. */
#define NMEA_SAME_TIME_S 1e-6

/* Sentences of one time of day make one fix: GGA's position and altitude
 * if it is valid, else RMC's position. */
typedef struct {
    int active;
    double tod_s;
    int64_t day;
    int have; /* a valid position */
    int from_gga;
    double lat, lon, alt;
    unsigned long line;
    int has_vel; /* RMC's of this time, else a VTG's after it */
    double sog, cog;
} epoch_t;

typedef struct {
    track_loader_t *L;
    epoch_t e;
    int alt_track;   /* a GGA at (nearly) every time: its fixes have an altitude */
    int64_t day;     /* current date, days since 1970 */
    double last_tod; /* for midnight without an RMC date */
    int have_t0;
    int64_t sec0;
    double frac0;
} nmea_t;

static int flush(nmea_t *N)
{
    epoch_t *e = &N->e;
    if (!e->active)
        return 0;
    e->active = 0;
    if (!e->have) {
        N->L->ignored++; /* no valid fix at this time (GGA quality 0, RMC status V) */
        return 0;
    }
    if (N->alt_track && !e->from_gga) {
        /* an RMC whose GGA of the same time was lost (cut, a bad checksum) in a
         * log that has one at (nearly) every time: its altitude is not known,
         * and the datum's in its place made a 31 m dip in the curve.  Ignored
         * as a fix not usable */
        N->L->ignored++;
        return 0;
    }
    double whole = floor(e->tod_s);
    int64_t sec = e->day * 86400 + (int64_t)whole;
    double frac = e->tod_s - whole;
    if (!N->have_t0) {
        N->have_t0 = 1;
        N->sec0 = sec;
        N->frac0 = frac;
    }
    double t = (double)(sec - N->sec0) + (frac - N->frac0);
    if (track_loader_add_row(N->L, t, e->lat, e->lon, e->alt, e->line) < 0)
        return -1;
    if (e->has_vel)
        track_loader_course_speed(N->L, e->cog, e->sog);
    return 0;
}

static int sentence(nmea_t *N, const nmea0183_fix_t *f, unsigned long lineno)
{
    epoch_t *e = &N->e;
    if (f->kind == NMEA0183_OTHER)
        return 0;
    if (f->kind == NMEA0183_VTG) { /* no time: of the epoch being read, if any */
        if (e->active && f->has_vel && !e->has_vel) {
            e->has_vel = 1;
            e->sog = f->sog_m_s;
            e->cog = f->cog_deg;
        }
        return 0;
    }
    if (f->has_date)
        N->day = f->days;
    else if (f->tod_s < N->last_tod - 43200.0)
        N->day++; /* past midnight with no RMC date to say so */
    N->last_tod = f->tod_s;
    if (!e->active || fabs(e->tod_s - f->tod_s) > NMEA_SAME_TIME_S ||
        e->day != N->day) { /* a new time: a new fix */
        if (flush(N) < 0)
            return -1;
        memset(e, 0, sizeof *e);
        e->active = 1;
        e->tod_s = f->tod_s;
        e->day = N->day;
        e->alt = NAN;
    }
    if (f->kind == NMEA0183_RMC && f->valid && f->has_vel) {
        e->has_vel = 1; /* RMC's own: aligned with its time (before a VTG's) */
        e->sog = f->sog_m_s;
        e->cog = f->cog_deg;
    }
    if (!f->valid || !f->has_pos || (e->have && e->from_gga))
        return 0;
    int rc = geo_check(f->lat_deg, f->lon_deg, isnan(f->alt_m) ? 0.0 : f->alt_m);
    if (rc)
        return track_loader_bad(N->L, lineno, "%s", geo_strerror(rc));
    e->have = 1;
    e->from_gga = f->kind == NMEA0183_GGA;
    e->lat = f->lat_deg;
    e->lon = f->lon_deg;
    e->alt = e->from_gga ? f->alt_m : NAN;
    e->line = lineno;
    return 0;
}

/* 1 if the log has a GGA for at least 9 in 10 of its RMCs (or GGAs only): a
 * time with an RMC alone lost its GGA (a receiver that sends GGA at a lower
 * rate than RMC gives its other times no altitude by design). */
static int gga_every_time(const char *buf, size_t len)
{
    size_t gga = 0, rmc = 0;
    for (const char *p = buf, *end = buf + len; (p = memchr(p, '$', (size_t)(end - p)));) {
        p++;
        if ((size_t)(end - p) >= 6) {
            gga += !memcmp(p + 2, "GGA,", 4);
            rmc += !memcmp(p + 2, "RMC,", 4);
        }
    }
    return gga > 0 && 10 * gga >= 9 * rmc;
}

/* The date of the first RMC that has one, so fixes before it are dated too. */
static int64_t first_date(const char *buf, size_t len)
{
    const char *p = buf, *end = buf + len;
    while (p < end) {
        const char *nl = memchr(p, '\n', (size_t)(end - p));
        size_t n = nl ? (size_t)(nl - p) : (size_t)(end - p);
        char line[128];
        nmea0183_fix_t f;
        if (n < sizeof line && memmem(p, n, "RMC,", 4)) {
            memcpy(line, p, n);
            line[n] = '\0';
            if (nmea0183_parse(line, &f) == 0 && f.has_date)
                return f.days;
        }
        p += n + 1;
    }
    return 0;
}

int track_nmea0183_parse(track_loader_t *L, const char *buf, size_t len)
{
    nmea_t N = {
        .L = L, .day = first_date(buf, len), .last_tod = -1, .alt_track = gga_every_time(buf, len)};
    track_lines_t it;
    int r;
    track_lines_init(&it, buf, len);
    while ((r = track_lines_next(L, &it)) > 0) {
        const char *s = it.line + strspn(it.line, " \t");
        if (*s == '\0')
            continue;
        nmea0183_fix_t f;
        int rc = nmea0183_parse(s, &f);
        if (rc < 0) {
            if (track_loader_bad(L, it.lineno, "%s", nmea0183_strerror(rc)))
                return -1;
            continue;
        }
        if (sentence(&N, &f, it.lineno) < 0)
            return -1;
    }
    if (r < 0)
        return -1;
    return flush(&N);
}

int track_nmea0183_sniff(const char *buf, size_t len)
{
    size_t i = 0;
    while (i < len && (buf[i] == ' ' || buf[i] == '\t' || buf[i] == '\r' || buf[i] == '\n'))
        i++;
    if (i + 6 >= len || buf[i] != '$')
        return 0;
    const char *nl = memchr(buf + i, '\n', len - i);
    size_t n = nl ? (size_t)(nl - (buf + i)) : len - i;
    while (n && buf[i + n - 1] == '\r')
        n--;
    return n >= 6 && buf[i + n - 3] == '*';
}
