/*
 * trajreplay - replay a logged track through the engine on a virtual clock
 * and write the setpoints the daemon would stream (the CSV of daemon/csv/csv_format.h).
 *
 * Tick k is at engine time now_ns = k * period_ns; for every tick,
 * replay_feed(now) then engine_tick(now), exactly as the daemon does, so the
 * output is byte-identical to trajd's CSV output for the same input and
 * settings.  No sleeping: a long track replays as fast as the CPU allows.
 *
 * Engine options are generated from lib/engine/engine_settings.h's table;
 * -c FILE --object NAME takes an object's settings from a trajd config
 * (daemon/tools/trajreplay_cfg.c).
 *
 * Gaps: while the engine holds (waiting, underrun, finished between two
 * trajectories) and the next waypoint is due more than max_gap_s later, the
 * virtual clock jumps to that waypoint's tick instead of writing hold rows
 * through the gap (the engine steps over skipped ticks without changing a
 * number); the row after the jump carries ENGINE_SP_SKIPPED.  --keep-gaps
 * writes every tick, as trajd streams them.  --max-rows bounds the output.
 *
 * Every rejected waypoint is reported as "file:line: rejected (reason)",
 * rate-limited, with a per-reason count at the end.
 *
 * Exit status: 0 done; 1 the track could not be loaded, or no waypoint of it
 * was usable; 2 usage or an invalid engine configuration; 3 writing an
 * output failed; 4 out of memory; 5 --max-rows reached; 6 --strict and a
 * waypoint was rejected or a line skipped; 7 a solver refused finite data
 * (numeric refusals, documented as impossible): a defect of trajd.
 */
#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "cfg_files.h"
#include "delay.h"
#include "engine.h"
#include "engine_settings.h"
#include "replay.h"
#include "angle.h"
#include "csv_shortest.h"
#include "geo.h"
#include "replay_summary.h"
#include "stdfds.h"
#include "csv_fixed.h"
#include "csv_format.h"
#include "svg.h"
#include "track.h"
#include "trajreplay_cfg.h"
#include "trajreplay_help.h"
#include "version.h"

/* Ticks written after the engine reports FINISHED for good: they show the
 * rest state (zero velocity, the last waypoint) to whoever reads the file. */
#define TAIL_TICKS 3
/* Default --max-rows: 5e7 rows (about 10 GB of CSV; 139 h of output at
 * 100 Hz, 14 h at 1 kHz).  A bound on what a slip in the input (timestamps
 * in seconds read as microseconds, a transfer across a continent) can make
 * trajreplay write; 0 = no bound. */
#define MAX_ROWS_DEFAULT 50000000ULL
/* Rejected waypoints reported one line each for the first REJECT_SHOW_FIRST,
 * then one in REJECT_SHOW_EVERY (all are counted in the summary). */
#define REJECT_SHOW_FIRST 20
#define REJECT_SHOW_EVERY 1000
/* Progress line (stderr a terminal only): from PROGRESS_AFTER_MS into the
 * run (--progress-after), at most every PROGRESS_EVERY_NS. */
#define PROGRESS_AFTER_MS 500
#define PROGRESS_EVERY_NS 250000000LL

static int parse_double(const char *s, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno == 0 && isfinite(*v) ? 0 : -1;
}

static int parse_uint(const char *s, unsigned *v)
{
    char *end;
    errno = 0;
    unsigned long x = strtoul(s, &end, 10);
    if (end == s || *end != '\0' || errno || x > 1000000UL || s[0] == '-')
        return -1;
    *v = (unsigned)x;
    return 0;
}

enum {
    OPT_RATE = 256,
    OPT_FORMAT,
    OPT_SVG,
    OPT_SUMMARY,
    OPT_SKIP_BAD,
    OPT_OBJECT,
    OPT_PROGRESS_AFTER,
    OPT_STRICT,
    OPT_KEEP_GAPS,
    OPT_MAX_ROWS,
    OPT_PRECISION,
    OPT_BINARY,
    OPT_GEO,
    OPT_OVERRIDE,
    OPT_ENGINE = 1024, /* + index in engine_settings[] */
};

static const struct option fixed_opts[] = {
    {"config", required_argument, NULL, 'c'},
    {"rate", required_argument, NULL, OPT_RATE},
    {"format", required_argument, NULL, OPT_FORMAT},
    {"svg", required_argument, NULL, OPT_SVG},
    {"summary", no_argument, NULL, OPT_SUMMARY},
    {"skip-bad", no_argument, NULL, OPT_SKIP_BAD},
    {"object", required_argument, NULL, OPT_OBJECT},
    {"progress-after", required_argument, NULL, OPT_PROGRESS_AFTER},
    {"strict", no_argument, NULL, OPT_STRICT},
    {"keep-gaps", no_argument, NULL, OPT_KEEP_GAPS},
    {"max-rows", required_argument, NULL, OPT_MAX_ROWS},
    {"precision", required_argument, NULL, OPT_PRECISION},
    {"binary", no_argument, NULL, OPT_BINARY},
    {"geo", no_argument, NULL, OPT_GEO},
    {"override", required_argument, NULL, OPT_OVERRIDE},
    {"output", required_argument, NULL, 'o'},
    {"quiet", no_argument, NULL, 'q'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, 'V'},
};
#define FIXED_OPTS (sizeof fixed_opts / sizeof fixed_opts[0])

