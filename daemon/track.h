/*
 * track.h - load a logged track into memory (CSV t,x,y,z; CSV t,lat,lon,alt
 * converted to local east/north/up metres about the first point; GPX).
 * Used by trajreplay and by the daemon's replay input.  Loading happens at
 * start-up or reload, never in the tick.
 *
 * Rows are kept as recorded (duplicates, backward steps, NaN altitude become
 * z = 0): it is the engine's job to reject or drop them, and to count them.
 */
#ifndef TRAJD_TRACK_H
#define TRAJD_TRACK_H

#include <stddef.h>
#include "engine.h"

typedef enum {
    TRACK_FMT_AUTO = 0,  /* from the extension (.gpx) and the CSV header */
    TRACK_FMT_XYZ,       /* CSV t,x,y,z in seconds and metres */
    TRACK_FMT_LATLON,    /* CSV t,lat,lon[,alt] in seconds, degrees, metres */
    TRACK_FMT_GPX,       /* GPX 1.0/1.1 trkpt with <time> (and <ele>) */
} track_format_t;

typedef struct {
    size_t n;                 /* waypoints */
    engine_waypoint_t *wp;    /* n waypoints, seq = 1-based row number */
    int geographic;           /* 1 if converted from lat/lon */
    double lat0_deg, lon0_deg, alt0_m; /* ENU origin (first point) when geographic */
} track_t;

/*
 * Load path.  Returns 0, or -1 with a message "path:line: what" in err.
 * On success trk owns memory to release with track_free.
 */
int track_load(const char *path, track_format_t fmt, track_t *trk, char *err,
               size_t errlen);

/* Release; safe on a zeroed or already freed track. */
void track_free(track_t *trk);

/* Parse "auto", "xyz", "latlon", "gpx"; returns -1 if unknown. */
int track_format_parse(const char *s, track_format_t *fmt);

#endif
