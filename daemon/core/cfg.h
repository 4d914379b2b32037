/*
 * cfg.h - trajd's configuration file (INI, parsed by libinih), checked as a
 * whole before anything is opened, so a bad file (at start, at SIGHUP, or with
 * `trajd --check-config FILE`) is rejected with "file:line: message" and
 * changes nothing.  Every key is documented, with its default and unit, in
 * config/trajd.conf.
 *
 * Sections:
 *   [daemon]        rate, replay speed, status line, stop policy, logging (core)
 *   [realtime]      SCHED_FIFO priority, mlockall, CPU affinity (core)
 *   [object.NAME]   one moving object: its engine settings, input = <transport>,
 *                   output = <transport>[, <transport> ...]; keys "T.key" belong
 *                   to transport T (e.g. replay.track, csv.path, can.rx_id)
 *   [T]             daemon-wide settings of transport T (e.g. [can], [modbus])
 *
 * How a transport adds its keys (see transport.h): it declares, in its
 * transport_t, the size of a daemon-wide config block and of a per-object
 * block, a function that fills defaults, and a key function that parses one
 * key into the block.  The parser here routes [T] keys and "T.key" object
 * keys to T's key function, and reports whatever it answers with file:line.
 * Nothing in this file needs editing for a new transport.
 *
 * Errors (negated in return values): see enum cfg_error.
 */
#ifndef TRAJD_CFG_H
#define TRAJD_CFG_H

#include <limits.h>
#include <sched.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "engine.h"
#include "geo.h"

/* The share of a configured safety_max_speed_m_s the engine keeps its output
 * within (engine_config_t cap_speed_m_s): the monitor judges finite differences
 * of the setpoints sent, the engine the curve's speed bound per segment. */
#define CFG_SAFETY_SPEED_SHARE 0.95
#define CFG_OBJECTS_MAX 1024             /* objects per daemon (make bench: bench_scale.sh) */
#define CFG_NAME_MAX 32                  /* object name, with its NUL ([A-Za-z0-9_-]) */
#define CFG_OUTPUTS_MAX 4                /* outputs per object */
#define CFG_TRANSPORTS_MAX 16            /* transports in transport_table */
#define CFG_WHY_MAX 256                  /* room for a key function's message */
#define CFG_ID_MAX (CFG_OBJECTS_MAX - 1) /* ids 0..1023; Modbus and CAN take fewer and say so */

enum cfg_error {
    CFG_OK = 0,
    CFG_EUNKNOWN = 1, /* unknown section or key */
    CFG_EVALUE = 2,   /* bad value (why says which rule) */
    CFG_EMISSING = 3, /* a required key or section is missing */
    CFG_EIO = 4,      /* cannot open or read the file */
    CFG_ENOMEM = 5,   /* out of memory */
    CFG_ESYNTAX = 6,  /* not INI (no '=', unterminated section, line too long) */
    CFG_EDUP = 7,     /* key or section given twice */
    CFG_ERROR_COUNT
};

/* Text for a cfg_error (positive or negated). */
const char *cfg_strerror(int err);

struct transport;

/* One "key = value" line, as handed to a transport's key function. */
typedef struct {
    const char *file;    /* config file path, for messages */
    const char *dir;     /* its directory: relative paths are resolved against it */
    const char *section; /* "can", "object.boat", ... */
    const char *object;  /* object name for [object.NAME] keys, else NULL */
    const char *key;     /* key without the "T." prefix */
    const char *value;   /* value, trimmed, inline ';' comment removed */
    int line;            /* 1-based line number */
} cfg_kv_t;

/* [daemon] clock (lib/engine/CLOCK.md) */
enum { CFG_CLOCK_AUTO = 0, CFG_CLOCK_EPOCH = 1, CFG_CLOCK_RELATIVE = 2 };