/* fixed_opts, then one option per engine setting, then the terminator. */
static void build_long_opts(struct option *lopts, size_t cap)
{
    size_t n = 0;
    for (; n < FIXED_OPTS; n++)
        lopts[n] = fixed_opts[n];
    for (size_t i = 0; i < engine_settings_count && n + 1 < cap; i++)
        if (engine_settings[i].option)
            lopts[n++] = (struct option){engine_settings[i].option, required_argument, NULL,
                                         OPT_ENGINE + (int)i};
    lopts[n] = (struct option){NULL, 0, NULL, 0};
}

/* --max-rows, --precision, --override.  Returns -1 to go on, else an exit status. */
static int parse_numeric(int c, trajreplay_opts_t *o)
{
    switch (c) {
    case OPT_MAX_ROWS: {
        char *end;
        errno = 0;
        o->max_rows = strtoull(optarg, &end, 10);
        if (end == optarg || *end || errno || optarg[0] == '-') {
            fprintf(stderr, "trajreplay: --max-rows: '%s' is not a number of rows\n", optarg);
            return EXIT_USAGE;
        }
        return -1;
    }
    case OPT_PRECISION: {
        unsigned p;
        if (strcmp(optarg, "g17") == 0) {
            o->precision = CSV_PREC_G17;
            return -1;
        }
        if (parse_uint(optarg, &p) || p > CSV_FIXED_PREC_MAX) {
            fprintf(stderr,
                    "trajreplay: --precision: '%s' is not a number of decimals "
                    "0..%d, nor g17\n",
                    optarg, CSV_FIXED_PREC_MAX);
            return EXIT_USAGE;
        }
        o->precision = (int)p;
        return -1;
    }
    case OPT_OVERRIDE:
        if (parse_double(optarg, &o->override) || !(o->override >= 1 && o->override <= 200)) {
            fprintf(stderr, "trajreplay: --override: '%s' is not a percentage 1..200\n", optarg);
            return EXIT_USAGE;
        }
        o->override /= 100;
        return -1;
    default: return -1;
    }
}

/* One option other than an engine setting.  Returns -1 to go on, else an exit status. */
static int parse_option(int c, char **argv, trajreplay_opts_t *o)
{
    switch (c) {
    case 'c': o->config = optarg; return -1;
    case OPT_RATE:
        if (parse_double(optarg, &o->rate_hz) || o->rate_hz <= 0) {
            fprintf(stderr, "trajreplay: --rate: '%s' is not a positive number of Hz\n", optarg);
            return EXIT_USAGE;
        }
        o->rate_given = 1;
        return -1;
    case OPT_FORMAT:
        if (track_format_parse(optarg, &o->format)) {
            fprintf(stderr, "trajreplay: --format: '%s' is not a track format (see --help)\n",
                    optarg);
            return EXIT_USAGE;
        }
        return -1;
    case OPT_SVG: o->svg = optarg; return -1;
    case OPT_SUMMARY: o->summary = 1; return -1;
    case OPT_SKIP_BAD: o->load_flags |= TRACK_SKIP_BAD; return -1;
    case OPT_OBJECT: o->object = optarg; return -1;
    case OPT_STRICT: o->strict = 1; return -1;
    case OPT_KEEP_GAPS: o->keep_gaps = 1; return -1;
    case OPT_MAX_ROWS:
    case OPT_PRECISION:
    case OPT_OVERRIDE: return parse_numeric(c, o);
    case OPT_BINARY: o->binary = 1; return -1;
    case OPT_GEO: o->geo = 1; return -1;
    case OPT_PROGRESS_AFTER:
        if (parse_uint(optarg, &o->progress_after_ms)) {
            fprintf(stderr, "trajreplay: --progress-after: '%s' is not milliseconds\n", optarg);
            return EXIT_USAGE;
        }
        return -1;
    case 'o': o->output = optarg; return -1;
    case 'q': o->quiet = 1; return -1;
    case 'h': trajreplay_usage(stdout); return 0;
    case 'V': printf("trajreplay %s\n", TRAJD_VERSION); return 0;
    case ':':
        fprintf(stderr, "trajreplay: %s needs a value\n", argv[optind - 1]);
        return EXIT_USAGE;
    default:
        if (c >= OPT_ENGINE && (size_t)(c - OPT_ENGINE) < engine_settings_count &&
            o->neng < ENGINE_ARGS_MAX) {
            o->eng[o->neng].s = &engine_settings[c - OPT_ENGINE];
            o->eng[o->neng++].arg = optarg;
            return -1;
        }
        if (c >= OPT_ENGINE) {
            fprintf(stderr, "trajreplay: more than %d engine options\n", ENGINE_ARGS_MAX);
            return EXIT_USAGE;
        }
        fprintf(stderr, "trajreplay: unknown option '%s' (see --help)\n", argv[optind - 1]);
        return EXIT_USAGE;
    }
}

/* Command-line engine settings, the rate, and the object column.  Returns -1
 * to go on, else an exit status. */
