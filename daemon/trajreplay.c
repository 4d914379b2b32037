/*
 * trajreplay - replay a logged track through the engine on a virtual clock
 * and write the setpoints the daemon would stream (daemon/csv/csv_format.h format).
 *
 * Tick k is at engine time now_ns = k * period_ns; for every tick,
 * replay_feed(now) then engine_tick(now), exactly as the daemon does, so the
 * output is byte-identical to trajd's CSV output for the same input and
 * settings.  No sleeping: a long track replays as fast as the CPU allows.
 *
 * Exit status: 0 done; 1 the track could not be loaded; 2 usage or an
 * invalid engine configuration; 3 writing an output failed; 4 the engine
 * did not reach FINISHED within the tick bound (a bug, reported as such).
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

#include "engine.h"
#include "replay.h"
#include "csv_format.h"
#include "svg.h"
#include "track.h"

#define TRAJREPLAY_VERSION "0.1"

enum { EXIT_INPUT = 1, EXIT_USAGE = 2, EXIT_OUTPUT = 3, EXIT_ENGINE = 4 };

/* Ticks written after the engine reports FINISHED for good: they show the
 * rest state (zero velocity, the last waypoint) to whoever reads the file. */
#define TAIL_TICKS 3
/* Bound on the virtual run: twice the track's duration plus an hour covers
 * the start-up lookahead, gap transfers and the final run-out many times
 * over; reaching it means the engine never finished. */
#define RUN_BOUND_EXTRA_S 3600.0
/* Progress line (stderr a terminal only): from PROGRESS_AFTER_MS into the
 * run (--progress-after), at most every PROGRESS_EVERY_NS. */
#define PROGRESS_AFTER_MS 500
#define PROGRESS_EVERY_NS 250000000LL

typedef struct {
    const char *input;
    const char *output;
    const char *svg;
    const char *object;
    track_format_t format;
    unsigned load_flags;
    int summary;
    int quiet;
    unsigned progress_after_ms;
    double rate_hz;
    engine_config_t cfg;
} opts_t;

static void usage(FILE *f)
{
    fputs(
        "usage: trajreplay [options] TRACK\n"
        "Replay a logged track (CSV t,x,y,z / t,lat,lon,alt, or GPX) through the trajd\n"
        "engine on a virtual clock and write the setpoints as CSV.\n"
        "\n"
        "  --rate HZ            output rate (default 100)\n"
        "  --fragment F         waypoints per fragment (default: engine's)\n"
        "  --overlap O          waypoints shared by consecutive fragments (even, < F)\n"
        "  --param P            uniform | time (knots at the timestamps)\n"
        "  --ends E             held | multiple | natural | clamped | rest\n"
        "  --start-vel VX,VY,VZ start velocity for --ends clamped, m/s (default 0,0,0)\n"
        "  --end-vel VX,VY,VZ   end velocity for --ends clamped, m/s (default 0,0,0)\n"
        "  --method M           bspline | cubic | smooth\n"
        "  --smooth-window W    smooth: waypoints per least-squares fit (default 24)\n"
        "  --smooth-ctrl C      smooth: control points per fit (default 6)\n"
        "  --max-gap S          a longer interval ends the trajectory and starts a new one\n"
        "  --max-speed M_S      reject waypoints implying a higher speed (0 = no limit)\n"
        "  --max-accel M_S2     reject waypoints implying a higher acceleration from the\n"
        "                       two before (timestamp jitter; default 30, 0 = no limit)\n"
        "  --format F           auto | xyz | latlon | gpx | path (default auto;\n"
        "                       path: lines and arcs, lib/spline/path.h, auto for *.path)\n"
        "  --skip-bad           skip and count malformed lines instead of failing\n"
        "  --object NAME        value of the object column (default \"replay\")\n"
        "  -o, --output FILE    setpoint CSV (default stdout; \"-\" = stdout)\n"
        "  --svg FILE           draw waypoints, curve and speed profile\n"
        "  --summary            counters on stderr at the end\n"
        "  -q, --quiet          no progress line\n"
        "  --progress-after MS  progress line (stderr a terminal only) after MS ms (default 500)\n"
        "  -h, --help           this text\n"
        "  -V, --version        version\n"
        "\n"
        "Exit status: 0 ok, 1 track not loadable, 2 usage or configuration,\n"
        "3 output write failed, 4 engine did not finish.\n",
        f);
}

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

