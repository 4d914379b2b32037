/*
 * engine.h - one moving object's trajectory engine: waypoints in, fixed-rate
 * setpoints out.  Pure: no clock, no I/O, no allocation after engine_new().
 *
 * Waypoints (time + position) are pushed as they arrive.  The engine keeps a
 * sliding window of fragments of F waypoints overlapping by O, solves each
 * fragment incrementally (forward sweep per waypoint, back substitution when
 * the fragment is complete), averages control values at the junction in the
 * middle of each overlap, and turns each finished segment into a cubic per
 * axis that the forward-difference stepper walks at the output period.
 *
 * Time is passed in: engine_tick(e, now_ns, &sp).  now_ns is the caller's
 * monotonic clock at the *scheduled* tick (not the wake-up time), so two
 * callers that tick at the same instants get bit-identical setpoints (this is
 * what lets trajreplay and the daemon agree exactly).  If ticks were skipped,
 * the next call steps over them (each step is the same three additions, so
 * skipping never changes the numbers, it only drops rows).
 *
 * Track time and the caller's clock: streaming starts once the lookahead is
 * buffered; from then on track time advances one period per tick while the
 * segments needed are solved.  When they are not (waypoints late) the engine
 * holds the last position (UNDERRUN), and resumes from that exact point: the
 * track is delayed, never jumped.
 */
#ifndef TRAJD_ENGINE_H
#define TRAJD_ENGINE_H

#include <stddef.h>
#include <stdint.h>

#include "fdiff.h"

#define ENGINE_AXES 3

/* Limits on the configuration (checked by engine_config_check). */
#define ENGINE_FRAGMENT_MIN 4
#define ENGINE_FRAGMENT_MAX 1024
#define ENGINE_PERIOD_NS_MIN 100000LL        /* 10 kHz */
#define ENGINE_PERIOD_NS_MAX 1000000000LL    /* 1 Hz */

enum engine_error {
    ENGINE_OK = 0,
    ENGINE_ENOTFINITE = 1,  /* NaN or infinite time or coordinate */
    ENGINE_ERANGE = 2,      /* |coordinate| above max_abs_m or |t| absurd */
    ENGINE_EBACKWARDS = 3,  /* timestamp earlier than the previous waypoint */
    ENGINE_ESAMETIME = 4,   /* same timestamp, different position */
    ENGINE_ESPEED = 5,      /* implied speed from the previous waypoint above max_speed_m_s */
    ENGINE_EFULL = 6,       /* waypoint buffer full: sender must wait (flow control) */
    ENGINE_ECONFIG = 7,     /* invalid configuration */
    ENGINE_ENOMEM = 8,      /* engine_new could not allocate */
    ENGINE_ESTATE = 9,      /* call not valid in this state */
    ENGINE_ENUMERIC = 10,   /* solver failed (singular system); waypoint rejected */
    ENGINE_ERROR_COUNT
};

/* Non-error outcome of engine_push: an exact duplicate was dropped. */
#define ENGINE_DUPLICATE 1

/* Human-readable text for an engine_error (positive or negated). */
const char *engine_strerror(int err);

typedef enum {
    ENGINE_PARAM_UNIFORM = 0, /* (a) the paper: uniform B-spline, each segment mapped onto its time interval */
    ENGINE_PARAM_TIME = 1,    /* (b) knots at the timestamps: C2 in physical time */
} engine_param_t;

typedef enum {
    ENGINE_ENDS_HELD = 0,     /* the paper: P*(0)=R(0), P*(N-1)=R(N-1); curve spans R(1)..R(N-2) */
    ENGINE_ENDS_MULTIPLE = 1, /* the paper: end points repeated twice more; loop segments never emitted */
    ENGINE_ENDS_NATURAL = 2,  /* zero second derivative at the ends */
    ENGINE_ENDS_CLAMPED = 3,  /* given start/end velocity (start_vel_m_s, end_vel_m_s) */
    ENGINE_ENDS_REST = 4,     /* start and stop at rest: clamped with zero velocity */
} engine_ends_t;

typedef enum {
    ENGINE_METHOD_BSPLINE = 0, /* exact interpolation, Hoang control points */
    ENGINE_METHOD_CUBIC = 1,   /* exact interpolation, second-derivative system (seed 002) */
    ENGINE_METHOD_SMOOTH = 2,  /* least-squares B-spline over the window (not exact) */
} engine_method_t;

