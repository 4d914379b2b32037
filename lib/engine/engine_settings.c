/*
 * engine_settings.c - the configuration stage: the table of the engine's
 * settings (engine_settings.h: names, ranges, parsing, formatting) and the
 * resolution of a configuration (engine.h): the defaults, the profiles'
 * limits, fragment and overlap picked for accuracy and max_lookahead, the
 * lookahead they imply and the check of a whole configuration.  It owns
 * engine_config_t and what a resolved one implies for an engine's sizes
 * (engine_cfg_*, engine_int.h, read by engine_new).
 */
#include "engine_settings.h"
#include "engine_int.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "accept.h"
#include "ends.h"
#include "frag.h"
#include "lsq.h"

static const char *const method_names[] = {
    [ENGINE_METHOD_BSPLINE] = "bspline",
    [ENGINE_METHOD_CUBIC] = "cubic",
    [ENGINE_METHOD_SMOOTH] = "smooth",
    [ENGINE_METHOD_HERMITE] = "hermite",
    [ENGINE_METHOD_HERMITE_CENTRED] = "hermite-centred",
    [ENGINE_METHOD_HERMITE_C2] = "hermite-c2",
    [ENGINE_METHOD_HERMITE_C2_CENTRED] = "hermite-c2-centred",
    NULL,
};
static const char *const param_names[] = {
    [ENGINE_PARAM_UNIFORM] = "uniform",
    [ENGINE_PARAM_TIME] = "time",
    NULL,
};
static const char *const ends_names[] = {
    [ENGINE_ENDS_HELD] = "held",       [ENGINE_ENDS_MULTIPLE] = "multiple",
    [ENGINE_ENDS_NATURAL] = "natural", [ENGINE_ENDS_CLAMPED] = "clamped",
    [ENGINE_ENDS_REST] = "rest",       NULL,
};

static const char *const profile_names[] = {
    [ENGINE_PROFILE_AUTO] = "auto",
    [ENGINE_PROFILE_VESSEL] = "vessel",
    [ENGINE_PROFILE_ROAD] = "road",
    [ENGINE_PROFILE_AIR] = "air",
    [ENGINE_PROFILE_MACHINE] = "machine",
    [ENGINE_PROFILE_NONE] = "none",
    NULL,
};

/* Enum fields are read and written as int. */
_Static_assert(sizeof(engine_method_t) == sizeof(int), "engine_method_t is not int-sized");
_Static_assert(sizeof(engine_param_t) == sizeof(int), "engine_param_t is not int-sized");
_Static_assert(sizeof(engine_ends_t) == sizeof(int), "engine_ends_t is not int-sized");
_Static_assert(sizeof(engine_profile_t) == sizeof(int), "engine_profile_t is not int-sized");
_Static_assert(ENGINE_AXES == 3, "VEC3 settings are written x,y,z");

/* One entry: the field f names the key, its offset and its size. */
#define S(f, opt_, type_, flags_, lo_, hi_, names_, arg_, help_)                                   \
    {                                                                                              \
        .name = #f, .option = opt_, .type = ENGINE_SETTING_##type_, .flags = flags_,               \
        .offset = offsetof(engine_config_t, f), .size = sizeof(((engine_config_t *)0)->f),         \
        .min = lo_, .max = hi_, .names = names_, .arg = arg_, .help = help_                        \
    }

/* Ranges: what the config parser always accepted for each key; the rules
 * between fields (overlap even and < fragment, capacity >= lookahead +
 * fragment, smooth_ctrl <= smooth_window, ...) are engine_config_check's. */