static int finish_opts(trajreplay_opts_t *o)
{
    for (unsigned i = 0; i < o->neng; i++) {
        char why[160];
        if (engine_setting_parse(o->eng[i].s, o->eng[i].arg, &o->cfg, why, sizeof why)) {
            fprintf(stderr, "trajreplay: --%s: %s\n", o->eng[i].s->option, why);
            return EXIT_USAGE;
        }
    }
    for (unsigned i = 0; i < o->neng; i++) { /* given, and no effect: said */
        const char *u = engine_setting_unused(o->eng[i].s, &o->cfg);
        if (u)
            fprintf(stderr, "trajreplay: warning: --%s is set but has no effect: %s\n",
                    o->eng[i].s->option, u);
    }
    /* 1e9 / rate rounded to whole nanoseconds: the grid is exact in ns. */
    double period = 1e9 / o->rate_hz;
    if (!(period >= (double)ENGINE_PERIOD_NS_MIN && period <= (double)ENGINE_PERIOD_NS_MAX)) {
        fprintf(stderr, "trajreplay: --rate %g Hz is outside %g..%g Hz\n", o->rate_hz,
                1e9 / (double)ENGINE_PERIOD_NS_MAX, 1e9 / (double)ENGINE_PERIOD_NS_MIN);
        return EXIT_USAGE;
    }
    o->cfg.period_ns = llround(period);
    char line[CSV_FORMAT_LINE_MAX];
    engine_setpoint_t probe;
    memset(&probe, 0, sizeof probe);
    if (csv_format_format(line, sizeof line, o->object, &probe) < 0) {
        fprintf(stderr,
                "trajreplay: --object: at most %d characters, no comma, quote or "
                "control character\n",
                CSV_FORMAT_OBJECT_MAX);
        return EXIT_USAGE;
    }
    return -1;
}

/* Returns -1 to go on, else an exit status. */
static int parse_args(int argc, char **argv, trajreplay_opts_t *o)
{
    struct option lopts[FIXED_OPTS + ENGINE_ARGS_MAX + 1];
    build_long_opts(lopts, sizeof lopts / sizeof lopts[0]);
    memset(o, 0, sizeof *o);
    engine_config_default(&o->cfg);
    o->rate_hz = 100.0;
    o->progress_after_ms = PROGRESS_AFTER_MS;
    o->precision = CSV_PREC_SHORTEST;
    o->max_rows = MAX_ROWS_DEFAULT;
    o->catchup = -1; /* the engine's, unless -c */
    opterr = 0;
    int c, rc;
    while ((c = getopt_long(argc, argv, ":c:o:qhV", lopts, NULL)) != -1)
        if ((rc = parse_option(c, argv, o)) >= 0)
            return rc;
    if (argc - optind > 1 || (optind == argc && !o->config)) {
        fprintf(stderr, optind >= argc ? "trajreplay: no track file given (see --help)\n"
                                       : "trajreplay: one track file only (see --help)\n");
        return EXIT_USAGE;
    }
    if (optind < argc)
        o->input = argv[optind];
    if (o->config && (rc = trajreplay_load_config(o)) >= 0)
        return rc;
    if (!o->object)
        o->object = "replay";
    return finish_opts(o);
}

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* One replay: its inputs, outputs and what was seen. */
typedef struct {
    const trajreplay_opts_t *o;
    track_t trk;
    engine_t *e;
    replay_t r;
    int *results; /* engine_push result of each waypoint */
    svg_plot_t *plot;
    FILE *out;
    double span_s; /* track time from first to last waypoint */
    double max_v, max_a;
    double last_v;        /* speed of the previous setpoint (hard stop reports) */
    uint64_t hard_seen;   /* hard stops reported so far */
    double und_t;         /* underrun_t_s of the last underrun reported (NaN: none) */
    uint64_t und_n;       /* underruns reported */
    size_t und_next;      /* r.next when they were last looked at */
    double axis_stop_t_s; /* t_s when the per-axis limits first stopped it (NaN: never) */
    uint64_t written;     /* setpoint rows */
    engine_status_t st;
    geo_enu_t frame;          /* --geo: the track's east/north/up origin */
    int geo_no_alt;           /* ... no fix with an altitude: up 0 at its height */
    size_t heading_hint;      /* --geo: interval of the last heading evaluation */
    int64_t t_start, t_shown; /* progress line */
    int progress, shown;
    size_t reported;   /* waypoints before this one were reported if rejected */
    uint64_t rejected; /* waypoints rejected as bad data */
    uint64_t rejected_by[ENGINE_ERROR_COUNT];
    size_t first_rejected; /* index of the first one */
    uint64_t skipped_gaps; /* gaps jumped over (not --keep-gaps) */
    uint64_t skipped_ticks;
    uint64_t nonfinite;      /* rows with a NaN or infinite value: flagged ENGINE_SP_FAULT */
    size_t seen_next;        /* run_report_rejections: r.next and replay_done at */
    int seen_done;           /* its last look (verdicts come only with a push or the close) */
    uint64_t reanchors_told; /* run_report_reanchor: re-anchors said so far */
    uint64_t duplicates;     /* exact duplicates met (the first REJECT_SHOW_FIRST said) */
    char *rows;              /* rows formatted in place, written ROWS_BUF bytes at a time */
    size_t nrows;            /* bytes of them not written yet */
} run_t;

/* Rows are formatted straight into one buffer and handed to stdio a buffer
 * at a time (one copy less than fwrite per row: make bench,
 * bench_trajreplay.sh); ROW_MAX is the longest row of any form. */
#define ROWS_BUF (1 << 20)
#define ROW_MAX (CSV_FORMAT_OBJECT_MAX + 16 * (CSV_FIXED_MAX + 1) + 64 + CSV_BIN_RECORD)

static void run_flush_rows(run_t *run)
{
    if (run->nrows)
        fwrite(run->rows, 1, run->nrows, run->out);
    run->nrows = 0;
}

/* The engine, made as trajd's new_objects makes it: with -c, [daemon] catchup
 * (cfg bounds: 0 .. 1) and where the object stands at start (initial_position:
 * the output holds there and reaches the first waypoint by a transfer); then
 * --override.  Returns -1 to go on, else an exit status. */
