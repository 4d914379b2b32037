/* igc.c - IGC date header and B records; see igc.h. */
#include "igc.h"

#include <string.h>

const char *igc_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case IGC_OK: return "ok";
    case IGC_ESYNTAX: return "not an IGC B record or date, or a field does not parse";
    case IGC_ERANGE: return "time, date, latitude or longitude out of range";
    default: return "unknown IGC error";
    }
}

/* n decimal digits at s. */
static int digits(const char *s, int n, int *v)
{
    int x = 0;
    for (int i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9')
            return -1;
        x = x * 10 + (s[i] - '0');
    }
    *v = x;
    return 0;
}

/* 5 characters of altitude: digits, or '-' and 4 digits. */
static int altitude(const char *s, int *v)
{
    if (s[0] == '-') {
        if (digits(s + 1, 4, v) < 0)
            return -1;
        *v = -*v;
        return 0;
    }
    return digits(s, 5, v);
}

/* DDMMmmm or DDDMMmmm and a hemisphere letter. */
static int angle(const char *s, int deg_digits, char pos, char neg, double *out)
{
    int deg, mmm;
    if (digits(s, deg_digits, &deg) < 0 || digits(s + deg_digits, 5, &mmm) < 0)
        return -IGC_ESYNTAX;
    char h = s[deg_digits + 5];
    if (h != pos && h != neg)
        return -IGC_ESYNTAX;
    if (mmm >= 60000)
        return -IGC_ERANGE;
    double d = deg + mmm / 60000.0;
    if (d > (deg_digits == 2 ? 90.0 : 180.0))
        return -IGC_ERANGE;
    *out = h == neg ? -d : d;
    return 0;
}

int igc_parse_b(const char *line, igc_fix_t *out)
{
    int h, m, s, rc;
    memset(out, 0, sizeof *out);
    size_t n = strlen(line);
    while (n && (line[n - 1] == '\r' || line[n - 1] == '\n'))
        n--;
    if (n < 35 || line[0] != 'B' || digits(line + 1, 2, &h) || digits(line + 3, 2, &m) ||
        digits(line + 5, 2, &s))
        return -IGC_ESYNTAX;
    if (h > 23 || m > 59 || s > 59)
        return -IGC_ERANGE;
    out->tod_s = h * 3600 + m * 60 + s;
    if ((rc = angle(line + 7, 2, 'N', 'S', &out->lat_deg)) < 0 ||
        (rc = angle(line + 15, 3, 'E', 'W', &out->lon_deg)) < 0)
        return rc;
    if (line[24] != 'A' && line[24] != 'V')
        return -IGC_ESYNTAX;
    out->valid_3d = line[24] == 'A';
    if (altitude(line + 25, &out->pressure_alt_m) < 0 || altitude(line + 30, &out->gnss_alt_m) < 0)
        return -IGC_ESYNTAX;
    return 0;
}

int igc_parse_date(const char *line, int64_t *days)
{
    static const int mdays[12] = {31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    int d, m, y;
    if (strncmp(line, "HFDTE", 5) != 0)
        return -IGC_ESYNTAX;
    const char *p = line + 5;
    if (strncmp(p, "DATE:", 5) == 0)
        p += 5;
    if (digits(p, 2, &d) || digits(p + 2, 2, &m) || digits(p + 4, 2, &y))
        return -IGC_ESYNTAX;
    if (p[6] != '\0' && p[6] != ',' && p[6] != '\r' && p[6] != '\n' && p[6] != ' ')
        return -IGC_ESYNTAX;
    y += y >= 80 ? 1900 : 2000;
    int leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    if (m < 1 || m > 12 || d < 1 || d > mdays[m - 1] || (m == 2 && d == 29 && !leap))
        return -IGC_ERANGE;
    int64_t yy = y - (m <= 2);
    int64_t era = yy / 400, yoe = yy - era * 400;
    int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    *days = era * 146097 + yoe * 365 + yoe / 4 - yoe / 100 + doy - 719468;
    return 0;
}
