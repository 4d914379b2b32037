/* nmea0183.c - GGA and RMC sentences; see nmea0183.h. */
#include "nmea0183.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NMEA0183_FIELDS_MAX 24
#define NMEA0183_LINE_MAX 120 /* 82 by the standard; some receivers write more */

const char *nmea0183_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case NMEA0183_OK: return "ok";
    case NMEA0183_ESYNTAX: return "not an NMEA 0183 sentence, or a field that does not parse";
    case NMEA0183_ECHECKSUM: return "missing or wrong checksum";
    case NMEA0183_ERANGE: return "time, date, latitude or longitude out of range";
    default: return "unknown NMEA 0183 error";
    }
}

static int hexval(char c)
{
    return c >= '0' && c <= '9'   ? c - '0'
           : c >= 'A' && c <= 'F' ? c - 'A' + 10
           : c >= 'a' && c <= 'f' ? c - 'a' + 10
                                  : -1;
}

/* A whole decimal number ("" is not one). */
static int num(const char *s, double *v)
{
    char *end;
    if (!*s || !((*s >= '0' && *s <= '9') || *s == '.' || *s == '-'))
        return -1;
    *v = strtod(s, &end);
    return *end == '\0' && isfinite(*v) ? 0 : -1;
}

/* hhmmss[.sss] into seconds of the day. */
static int time_of_day(const char *s, double *tod)
{
    double v;
    if (strlen(s) < 6 || num(s, &v) < 0 || v < 0)
        return -NMEA0183_ESYNTAX;
    int h = (s[0] - '0') * 10 + (s[1] - '0'), m = (s[2] - '0') * 10 + (s[3] - '0');
    double sec = v - (double)(h * 10000 + m * 100);
    if (h > 23 || m > 59 || !(sec >= 0 && sec < 61))
        return -NMEA0183_ERANGE;
    *tod = h * 3600.0 + m * 60.0 + sec;
    return *tod < 86400.0 ? 0 : -NMEA0183_ERANGE;
}

/* (d)ddmm.mmmm and a hemisphere into degrees; deg_digits 2 or 3. */
static int angle(const char *s, const char *hemi, int deg_digits, double *out)
{
    double v;
    if ((int)strlen(s) < deg_digits + 2 || num(s, &v) < 0 || v < 0)
        return -NMEA0183_ESYNTAX;
    int deg = 0;
    for (int i = 0; i < deg_digits; i++) {
        if (s[i] < '0' || s[i] > '9')
            return -NMEA0183_ESYNTAX;
        deg = deg * 10 + (s[i] - '0');
    }
    double min;
    if (num(s + deg_digits, &min) < 0)
        return -NMEA0183_ESYNTAX;
    if (min >= 60.0 || deg > (deg_digits == 2 ? 90 : 180))
        return -NMEA0183_ERANGE;
    double d = deg + min / 60.0;
    if (d > (deg_digits == 2 ? 90.0 : 180.0))
        return -NMEA0183_ERANGE;
    if (strcmp(hemi, deg_digits == 2 ? "S" : "W") == 0)
        d = -d;
    else if (strcmp(hemi, deg_digits == 2 ? "N" : "E") != 0)
        return -NMEA0183_ESYNTAX;
    *out = d;
    return 0;
}

/* ddmmyy into days since 1970 (years 80..99 are 1980..1999). */
static int date(const char *s, int64_t *days)
{
    static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (strlen(s) != 6 || strspn(s, "0123456789") != 6)
        return -NMEA0183_ESYNTAX;
    int d = (s[0] - '0') * 10 + (s[1] - '0'), m = (s[2] - '0') * 10 + (s[3] - '0');
    int y = (s[4] - '0') * 10 + (s[5] - '0');
    y += y >= 80 ? 1900 : 2000;
    int leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    if (m < 1 || m > 12 || d < 1 || d > mdays[m - 1] || (m == 2 && d == 29 && !leap))
        return -NMEA0183_ERANGE;
    /* days_from_civil (H. Hinnant), as lib-pure code may not call daemon/ */
    int64_t yy = y - (m <= 2);
    int64_t era = yy / 400, yoe = yy - era * 400;
    int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    *days = era * 146097 + yoe * 365 + yoe / 4 - yoe / 100 + doy - 719468;
    return 0;
}

