/* track_igc.c - IGC flight logs: B records dated by HFDTE (decoded by
 * lib/format/igc.h).  See track.h for the rules. */
#include "track_loader.h"

#include <ctype.h>
#include <math.h>
#include <string.h>

#include "geo.h"
#include "igc.h"

typedef struct {
    track_loader_t *L;
    int64_t day;
    int last_tod;
    int have_t0;
    int64_t sec0;
} igc_t;

static int b_record(igc_t *G, const char *line, unsigned long lineno)
{
    igc_fix_t f;
    int rc = igc_parse_b(line, &f);
    if (rc < 0)
        return track_loader_bad(G->L, lineno, "%s", igc_strerror(rc));
    if (f.tod_s < G->last_tod)
        G->day++; /* B records are in time order: an earlier time is the next day */
    G->last_tod = f.tod_s;
    /* validity V: a 2-D fix, its GNSS altitude is not one */
    double alt = f.valid_3d ? (double)f.gnss_alt_m : NAN;
    if ((rc = geo_check(f.lat_deg, f.lon_deg, isnan(alt) ? 0.0 : alt)) != 0)
        return track_loader_bad(G->L, lineno, "%s", geo_strerror(rc));
    int64_t sec = G->day * 86400 + f.tod_s;
    if (!G->have_t0) {
        G->have_t0 = 1;
        G->sec0 = sec;
    }
    return track_loader_add_row(G->L, (double)(sec - G->sec0), f.lat_deg, f.lon_deg, alt, lineno);
}

int track_igc_parse(track_loader_t *L, const char *buf, size_t len)
{
    igc_t G = {.L = L, .last_tod = -1};
    track_lines_t it;
    int r, dated = 0;
    track_lines_init(&it, buf, len);
    while ((r = track_lines_next(L, &it)) > 0) {
        const char *s = it.line;
        if (*s == '\0')
            continue;
        if (s[0] == 'B') {
            if (b_record(&G, s, it.lineno) < 0)
                return -1;
        } else if (strncmp(s, "HFDTE", 5) == 0 && !dated) {
            int rc = igc_parse_date(s, &G.day);
            if (rc < 0 && track_loader_bad(L, it.lineno, "%s", igc_strerror(rc)))
                return -1;
            dated = rc == 0;
        } else if (!isupper((unsigned char)s[0])) {
            /* every IGC record starts with its type letter A..Z */
            if (track_loader_bad(L, it.lineno, "not an IGC record"))
                return -1;
        }
    }
    return r < 0 ? -1 : 0;
}

int track_igc_sniff(const char *buf, size_t len)
{
    /* an A record (manufacturer) first, then an H or B record */
    if (len < 6 || buf[0] != 'A' || !isalnum((unsigned char)buf[1]))
        return 0;
    const char *nl = memchr(buf, '\n', len);
    return nl && nl + 1 < buf + len && (nl[1] == 'H' || nl[1] == 'B');
}