/* [daemon] */
typedef struct {
    double rate_hz;           /* output rate shared by all objects */
    int64_t period_ns;        /* 1e9 / rate_hz, rounded */
    double speed;             /* engine time per wall-clock time (replay speed) */
    double status_interval_s; /* status line period, 0 = never */
    double stop_timeout_s;    /* SIGTERM: longest wait for objects to come to rest */
    int exit_when_done;       /* exit 0 once every input is done and every object is finished */
    int log_level;            /* LOG_ERR .. LOG_DEBUG */
    int origin_given;         /* origin = lat,lon,alt: the datum of every geographic object */
    double origin[3];         /* degrees, degrees, metres above the WGS84 ellipsoid */
    int origin_line;
    int clock;                     /* CFG_CLOCK_*: one clock for epoch-stamped objects (CLOCK.md) */
    double delay_s;                /* play-out delay D: clocked objects stand at now - D */
    double catchup;                /* most the rate rises above the clock's to win back a lag */
    double drift_max_ppm;          /* sender clock drift absorbed at most */
    double clock_window_s;         /* auto: epoch when the first time is this close to now */
    char user[64];                 /* started as root: drop to this user once the sockets are
                                 * open ("" = stay, with a warning outside systemd) */
    char control_socket[PATH_MAX]; /* the control socket (daemon/ctl/ctl.h); "" = the
                                    * default place (ctl_socket_path) */
    char control_group[64];        /* its group ("" = trajd's own), mode 0660 */
} cfg_daemon_t;

/* [realtime] (all off by default) */
typedef struct {
    int fifo_priority;  /* 0 = SCHED_OTHER, 1..99 = SCHED_FIFO priority */
    int mlockall;       /* lock current and future pages */
    int affinity_set;   /* 1 if cpu_affinity was given */
    cpu_set_t affinity; /* CPUs the daemon may run on */
} cfg_rt_t;

/* Engine settings whose line an object remembers (engine_settings_count is less:
 * test_engine_settings). */
#define CFG_ENGINE_KEYS 64

/* [object.NAME] */
typedef struct {
    char name[CFG_NAME_MAX];
    int line; /* line of its section header */
    /* id = N: the object's identity on the buses, 0..CFG_ID_MAX.  Its Modbus
     * block (MBMAP_OBJ_BASE(id)) and its default CAN ids (can.index = id)
     * derive from it, never from its place in the file.  Required when the
     * file has more than one object; a lone object without it is id 0.  A
     * reload may not change it (cfg_reload_check). */
    int id;
    int id_line;                   /* line of the id key, 0 if not given */
    int eng_line[CFG_ENGINE_KEYS]; /* line of each engine setting given (by its index in
                                      engine_settings[]), 0 if not: an error names its key's line */
    engine_config_t engine;        /* period_ns = daemon.period_ns */
    const struct transport *input; /* required */
    const struct transport *output[CFG_OUTPUTS_MAX];
    unsigned noutput;               /* >= 1 */
    void *tcfg[CFG_TRANSPORTS_MAX]; /* per-object block of each transport, by index */
    /* The safety monitor's bounds (lib/safety/safety.h), keys safety_max_step_m,
     * safety_max_speed_m_s, safety_max_accel_m_s2: < 0 = derived from the
     * engine's limits (obj_safety_limits in core.c), 0 = not checked. */
    double safety_max_step_m, safety_max_speed_m_s, safety_max_accel_m_s2;
    /* (a configured safety_max_speed_m_s, or safety_max_step_m a period: the
     * engine keeps its output within CFG_SAFETY_SPEED_SHARE of it,
     * engine.cap_speed_m_s) */
    /* initial_position = x,y,z: where the object stands at start (the output
     * holds there and reaches the first trajectory by a transfer) */
    int has_initial_position;
    int initial_position_line; /* its line, for the range check against max_abs_m */
    double initial_position_m[ENGINE_AXES];
    struct {
        const double *t_s, *deg; /* n samples, track time and unwrapped degrees */
        size_t n;                /* 0: no heading axis */
    } heading;                   /* set by its input (a replay track with a heading column) */
    int geographic;              /* its positions are east/north/up about the daemon's datum
                     * (a geographic replay track): outputs give lat/lon/alt */
    int geo_no_alt;              /* ... and the track has no altitude: up is 0 at the datum's
                     * height, and outputs give lat/lon at that height, alt NaN
                     * (geo_from_enu_at) */
    int writable;                /* writable = yes/no: commands and waypoints
                                                 * from outside (Modbus) may change it;
                                                 * -1 not given (the input decides) */
    /* position_min_m / position_max_m = x,y,z (cfg_box.h): the box the
     * safety monitor keeps the object in (soft limits).  box_keys: bit 0 min
     * given, bit 1 max; box: 0 none, 1 given, 2 derived by an output whose
     * fields cannot hold more (can_box.h: int32 positions); box_line its line. */
    unsigned box_keys;
    int box, box_line;
    double box_min_m[ENGINE_AXES], box_max_m[ENGINE_AXES];
} cfg_obj_t;