static int run_engine(run_t *run, const trajreplay_opts_t *o)
{
    int eng_err = 0;
    run->e = engine_new(&o->cfg, &eng_err);
    if (!run->e) {
        fprintf(stderr, "trajreplay: engine: %s\n", engine_strerror(eng_err));
        return EXIT_MEMORY;
    }
    if (o->catchup >= 0)
        (void)engine_set_catchup(run->e, o->catchup);
    if (o->has_initial_position && engine_set_position(run->e, o->initial_position_m) < 0) {
        fprintf(stderr, "trajreplay: %s: object %s: initial_position outside max_abs_m\n",
                o->config, o->object);
        return EXIT_USAGE;
    }
    if (o->override > 0)
        (void)engine_set_override(run->e, o->override); /* within its range: parsed so */
    return -1;
}

/* Load the track, make the engine and open the outputs.  Returns -1 to go
 * on, else an exit status (run_free releases what was made). */
static int run_open(run_t *run, const trajreplay_opts_t *o)
{
    static char outbuf[1 << 20]; /* static: stdout may still use it at exit */
    static char rows[ROWS_BUF];
    char err[512];
    memset(run, 0, sizeof *run);
    run->o = o;
    run->out = stdout;
    run->rows = rows;
    run->seen_next = (size_t)-1;
    run->und_t = run->axis_stop_t_s = NAN;
    if (trajreplay_check_config(&o->cfg))
        return EXIT_USAGE;
    const char *same = cfg_same_file(o->input, o->output) ? o->output
                       : cfg_same_file(o->input, o->svg)  ? o->svg
                                                          : NULL;
    if (same) { /* by identity (issue 24): writing it would destroy the track */
        fprintf(stderr, "trajreplay: %s and the track %s are one file\n", same, o->input);
        return EXIT_USAGE;
    }
    if (track_load_opts(o->input, o->format, o->load_flags, &run->trk, err, sizeof err)) {
        fprintf(stderr, "trajreplay: %s\n", err);
        return EXIT_INPUT;
    }
    /* -c: about the daemon's one datum, as trajd writes it */
    if (o->origin_set && run->trk.geographic)
        (void)track_reframe(&run->trk, o->origin[0], o->origin[1], o->origin[2]);
    if (run->trk.geographic) {
        (void)geo_enu_init(run->trk.lat0_deg, run->trk.lon0_deg, run->trk.alt0_m, &run->frame);
        run->geo_no_alt = track_no_altitude(&run->trk); /* as trajd's replay transport */
    }
    for (size_t i = 0; i < run->trk.nreports; i++)
        fprintf(stderr, "trajreplay: skipped %s\n", run->trk.reports[i]);
    if (run->trk.ignored)
        fprintf(stderr,
                "trajreplay: ignored %zu record%s without a usable fix (no fix, position "
                "not available, a fast packet missing a frame, another source, an RMC whose "
                "GGA was lost in a log with altitudes)\n",
                run->trk.ignored, run->trk.ignored == 1 ? "" : "s");
    if (run->trk.skipped)
        fprintf(stderr, "trajreplay: skipped %zu bad line%s in all%s, the first: %s\n",
                run->trk.skipped, run->trk.skipped == 1 ? "" : "s",
                run->trk.skipped > run->trk.nreports ? " (the first ones listed above)" : "", err);
    int rc = run_engine(run, o);
    if (rc >= 0)
        return rc;
    run->results = malloc(run->trk.n * sizeof *run->results);
    if (o->svg)
        run->plot = svg_plot_new(SVG_POINTS_DEFAULT, run->trk.geographic);
    if (!run->results || (o->svg && !run->plot)) {
        fprintf(stderr, "trajreplay: out of memory\n");
        return EXIT_MEMORY;
    }
    if (o->output && strcmp(o->output, "-") != 0) {
        FILE *f = fopen(o->output, "w");
        if (!f) {
            fprintf(stderr, "trajreplay: %s: %s\n", o->output, strerror(errno));
            return EXIT_OUTPUT;
        }
        run->out = f;
    }
    setvbuf(run->out, outbuf, _IOFBF, sizeof outbuf);
    replay_init(&run->r, &run->trk, o->start_ns);
    run->r.results = run->results;
    run->span_s = run->trk.wp[run->trk.n - 1].t_s - run->trk.wp[0].t_s;
    if (!(run->span_s >= 0 && run->span_s < REPLAY_T_MAX_S))
        run->span_s = 0; /* backward or absurd last time: the run bound still holds */
    run->progress = !o->quiet && isatty(2);
    run->t_start = run->progress ? mono_ns() : 0;
    return -1;
}

/* Progress line on stderr (a terminal only), at most every PROGRESS_EVERY_NS. */
static void run_progress(run_t *run, const engine_setpoint_t *sp)
{
    int64_t t = mono_ns();
    if (t - run->t_start < (int64_t)run->o->progress_after_ms * 1000000 ||
        (run->shown && t - run->t_shown <= PROGRESS_EVERY_NS))
        return;
    fprintf(stderr,
            "\rtrajreplay: %zu/%zu waypoints, track time %.1f/%.1f s, "
            "%" PRIu64 " setpoints\033[K",
            run->r.next, run->trk.n, sp->t_s - run->trk.wp[0].t_s, run->span_s, run->written);
    run->t_shown = t;
    run->shown = 1;
}

/* Clear the progress line before a message (it is drawn again later). */
static void run_clear_progress(run_t *run)
{
    if (run->shown)
        fputs("\r\033[K", stderr);
    run->shown = 0;
}