const engine_setting_t engine_settings[] = {
    S(method, "method", ENUM, 0, 0, 0, method_names, "M",
      "bspline | cubic | smooth (least squares, not exact) | hermite | hermite-centred (local, "
      "C1) | hermite-c2 | hermite-c2-centred (local, C2)"),
    S(param, "param", ENUM, 0, 0, 0, param_names, "P",
      "uniform (the paper) | time (knots at the timestamps)"),
    S(ends, "ends", ENUM, 0, 0, 0, ends_names, "E",
      "end condition: held | multiple | natural | clamped | rest"),
    S(start_vel_m_s, "start-vel", VEC3, 0, 0, 0, NULL, "VX,VY,VZ",
      "start velocity for ends = clamped, m/s"),
    S(end_vel_m_s, "end-vel", VEC3, 0, 0, 0, NULL, "VX,VY,VZ",
      "end velocity for ends = clamped, m/s"),
    S(fragment, "fragment", UNSIGNED, ENGINE_SETTING_AUTO, ENGINE_FRAGMENT_MIN, ENGINE_FRAGMENT_MAX,
      NULL, "F", "waypoints per fragment (auto: from max_lookahead)"),
    S(overlap, "overlap", UNSIGNED, ENGINE_SETTING_AUTO, 0, ENGINE_FRAGMENT_MAX - 1, NULL, "O",
      "waypoints shared by two fragments (even, < fragment; auto: from accuracy)"),
    S(accuracy, "accuracy", DOUBLE, 0, 1e-300, 0.999, NULL, "A",
      "overlap auto: error bound against one global solve, of the curvature scale"),
    S(max_lookahead, "max-lookahead", UNSIGNED, 0, 1, ENGINE_FRAGMENT_MAX, NULL, "N",
      "fragment auto: lookahead at most, waypoints (regular input, slack included)"),
    S(period_ns, NULL, INT64, ENGINE_SETTING_DERIVED, 0, 0, NULL, NULL,
      "output period, ns: 1e9 / rate_hz of [daemon] (trajreplay --rate)"),
    S(capacity, "capacity", UNSIGNED, 0, 1, 1 << 20, NULL, "N",
      "waypoints buffered at most (>= lookahead + fragment + 8)"),
    S(max_gap_s, "max-gap", DOUBLE, 0, 1e-6, 1e9, NULL, "S",
      "a longer interval ends the trajectory at rest, s"),
    S(max_abs_m, "max-abs", DOUBLE, 0, 1e-6, 1e12, NULL, "M",
      "reject a waypoint with a |coordinate| above this, m"),
    S(profile, "profile", ENUM, 0, 0, 0, profile_names, "P",
      "kind of object: auto | vessel | road | air | machine | none (the limits)"),
    S(max_speed_m_s, "max-speed", DOUBLE, 0, ENGINE_LIMIT_PROFILE, 1e9, NULL, "M_S",
      "reject a higher chord speed, m/s (0 = no limit, -1 = the profile's)"),
    S(max_accel_m_s2, "max-accel", DOUBLE, 0, ENGINE_LIMIT_PROFILE, 1e9, NULL, "M_S2",
      "reject a higher implied acceleration, m/s^2 (0 = none, -1 = the profile's)"),
    S(confirm, "confirm", UNSIGNED, 0, 1, 8, NULL, "K",
      "consistent waypoints that confirm a new trajectory far from the current one"),
    S(transfer_speed_m_s, "transfer-speed", DOUBLE, 0, 0, 1e9, NULL, "M_S",
      "speed of transfers to a new trajectory, m/s (0 = the object's own)"),
    S(transfer_accel_m_s2, "transfer-accel", DOUBLE, 0, 0, 1e9, NULL, "M_S2",
      "acceleration of transfers, m/s^2 (0 = the object's own)"),
    S(max_segment_s, "max-segment", DOUBLE, 0, 1e-6, 1e9, NULL, "S",
      "longest segment the stepper is trusted for, s"),
    S(start_slack, "start-slack", UNSIGNED, ENGINE_SETTING_AUTO, 0, ENGINE_FRAGMENT_MAX, NULL, "N",
      "waypoints buffered beyond the solver's lookahead (auto: from the input's timing)"),
    S(smooth_window, "smooth-window", UNSIGNED, 0, 4, ENGINE_SMOOTH_WINDOW_MAX, NULL, "W",
      "method smooth: waypoints per least-squares fit"),
    S(smooth_ctrl, "smooth-ctrl", UNSIGNED, 0, 4, ENGINE_SMOOTH_WINDOW_MAX, NULL, "C",
      "method smooth: control points per fit (<= smooth-window)"),
    S(scale_accel_m_s2, "scale-accel", DOUBLE, 0, 1e-6, 1e6, NULL, "M_S2",
      "time scaling (stop, clear, underrun, override): acceleration it adds, m/s^2"),
    S(scale_jerk_m_s3, "scale-jerk", DOUBLE, 0, 1e-6, 1e9, NULL, "M_S3",
      "time scaling: jerk it adds, m/s^3"),
    /* issue 26: the play-out delay D, stated (delay.h) */
    S(delay_s, "delay", DOUBLE, 0, 0, 3600, NULL, "S",
      "play-out delay D, s (0 = what the settings and the input need)"),
    /* issue 32: per-axis limits, kept by the time scaling along the path */
    S(axis_max_speed_m_s, "axis-max-speed", VEC3, 0, 0, 0, NULL, "VX,VY,VZ",
      "per-axis speed limits, m/s (0: that axis free)"),
    S(axis_max_accel_m_s2, "axis-max-accel", VEC3, 0, 0, 0, NULL, "AX,AY,AZ",
      "per-axis acceleration limits, m/s^2 (0: that axis free)"),
    S(axis_max_jerk_m_s3, "axis-max-jerk", VEC3, 0, 0, 0, NULL, "JX,JY,JZ",
      "per-axis jerk limits, m/s^3 (0: that axis free; C2 curves only: refused with hermite)"),
    S(max_lag_s, "max-lag", DOUBLE, 0, 0, 1e6, NULL, "S",
      "the lag the per-axis limits may cause, s: beyond it the object stops (0: unbounded)"),
    S(cap_speed_m_s, NULL, DOUBLE, ENGINE_SETTING_DERIVED, 0, 1e9, NULL, NULL,
      "the output's speed cap, m/s: 95 % of a configured safety_max_speed_m_s (trajd; 0: none)"),
    S(cap_accel_m_s2, NULL, DOUBLE, ENGINE_SETTING_DERIVED, 0, 1e9, NULL, NULL,
      "the output's acceleration cap, m/s^2: 95 % of a configured safety_max_accel_m_s2 "
      "(trajd; 0: none)"),
};

const size_t engine_settings_count = sizeof engine_settings / sizeof engine_settings[0];

const engine_setting_t *engine_setting_find(const char *name)
{
    for (size_t i = 0; i < engine_settings_count; i++)
        if (strcmp(engine_settings[i].name, name) == 0)
            return &engine_settings[i];
    return NULL;
}

const engine_setting_t *engine_setting_find_option(const char *opt)
{
    for (size_t i = 0; i < engine_settings_count; i++)
        if (engine_settings[i].option && strcmp(engine_settings[i].option, opt) == 0)
            return &engine_settings[i];
    return NULL;
}

static int why_set(char *why, size_t whylen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int why_set(char *why, size_t whylen, const char *fmt, ...)
{
    if (why && whylen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, whylen, fmt, ap);
        va_end(ap);
    }
    return -ENGINE_ECONFIG;
}

static void *field(const engine_setting_t *s, engine_config_t *cfg)
{
    return (char *)cfg + s->offset;
}