static int parse_vec3(const char *s, double v[3])
{
    char buf[256];
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    for (int k = 0; k < 3; k++) {
        if (!tok || parse_double(tok, &v[k]))
            return -1;
        tok = strtok_r(NULL, ",", &save);
    }
    return tok ? -1 : 0;
}

static int lookup(const char *s, const char *const *names, int n)
{
    for (int i = 0; i < n; i++)
        if (strcmp(s, names[i]) == 0)
            return i;
    return -1;
}

static const char *const param_names[] = {"uniform", "time"};
static const char *const ends_names[] = {"held", "multiple", "natural", "clamped", "rest"};
static const char *const method_names[] = {"bspline", "cubic", "smooth"};

/* Short names of the reasons a waypoint can be refused for bad data
 * (NULL for codes engine_push does not return for data). */
static const char *reason_name(int e)
{
    switch (e) {
    case ENGINE_ENOTFINITE: return "not_finite";
    case ENGINE_ERANGE: return "range";
    case ENGINE_EBACKWARDS: return "backwards";
    case ENGINE_ESAMETIME: return "same_time";
    case ENGINE_ESPEED: return "speed";
    case ENGINE_ENUMERIC: return "numeric";
    case ENGINE_EACCEL: return "accel";
    default: return NULL;
    }
}

enum {
    OPT_RATE = 256, OPT_FRAGMENT, OPT_OVERLAP, OPT_PARAM, OPT_ENDS, OPT_METHOD, OPT_SMOOTH_WINDOW, OPT_SMOOTH_CTRL, OPT_FORMAT,
    OPT_SVG, OPT_SUMMARY, OPT_MAX_GAP, OPT_MAX_SPEED, OPT_MAX_ACCEL, OPT_SKIP_BAD, OPT_OBJECT,
    OPT_START_VEL, OPT_END_VEL, OPT_PROGRESS_AFTER,
};

