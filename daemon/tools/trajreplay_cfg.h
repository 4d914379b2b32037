/*
 * trajreplay_cfg.h - trajreplay's options (daemon/trajreplay.c), its exit
 * statuses, and what -c FILE --object NAME takes from a trajd config
 * (trajreplay_cfg.c).
 */
#ifndef TRAJD_TRAJREPLAY_CFG_H
#define TRAJD_TRAJREPLAY_CFG_H

#include <limits.h>
#include <stdint.h>

#include "cfg.h"
#include "engine.h"
#include "engine_settings.h"
#include "track.h"

/* trajreplay's exit statuses (its --help lists them). */
enum {
    EXIT_INPUT = 1, /* track not loadable, or nothing in it usable */
    EXIT_USAGE = 2,
    EXIT_OUTPUT = 3,
    EXIT_MEMORY = 4,   /* out of memory (never from the input) */
    EXIT_MAX_ROWS = 5, /* --max-rows reached: the output is cut */
    EXIT_STRICT = 6,   /* --strict: a waypoint was rejected or a line skipped */
    EXIT_INTERNAL = 7, /* a solver refused finite data, which the engine documents cannot
                          happen (a defect to report) */
    EXIT_AXIS = 8,     /* the per-axis limits stopped the output on its path (issue 32:
                          axis_lag_stops, axis_beyond): the track was not followed there */
};

/* Engine options given on the command line, applied in order after the
 * settings of -c's object (so they override them). */
#define ENGINE_ARGS_MAX 64

/* trajreplay's options: the command line's, and -c's object's. */
typedef struct {
    const char *input;
    const char *output;
    const char *svg;
    const char *object;
    const char *config;
    track_format_t format;
    unsigned load_flags;
    int summary;
    int quiet;
    int rate_given;
    int keep_gaps;               /* write hold rows through gaps too */
    int strict;                  /* any rejection or skipped line: EXIT_STRICT */
    unsigned long long max_rows; /* 0 = no bound */
    unsigned progress_after_ms;
    int precision; /* --precision: decimals in fixed notation, or CSV_PREC_* */
    int binary;    /* --binary: the records of lib/format/spfile.h instead of CSV */
    int geo;       /* --geo: columns lat_deg,lon_deg,alt_m,heading_deg appended */
    double rate_hz;
    double override;  /* --override: the feed override, 0.01..2 (engine_set_override) */
    int64_t start_ns; /* engine time at which the first waypoint is due */
    int origin_set;   /* -c: the daemon's datum, about which a geographic track is expressed */
    double origin[3];
    double catchup;           /* -c: [daemon] catchup (engine_set_catchup); < 0: the engine's */
    int has_initial_position; /* -c: the object's initial_position, where trajd starts it */
    double initial_position_m[ENGINE_AXES];
    engine_config_t cfg;
    struct {
        const engine_setting_t *s;
        const char *arg;
    } eng[ENGINE_ARGS_MAX];
    unsigned neng;
    char track_buf[PATH_MAX];      /* replay.track of -c's object */
    char object_buf[CFG_NAME_MAX]; /* -c's object name */
} trajreplay_opts_t;

/*
 * -c FILE: the engine settings and rate of one object of a trajd config,
 * and its replay.track, replay.format, replay.skip_bad and replay.start_s
 * (a TRACK given on the command line wins, with --format and --skip-bad),
 * [daemon] catchup (the lag won back, in relative time too), and its
 * initial_position (where trajd starts it: the engine's position before
 * the first waypoint).  Where trajd takes the start from the drives
 * (can.cia402 = feedback or managed), which no file gives, a notice says so.
 * Returns -1 to go on, else an exit status (said on stderr).
 */
int trajreplay_load_config(trajreplay_opts_t *o);

#endif
