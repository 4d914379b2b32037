/* track_csv.c - CSV tracks: t,x,y[,z] in metres or t,lat,lon[,alt] in
 * degrees, columns named by a header or taken by position.  See track.h. */
#include "track_loader.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "geo.h"

enum {
    COL_T,
    COL_X,
    COL_Y,
    COL_Z,
    COL_LAT,
    COL_LON,
    COL_ALT,
    COL_HDG,
    COL_VX,
    COL_VY,
    COL_VZ,
    COL_COUNT
};

static const char *const col_names[COL_COUNT][5] = {
    [COL_T] = {"t", "t_s", "time", "time_s", NULL},
    [COL_X] = {"x", "x_m", "east_m", NULL},
    [COL_Y] = {"y", "y_m", "north_m", NULL},
    [COL_Z] = {"z", "z_m", "up_m", NULL},
    [COL_LAT] = {"lat", "lat_deg", "latitude", NULL},
    [COL_LON] = {"lon", "lon_deg", "lng", "longitude", NULL},
    [COL_ALT] = {"alt", "alt_m", "ele", "altitude", NULL},
    [COL_HDG] = {"heading", "heading_deg", "yaw", "yaw_deg", NULL},
    /* the source's velocity (issue 31): x,y,z, or east,north,up at a fix */
    [COL_VX] = {"vx", "vx_m_s", "ve", "ve_m_s", NULL},
    [COL_VY] = {"vy", "vy_m_s", "vn", "vn_m_s", NULL},
    [COL_VZ] = {"vz", "vz_m_s", "vu", "vu_m_s", NULL},
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
        if (track_field_num(field[i], &v, NULL) != 0)
            return 0;
    }
    return 1;
}

typedef struct {
    track_loader_t *L;
    track_format_t fmt; /* AUTO until the header decided */
    int col[COL_COUNT]; /* field index of each column, -1 if absent */
    int have_header;
    int geographic;
    int needed;     /* fields a data row must have (that of the header) */
    int positional; /* columns by position: rows have as many as the first */
} csv_t;

/* A line that cannot be split or read: before the header it is fatal (the
 * file is not a CSV track), after it a bad line. */
static int csv_refuse(csv_t *c, unsigned long lineno, const char *what)
{
    if (!c->have_header) {
        track_loader_fatal(c->L, lineno, "%s", what);
        return -1;
    }
    return track_loader_bad(c->L, lineno, "%s", what);
}

/* Whether rows hold lat/lon follows from the format. */
static void csv_columns_set(csv_t *c)
{
    c->geographic = c->fmt == TRACK_FMT_LATLON;
}

/* The first non-blank line.  Returns 1 if it is data (positional columns),
 * 0 if it was a header, -1 on a fatal error. */
static int csv_header(csv_t *c, char **field, int nf, unsigned long lineno)
{
    int *col = c->col;
    c->have_header = 1;
    if (numeric_line(field, nf)) {
        if (c->fmt != TRACK_FMT_XYZ && c->fmt != TRACK_FMT_LATLON) {
            track_loader_fatal(c->L, lineno,
                               "no header line: expected one naming the "
                               "columns (t,x,y,z or t,lat,lon,alt), or give the format");
            return -1;
        }
        int geo = c->fmt == TRACK_FMT_LATLON;
        col[COL_T] = 0;
        col[geo ? COL_LAT : COL_X] = 1;
        col[geo ? COL_LON : COL_Y] = 2;
        col[geo ? COL_ALT : COL_Z] = 3;
        if (nf < 3 || nf > 4) {
            track_loader_fatal(c->L, lineno, "%d fields: by position a row is t,%s[,%s]", nf,
                               geo ? "lat,lon" : "x,y", geo ? "alt" : "z");
            return -1;
        }
        c->positional = 1;
        c->needed = nf;
        c->geographic = geo;
        return 1;
    }
    for (int i = 0; i < nf; i++) {
        int k = col_lookup(field[i]);
        if (k >= 0 && col[k] >= 0) { /* one of them would be dropped unsaid */
            track_loader_fatal(c->L, lineno,
                               "header names one column twice: '%s' (field %d) and '%s' (field "
                               "%d)",
                               field[col[k]], col[k] + 1, field[i], i + 1);
            return -1;
        }
        if (k >= 0)
            col[k] = i;
    }
    if (col[COL_T] < 0) {
        track_loader_fatal(c->L, lineno, "header has no time column (t or t_s)");
        return -1;
    }
    int has_ll = col[COL_LAT] >= 0 && col[COL_LON] >= 0;
    int has_xy = col[COL_X] >= 0 && col[COL_Y] >= 0;
    if (c->fmt == TRACK_FMT_AUTO && has_ll && has_xy) {
        track_loader_fatal(c->L, lineno,
                           "header names both x,y and lat,lon: give the format (xyz or latlon) "
                           "to say which the track is");
        return -1;
    }
    if (c->fmt == TRACK_FMT_AUTO)
        c->fmt = has_ll ? TRACK_FMT_LATLON : TRACK_FMT_XYZ;
    if (c->fmt == TRACK_FMT_LATLON && !has_ll) {
        track_loader_fatal(c->L, lineno, "header has no lat and lon columns");
        return -1;
    }
    if (c->fmt == TRACK_FMT_XYZ && !has_xy) {
        track_loader_fatal(c->L, lineno,
                           has_ll ? "header has no x and y columns"
                                    " (it has lat/lon: use format latlon)"
                                  : "header names neither t,x,y[,z] nor t,lat,lon[,alt]");
        return -1;
    }
    csv_columns_set(c);
    c->needed = nf;
    return 0;
}

