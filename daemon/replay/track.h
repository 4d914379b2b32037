/*
 * track.h - load a logged track into memory (CSV t,x,y,z; CSV t,lat,lon,alt
 * converted to local east/north/up metres about the first point; GPX).
 * Used by trajreplay and by the daemon's replay input.  Loading happens at
 * start-up or reload, never in the tick.
 *
 * Rows are kept as recorded (duplicates, backward steps): it is the engine's
 * job to reject or drop them, and to count them.  What the loader itself
 * refuses is what cannot be a waypoint at all: text that is not a number, a
 * missing column, NaN or infinite time or horizontal coordinate, a latitude
 * or longitude out of range.  By default such a line is an error
 * "path:line: what"; with TRACK_SKIP_BAD it is skipped and counted instead
 * (real logs have the odd corrupt line; skipping keeps the rest usable, and
 * the count and the first message say what was lost).
 *
 * CSV: comma-separated; blank lines and lines starting with '#' are skipped;
 * '\r' before '\n' is ignored; no quoting.  The first other line is a header
 * naming the columns (case-insensitive, surrounding spaces ignored):
 *   time      t, t_s, time, time_s                        (seconds)
 *   metric    x, x_m, east_m / y, y_m, north_m / z, z_m, up_m   (metres; z optional)
 *   geographic lat, lat_deg, latitude / lon, lon_deg, lng, longitude /
 *             alt, alt_m, ele, altitude                  (degrees, metres; alt optional)
 *   heading   heading, heading_deg, yaw, yaw_deg   (degrees, optional, any range:
 *             the axis wraps, see track_t.heading; an empty field: none on that row)
 * Extra columns are ignored.  With an explicit format (XYZ or LATLON) and a
 * first line made of numbers, the columns are taken by position instead:
 * t,x,y[,z] or t,lat,lon[,alt].  Times are kept as written.
 * Every data row has exactly as many fields as the header (or as the first
 * row, by position): a missing or an extra field is a bad line, never a
 * guess (a row "0,1,2" under "t,x,y,z" is not z = 0).
 *
 * Altitude / z: NaN, an empty field or no such column give z = 0 ("0 up").
 * Geographic rows are converted on the WGS84 ellipsoid (lib/util/geo.h) to east,
 * north, up about the first row; a row without altitude gets its east/north
 * at the origin's altitude and up = 0.  If the first row has no altitude the
 * origin altitude is 0 m.
 *
 * GPX 1.0/1.1 (parsed with expat): every <trkpt lat lon> of every <trk>, in
 * document order, several <trkseg> kept in order; <ele> optional; <time>
 * required (ISO 8601, fractional seconds allowed, 'Z' or a +hh:mm offset;
 * no offset = UTC as GPX specifies).  t is relative to the first point.
 * <wpt> and <rtept> are ignored.
 *
 * Path (lib/spline/path.h, added by the toolkit): lines "start x y z [t]", "speed
 * v", "step s", "line x y z", "arc cx cy r a0 a1", "circle cx cy r a0
 * ccw|cw", "wait s"; expanded into timed waypoints in metres (arc points
 * exactly on the circle).  A bad line is an error "path:line: what" (never
 * skipped: a path is a program, not a log).  line[] holds the line of the
 * element that produced each waypoint.
 *
 * Logged positions (lat/lon converted like CSV latlon; t from the first fix):
 *   n2k   a candump log (-l/-L text) of NMEA 2000: PGN 129029 GNSS Position
 *         Data, fast packets reassembled (t from its date and time; altitude),
 *         or, if the log has none, PGN 129025 Position Rapid Update (t from
 *         the log's stamps; no altitude).  Of that PGN, the source address with
 *         the most fixes.  AUTO: the first line that is not a comment is a
 *         stamped candump frame.  Decoders: lib/proto/nmea2000.h.
 *   nmea  NMEA 0183 GGA and RMC of any talker, checksum required; sentences of
 *         one time make one fix (GGA's position and altitude above MSL, else
 *         RMC's); the date from RMC (before the first RMC: the first RMC's),
 *         midnight without an RMC from a time that runs backwards by > 12 h.
 *         Other sentences are passed over.  AUTO: *.nmea, or a first line
 *         "$...*hh".  Decoder: lib/format/nmea0183.h.
 *   igc   IGC B records dated by HFDTE; an earlier time than the last is the
 *         next day; GNSS altitude, none for validity V.  AUTO: *.igc, or an A
 *         record then an H or B record.  Decoder: lib/format/igc.h.
 * A malformed line is a bad line (error, or skipped with TRACK_SKIP_BAD); a
 * well-formed record without a usable fix is counted in track_t.ignored.
 *
 * Files: track.c (this API, the choice of format, rows to waypoints), one
 * parser per format in track_<format>.c (csv, gpx, path, n2k, nmea0183, igc), what they share in
 * track_loader.h/.c, dates in track_time.c.
 */
#ifndef TRAJD_TRACK_H
#define TRAJD_TRACK_H

#include <stddef.h>
#include <stdint.h>
#include "engine.h"

typedef enum {
    TRACK_FMT_AUTO = 0, /* from the extension, else the content, else the CSV header */
    TRACK_FMT_XYZ,      /* CSV t,x,y,z in seconds and metres */
    TRACK_FMT_LATLON,   /* CSV t,lat,lon[,alt] in seconds, degrees, metres */
    TRACK_FMT_GPX,      /* GPX 1.0/1.1 trkpt with <time> (and <ele>) */
    TRACK_FMT_PATH, /* a path of lines and arcs (lib/spline/path.h text form; AUTO: extension .path) */
    TRACK_FMT_N2K,      /* candump log of NMEA 2000 PGN 129029 / 129025 */
    TRACK_FMT_NMEA0183, /* NMEA 0183 GGA / RMC sentences */
    TRACK_FMT_IGC,      /* IGC flight log, B records */
    TRACK_FMT_COUNT
} track_format_t;