static const void *cfield(const engine_setting_t *s, const engine_config_t *cfg)
{
    return (const char *)cfg + s->offset;
}

static int parse_double(const engine_setting_t *s, const char *text, double *out, char *why,
                        size_t whylen)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end || errno == ERANGE || !isfinite(v) || v < s->min || v > s->max)
        return why_set(why, whylen, "expected a number in [%g, %g], got '%s'", s->min, s->max,
                       text);
    *out = v;
    return 0;
}

static int parse_unsigned(const engine_setting_t *s, const char *text, unsigned *out, char *why,
                          size_t whylen)
{
    char *end;
    errno = 0;
    int base = (text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) ? 16 : 10;
    long long v = strtoll(text, &end, base);
    if (end == text || *end || errno == ERANGE || (double)v < s->min || (double)v > s->max)
        return why_set(why, whylen, "expected an integer in [%.0f, %.0f]%s, got '%s'", s->min,
                       s->max, (s->flags & ENGINE_SETTING_AUTO) ? " or auto" : "", text);
    *out = (unsigned)v;
    return 0;
}

static int parse_enum(const engine_setting_t *s, const char *text, int *out, char *why,
                      size_t whylen)
{
    char list[160] = "";
    for (int i = 0; s->names[i]; i++) {
        if (strcmp(text, s->names[i]) == 0) {
            *out = i;
            return 0;
        }
        size_t n = strlen(list);
        snprintf(list + n, sizeof list - n, "%s%s", i ? ", " : "", s->names[i]);
    }
    return why_set(why, whylen, "expected one of %s, got '%s'", list, text);
}

static int parse_bool(const char *text, int *out, char *why, size_t whylen)
{
    static const char *const yes[] = {"yes", "true", "on", "1", NULL};
    static const char *const no[] = {"no", "false", "off", "0", NULL};
    for (int i = 0; yes[i]; i++) {
        if (strcasecmp(text, yes[i]) == 0) {
            *out = 1;
            return 0;
        }
        if (strcasecmp(text, no[i]) == 0) {
            *out = 0;
            return 0;
        }
    }
    return why_set(why, whylen, "expected yes or no, got '%s'", text);
}

/* "x,y,z" (blanks allowed around the numbers) into three finite numbers. */
static int parse_vec3(const char *text, double v[ENGINE_AXES], char *why, size_t whylen)
{
    const char *s = text;
    double r[ENGINE_AXES];
    for (int i = 0; i < ENGINE_AXES; i++) {
        char *end;
        errno = 0;
        r[i] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(r[i]))
            return why_set(why, whylen, "expected three numbers x,y,z, got '%s'", text);
        while (*end == ' ' || *end == '\t')
            end++;
        if (i < ENGINE_AXES - 1) {
            if (*end != ',')
                return why_set(why, whylen, "expected three numbers x,y,z, got '%s'", text);
            s = end + 1;
        } else if (*end) {
            return why_set(why, whylen, "expected three numbers x,y,z, got '%s'", text);
        }
    }
    memcpy(v, r, sizeof r);
    return 0;
}

int engine_setting_parse(const engine_setting_t *s, const char *text, engine_config_t *cfg,
                         char *why, size_t whylen)
{
    if (s->flags & ENGINE_SETTING_DERIVED)
        return why_set(why, whylen, "%s is set by the program, not given", s->name);
    switch (s->type) {
    case ENGINE_SETTING_DOUBLE: return parse_double(s, text, field(s, cfg), why, whylen);
    case ENGINE_SETTING_UNSIGNED:
        if ((s->flags & ENGINE_SETTING_AUTO) && strcmp(text, "auto") == 0) {
            *(unsigned *)field(s, cfg) = ENGINE_AUTO;
            return 0;
        }
        return parse_unsigned(s, text, field(s, cfg), why, whylen);
    case ENGINE_SETTING_ENUM: {
        int v = 0, rc = parse_enum(s, text, &v, why, whylen);
        if (rc == 0) /* every engine enum is int-sized (checked by the unit test) */
            memcpy(field(s, cfg), &v, sizeof v);
        return rc;
    }
    case ENGINE_SETTING_BOOL: return parse_bool(text, field(s, cfg), why, whylen);
    case ENGINE_SETTING_VEC3: return parse_vec3(text, field(s, cfg), why, whylen);
    case ENGINE_SETTING_INT64:
    default: return why_set(why, whylen, "%s cannot be parsed", s->name);
    }
}

/* Shortest of %.15g .. %.17g that reads back to the same double. */
static int format_double(double v, char *buf, size_t len)
{
    char tmp[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(tmp, sizeof tmp, "%.*g", prec, v);
        if (prec == 17 || memcmp(&(double){strtod(tmp, NULL)}, &v, sizeof v) == 0)
            break;
    }
    return snprintf(buf, len, "%s", tmp);
}

const char *engine_setting_enum_name(const engine_setting_t *s, int v)
{
    if (s->type != ENGINE_SETTING_ENUM || v < 0)
        return "?";
    for (int i = 0; s->names[i]; i++)
        if (i == v)
            return s->names[i];
    return "?";
}