/* One data row.  Returns 0 (added or skipped) or -1 (loading stops). */
static int csv_row(csv_t *c, char **field, int nf, unsigned long lineno)
{
    track_loader_t *L = c->L;
    int geo = c->geographic;
    int a = geo ? COL_LAT : COL_X, b = geo ? COL_LON : COL_Y, c3 = geo ? COL_ALT : COL_Z;
    double t, va, vb, vc = NAN;
    int empty;

    if (nf != c->needed)
        return track_loader_bad(L, lineno, "%d fields, the %s has %d (%s)", nf,
                                c->positional ? "first row" : "header", c->needed,
                                nf < c->needed ? "field missing" : "extra field");
    if (track_field_num(field[c->col[COL_T]], &t, NULL) || !isfinite(t))
        return track_loader_bad(L, lineno, "time '%s' is not a finite number",
                                track_field_show(field[c->col[COL_T]]).s);
    if (track_field_num(field[c->col[a]], &va, NULL) || !isfinite(va))
        return track_loader_bad(L, lineno, "%s '%s' is not a finite number", geo ? "latitude" : "x",
                                track_field_show(field[c->col[a]]).s);
    if (track_field_num(field[c->col[b]], &vb, NULL) || !isfinite(vb))
        return track_loader_bad(L, lineno, "%s '%s' is not a finite number",
                                geo ? "longitude" : "y", track_field_show(field[c->col[b]]).s);
    if (c->col[c3] >= 0 && c->col[c3] < nf &&
        (track_field_num(field[c->col[c3]], &vc, &empty) || isinf(vc)))
        return track_loader_bad(L, lineno, "%s '%s' is not a number", geo ? "altitude" : "z",
                                track_field_show(field[c->col[c3]]).s);
    if (geo) {
        int rc = geo_check(va, vb, isnan(vc) ? 0.0 : vc);
        if (rc)
            return track_loader_bad(L, lineno, "%s", geo_strerror(rc));
    }
    double vh = NAN;
    if (c->col[COL_HDG] >= 0 && c->col[COL_HDG] < nf &&
        (track_field_num(field[c->col[COL_HDG]], &vh, &empty) || isinf(vh)))
        return track_loader_bad(L, lineno, "heading '%s' is not a number",
                                track_field_show(field[c->col[COL_HDG]]).s);
    if (fabs(vh) > TRACK_HEADING_MAX_DEG) /* NaN (empty) passes */
        return track_loader_bad(L, lineno, "heading '%s' beyond +-%g degrees",
                                track_field_show(field[c->col[COL_HDG]]).s, TRACK_HEADING_MAX_DEG);
    double vel[3] = {0, 0, 0};
    int nv = 0;
    if (c->col[COL_VX] >= 0 && c->col[COL_VY] >= 0) { /* vz alone is no velocity */
        static const int vc3[3] = {COL_VX, COL_VY, COL_VZ};
        for (int k = 0; k < 3; k++) {
            int i = c->col[vc3[k]];
            double v = NAN;
            if (i < 0 || i >= nf)
                continue;
            if (track_field_num(field[i], &v, &empty) || isinf(v))
                return track_loader_bad(L, lineno, "velocity '%s' is not a number",
                                        track_field_show(field[i]).s);
            if (!isnan(v)) { /* an empty cell: none */
                vel[k] = v;
                nv += k < 2;
            }
        }
        if (nv == 1)
            return track_loader_bad(L, lineno, "velocity: vx given without vy or vy without vx");
    }
    if (track_loader_add_row(L, t, va, vb, vc, lineno) < 0)
        return -1;
    L->rows[L->n - 1].h = vh;
    if (nv == 2) {
        L->rows[L->n - 1].has_v = 1;
        memcpy(L->rows[L->n - 1].v, vel, sizeof vel);
    }
    return 0;
}

/* One line (NUL-terminated copy in line).  Returns 0 or -1. */
static int csv_line(csv_t *c, char *line, unsigned long lineno)
{
    char *field[MAX_FIELDS];
    char *s = line;
    /* Skip a UTF-8 byte order mark on the first line. */
    if (lineno == 1 && (unsigned char)s[0] == 0xef && (unsigned char)s[1] == 0xbb &&
        (unsigned char)s[2] == 0xbf)
        s += 3;
    while (*s == ' ' || *s == '\t')
        s++;
    if (*s == '\0' || *s == '#')
        return 0;
    int nf = split(s, field, MAX_FIELDS);
    if (nf < 0) {
        char what[64];
        snprintf(what, sizeof what, "more than %d columns", MAX_FIELDS);
        return csv_refuse(c, lineno, what);
    }
    if (!c->have_header) {
        int rc = csv_header(c, field, nf, lineno);
        if (rc <= 0)
            return rc;
    }
    return csv_row(c, field, nf, lineno);
}

int track_csv_parse(track_loader_t *L, const char *buf, size_t len, track_format_t fmt,
                    track_format_t *got)
{
    csv_t c = {.L = L, .fmt = fmt};
    unsigned long lineno = 0;
    size_t pos = 0;
    char line[TRACK_LINE_MAX + 1];

    for (int k = 0; k < COL_COUNT; k++)
        c.col[k] = -1;
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
        int rc;
        if (ll > TRACK_LINE_MAX) {
            char what[64];
            snprintf(what, sizeof what, "line longer than %d bytes", TRACK_LINE_MAX);
            rc = csv_refuse(&c, lineno, what);
        } else if (memchr(src, '\0', ll)) {
            rc = csv_refuse(&c, lineno, "NUL byte (binary file?)");
        } else {
            memcpy(line, src, ll);
            line[ll] = '\0';
            rc = csv_line(&c, line, lineno);
        }
        if (rc)
            return -1;
    }
    if (!c.have_header) {
        track_loader_fatal(L, 0, "no waypoints (empty file)");
        return -1;
    }
    *got = c.fmt;
    return 0;
}