/* track_load_opts flags */
#define TRACK_SKIP_BAD 0x1u /* skip and count bad lines instead of failing */

/* Largest file accepted (the whole file is read into memory). */
#define TRACK_FILE_MAX_BYTES (1024L * 1024L * 1024L)
/* Most waypoints a .path file may expand to (its `step` and lines): 16 Mi,
 * 704 MiB of waypoints and line numbers, below the track file limit above.
 * Counted before anything is made (track_path.c). */
#define TRACK_PATH_WAYPOINTS_MAX (16UL * 1024UL * 1024UL)
/* Largest |heading| a track may give, degrees: 10^7 (27 777 turns, where a
 * double still resolves 2e-9 degree); 1e300 is a bad line, not an axis. */
#define TRACK_HEADING_MAX_DEG 1e7
/* Skipped lines whose message is kept in track_t.reports (the count is in
 * skipped): the caller prints them, so a log says which lines were lost. */
#define TRACK_REPORT_MAX 10
#define TRACK_REPORT_LEN 256
/* Longest CSV line accepted, bytes. */
#define TRACK_LINE_MAX 4096

typedef struct {
    size_t n;                          /* waypoints */
    engine_waypoint_t *wp;             /* n waypoints, seq = 1-based row number */
    uint32_t *line;                    /* n source line numbers (CSV line, or line of <trkpt>) */
    track_format_t format;             /* the format actually read (never AUTO) */
    int geographic;                    /* 1 if converted from lat/lon */
    double lat0_deg, lon0_deg, alt0_m; /* ENU origin when geographic: the first point,
                                 * or the datum given to track_reframe */
    double *heading_t, *heading;       /* nheading samples of the heading axis (CSV column
                                 * heading, heading_deg, yaw or yaw_deg): track time
                                 * (strictly increasing) and angle in degrees,
                                 * unwrapped (lib/util/angle.h); NULL if none */
    size_t nheading;
    double (*geo)[3];                  /* n rows lat, lon (deg), alt (m, NaN: none) when
                                 * geographic, else NULL */
    double (*geo_vel)[3];              /* geographic rows with the source's velocity: east,
                                 * north, up at the fix (m/s; NaN: none), turned into
                                 * the frame's axes by track_reframe; NULL if no row
                                 * has one (metric rows: in wp[].vel_m_s directly) */
    size_t skipped;                    /* bad lines skipped (TRACK_SKIP_BAD) */
    size_t ignored;                    /* well-formed records that give no waypoint: N2K
                                 position n/a, no fix, a fast packet missing a
                                 frame, another source; NMEA status V / quality 0;
                                 IGC validity V is kept (2-D fix: no altitude) */
    size_t nreports;                   /* messages in reports[] (at most TRACK_REPORT_MAX) */
    char (*reports)[TRACK_REPORT_LEN]; /* "file:line: what" of the first skipped lines */
    size_t segments;                   /* GPX <trkseg> elements seen (0 for CSV) */
} track_t;

/*
 * Load path.  Returns 0, or -1 with a message "path:line: what" in err
 * (err may be NULL; errlen 0 is fine).  On success trk owns memory to
 * release with track_free; on failure trk is zeroed.
 * A track with no waypoint is an error ("no waypoints").
 * flags: 0 or TRACK_SKIP_BAD.  When lines were skipped, trk->skipped counts
 * them and err holds the message of the first one even though the call
 * succeeded.
 */
int track_load_opts(const char *path, track_format_t fmt, unsigned flags, track_t *trk, char *err,
                    size_t errlen);

/*
 * Re-express a geographic track's waypoints as east/north/up about another
 * origin (a daemon's one datum, so all its objects share one frame) instead
 * of its first point; rows without altitude get east/north at alt0_m and
 * up = 0, as about the first point.  Returns 0, or -1 for a metric track or
 * an origin geo_check refuses (trk untouched).
 */
int track_reframe(track_t *trk, double lat0_deg, double lon0_deg, double alt0_m);

/* 1 if trk is geographic and no fix has an altitude (each is expressed at the
 * datum's height, up 0: its setpoints go back at that height, geo_from_enu_at). */
int track_no_altitude(const track_t *trk);

/* Release; safe on a zeroed or already freed track. */
void track_free(track_t *trk);

/* Format names indexed by track_format_t ("auto", "xyz", "latlon", "gpx",
 * "path", "n2k", "nmea", "igc"), NULL-terminated: for --format, replay.format
 * and help texts, so a new format needs no edit there. */
extern const char *const track_format_names[TRACK_FMT_COUNT + 1];

/* Parse a name of track_format_names; returns -1 if unknown. */
int track_format_parse(const char *s, track_format_t *fmt);

/* Name of a format, "unknown" if out of range. */
const char *track_format_name(track_format_t fmt);

/* One line saying what a format reads (for --help), "" if out of range. */
const char *track_format_help(track_format_t fmt);

/*
 * Parse an ISO 8601 UTC date-time as used by GPX ("2014-08-22T16:48:52Z",
 * "2014-08-22T16:48:52.25Z", "...+02:00").  On success returns 0 with whole
 * seconds since 1970-01-01T00:00:00Z in *sec and the fraction in [0,1) in
 * *frac (kept apart so differences stay exact).  Returns -1 if malformed.
 */
int track_parse_iso8601(const char *s, int64_t *sec, double *frac);

#endif