int engine_setting_format(const engine_setting_t *s, const engine_config_t *cfg, char *buf,
                          size_t len)
{
    const void *p = cfield(s, cfg);
    switch (s->type) {
    case ENGINE_SETTING_DOUBLE: return format_double(*(const double *)p, buf, len);
    case ENGINE_SETTING_UNSIGNED:
        if ((s->flags & ENGINE_SETTING_AUTO) && *(const unsigned *)p == ENGINE_AUTO)
            return snprintf(buf, len, "auto");
        return snprintf(buf, len, "%u", *(const unsigned *)p);
    case ENGINE_SETTING_ENUM: {
        int v;
        memcpy(&v, p, sizeof v);
        return snprintf(buf, len, "%s", engine_setting_enum_name(s, v));
    }
    case ENGINE_SETTING_BOOL: return snprintf(buf, len, "%s", *(const int *)p ? "yes" : "no");
    case ENGINE_SETTING_VEC3: {
        const double *v = p;
        char a[3][40];
        for (int i = 0; i < ENGINE_AXES; i++)
            format_double(v[i], a[i], sizeof a[i]);
        return snprintf(buf, len, "%s,%s,%s", a[0], a[1], a[2]);
    }
    case ENGINE_SETTING_INT64: return snprintf(buf, len, "%lld", (long long)*(const int64_t *)p);
    default: return snprintf(buf, len, "?");
    }
}

int engine_setting_same(const engine_setting_t *s, const engine_config_t *a,
                        const engine_config_t *b)
{
    return memcmp(cfield(s, a), cfield(s, b), s->size) == 0;
}

const char *engine_setting_unused(const engine_setting_t *s, const engine_config_t *cfg)
{
    const char *why = NULL;
    if ((!strcmp(s->name, "start_vel_m_s") || !strcmp(s->name, "end_vel_m_s")) &&
        cfg->ends != ENGINE_ENDS_CLAMPED)
        why = "only ends = clamped uses it";
    else if ((!strcmp(s->name, "smooth_window") || !strcmp(s->name, "smooth_ctrl")) &&
             cfg->method != ENGINE_METHOD_SMOOTH)
        why = "only method = smooth uses it";
    if (!why)
        return NULL; /* (the defaults made only for the four it can concern) */
    engine_config_t d;
    engine_config_default(&d);
    return engine_setting_same(s, cfg, &d) ? NULL : why;
}

int engine_config_same(const engine_config_t *a, const engine_config_t *b)
{
    for (size_t i = 0; i < engine_settings_count; i++)
        if (!engine_setting_same(&engine_settings[i], a, b))
            return 0;
    return 1;
}

/* ---- resolution of a configuration (engine.h) ---------------------------- */

/* Capacity accepted at most (memory is sized from it). */
#define ENGINE_CAPACITY_MAX (1u << 20)

void engine_config_default(engine_config_t *cfg)
{
    memset(cfg, 0, sizeof(*cfg));
    cfg->method = ENGINE_METHOD_CUBIC;
    cfg->param = ENGINE_PARAM_TIME;
    cfg->ends = ENGINE_ENDS_REST;
    cfg->fragment = ENGINE_AUTO;
    cfg->overlap = ENGINE_AUTO;
    cfg->accuracy = ENGINE_ACCURACY_DEFAULT;
    cfg->max_lookahead = 18;
    cfg->period_ns = 10000000;
    cfg->capacity = 4096;
    cfg->max_gap_s = 60.0;
    cfg->max_abs_m = 1e7;
    cfg->profile = ENGINE_PROFILE_AUTO;
    cfg->max_speed_m_s = ENGINE_LIMIT_PROFILE;
    cfg->max_accel_m_s2 = ENGINE_LIMIT_PROFILE;
    cfg->confirm = 3;
    cfg->max_segment_s = 60.0;
    cfg->start_slack = ENGINE_AUTO;
    cfg->smooth_window = 24;
    cfg->smooth_ctrl = 6;
    cfg->scale_accel_m_s2 = 5.0;
    cfg->scale_jerk_m_s3 = 50.0;
}

/* The numbers and where they come from: engine.h, engine_profile_t. */
static const struct {
    double speed_m_s, accel_m_s2;
} profile_limits[ENGINE_PROFILE_COUNT] = {
    [ENGINE_PROFILE_AUTO] = {400.0, 30.0}, [ENGINE_PROFILE_VESSEL] = {40.0, 30.0},
    [ENGINE_PROFILE_ROAD] = {100.0, 30.0}, [ENGINE_PROFILE_AIR] = {400.0, 30.0},
    [ENGINE_PROFILE_MACHINE] = {0.0, 0.0}, [ENGINE_PROFILE_NONE] = {0.0, 0.0},
};

static engine_profile_t profile_of(const engine_config_t *cfg)
{
    return (unsigned)cfg->profile < ENGINE_PROFILE_COUNT ? cfg->profile : ENGINE_PROFILE_AUTO;
}

double engine_config_max_speed(const engine_config_t *cfg)
{
    return cfg->max_speed_m_s < 0 ? profile_limits[profile_of(cfg)].speed_m_s : cfg->max_speed_m_s;
}

double engine_config_max_accel(const engine_config_t *cfg)
{
    return cfg->max_accel_m_s2 < 0 ? profile_limits[profile_of(cfg)].accel_m_s2
                                   : cfg->max_accel_m_s2;
}

int engine_cfg_axis_jerk(const engine_config_t *cfg)
{
    for (int k = 0; k < ENGINE_AXES; k++)
        if (cfg->axis_max_jerk_m_s3[k] > 0)
            return 1;
    return 0;
}

int engine_cfg_uses_pstar(const engine_config_t *cfg)
{
    return cfg->method == ENGINE_METHOD_BSPLINE && cfg->param == ENGINE_PARAM_UNIFORM;
}

/*
 * largest lookahead over segments j in [j0, j1) for start offset delta, in
 * waypoints received.  SMOOTH (toolkit): node n exists once waypoint
 * max(n + extra, first) is in (extra = smooth_window/2, first =
 * smooth_window - 1); otherwise extra = first = 0 and nodes are waypoints.
 */