typedef struct cfg {
    char path[PATH_MAX];
    char dir[PATH_MAX];
    cfg_daemon_t daemon;
    cfg_rt_t rt;
    cfg_obj_t obj[CFG_OBJECTS_MAX];
    unsigned nobj;                  /* >= 1 */
    void *tcfg[CFG_TRANSPORTS_MAX]; /* daemon-wide block of each transport, by index */
    int tline[CFG_TRANSPORTS_MAX];  /* line of its [T] section, 0 if absent */
    /* The one datum of all geographic objects (set by the replay transport's
     * check): [daemon] origin, or the first fix of the geographic object with
     * the lowest id (stable under reordering, like the addresses). */
    int datum_set;
    int datum_line; /* line of origin, or of that object's section */
    geo_enu_t datum;
    /* The engines built beside the running core (cfgload.c, issue 28), by
     * object index: one for each object the load adds or changes (its
     * engine's zeroed memory and resolved settings off the tick), NULL
     * elsewhere; core_open takes them (cfg_take_engine), cfg_free frees the
     * rest.  NULL: none built. */
    engine_t **prebuilt;
    /* The new core's object array (nobj obj_t, core.h) built there too, its
     * pages written so that the loop does not fault them in, and fini, which
     * frees one not taken (what its objects hold with it); core_open takes
     * objs (cfgload_take_objs).  NULL: none. */
    struct cfg_built_objs {
        void *objs;
        void (*fini)(void *objs, unsigned n);
    } * prebuilt_objs;
} cfg_t;

/*
 * Read and check path.  On success *out is a new cfg_t (release with
 * cfg_free) and 0 is returned.  On failure returns a negated cfg_error, *out
 * is NULL and err holds "path:line: [section] key: message" (the first
 * error found; line 0 is left out for whole-file errors).
 */
int cfg_load(const char *path, cfg_t **out, char *err, size_t errlen);

/*
 * Whether nw may replace the running old at a reload: no object present in
 * both (by name) may change its id, nor any address a transport derives for it
 * (transport_t.reload_check: CAN ids, CiA 402 COB-IDs).  Returns 0, or
 * -CFG_EVALUE with err holding "newpath:line: message".
 */
int cfg_reload_check(const cfg_t *old, const cfg_t *nw, char *err, size_t errlen);

/* Object by name, or NULL. */
const cfg_obj_t *cfg_obj_by_name(const cfg_t *c, const char *name);

/* Release (the transports' blocks too, via their cfg_fini/obj_cfg_fini, and
 * the engines built for it and not taken).  NULL is a no-op. */
void cfg_free(cfg_t *c);

/* The engine built beside the running core for object i, handed over (the
 * caller frees it), or NULL if none was. */
engine_t *cfg_take_engine(const cfg_t *c, unsigned i);

/* Daemon-wide block of transport t (its defaults if [t] was absent). */
const void *cfg_transport(const cfg_t *c, const struct transport *t);

/* Per-object block of transport t for object o (its defaults if no "t." key was given). */
const void *cfg_obj_transport(const cfg_obj_t *o, const struct transport *t);

/* 1 if t is some object's input or output, or its [t] section is present. */
int cfg_uses(const cfg_t *c, const struct transport *t);

/* 1 if object o has t as input, 2 as output, 3 both, 0 neither. */
int cfg_obj_uses(const cfg_obj_t *o, const struct transport *t);

/* ---- value helpers for key functions: 0, or -CFG_EVALUE with why filled ---- */

/* why (if not NULL) receives the message; returns -CFG_EVALUE (daemon/core/cfg_value.c). */
int cfg_why(char *why, size_t whylen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* Finite decimal number in [lo, hi]. */
int cfg_get_double(const cfg_kv_t *kv, double lo, double hi, double *out, char *why, size_t whylen);

/* Integer (decimal, or 0x hex) in [lo, hi]. */
int cfg_get_int(const cfg_kv_t *kv, long long lo, long long hi, long long *out, char *why,
                size_t whylen);

/* yes/no, true/false, on/off, 1/0. */
int cfg_get_bool(const cfg_kv_t *kv, int *out, char *why, size_t whylen);

/* One of names[] (NULL-terminated); *out is its index. */
int cfg_get_enum(const cfg_kv_t *kv, const char *const *names, int *out, char *why, size_t whylen);

/* A path, made absolute against kv->dir if relative (not checked for existence). */
int cfg_get_path(const cfg_kv_t *kv, char *out, size_t outlen, char *why, size_t whylen);

#endif