/* --geo: lat_deg,lon_deg,alt_m,heading_deg appended to a row (as trajd's csv.geo). */
static int append_geo(run_t *run, const engine_setpoint_t *sp, char *line, size_t len, int n)
{
    double v[4] = {NAN, NAN, NAN, NAN};
    if (run->trk.geographic)
        (void)geo_from_enu_track(&run->frame, sp->pos_m, run->geo_no_alt, v);
    if (run->trk.nheading && isfinite(sp->t_s) && isfinite(sp->pos_m[0]))
        v[3] = angle_wrap_deg(angle_pchip_eval(run->trk.heading_t, run->trk.heading,
                                               run->trk.nheading, sp->t_s, &run->heading_hint));
    char extra[4 * (CSV_SHORTEST_MAX + 1) + 1];
    size_t m = 0;
    for (int k = 0; k < 4; k++) {
        extra[m++] = ',';
        m += (size_t)csv_shortest(extra + m, v[k]);
    }
    extra[m] = '\0';
    return csv_format_append(line, len, n, extra);
}

/* Write one setpoint row and keep its statistics. */
/* A hard stop (engine_status hard_stops: the velocity set to 0 in one tick)
 * is reported where it happened (issue 27): the track time, the position,
 * the speed lost, and the input line of the last waypoint read then. */
static void run_report_hard_stop(run_t *run, const engine_setpoint_t *sp)
{
    engine_status_t st;
    engine_status(run->e, &st);
    if (st.hard_stops <= run->hard_seen)
        return;
    run->hard_seen = st.hard_stops;
    run_clear_progress(run);
    fprintf(stderr,
            "%s:%" PRIu32 ": warning: hard stop at t = %.3f s, position (%.3f, %.3f, %.3f) m: "
            "%.3g m/s to 0 in one tick (the solved curve ended under a moving output; the "
            "line is the last waypoint read)\n",
            run->o->input, run->r.next ? run->trk.line[run->r.next - 1] : 0, sp->t_s, sp->pos_m[0],
            sp->pos_m[1], sp->pos_m[2], run->last_v);
}

/* Each underrun once the silence it met ended (issue 26), or at the end,
 * the line that of the last waypoint read then: where and why
 * (engine_underrun_format), the first REJECT_SHOW_FIRST, then one in
 * REJECT_SHOW_EVERY (all counted in the summary).  Looked at only when
 * waypoints were pushed: a silence ends with one. */
static void run_report_underrun(run_t *run, int at_end)
{
    engine_status_t st;
    char msg[320];
    if (run->r.next == run->und_next && !at_end)
        return;
    run->und_next = run->r.next;
    engine_status(run->e, &st);
    if (!engine_underrun_due(&st, run->und_t, at_end))
        return;
    run->und_t = st.underrun_t_s;
    if (++run->und_n > REJECT_SHOW_FIRST && run->und_n % REJECT_SHOW_EVERY)
        return;
    (void)engine_underrun_format(&st, msg, sizeof msg);
    run_clear_progress(run);
    fprintf(stderr, "%s:%" PRIu32 ": %s\n", run->o->input,
            run->r.next ? run->trk.line[run->r.next - 1] : 0, msg);
}

static void run_emit(run_t *run, const engine_setpoint_t *sp)
{
    if (run->nrows > ROWS_BUF - ROW_MAX)
        run_flush_rows(run);
    char *line = run->rows + run->nrows;
    size_t room = ROWS_BUF - run->nrows;
    if (run->o->binary) {
        csv_format_bin_record((unsigned char *)line, sp);
        run->nrows += CSV_BIN_RECORD;
    } else {
        int len = csv_format_format_prec(line, room, run->o->object, sp, run->o->precision);
        if (len > 0 && run->o->geo)
            len = append_geo(run, sp, line, room, len);
        if (len > 0)
            run->nrows += (size_t)len;
    }
    run->written++;
    double v = sqrt(sp->vel_m_s[0] * sp->vel_m_s[0] + sp->vel_m_s[1] * sp->vel_m_s[1] +
                    sp->vel_m_s[2] * sp->vel_m_s[2]);
    double a = sqrt(sp->acc_m_s2[0] * sp->acc_m_s2[0] + sp->acc_m_s2[1] * sp->acc_m_s2[1] +
                    sp->acc_m_s2[2] * sp->acc_m_s2[2]);
    if (v > run->max_v)
        run->max_v = v;
    if (a > run->max_a)
        run->max_a = a;
    if (run->plot)
        svg_plot_setpoint(run->plot, sp);
    if (!(v > 0) && run->last_v > 0)
        run_report_hard_stop(run, sp);
    run->last_v = v;
}

/* A new trajectory begun where nothing continued the current one (the
 * time stepped back or far ahead, a log recorded twice): said at its line,
 * with the times (it was only counted, reanchors in --summary). */
static void run_report_reanchor(run_t *run)
{
    if (run->st.reanchors <= run->reanchors_told)
        return;
    run->reanchors_told = run->st.reanchors;
    size_t i = run->st.reanchor_seq ? (size_t)run->st.reanchor_seq - 1 : 0;
    double d = run->st.reanchor_t_s - run->st.reanchor_from_t_s;
    run_clear_progress(run);
    fprintf(stderr,
            "%s:%" PRIu32 ": a new trajectory: t = %.3f s, %.3f s %s the last waypoint kept "
            "(%.3f s), and nothing after it continues that one (a clock stepped %s, a log "
            "recorded twice, a jump): the output reaches it by a transfer (re-anchor %" PRIu64
            ")\n",
            run->o->input, i < run->trk.n ? run->trk.line[i] : 0, run->st.reanchor_t_s, fabs(d),
            d < 0 ? "before" : "after", run->st.reanchor_from_t_s, d < 0 ? "back" : "ahead",
            run->st.reanchors);
}