static unsigned scan_lookahead(unsigned f, unsigned o, unsigned delta, unsigned need, uint64_t j0,
                               uint64_t j1, uint64_t extra, uint64_t first)
{
    unsigned best = 0;
    uint64_t j, n = 0, raw;

    /* Row r is pushed when node r+1 arrives; segment j (waypoint j to j+1)
     * is built once frag_final_after(rows pushed) reaches x[j + need - 1].
     * frag_final_after is non-decreasing in r and the bound rises with j, so
     * the least n of segment j + 1 is not below segment j's: one pass (the
     * search from j + 1 for every j cost O(F^2) a scan, and engine_config_
     * resolve scans for up to 500 fragment sizes: 0.7 s for overlap = 828) */
    for (j = j0; j < j1; j++) {
        if (n < j + 1)
            n = j + 1;
        while (frag_final_after(f, o, delta, n - 1) < j + need)
            n++;
        raw = n + extra > first ? n + extra : first;
        if (raw - (j + 1) > best)
            best = (unsigned)(raw - (j + 1));
    }
    return best;
}

static int config_sizes_ok(const engine_config_t *cfg)
{
    return cfg->fragment >= ENGINE_FRAGMENT_MIN && cfg->fragment <= ENGINE_FRAGMENT_MAX &&
           cfg->overlap >= 2 && cfg->overlap % 2 == 0 && cfg->overlap < cfg->fragment;
}

/* The local methods (hermite.h): 1 HERMITE, 2 HERMITE_CENTRED, 3
 * HERMITE_C2, 4 HERMITE_C2_CENTRED, else 0 */
int engine_cfg_local(const engine_config_t *cfg)
{
    switch (cfg->method) {
    case ENGINE_METHOD_HERMITE: return 1;
    case ENGINE_METHOD_HERMITE_CENTRED: return 2;
    case ENGINE_METHOD_HERMITE_C2: return 3;
    case ENGINE_METHOD_HERMITE_C2_CENTRED: return 4;
    default: return 0;
    }
}

unsigned engine_cfg_accept_lag(const engine_config_t *cfg)
{
    return engine_cfg_local(cfg) && cfg->max_lookahead == 1 ? 0u : ACCEPT_LAG;
}

unsigned engine_cfg_slack_min(const engine_config_t *cfg)
{
    return engine_cfg_accept_lag(cfg) ? ENGINE_SLACK_AUTO_MIN : 0u;
}

/* most waypoints beyond a segment the solver needs, far from the start */
unsigned engine_cfg_steady_lookahead(const engine_config_t *cfg)
{
    if (engine_cfg_local(cfg)) /* segment j is built once node j + 1 (centred: j + 2) is in */
        return engine_cfg_local(cfg) % 2 ? 1u : 2u;
    unsigned f = cfg->fragment, o = cfg->overlap, s = f - o;
    unsigned need = engine_cfg_uses_pstar(cfg) ? 3 : 2; /* x[j + need - 1] final for segment j */

    /* the pattern repeats every S segments */
    return scan_lookahead(f, o, 0, need, 2u * f, 2u * f + 2u * s, 0, 0);
}

/*
 * Start offset of the fragment grid: the first fragment is cut short so that
 * its first segment is final no later than the output wants to start
 * (steady-state lookahead + start_slack) instead of after F - 1 waypoints;
 * never beyond S - 1 (see frag.h).
 */
/* start_slack in waypoints (auto: its least) */
static unsigned slack_of(const engine_config_t *cfg)
{
    return cfg->start_slack == ENGINE_AUTO ? engine_cfg_slack_min(cfg) : cfg->start_slack;
}

unsigned engine_cfg_frag_delta(const engine_config_t *cfg)
{
    unsigned f = cfg->fragment, dmax = frag_delta_max(f, cfg->overlap);
    unsigned want = engine_cfg_steady_lookahead(cfg) + slack_of(cfg);
    unsigned d = f - 1 > want ? f - 1 - want : 0;

    return d < dmax ? d : dmax;
}

unsigned engine_cfg_smooth_extra(const engine_config_t *cfg)
{
    /* SMOOTH: the smoother holds smooth_window/2 waypoints back (lsq.h) */
    int sm = cfg->method == ENGINE_METHOD_SMOOTH && cfg->smooth_window >= 1;
    return sm ? lsq_smooth_delay(cfg->smooth_window) : 0;
}

/* engine_lookahead of a resolved configuration */
unsigned engine_cfg_lookahead(const engine_config_t *cfg)
{
    unsigned f = cfg->fragment, o = cfg->overlap, la, want;
    int sm = cfg->method == ENGINE_METHOD_SMOOTH && cfg->smooth_window >= 1;
    unsigned extra = engine_cfg_smooth_extra(cfg);
    unsigned first = sm ? cfg->smooth_window - 1 : 0;

    if (!config_sizes_ok(cfg) || slack_of(cfg) > ENGINE_FRAGMENT_MAX)
        return 0;
    if (engine_cfg_local(cfg)) {
        /* no system: the segment's own nodes (and, centred, the next), each
         * a node once its next neighbour is in (ACCEPT_LAG; max_lookahead 1:
         * as it comes, engine_cfg_accept_lag) */
        la = engine_cfg_steady_lookahead(cfg) + engine_cfg_accept_lag(cfg);
        want = engine_cfg_steady_lookahead(cfg) + slack_of(cfg);
        return la > want ? la : want;
    }
    /* what the solver needs, from the start on (a few periods cover it) ... */
    la = scan_lookahead(f, o, engine_cfg_frag_delta(cfg), engine_cfg_uses_pstar(cfg) ? 3 : 2, 0,
                        4u * f, extra, first) +
         ACCEPT_LAG; /* a waypoint becomes a node once its next neighbour is in */
    /* ... and what the output waits for */
    want = engine_cfg_steady_lookahead(cfg) + extra + slack_of(cfg);
    return la > want ? la : want;
}