/* Check "$...*hh", split the body at commas (in place in buf). */
static int split(const char *line, char *buf, char **f, int *nf)
{
    while (*line == ' ' || *line == '\t')
        line++;
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\r' || line[n - 1] == '\n' || line[n - 1] == ' '))
        n--;
    if (n < 6 || n > NMEA0183_LINE_MAX || (line[0] != '$' && line[0] != '!'))
        return -NMEA0183_ESYNTAX;
    if (line[n - 3] != '*')
        return -NMEA0183_ECHECKSUM;
    int hi = hexval(line[n - 2]), lo = hexval(line[n - 1]);
    unsigned sum = 0;
    for (size_t i = 1; i < n - 3; i++)
        sum ^= (unsigned char)line[i];
    if (hi < 0 || lo < 0 || sum != (unsigned)(hi * 16 + lo))
        return -NMEA0183_ECHECKSUM;
    memcpy(buf, line + 1, n - 4);
    buf[n - 4] = '\0';
    *nf = 0;
    for (char *p = buf;; p++) {
        if (*nf == NMEA0183_FIELDS_MAX)
            return -NMEA0183_ESYNTAX;
        f[(*nf)++] = p;
        p = strchr(p, ',');
        if (!p)
            return 0;
        *p = '\0';
    }
}

/* Speed (sog, in unit m/s per unit) and course (cog, degrees true) of an
 * RMC or VTG: has_vel once both are there (a speed of 0 needs no course). */
static int velocity(const char *sog, double unit, const char *cog, nmea0183_fix_t *o)
{
    double s, c = 0.0;
    if (!sog[0])
        return 0;
    if (num(sog, &s) < 0 || (cog[0] && num(cog, &c) < 0))
        return -NMEA0183_ESYNTAX;
    if (!(s >= 0 && s < 1e6) || !(c >= 0 && c <= 360))
        return -NMEA0183_ERANGE;
    if (!cog[0] && s > 0)
        return 0; /* a speed without a course: no velocity */
    o->has_vel = 1;
    o->sog_m_s = s * unit;
    o->cog_deg = c;
    return 0;
}

static int parse_vtg(char **f, int nf, nmea0183_fix_t *o)
{
    o->kind = NMEA0183_VTG;
    if (nf < 9)
        return -NMEA0183_ESYNTAX;
    if (nf >= 10 && strcmp(f[9], "N") == 0)
        return 0; /* mode: not valid */
    if (f[5][0])
        return velocity(f[5], 1852.0 / 3600.0, f[1], o);
    return velocity(f[7], 1000.0 / 3600.0, f[1], o);
}

static int parse_gga(char **f, int nf, nmea0183_fix_t *o)
{
    int rc;
    if (nf < 12)
        return -NMEA0183_ESYNTAX;
    o->kind = NMEA0183_GGA;
    if ((rc = time_of_day(f[1], &o->tod_s)) < 0)
        return rc;
    o->valid = f[6][0] != '\0' && f[6][0] != '0';
    if (f[2][0] || f[4][0]) {
        if ((rc = angle(f[2], f[3], 2, &o->lat_deg)) < 0 ||
            (rc = angle(f[4], f[5], 3, &o->lon_deg)) < 0)
            return rc;
        o->has_pos = 1;
    }
    if (f[9][0] && num(f[9], &o->alt_m) < 0)
        return -NMEA0183_ESYNTAX;
    if (f[11][0] && num(f[11], &o->sep_m) < 0)
        return -NMEA0183_ESYNTAX;
    return 0;
}

static int parse_rmc(char **f, int nf, nmea0183_fix_t *o)
{
    int rc;
    if (nf < 10)
        return -NMEA0183_ESYNTAX;
    o->kind = NMEA0183_RMC;
    if ((rc = time_of_day(f[1], &o->tod_s)) < 0)
        return rc;
    o->valid = strcmp(f[2], "A") == 0;
    if (f[3][0] || f[5][0]) {
        if ((rc = angle(f[3], f[4], 2, &o->lat_deg)) < 0 ||
            (rc = angle(f[5], f[6], 3, &o->lon_deg)) < 0)
            return rc;
        o->has_pos = 1;
    }
    if (f[9][0]) {
        if ((rc = date(f[9], &o->days)) < 0)
            return rc;
        o->has_date = 1;
    }
    return velocity(f[7], 1852.0 / 3600.0, f[8], o);
}

int nmea0183_parse(const char *line, nmea0183_fix_t *out)
{
    char buf[NMEA0183_LINE_MAX + 1], *f[NMEA0183_FIELDS_MAX];
    int nf, rc;
    memset(out, 0, sizeof *out);
    out->alt_m = NAN;
    out->sep_m = NAN;
    if ((rc = split(line, buf, f, &nf)) < 0)
        return rc;
    size_t tl = strlen(f[0]);
    if (tl < 5)
        return 0; /* a sentence we do not read */
    const char *type = f[0] + tl - 3;
    if (strcmp(type, "GGA") == 0)
        return parse_gga(f, nf, out);
    if (strcmp(type, "RMC") == 0)
        return parse_rmc(f, nf, out);
    if (strcmp(type, "VTG") == 0)
        return parse_vtg(f, nf, out);
    return 0;
}