/* "file:line: rejected (reason)" for each waypoint the engine rejected since
 * the last call: the first REJECT_SHOW_FIRST, then one in REJECT_SHOW_EVERY. */
static void run_report_rejections(run_t *run)
{
    /* the engine judges a waypoint with its neighbours: the last `judging`
     * offered have no verdict yet (replay_feed records it when it comes) */
    int done = replay_done(&run->r);
    if (run->r.next == run->seen_next && done == run->seen_done)
        return; /* no push, no close: no new verdict */
    run->seen_next = run->r.next;
    run->seen_done = done;
    engine_status(run->e, &run->st);
    run_report_reanchor(run);
    size_t judged = run->r.next > run->st.judging ? run->r.next - run->st.judging : 0;
    for (; run->reported < judged; run->reported++) {
        int rc = run->results[run->reported];
        if (rc == ENGINE_DUPLICATE && run->duplicates++ < REJECT_SHOW_FIRST) {
            run_clear_progress(run); /* counted (duplicates), and said as a rejection is */
            fprintf(stderr,
                    "%s:%" PRIu32 ": duplicate of a waypoint before it (same time and "
                    "position): dropped\n",
                    run->o->input, run->trk.line[run->reported]);
        }
        if (rc >= 0)
            continue; /* accepted, or an exact duplicate dropped */
        int e = -rc;
        if (e > 0 && e < ENGINE_ERROR_COUNT)
            run->rejected_by[e]++;
        if (run->rejected++ == 0)
            run->first_rejected = run->reported;
        if (run->rejected <= REJECT_SHOW_FIRST || run->rejected % REJECT_SHOW_EVERY == 0) {
            const char *why = engine_reason_name(e);
            run_clear_progress(run);
            fprintf(stderr, "%s:%" PRIu32 ": rejected (%s)\n", run->o->input,
                    run->trk.line[run->reported], why ? why : engine_strerror(e));
        }
        if (run->rejected == REJECT_SHOW_FIRST + 1) {
            run_clear_progress(run);
            fprintf(stderr,
                    "trajreplay: more rejected waypoints: one in %d shown, all "
                    "counted at the end\n",
                    REJECT_SHOW_EVERY);
        }
    }
}

/* param = uniform on irregular intervals: say so once, with the numbers. */
static void run_report_uniform(run_t *run)
{
    engine_status(run->e, &run->st);
    if (!run->st.uniform_irregular)
        return;
    fprintf(stderr,
            "trajreplay: %s: warning: param = uniform on irregular intervals: %" PRIu64
            " waypoints between intervals differing by more than %.2gx (worst %.3gx, at t = "
            "%.3f s): the velocity steps by that ratio there (param = time is C2 in time)\n",
            run->o->input, run->st.uniform_irregular, ENGINE_UNIFORM_RATIO_WARN,
            run->st.uniform_ratio_max, run->st.uniform_ratio_t_s);
}

/* issue 32: a track that persistently exceeds the per-axis limits, whose
 * lag therefore grows: say so once, with the time lost. */
#define AXIS_LOST_WARN_FRAC 0.1
static void run_report_axis(run_t *run)
{
    engine_status(run->e, &run->st);
    if (!(run->st.axis_lost_s > AXIS_LOST_WARN_FRAC * run->span_s))
        return;
    fprintf(stderr,
            "trajreplay: %s: warning: the track exceeds the per-axis limits (axis_max_*) "
            "persistently: the time scaling slowed %" PRIu64
            " segments and lost %.1f s over %.1f s of track (its lag grows by that)\n",
            run->o->input, run->st.axis_slowed, run->st.axis_lost_s, run->span_s);
}

/* The same for the object's own speed and acceleration limits (the
 * profile's max_speed_m_s, max_accel_m_s2): a curve that bends harder than
 * them throughout (jittery stamps) plays slower than its track. */
static void run_report_limits(run_t *run)
{
    if (!(run->st.limits_lost_s > AXIS_LOST_WARN_FRAC * run->span_s))
        return;
    fprintf(stderr,
            "trajreplay: %s: warning: the curve exceeds the object's speed or acceleration "
            "limit (max_speed_m_s, max_accel_m_s2: the profile's) persistently: the time "
            "scaling slowed %" PRIu64 " segments and lost %.1f s over %.1f s of track (its lag "
            "grows by that; jittery stamps bend the curve: --profile none, or a higher "
            "max_accel_m_s2)\n",
            run->o->input, run->st.limits_slowed, run->st.limits_lost_s, run->span_s);
}

/* The per-reason count of rejections, if any. */
static void run_report_rejected_total(const run_t *run)
{
    if (!run->rejected)
        return;
    char reasons[256] = "";
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++) {
        size_t n = strlen(reasons);
        if (run->rejected_by[e])
            snprintf(reasons + n, sizeof reasons - n, "%s%s %" PRIu64, n ? ", " : "",
                     engine_reason_name(e) ? engine_reason_name(e) : engine_strerror(e),
                     run->rejected_by[e]);
    }
    fprintf(stderr,
            "trajreplay: %s: rejected %" PRIu64 " of %zu waypoints (%s), the first at "
            "line %" PRIu32 "\n",
            run->o->input, run->rejected, run->trk.n, reasons, run->trk.line[run->first_rejected]);
    if (run->rejected * 10 > run->trk.n) /* issue 24: never a quiet exit 0 for a lost track */
        fprintf(stderr,
                "trajreplay: %s: warning: %.1f %% of the track's fixes were refused (more than "
                "10 %%): check the profile, the time column and the units (--strict: exit 6)\n",
                run->o->input, 100.0 * (double)run->rejected / (double)run->trk.n);
}