/* overlap auto: the smallest even O with 2 rho^(O/2) <= accuracy (frag.h) */
static unsigned auto_overlap(double accuracy)
{
    const double rho = 2.0 - sqrt(3.0);
    double bound = 2.0 * rho;
    unsigned o = 2;

    while (bound > accuracy && o + 2 < ENGINE_FRAGMENT_MAX) {
        o += 2;
        bound *= rho;
    }
    return o;
}

/* issue 32: every per-axis limit 0 (free) or positive and finite */
static int axis_limits_ok(const engine_config_t *cfg)
{
    for (int k = 0; k < ENGINE_AXES; k++) {
        const double v[3] = {cfg->axis_max_speed_m_s[k], cfg->axis_max_accel_m_s2[k],
                             cfg->axis_max_jerk_m_s3[k]};
        for (int i = 0; i < 3; i++)
            if (!(v[i] >= 0) || !isfinite(v[i]))
                return 0;
    }
    return 1;
}

/* issue 32: with per-axis acceleration (jerk) limits the time scaling's own
 * share, scale_accel_m_s2, is at most ENGINE_AXIS_SCALE_SHARE of the
 * smallest (scale_jerk_m_s3 at most a quarter of the smallest jerk limit,
 * whose other quarter the scaling's cross term 3 k'' r dr/dt keeps,
 * engine_solve.c jerk_rate_accel, and half the curve's own): the rest is the curve's k'' r^2
 * at the ceilings (engine_solve.c axis_ceiling).  Outside a stop the scaling
 * takes more where the curve leaves it (engine_solve.c accel_speed).  On the
 * figure-8 and the rectangle of tests/bench/bench_axis.py the runs take 92.8
 * and 58.2 s with a quarter, 93.7 and 58.3 s with a third, 99.6 and 60.4 s
 * with a half. */
#define ENGINE_AXIS_SCALE_SHARE (1.0 / 3.0)

static void resolve_axis_limits(engine_config_t *out)
{
    for (int k = 0; k < ENGINE_AXES; k++) {
        if (out->axis_max_accel_m_s2[k] > 0 &&
            out->scale_accel_m_s2 > ENGINE_AXIS_SCALE_SHARE * out->axis_max_accel_m_s2[k])
            out->scale_accel_m_s2 = ENGINE_AXIS_SCALE_SHARE * out->axis_max_accel_m_s2[k];
        if (out->axis_max_jerk_m_s3[k] > 0 &&
            out->scale_jerk_m_s3 > 0.25 * out->axis_max_jerk_m_s3[k])
            out->scale_jerk_m_s3 = 0.25 * out->axis_max_jerk_m_s3[k];
    }
}

/*
 * No fragment fits within max_lookahead (issue 31): an exact method that
 * solves a system (CUBIC, BSPLINE with natural, clamped or rest ends) gives
 * way to the local one that fits, HERMITE_C2_CENTRED if it does, else
 * HERMITE_C2 (max_lookahead 1: its fixes kept as they arrive,
 * engine_cfg_accept_lag);
 * -ENGINE_ECONFIG if neither does (start_slack too long) or the method and
 * ends have no local counterpart.
 */
static int resolve_local(const engine_config_t *cfg, engine_config_t *out)
{
    static const engine_method_t local[] = {ENGINE_METHOD_HERMITE_C2_CENTRED,
                                            ENGINE_METHOD_HERMITE_C2};
    engine_config_t r = *out;

    if ((cfg->method != ENGINE_METHOD_CUBIC && cfg->method != ENGINE_METHOD_BSPLINE) ||
        cfg->ends == ENGINE_ENDS_HELD || cfg->ends == ENGINE_ENDS_MULTIPLE)
        return -ENGINE_ECONFIG;
    for (size_t i = 0; i < sizeof local / sizeof local[0]; i++) {
        r.method = local[i];
        unsigned la = engine_cfg_lookahead(&r);
        if (la && la <= cfg->max_lookahead) {
            *out = r;
            return 0;
        }
    }
    return -ENGINE_ECONFIG;
}

int engine_config_resolve(const engine_config_t *cfg, engine_config_t *out)
{
    *out = *cfg;
    resolve_axis_limits(out);
    /* the caller's acceleration cap: the time scaling's share of it (engine.h) */
    if (cfg->cap_accel_m_s2 > 0 &&
        out->scale_accel_m_s2 > ENGINE_CAP_SCALE_SHARE * cfg->cap_accel_m_s2)
        out->scale_accel_m_s2 = ENGINE_CAP_SCALE_SHARE * cfg->cap_accel_m_s2;
    if (cfg->overlap == ENGINE_AUTO) {
        if (!(cfg->accuracy > 0) || !isfinite(cfg->accuracy))
            return -ENGINE_ECONFIG;
        out->overlap = auto_overlap(cfg->accuracy);
    }
    if (cfg->fragment == ENGINE_AUTO && engine_cfg_local(cfg)) {
        out->fragment = out->overlap + 1; /* no fragments: valid sizes, unused */
        return 0;
    }
    if (cfg->fragment == ENGINE_AUTO) {
        unsigned o = out->overlap;
        if (o < 2 || o % 2 || o >= ENGINE_FRAGMENT_MAX) {
            out->fragment = ENGINE_FRAGMENT_MAX; /* engine_config_check: "overlap" */
            return 0;
        }
        /* the largest S (least work: about 2F/S rows per waypoint) that fits;
         * beyond S = O the work hardly falls */
        for (unsigned s = o; s >= 1; s--) {
            if (o + s > ENGINE_FRAGMENT_MAX)
                continue;
            out->fragment = o + s;
            /* SMOOTH's smoother holds smooth_window/2 more back: not counted */
            unsigned la = engine_cfg_lookahead(out);
            if (la && la - engine_cfg_smooth_extra(out) <= cfg->max_lookahead)
                return 0;
        }
        out->fragment = o + 1;
        /* an accuracy tighter than the default that no fragment meets is
         * refused (engine_config_check says so): a local method would be
         * far less accurate than asked */
        if (cfg->accuracy < ENGINE_ACCURACY_DEFAULT)
            return -ENGINE_ECONFIG;
        return resolve_local(cfg, out);
    }
    return 0;
}