/* Returns -1 to go on, else an exit status. */
static int parse_args(int argc, char **argv, opts_t *o)
{
    static const struct option lopts[] = {
        {"rate", required_argument, NULL, OPT_RATE},
        {"fragment", required_argument, NULL, OPT_FRAGMENT},
        {"overlap", required_argument, NULL, OPT_OVERLAP},
        {"param", required_argument, NULL, OPT_PARAM},
        {"ends", required_argument, NULL, OPT_ENDS},
        {"method", required_argument, NULL, OPT_METHOD},
        {"smooth-window", required_argument, NULL, OPT_SMOOTH_WINDOW},
        {"smooth-ctrl", required_argument, NULL, OPT_SMOOTH_CTRL},
        {"format", required_argument, NULL, OPT_FORMAT},
        {"svg", required_argument, NULL, OPT_SVG},
        {"summary", no_argument, NULL, OPT_SUMMARY},
        {"max-gap", required_argument, NULL, OPT_MAX_GAP},
        {"max-speed", required_argument, NULL, OPT_MAX_SPEED},
        {"max-accel", required_argument, NULL, OPT_MAX_ACCEL},
        {"skip-bad", no_argument, NULL, OPT_SKIP_BAD},
        {"object", required_argument, NULL, OPT_OBJECT},
        {"start-vel", required_argument, NULL, OPT_START_VEL},
        {"end-vel", required_argument, NULL, OPT_END_VEL},
        {"progress-after", required_argument, NULL, OPT_PROGRESS_AFTER},
        {"output", required_argument, NULL, 'o'},
        {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'},
        {"version", no_argument, NULL, 'V'},
        {NULL, 0, NULL, 0},
    };
    int c, k;
    memset(o, 0, sizeof *o);
    engine_config_default(&o->cfg);
    o->rate_hz = 100.0;
    o->progress_after_ms = PROGRESS_AFTER_MS;
    o->object = "replay";
    opterr = 0;
    while ((c = getopt_long(argc, argv, ":o:qhV", lopts, NULL)) != -1) {
        switch (c) {
        case OPT_RATE:
            if (parse_double(optarg, &o->rate_hz) || o->rate_hz <= 0) {
                fprintf(stderr, "trajreplay: --rate: '%s' is not a positive number of Hz\n", optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_FRAGMENT:
            if (parse_uint(optarg, &o->cfg.fragment)) {
                fprintf(stderr, "trajreplay: --fragment: '%s' is not a count\n", optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_OVERLAP:
            if (parse_uint(optarg, &o->cfg.overlap)) {
                fprintf(stderr, "trajreplay: --overlap: '%s' is not a count\n", optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_PARAM:
            if ((k = lookup(optarg, param_names, 2)) < 0) {
                fprintf(stderr, "trajreplay: --param: '%s' is not uniform or time\n", optarg);
                return EXIT_USAGE;
            }
            o->cfg.param = (engine_param_t)k;
            break;
        case OPT_ENDS:
            if ((k = lookup(optarg, ends_names, 5)) < 0) {
                fprintf(stderr, "trajreplay: --ends: '%s' is not held, multiple, natural, "
                        "clamped or rest\n", optarg);
                return EXIT_USAGE;
            }
            o->cfg.ends = (engine_ends_t)k;
            break;
        case OPT_METHOD:
            if ((k = lookup(optarg, method_names, 3)) < 0) {
                fprintf(stderr, "trajreplay: --method: '%s' is not bspline, cubic or smooth\n",
                        optarg);
                return EXIT_USAGE;
            }
            o->cfg.method = (engine_method_t)k;
            break;
        case OPT_SMOOTH_WINDOW:
        case OPT_SMOOTH_CTRL:
            if (parse_uint(optarg, c == OPT_SMOOTH_WINDOW ? &o->cfg.smooth_window
                                                          : &o->cfg.smooth_ctrl)) {
                fprintf(stderr, "trajreplay: --%s: '%s' is not a count\n",
                        c == OPT_SMOOTH_WINDOW ? "smooth-window" : "smooth-ctrl", optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_FORMAT:
            if (track_format_parse(optarg, &o->format)) {
                fprintf(stderr, "trajreplay: --format: '%s' is not auto, xyz, latlon, gpx or path\n",
                        optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_SVG: o->svg = optarg; break;
        case OPT_SUMMARY: o->summary = 1; break;
        case OPT_SKIP_BAD: o->load_flags |= TRACK_SKIP_BAD; break;
        case OPT_OBJECT: o->object = optarg; break;
        case OPT_MAX_GAP:
            if (parse_double(optarg, &o->cfg.max_gap_s) || o->cfg.max_gap_s <= 0) {
                fprintf(stderr, "trajreplay: --max-gap: '%s' is not a positive number of seconds\n",
                        optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_MAX_SPEED:
            if (parse_double(optarg, &o->cfg.max_speed_m_s) || o->cfg.max_speed_m_s < 0) {
                fprintf(stderr, "trajreplay: --max-speed: '%s' is not a speed >= 0 in m/s\n",
                        optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_MAX_ACCEL:
            if (parse_double(optarg, &o->cfg.max_accel_m_s2) || o->cfg.max_accel_m_s2 < 0) {
                fprintf(stderr,
                        "trajreplay: --max-accel: '%s' is not an acceleration >= 0 in m/s^2\n",
                        optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_START_VEL:
        case OPT_END_VEL:
            if (parse_vec3(optarg, c == OPT_START_VEL ? o->cfg.start_vel_m_s : o->cfg.end_vel_m_s)) {
                fprintf(stderr, "trajreplay: --%s: '%s' is not VX,VY,VZ in m/s\n",
                        c == OPT_START_VEL ? "start-vel" : "end-vel", optarg);
                return EXIT_USAGE;
            }
            break;
        case OPT_PROGRESS_AFTER:
            if (parse_uint(optarg, &o->progress_after_ms)) {
                fprintf(stderr, "trajreplay: --progress-after: '%s' is not milliseconds\n", optarg);
                return EXIT_USAGE;
            }
            break;
        case 'o': o->output = optarg; break;
        case 'q': o->quiet = 1; break;
        case 'h': usage(stdout); return 0;
        case 'V': printf("trajreplay %s\n", TRAJREPLAY_VERSION); return 0;
        case ':':
            fprintf(stderr, "trajreplay: %s needs a value\n", argv[optind - 1]);
            return EXIT_USAGE;
        default:
            fprintf(stderr, "trajreplay: unknown option '%s' (see --help)\n", argv[optind - 1]);
            return EXIT_USAGE;
        }
    }
    if (optind != argc - 1) {
        fprintf(stderr, optind >= argc ? "trajreplay: no track file given (see --help)\n"
                                       : "trajreplay: one track file only (see --help)\n");
        return EXIT_USAGE;
    }
    o->input = argv[optind];
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
        fprintf(stderr, "trajreplay: --object: at most %d characters, no comma, quote or "
                "control character\n", CSV_FORMAT_OBJECT_MAX);
        return EXIT_USAGE;
    }
    return -1;
}

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* One "summary: name value" line each, so scripts can read them.  rejected
 * counts bad data only: ENGINE_EFULL refusals are flow control, retried by
 * the replay, and shown as full_retries. */
static void print_summary(const track_t *trk, const replay_t *r, const engine_status_t *st,
                          double max_v, double max_a, uint64_t ticks)
{
    uint64_t rejected = 0;
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++)
        if (e != ENGINE_EFULL)
            rejected += st->rejected_by[e];
    fprintf(stderr,
            "summary: waypoints %zu\n"
            "summary: skipped_lines %zu\n"
            "summary: accepted %" PRIu64 "\n"
            "summary: duplicates %" PRIu64 "\n"
            "summary: rejected %" PRIu64 "\n",
            trk->n, trk->skipped, st->accepted, st->duplicates, rejected);
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++)
        if (e != ENGINE_EFULL && reason_name(e))
            fprintf(stderr, "summary: rejected_%s %" PRIu64 "\n", reason_name(e),
                    st->rejected_by[e]);
    fprintf(stderr,
            "summary: full_retries %" PRIu64 "\n"
            "summary: underruns %" PRIu64 "\n"
            "summary: underrun_ticks %" PRIu64 "\n"
            "summary: gaps %" PRIu64 "\n"
            "summary: tracks %" PRIu64 "\n"
            "summary: setpoints %" PRIu64 "\n"
            "summary: max_speed_m_s %.6g\n"
            "summary: max_acc_m_s2 %.6g\n",
            r->retries, st->underruns, st->underrun_ticks, st->gaps, st->tracks, ticks,
            max_v, max_a);
}

int main(int argc, char **argv)
{
    opts_t o;
    int rc = parse_args(argc, argv, &o);
    if (rc >= 0)
        return rc;

    const char *why = NULL;
    if (engine_config_check(&o.cfg, &why)) {
        fprintf(stderr, "trajreplay: invalid engine configuration: %s\n", why ? why : "?");
        return EXIT_USAGE;
    }

    track_t trk;
    char err[512];
    if (track_load_opts(o.input, o.format, o.load_flags, &trk, err, sizeof err)) {
        fprintf(stderr, "trajreplay: %s\n", err);
        return EXIT_INPUT;
    }
    if (trk.skipped)
        fprintf(stderr, "trajreplay: skipped %zu bad line%s, the first: %s\n", trk.skipped,
                trk.skipped == 1 ? "" : "s", err);

    int status = 0, eng_err = 0;
    engine_t *e = NULL;
    svg_plot_t *plot = NULL;
    int *results = NULL;
    FILE *out = stdout;
    static char outbuf[1 << 20]; /* static: stdout may still use it at exit */

    e = engine_new(&o.cfg, &eng_err);
    if (!e) {
        fprintf(stderr, "trajreplay: engine: %s\n", engine_strerror(eng_err));
        status = EXIT_ENGINE;
        goto out;
    }
    results = malloc(trk.n * sizeof *results);
    if (o.svg)
        plot = svg_plot_new(SVG_POINTS_DEFAULT, trk.geographic);
    if (!results || (o.svg && !plot)) {
        fprintf(stderr, "trajreplay: out of memory\n");
        status = EXIT_ENGINE;
        goto out;
    }
    if (o.output && strcmp(o.output, "-") != 0) {
        out = fopen(o.output, "w");
        if (!out) {
            fprintf(stderr, "trajreplay: %s: %s\n", o.output, strerror(errno));
            out = stdout;
            status = EXIT_OUTPUT;
            goto out;
        }
    }
    setvbuf(out, outbuf, _IOFBF, sizeof outbuf);

    char line[CSV_FORMAT_LINE_MAX];
    int len = csv_format_header(line, sizeof line);
    fwrite(line, 1, (size_t)len, out);

    replay_t r;
    replay_init(&r, &trk, 0);
    r.results = results;

    const int64_t period = o.cfg.period_ns;
    double span_s = trk.wp[trk.n - 1].t_s - trk.wp[0].t_s;
    if (!(span_s >= 0 && span_s < REPLAY_T_MAX_S))
        span_s = 0; /* backward or absurd last time: the bound below still holds */
    const uint64_t max_ticks = (uint64_t)((2 * span_s + RUN_BOUND_EXTRA_S) * 1e9 / (double)period);

    int progress = !o.quiet && isatty(2);
    int64_t t_start = progress ? mono_ns() : 0, t_shown = 0;
    int shown = 0;

    double max_v = 0, max_a = 0;
    uint64_t k = 0, tail = 0, written = 0;
    engine_status_t st;
    for (;; k++) {
        if (k > max_ticks) {
            fprintf(stderr, "trajreplay: the engine did not finish within %" PRIu64 " ticks "
                    "(%.0f s of track time): engine bug\n", max_ticks,
                    (double)max_ticks * (double)period * 1e-9);
            status = EXIT_ENGINE;
            break;
        }
        int64_t now = (int64_t)k * period;
        engine_setpoint_t sp;
        replay_feed(&r, e, now);
        (void)engine_tick(e, now, &sp);
        len = csv_format_format(line, sizeof line, o.object, &sp);
        if (len > 0)
            fwrite(line, 1, (size_t)len, out);
        written++;
        double v = sqrt(sp.vel_m_s[0] * sp.vel_m_s[0] + sp.vel_m_s[1] * sp.vel_m_s[1] +
                        sp.vel_m_s[2] * sp.vel_m_s[2]);
        double a = sqrt(sp.acc_m_s2[0] * sp.acc_m_s2[0] + sp.acc_m_s2[1] * sp.acc_m_s2[1] +
                        sp.acc_m_s2[2] * sp.acc_m_s2[2]);
        if (v > max_v)
            max_v = v;
        if (a > max_a)
            max_a = a;
        if (plot)
            svg_plot_setpoint(plot, &sp);
        if (replay_done(&r) && sp.state == ENGINE_STATE_FINISHED) {
            engine_status(e, &st);
            /* FINISHED with nothing buffered: the end of the last
             * trajectory, not a rest between two (after a gap). */
            if (st.buffered == 0 && ++tail > TAIL_TICKS)
                break;
        }
        if ((k & 1023) == 0 && ferror(out))
            break; /* a full disk: stop now, reported below */
        if (progress && (k & 1023) == 0) {
            int64_t t = mono_ns();
            if (t - t_start >= (int64_t)o.progress_after_ms * 1000000 &&
                (!shown || t - t_shown > PROGRESS_EVERY_NS)) {
                fprintf(stderr, "\rtrajreplay: %zu/%zu waypoints, track time %.1f/%.1f s, "
                        "%" PRIu64 " setpoints\033[K", r.next, trk.n, sp.t_s - trk.wp[0].t_s, span_s,
                        written);
                t_shown = t;
                shown = 1;
            }
        }
    }
    if (shown)
        fputs("\r\033[K", stderr);
    engine_status(e, &st);

    if (fflush(out) || ferror(out)) {
        fprintf(stderr, "trajreplay: %s: write error: %s\n", o.output ? o.output : "stdout",
                strerror(errno));
        status = EXIT_OUTPUT;
    }

    if (plot) {
        for (size_t i = 0; i < trk.n; i++)
            svg_plot_waypoint(plot, trk.wp[i].pos_m[0], trk.wp[i].pos_m[1],
                              i < r.next && results[i] >= 0);
        char title[512];
        snprintf(title, sizeof title, "%s: %zu waypoints, %s %s, F=%u O=%u, %g Hz", o.input,
                 trk.n, method_names[o.cfg.method], param_names[o.cfg.param], o.cfg.fragment,
                 o.cfg.overlap, o.rate_hz);
        FILE *f = fopen(o.svg, "w");
        if (!f) {
            fprintf(stderr, "trajreplay: %s: %s\n", o.svg, strerror(errno));
            status = EXIT_OUTPUT;
        } else {
            int wrc = svg_plot_write(plot, f, title);
            if (fclose(f) || wrc) {
                fprintf(stderr, "trajreplay: %s: write error\n", o.svg);
                status = EXIT_OUTPUT;
            }
        }
    }
    if (o.summary)
        print_summary(&trk, &r, &st, max_v, max_a, written);

out:
    if (out != stdout) {
        if (fclose(out) && !status) {
            fprintf(stderr, "trajreplay: %s: %s\n", o.output, strerror(errno));
            status = EXIT_OUTPUT;
        }
    } else if (fflush(stdout) && !status) {
        status = EXIT_OUTPUT;
    }
    free(results);
    svg_plot_free(plot);
    engine_free(e);
    track_free(&trk);
    return status;
}