/*
 * After the row of tick k: while the engine is stalled (holds, and nothing
 * can change before the next push) and the next waypoint is due more than
 * max_gap_s after now_ns, the tick to jump to (the first one at or after
 * that waypoint's due time), else k + 1.
 */
static uint64_t run_next_tick(run_t *run, uint64_t k, int64_t now_ns, const engine_setpoint_t *sp)
{
    if (run->o->keep_gaps || !(sp->flags & ENGINE_SP_HOLD) || replay_done(&run->r))
        return k + 1;
    engine_status(run->e, &run->st);
    if (!run->st.stalled)
        return k + 1; /* holding for a tick between two trajectories, say */
    int64_t due = replay_next_due_ns(&run->r);
    const int64_t period = run->o->cfg.period_ns;
    int sil = run->st.silence_at_ns < due; /* a short trajectory's silence first */
    if (sil) /* to the tick before it: the holds skipped, it ends at the tick after */
        due = run->st.silence_at_ns - period;
    else if (due == INT64_MAX || (double)(due - now_ns) <= run->o->cfg.max_gap_s * 1e9)
        return k + 1;
    /* due > now_ns >= 0 here, so the division rounds up a positive number */
    uint64_t next = (uint64_t)((due + period - 1) / period);
    if (next <= k + 1)
        return k + 1;
    run->skipped_gaps++;
    run->skipped_ticks += next - k - 1;
    return next;
}

/* Tick the engine on the virtual clock until the track ran out.  Returns 0
 * or an exit status (EXIT_INPUT: nothing usable, EXIT_MAX_ROWS). */
static int run_ticks(run_t *run)
{
    const int64_t period = run->o->cfg.period_ns;
    if (run->o->binary) {
        unsigned char hdr[CSV_BIN_HEADER];
        csv_format_bin_header(hdr, run->o->object);
        fwrite(hdr, 1, sizeof hdr, run->out);
    } else {
        char line[CSV_FORMAT_LINE_MAX];
        int len = csv_format_header(line, sizeof line);
        if (run->o->geo)
            len = csv_format_append(line, sizeof line, len, ",lat_deg,lon_deg,alt_m,heading_deg");
        if (len > 0)
            fwrite(line, 1, (size_t)len, run->out);
    }
    int status = 0, skipped = 0;
    uint64_t tail = 0;
    for (uint64_t k = 0;;) {
        if (run->o->max_rows && run->written >= run->o->max_rows) {
            run_clear_progress(run);
            fprintf(stderr,
                    "trajreplay: stopped after %" PRIu64 " rows (--max-rows), %zu of "
                    "%zu waypoints replayed: raise --max-rows (0 = no limit)\n",
                    run->written, run->r.next, run->trk.n);
            status = EXIT_MAX_ROWS;
            break;
        }
        int64_t now = (int64_t)k * period;
        engine_setpoint_t sp;
        replay_feed(&run->r, run->e, now);
        run_report_rejections(run);
        (void)engine_tick(run->e, now, &sp);
        run_report_underrun(run, 0);
        if (engine_axis_lag_over(run->e)) { /* max_lag_s passed: stop on the path (issue 32) */
            (void)engine_stop(run->e);
            if (isnan(run->axis_stop_t_s))
                run->axis_stop_t_s = sp.t_s;
        }
        if (skipped)
            sp.flags |= ENGINE_SP_SKIPPED;
        if (!(sp.flags & ENGINE_SP_NO_POSITION) &&
            !isfinite(sp.pos_m[0] + sp.pos_m[1] + sp.pos_m[2] + sp.vel_m_s[0] + sp.vel_m_s[1] +
                      sp.vel_m_s[2] + sp.acc_m_s2[0] + sp.acc_m_s2[1] + sp.acc_m_s2[2])) {
            sp.flags |= ENGINE_SP_FAULT; /* never an unflagged NaN row (issue 24) */
            run->nonfinite++;
        }
        run_emit(run, &sp);
        if (replay_done(&run->r) && (sp.flags & ENGINE_SP_HOLD)) {
            engine_status(run->e, &run->st);
            /* At rest with nothing buffered once the track ran out: the
             * end of the last trajectory, or nothing was ever accepted. */
            if (run->st.buffered == 0 && run->st.accepted == 0) {
                run_clear_progress(run);
                fprintf(stderr, "trajreplay: %s: no usable waypoint: all %zu rejected\n",
                        run->o->input, run->trk.n);
                status = EXIT_INPUT;
                break;
            }
            if (run->st.buffered == 0 && ++tail > TAIL_TICKS)
                break;
        }
        if ((run->written & 1023) == 0 && ferror(run->out))
            break; /* a full disk: stop now, reported by the caller (rows are
                    * written a buffer at a time, run_flush_rows) */
        if (run->progress && (run->written & 1023) == 0)
            run_progress(run, &sp);
        uint64_t next = run_next_tick(run, k, now, &sp);
        skipped = next != k + 1;
        if (skipped) /* bring the engine to the tick before (no waypoint is due
                      * there), so the next waypoint meets it where it would have */
            (void)engine_tick(run->e, (int64_t)(next - 1) * period, &sp);
        k = next;
    }
    run_flush_rows(run);
    run_clear_progress(run);
    engine_status(run->e, &run->st);
    return status;
}