unsigned engine_lookahead(const engine_config_t *cfg)
{
    engine_config_t r;

    if (engine_config_resolve(cfg, &r) < 0)
        return 0;
    return engine_cfg_lookahead(&r);
}

int engine_config_check(const engine_config_t *cfg_in, const char **why)
{
    engine_config_t r;
    return engine_config_check_resolve(cfg_in, &r, why);
}

int engine_config_check_resolve(const engine_config_t *cfg_in, engine_config_t *out,
                                const char **why)
{
    const char *w = NULL;
    unsigned la;
    engine_config_t r;
    const engine_config_t *cfg = &r;
    int resolved = -1;

    if (cfg_in->overlap == ENGINE_AUTO &&
        (!(cfg_in->accuracy > 0 && cfg_in->accuracy < 1) || !isfinite(cfg_in->accuracy)))
        w = "accuracy: must be within (0, 1)";
    else if ((resolved = engine_config_resolve(cfg_in, &r)) < 0 && cfg_in->overlap == ENGINE_AUTO &&
             cfg_in->fragment == ENGINE_AUTO && cfg_in->accuracy < ENGINE_ACCURACY_DEFAULT)
        w = "accuracy: tighter than the default 3e-7, and no fragment meets it within "
            "max_lookahead: raise max_lookahead or accuracy (lib/engine/DESIGN.md tabulates "
            "the lookahead of each overlap); at the default accuracy, a max_lookahead too "
            "short for it picks a local method";
    else if (resolved < 0)
        w = "max_lookahead: too short for the overlap accuracy asks plus start_slack: no "
            "fragment fits, nor a local method (1 waypoint with start_slack auto or 0, ends not "
            "held or multiple); raise max_lookahead or accuracy, or lower start_slack";
    if (w) {
        if (why)
            *why = w;
        return -ENGINE_ECONFIG;
    }

    if (cfg->method != ENGINE_METHOD_BSPLINE && cfg->method != ENGINE_METHOD_CUBIC &&
        cfg->method != ENGINE_METHOD_SMOOTH && !engine_cfg_local(cfg))
        w = "method: unknown";
    else if (cfg->method == ENGINE_METHOD_SMOOTH &&
             (cfg->smooth_window < 4 || cfg->smooth_window > ENGINE_SMOOTH_WINDOW_MAX))
        w = "smooth_window: must be within 4..ENGINE_SMOOTH_WINDOW_MAX";
    else if (cfg->method == ENGINE_METHOD_SMOOTH &&
             (cfg->smooth_ctrl < 4 || cfg->smooth_ctrl > cfg->smooth_window))
        w = "smooth_ctrl: must be at least 4 and at most smooth_window";
    else if (cfg->param != ENGINE_PARAM_UNIFORM && cfg->param != ENGINE_PARAM_TIME)
        w = "param: unknown";
    else if ((unsigned)cfg->ends > ENGINE_ENDS_REST)
        w = "ends: unknown";
    else if ((cfg->ends == ENGINE_ENDS_HELD || cfg->ends == ENGINE_ENDS_MULTIPLE) &&
             !engine_cfg_uses_pstar(cfg))
        w = "ends: held and multiple are the paper's B-spline control-polygon ends: "
            "they need method bspline with param uniform";
    else if (cfg->fragment < ENGINE_FRAGMENT_MIN || cfg->fragment > ENGINE_FRAGMENT_MAX)
        w = "fragment: must be within ENGINE_FRAGMENT_MIN..ENGINE_FRAGMENT_MAX";
    else if (cfg_in->overlap == ENGINE_AUTO && cfg_in->fragment != ENGINE_AUTO &&
             cfg->overlap >= cfg->fragment)
        w = "fragment: must be above the overlap, which accuracy picks when overlap is auto "
            "(24 at the default 3e-7; lib/engine/DESIGN.md): raise fragment, or give overlap, "
            "or raise accuracy";
    else if (cfg->overlap < 2 || cfg->overlap % 2 || cfg->overlap >= cfg->fragment)
        w = "overlap: must be even, at least 2 and below fragment";
    else if (cfg->period_ns < ENGINE_PERIOD_NS_MIN || cfg->period_ns > ENGINE_PERIOD_NS_MAX)
        w = "period_ns: must be within ENGINE_PERIOD_NS_MIN..ENGINE_PERIOD_NS_MAX";
    else if (!(cfg->max_gap_s > 0) || !isfinite(cfg->max_gap_s))
        w = "max_gap_s: must be positive and finite";
    else if (!(cfg->max_abs_m > 0) || !isfinite(cfg->max_abs_m))
        w = "max_abs_m: must be positive and finite";
    else if (!(cfg->max_speed_m_s >= ENGINE_LIMIT_PROFILE) || !isfinite(cfg->max_speed_m_s))
        w = "max_speed_m_s: must be -1 (the profile's), 0 (no limit) or positive and finite";
    else if (!(cfg->max_accel_m_s2 >= ENGINE_LIMIT_PROFILE) || !isfinite(cfg->max_accel_m_s2))
        w = "max_accel_m_s2: must be -1 (the profile's), 0 (no limit) or positive and finite";
    else if ((unsigned)cfg->profile >= ENGINE_PROFILE_COUNT)
        w = "profile: unknown";
    else if (cfg->confirm < 1 || cfg->confirm > ACCEPT_WINDOW_MAX)
        w = "confirm: must be within 1..8";
    else if (!(cfg->transfer_speed_m_s >= 0) || !isfinite(cfg->transfer_speed_m_s))
        w = "transfer_speed_m_s: must be 0 (derived) or positive and finite";
    else if (!(cfg->transfer_accel_m_s2 >= 0) || !isfinite(cfg->transfer_accel_m_s2))
        w = "transfer_accel_m_s2: must be 0 (derived) or positive and finite";
    else if (!(cfg->cap_speed_m_s >= 0) || !isfinite(cfg->cap_speed_m_s))
        w = "cap_speed_m_s: must be 0 (none) or positive and finite";
    else if (!(cfg->cap_accel_m_s2 >= 0) || !isfinite(cfg->cap_accel_m_s2))
        w = "cap_accel_m_s2: must be 0 (none) or positive and finite";
    else if (!(cfg->max_segment_s >= 0) || !isfinite(cfg->max_segment_s))
        w = "max_segment_s: must be 0 or positive and finite";
    else if (!(cfg->scale_accel_m_s2 > 0) || !isfinite(cfg->scale_accel_m_s2))
        w = "scale_accel_m_s2: must be positive and finite";
    else if (!(cfg->scale_jerk_m_s3 > 0) || !isfinite(cfg->scale_jerk_m_s3))
        w = "scale_jerk_m_s3: must be positive and finite";
    else if (cfg->start_slack > ENGINE_FRAGMENT_MAX && cfg->start_slack != ENGINE_AUTO)
        w = "start_slack: at most ENGINE_FRAGMENT_MAX waypoints";
    else if (!(cfg->delay_s >= 0) || !isfinite(cfg->delay_s)) /* issue 26 */
        w = "delay_s: must be 0 (auto) or positive and finite";
    else if (!axis_limits_ok(cfg)) /* issue 32 */
        w = "axis_max_speed_m_s/axis_max_accel_m_s2/axis_max_jerk_m_s3: each must be 0 (that "
            "axis free) or positive and finite";
    else if ((engine_cfg_local(cfg) == 1 || engine_cfg_local(cfg) == 2) &&
             engine_cfg_axis_jerk(cfg)) /* the safety monitor holds it: it would trip */
        w = "axis_max_jerk_m_s3: cannot be held on a C1 curve: method hermite and "
            "hermite-centred step their acceleration at every waypoint; use a C2 curve (method "
            "cubic, hermite-c2, hermite-c2-centred) or no jerk limit";
    else if (cfg->ends == ENGINE_ENDS_CLAMPED &&
             !(isfinite(cfg->start_vel_m_s[0]) && isfinite(cfg->start_vel_m_s[1]) &&
               isfinite(cfg->start_vel_m_s[2]) && isfinite(cfg->end_vel_m_s[0]) &&
               isfinite(cfg->end_vel_m_s[1]) && isfinite(cfg->end_vel_m_s[2])))
        w = "start_vel_m_s/end_vel_m_s: must be finite";
    else if (cfg->ends == ENGINE_ENDS_CLAMPED && !engine_ends_within_limit(cfg))
        w = "start_vel_m_s/end_vel_m_s: faster than max_speed_m_s in force (without a speed "
            "limit: than max_abs_m per second)";
    if (!w) {
        la = engine_cfg_lookahead(cfg);
        if (cfg->capacity < la + cfg->fragment + 8 || cfg->capacity > ENGINE_CAPACITY_MAX)
            w = "capacity: must be at least lookahead + fragment + 8 and at most 2^20";
    }
    if (why)
        *why = w;
    if (!w)
        *out = r;
    return w ? -ENGINE_ECONFIG : 0;
}

int engine_axis_jerk_check(const engine_config_t *cfg, char *why, size_t whylen)
{
    engine_config_t a = *cfg, r;
    if (!engine_cfg_axis_jerk(cfg) || (cfg->fragment == ENGINE_AUTO && cfg->overlap == ENGINE_AUTO))
        return 0;
    a.fragment = a.overlap = ENGINE_AUTO;
    if (engine_config_resolve(&a, &r) < 0 || engine_cfg_local(&r))
        return 0; /* (no fragments: the local methods; or refused elsewhere) */
    unsigned o = cfg->overlap == ENGINE_AUTO ? r.overlap : cfg->overlap;
    if (o >= r.overlap)
        return 0;
    if (why && whylen)
        snprintf(why, whylen,
                 "axis_max_jerk_m_s3 with overlap %u: the fragments' junctions step the "
                 "acceleration by more than the jerk limit takes; the accuracy %g picks overlap "
                 "%u (leave fragment and overlap auto, or raise overlap to %u)",
                 o, cfg->accuracy, r.overlap, r.overlap);
    return -ENGINE_ECONFIG;
}
