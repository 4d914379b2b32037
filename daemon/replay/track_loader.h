/*
 * track_loader.h - what every track format parser shares (internal to
 * daemon/replay/track*.c): the rows read so far, the error and skip rules,
 * number parsing and the quoting of bad fields in messages.
 *
 * A parser reads its format and calls track_loader_add_row() per fix, in
 * file order; track.c then turns rows into waypoints (converting lat/lon to
 * local metres when the parser set L->geographic).  A parser that makes
 * waypoints itself (the path expander) fills the track_t directly.
 */
#ifndef TRAJD_TRACK_LOADER_H
#define TRAJD_TRACK_LOADER_H

#include <stddef.h>
#include <stdint.h>

#include "track.h"

/* One row as read, before the geographic conversion. */
typedef struct {
    double t_s;
    double a, b, c; /* x,y,z or lat,lon,alt (c NaN: no altitude / z) */
    double h;       /* heading, degrees (NaN: none) */
    double v[3];    /* the source's velocity, m/s: x,y,z or east,north,up at the fix */
    int has_v;      /* v given (issue 31: CSV vx,vy[,vz]) */
    uint32_t line;
} track_row_t;

typedef struct {
    const char *name;
    unsigned flags;
    char *err;
    size_t errlen;
    track_row_t *rows;
    size_t n, cap;
    size_t skipped;
    size_t ignored;                    /* records without a usable fix (see track_t.ignored) */
    char (*reports)[TRACK_REPORT_LEN]; /* TRACK_REPORT_MAX, allocated on the first skip */
    size_t nreports;
    int geographic; /* rows hold lat, lon, alt (set by the parser) */
    int failed;     /* a fatal error was recorded in err */
    int oom;
} track_loader_t;

/* A fatal error (not skippable): I/O, memory, header, XML well-formedness.
 * Only the first error is kept. */
void track_loader_fatal(track_loader_t *L, unsigned long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* A bad line: fatal unless TRACK_SKIP_BAD, then counted (first message kept
 * in err, the first TRACK_REPORT_MAX in reports).
 * Returns 0 if the caller may go on, -1 if loading must stop. */
int track_loader_bad(track_loader_t *L, unsigned long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Append a row; -1 (fatal "out of memory" recorded) if it cannot grow. */
int track_loader_add_row(track_loader_t *L, double t_s, double a, double b, double c,
                         unsigned long line);

/* The last row added gets the source's velocity of a speed over ground
 * (m/s) and a course over ground (degrees true): east, north, up at the fix
 * (issue 31: NMEA 0183 RMC/VTG, NMEA 2000 PGN 129026). */
void track_loader_course_speed(track_loader_t *L, double cog_deg, double sog_m_s);

/* Parse a whole field as a double.  Leading/trailing blanks allowed.
 * An empty field gives NaN with *empty set (empty may be NULL: then an
 * empty field is an error).  Returns 0 or -1. */
int track_field_num(const char *s, double *v, int *empty);

/* A field as it may appear in a message: printable ASCII, other bytes as
 * \xHH, cut at TRACK_SHOW_MAX characters ("..." appended), so that garbage
 * in a file cannot put control characters or invalid UTF-8 on a terminal. */
#define TRACK_SHOW_MAX 40
typedef struct {
    char s[TRACK_SHOW_MAX * 4 + 4];
} track_shown_t;
track_shown_t track_field_show(const char *f);

/* Lines of a buffer, for the text formats: each call gives the next line
 * as a NUL-terminated copy in line[] ('\n' and a '\r' before it removed).
 * Returns 1 (it->lineno is its number), 0 at the end, -1 when loading must
 * stop.  A line longer than TRACK_LINE_MAX or holding a NUL byte is a bad
 * line (track_loader_bad): skipped with TRACK_SKIP_BAD, else -1. */
typedef struct {
    const char *buf;
    size_t len, pos;
    unsigned long lineno;
    char line[TRACK_LINE_MAX + 1];
} track_lines_t;

void track_lines_init(track_lines_t *it, const char *buf, size_t len);
int track_lines_next(track_loader_t *L, track_lines_t *it);

/* The parsers, one file each (track_<format>.c). */
int track_csv_parse(track_loader_t *L, const char *buf, size_t len, track_format_t fmt,
                    track_format_t *got);
int track_gpx_parse(track_loader_t *L, const char *buf, size_t len, size_t *segments);
int track_path_parse(track_loader_t *L, const char *buf, size_t len, track_t *trk);
int track_n2k_parse(track_loader_t *L, const char *buf, size_t len);
int track_nmea0183_parse(track_loader_t *L, const char *buf, size_t len);
int track_igc_parse(track_loader_t *L, const char *buf, size_t len);
/* Content sniffers for TRACK_FMT_AUTO (1: looks like this format). */
int track_n2k_sniff(const char *buf, size_t len);
int track_nmea0183_sniff(const char *buf, size_t len);
int track_igc_sniff(const char *buf, size_t len);

#endif