/* The --svg drawing.  Returns 0 or EXIT_OUTPUT. */
static int run_svg(run_t *run)
{
    const trajreplay_opts_t *o = run->o;
    for (size_t i = 0; i < run->trk.n; i++)
        svg_plot_waypoint(run->plot, run->trk.wp[i].pos_m[0], run->trk.wp[i].pos_m[1],
                          i < run->r.next && run->results[i] >= 0);
    char title[512];
    engine_config_t rc = o->cfg; /* fragment and overlap as resolved from auto */
    if (engine_config_resolve(&o->cfg, &rc) < 0)
        rc = o->cfg;
    snprintf(title, sizeof title,
             "%s: %zu waypoints, %s %s, F=%u O=%u, %g Hz; setpoints drawn: 1 in %zu (%zu)",
             o->input, run->trk.n,
             engine_setting_enum_name(engine_setting_find("method"), o->cfg.method),
             engine_setting_enum_name(engine_setting_find("param"), o->cfg.param), rc.fragment,
             rc.overlap, o->rate_hz, svg_plot_stride(run->plot), svg_plot_kept(run->plot));
    FILE *f = fopen(o->svg, "w");
    if (!f) {
        fprintf(stderr, "trajreplay: %s: %s\n", o->svg, strerror(errno));
        return EXIT_OUTPUT;
    }
    int wrc = svg_plot_write(run->plot, f, title);
    if (fclose(f) || wrc) {
        fprintf(stderr, "trajreplay: %s: write error\n", o->svg);
        return EXIT_OUTPUT;
    }
    return 0;
}

/* Close the output (status: the exit status so far) and free everything.
 * Returns the exit status. */
static int run_close(run_t *run, int status)
{
    const char *name = run->o->output ? run->o->output : "stdout";
    if (run->out && (fflush(run->out) || ferror(run->out)) && status != EXIT_OUTPUT) {
        fprintf(stderr, "trajreplay: %s: write error: %s\n", name, strerror(errno));
        status = EXIT_OUTPUT;
    }
    if (run->out && run->out != stdout && fclose(run->out) && !status) {
        fprintf(stderr, "trajreplay: %s: %s\n", name, strerror(errno));
        status = EXIT_OUTPUT;
    }
    free(run->results);
    svg_plot_free(run->plot);
    engine_free(run->e);
    track_free(&run->trk);
    return status;
}

int main(int argc, char **argv)
{
    trajreplay_opts_t o;
    run_t run;
    if (stdfds_open() < 0)
        return 71; /* EX_OSERR: no /dev/null */
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0)
        return rc;
    int status = run_open(&run, &o);
    if (status >= 0)
        return run_close(&run, status);
    status = run_ticks(&run);
    if (fflush(run.out) || ferror(run.out)) {
        fprintf(stderr, "trajreplay: %s: write error: %s\n", o.output ? o.output : "stdout",
                strerror(errno));
        status = EXIT_OUTPUT;
    }
    if (run.plot && run_svg(&run))
        status = EXIT_OUTPUT;
    run_report_underrun(&run, 1);
    run_report_rejected_total(&run);
    run_report_uniform(&run);
    run_report_axis(&run);
    run_report_limits(&run);
    if (o.summary) {
        replay_print_summary(&run.trk, &run.r, &run.st, run.max_v, run.max_a, run.written);
        fprintf(stderr, "summary: skipped_gaps %" PRIu64 "\nsummary: skipped_ticks %" PRIu64 "\n",
                run.skipped_gaps, run.skipped_ticks);
        replay_print_delay(run.e);
    }
    size_t judged = run.r.next > run.st.judging ? run.r.next - run.st.judging : 0;
    if (replay_report_axis_stop(o.input, &run.trk, run.results, judged, &run.st, run.axis_stop_t_s,
                                o.cfg.max_lag_s) &&
        !status)
        status = EXIT_AXIS;
    if (!status && o.strict && (run.rejected || run.trk.skipped)) {
        fprintf(stderr,
                "trajreplay: --strict: %" PRIu64 " waypoint%s rejected, %zu line%s "
                "skipped\n",
                run.rejected, run.rejected == 1 ? "" : "s", run.trk.skipped,
                run.trk.skipped == 1 ? "" : "s");
        status = EXIT_STRICT;
    }
    uint64_t hard = run.st.hard_stops, numeric = run.st.rejected_by[ENGINE_ENUMERIC];
    if (hard) /* the time scaling brakes in time (engine_scale.c scale_remaining()): loud should it not */
        fprintf(stderr,
                "trajreplay: %s: warning: %" PRIu64 " hard stop%s (velocity to 0 in one tick: "
                "the solved curve ended under a moving output)\n",
                o.input, hard, hard == 1 ? "" : "s");
    if (run.nonfinite && status != EXIT_OUTPUT && status != EXIT_MEMORY) {
        fprintf(stderr,
                "trajreplay: %s: internal fault: %" PRIu64 " rows with a NaN or infinite value "
                "(flagged %#x): a defect of trajd; please report it with the track (exit %d)\n",
                o.input, run.nonfinite, ENGINE_SP_FAULT, EXIT_INTERNAL);
        status = EXIT_INTERNAL;
    }
    if (numeric && status != EXIT_OUTPUT && status != EXIT_MEMORY) {
        fprintf(stderr,
                "trajreplay: %s: internal fault: %" PRIu64 " numeric refusal%s of finite "
                "data: a defect of trajd, not of the track; please report it with the track "
                "(exit %d)\n",
                o.input, numeric, numeric == 1 ? "" : "s", EXIT_INTERNAL);
        status = EXIT_INTERNAL;
    }
    return run_close(&run, status);
}