/*
 * ENGINE_METHOD_SMOOTH (lib/lsq.h, lsq_smooth_*): each waypoint's position
 * is replaced by the value, at its own time, of the least-squares cubic
 * B-spline with smooth_ctrl control points fitted to the smooth_window
 * waypoints around it; the smoothed waypoints then go through the CUBIC
 * path (fragments, end condition, forward differences) unchanged.  The
 * curve no longer passes through the waypoints; it adds smooth_window/2
 * waypoints of lookahead.  For noisy positions (a GNSS fix standing still).
 */
#define ENGINE_SMOOTH_WINDOW_MAX 1024

typedef struct {
    engine_method_t method;
    engine_param_t param;
    engine_ends_t ends;
    double start_vel_m_s[ENGINE_AXES]; /* ENGINE_ENDS_CLAMPED only */
    double end_vel_m_s[ENGINE_AXES];   /* ENGINE_ENDS_CLAMPED only */
    unsigned fragment;      /* F: waypoints per fragment */
    unsigned overlap;       /* O: waypoints shared by consecutive fragments, even, < F */
    int64_t period_ns;      /* output period */
    unsigned capacity;      /* waypoints buffered at most (>= lookahead + fragment) */
    double max_gap_s;       /* a longer interval ends the trajectory at rest and starts a new one */
    double max_abs_m;       /* |coordinate| above this is rejected */
    double max_speed_m_s;   /* implied speed above this is rejected (0 = no limit) */
    double max_segment_s;   /* longest segment the stepper is tested for (drift bound) */
    unsigned smooth_window; /* SMOOTH only: waypoints per local fit, 4 .. ENGINE_SMOOTH_WINDOW_MAX */
    unsigned smooth_ctrl;   /* SMOOTH only: control points per fit, 4 .. smooth_window */
} engine_config_t;

/* Fill cfg with working defaults (documented in config/trajd.conf). */
void engine_config_default(engine_config_t *cfg);

/*
 * Check a configuration.  Returns 0 or -ENGINE_ECONFIG; if why is not NULL
 * it receives a static string naming the offending field and the rule.
 */
int engine_config_check(const engine_config_t *cfg, const char **why);

typedef struct {
    double t_s;                  /* waypoint time, seconds, sender's track clock */
    double pos_m[ENGINE_AXES];   /* x, y, z (east, north, up for geographic input), metres */
    uint32_t seq;                /* transport sequence number (0 if none) */
} engine_waypoint_t;

typedef enum {
    ENGINE_STATE_WAITING = 0,   /* no trajectory yet, or lookahead not yet buffered; holding */
    ENGINE_STATE_STREAMING = 1, /* moving along the curve */
    ENGINE_STATE_UNDERRUN = 2,  /* waypoints late: holding the last setpoint */
    ENGINE_STATE_FINISHED = 3,  /* end of track reached, at rest on the last waypoint */
} engine_state_t;

/* Setpoint flags. */
#define ENGINE_SP_HOLD      0x01u /* position held (waiting, underrun, finished) */
#define ENGINE_SP_NEW_TRACK 0x02u /* first setpoint of a new trajectory (after a gap or clear) */
#define ENGINE_SP_SKIPPED   0x04u /* ticks were skipped before this one */
#define ENGINE_SP_TRANSFER  0x08u /* rest-to-rest transfer to a new trajectory's start */

typedef struct {
    int64_t now_ns;                 /* the tick this setpoint is for (as passed in) */
    double t_s;                     /* track time of the setpoint (sender's clock) */
    double pos_m[ENGINE_AXES];
    double vel_m_s[ENGINE_AXES];
    double acc_m_s2[ENGINE_AXES];
    engine_state_t state;
    uint32_t flags;                 /* ENGINE_SP_* */
    uint32_t cycle;                 /* tick counter, wraps */
    uint32_t track;                 /* trajectory number, +1 at each new trajectory */
} engine_setpoint_t;

typedef struct {
    engine_state_t state;
    uint32_t last_seq;              /* seq of the last accepted waypoint */
    uint32_t buffered;              /* waypoints held, not yet passed by the output */
    uint32_t free;                  /* waypoints that can still be pushed */
    uint32_t lookahead;             /* waypoints needed ahead of the output (from F, O) */
    double ahead_s;                 /* track time buffered ahead of the output */
    uint64_t accepted;
    uint64_t duplicates;
    uint64_t rejected;              /* sum of rejected_by[] */
    uint64_t rejected_by[ENGINE_ERROR_COUNT]; /* per engine_error */
    uint64_t underruns;             /* transitions into UNDERRUN */
    uint64_t underrun_ticks;        /* ticks spent in UNDERRUN */
    uint64_t skipped_ticks;         /* ticks stepped over (caller late) */
    uint64_t gaps;                  /* trajectories ended by a gap */
    uint64_t tracks;                /* trajectories started */
    uint64_t setpoints;             /* ticks answered */
} engine_status_t;

typedef struct engine engine_t;

/*
 * Allocate an engine for cfg (all memory it will ever use is taken here).
 * err (may be NULL) receives 0, ENGINE_ECONFIG or ENGINE_ENOMEM.
 */
engine_t *engine_new(const engine_config_t *cfg, int *err);

/* Free; NULL is a no-op. */
void engine_free(engine_t *e);

/*
 * Offer a waypoint.  Returns 0 (accepted), ENGINE_DUPLICATE (same time and
 * position as the previous one: dropped, counted), or a negated
 * engine_error (rejected, counted in status.rejected_by, nothing changed).
 * A time gap above max_gap_s ends the current trajectory at rest on its
 * last waypoint and starts a new one with this waypoint.
 */
int engine_push(engine_t *e, const engine_waypoint_t *wp);

/*
 * End of input for the current trajectory: the last fragment is closed with
 * the configured end condition and the output runs to the last waypoint and
 * stops there (FINISHED).  Pushing again afterwards starts a new trajectory.
 */
int engine_finish(engine_t *e);

/*
 * Produce the setpoint for now_ns (the scheduled tick).  Never allocates,
 * never fails on data: bad waypoints were refused at push.  Returns 0, or
 * -ENGINE_ESTATE if now_ns went backwards (sp then repeats the last setpoint).
 */
int engine_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp);

/* Commands (Modbus holding registers, CAN, the daemon on SIGTERM). */
void engine_clear(engine_t *e);          /* drop all waypoints; hold where it is; WAITING */
int engine_stop(engine_t *e);            /* as engine_finish: run to the last waypoint and rest */
void engine_reset_counters(engine_t *e);

/* Snapshot of state and counters. */
void engine_status(const engine_t *e, engine_status_t *st);

/* Waypoints of lookahead this configuration needs (depends on F and O). */
unsigned engine_lookahead(const engine_config_t *cfg);

/* Name of a state, "waiting", "streaming", "underrun", "finished". */
const char *engine_state_name(engine_state_t s);

/*
 * Offline: the curve the engine streams for a whole track, built by the same
 * code as engine_push/engine_finish (the queue drained after every push), as
 * cubic segments in absolute track time (see fdiff.h).  For tests, benches
 * and tools; allocates an engine (not for a periodic path).
 * Waypoints the engine refuses are skipped as engine_push would.
 * Returns 0, -ENGINE_ECONFIG (bad cfg, or more than max_seg segments),
 * -ENGINE_ENOMEM.  *nseg receives the number of segments written.
 */
int engine_curve(const engine_config_t *cfg, const engine_waypoint_t *wp,
                 size_t n, fdiff_seg_t *seg, size_t max_seg, size_t *nseg);

/*
 * engine_curve with flat arguments, for Python ctypes: the default
 * configuration with method, param, ends, fragment, overlap given,
 * max_speed_m_s = 0 and max_gap_s = 1e9 (one trajectory).  t_s: n times,
 * xyz: n x 3; seg_out: max_seg x 14 doubles (t0_s, dur_s, then c[axis][0..3]
 * for x, y, z).  Returns the number of segments, or a negated engine_error.
 */
long engine_curve_flat(int method, int param, int ends, unsigned fragment,
                       unsigned overlap, size_t n, const double *t_s,
                       const double *xyz, double *seg_out, size_t max_seg);

#endif
