/*
 * motion.h - the types every part of trajd shares: a waypoint in, a setpoint
 * out, the engine's state and counters, and the error codes that explain a
 * refused waypoint.  The streaming engine (lib/engine/), the protocol codecs
 * (lib/proto/) and the path toolkit (lib/spline/path.h) include this header
 * rather than each other, so a codec never depends on the engine for a struct.
 * The names keep the engine_ prefix: they are the engine's interface types.
 * Their names (engine_strerror, engine_reason_name, engine_state_name) are in
 * motion.c, so a codec that names a refusal links no engine.
 */
#ifndef TRAJD_MOTION_H
#define TRAJD_MOTION_H
/* trajd public API: installed as <trajd/motion.h> (make install; pkg-config trajd). */
/* The #define tables are read by the tests (tests/helpers/mbsim.py,
 * tests/oracle/test_trajreplay.py) one line each: kept as written. */
/* clang-format off */

#include <stdint.h>

/* Linear axes of every waypoint and setpoint: x, y, z. */
#define ENGINE_AXES 3

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
    ENGINE_EACCEL = 11,     /* implied acceleration from the last two waypoints above max_accel_m_s2 */
    ENGINE_EUNCONFIRMED = 12, /* far from the trajectory in time or space (or at odds with its
                                 neighbours) and not confirmed by `confirm` consistent waypoints */
    ENGINE_ESTALE = 13,     /* repeats the last position while the object was moving: a frozen fix */
    ENGINE_ERROR_COUNT
};

/* Non-error outcome of engine_push: an exact duplicate was dropped. */
#define ENGINE_DUPLICATE 1

/* Human-readable text for an engine_error (positive or negated). */
const char *engine_strerror(int err);

/* Short name of a reason a waypoint is refused for bad data ("speed",
 * "stale", ...: trajreplay's reports, the daemon's log, config/PROTOCOL.md),
 * NULL for codes that are not such a reason (EFULL, ECONFIG, ...). */
const char *engine_reason_name(int err);

typedef struct {
    double t_s;                  /* waypoint time, seconds, sender's track clock */
    double pos_m[ENGINE_AXES];   /* x, y, z (east, north, up for geographic input), metres */
    uint32_t seq;                /* transport sequence number (0 if none) */
    uint32_t has_vel;            /* 1: vel_m_s is the source's velocity at t_s */
    double vel_m_s[ENGINE_AXES]; /* m/s, same axes; read only with has_vel (zero-initialise
                                    waypoints: {0} or calloc), only by the local methods */
} engine_waypoint_t;

/* A waypoint the engine refused, as reported by engine_rejection_next: the
 * verdict on a waypoint may come a few waypoints after it was pushed (it is
 * judged with its neighbours), so the caller learns it here. */
typedef struct {
    uint32_t seq;                /* the waypoint's seq as pushed */
    int reason;                  /* engine_error (positive) */
    double t_s;
    double pos_m[ENGINE_AXES];
} engine_rejection_t;

typedef enum {
    ENGINE_STATE_WAITING = 0,   /* no trajectory yet, or lookahead not yet buffered; holding */
    ENGINE_STATE_STREAMING = 1, /* moving along the curve */
    ENGINE_STATE_UNDERRUN = 2,  /* waypoints late: holding the last setpoint */
    ENGINE_STATE_FINISHED = 3,  /* end of track reached, at rest on the last waypoint */
} engine_state_t;

/* Name of a state, "waiting", "streaming", "underrun", "finished". */
const char *engine_state_name(engine_state_t s);

/* Setpoint flags. */
#define ENGINE_SP_HOLD      0x01u /* position held (waiting, underrun, finished) */
#define ENGINE_SP_NEW_TRACK 0x02u /* first setpoint of a new trajectory (after a gap or clear) */
#define ENGINE_SP_SKIPPED   0x04u /* ticks were skipped before this one (trajd: missed
                                         deadlines; trajreplay: a gap not written) */
#define ENGINE_SP_TRANSFER  0x08u /* transfer to a new trajectory: rest-to-rest to its start,
                                   * or a join that keeps moving (lib/engine/join.c) */
/* No valid position exists yet (nothing received, or a required position not
 * yet given): pos_m[] is NaN and is NOT a setpoint.  A subscriber must not
 * move; CiA 402 RPDOs are not sent at all while it is set. */
#define ENGINE_SP_NO_POSITION 0x10u
/* The safety monitor (lib/safety/safety.h) refused the engine's setpoint:
 * this one holds the last position sent, and the object is faulted. */
#define ENGINE_SP_FAULT       0x20u
#define ENGINE_SP_SCALED    0x40u /* time-scaled: the output runs along the curve at a
                                     rate other than 1 (stop, clear, underrun, override) */

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
    double age_s;                   /* under one clock (engine_set_clock): now - t_s, the age of
                                       the instant this setpoint stands for, on the sender's
                                       time base (the play-out delay D plus the lag); NaN for
                                       relative-time tracks and before any position */
} engine_setpoint_t;

typedef struct {
    engine_state_t state;
    uint32_t last_seq;              /* seq of the last accepted waypoint */
    uint32_t buffered;              /* waypoints held, not yet passed by the output */
    uint32_t free;                  /* waypoints that can still be pushed */
    uint32_t lookahead;             /* waypoints needed ahead of the output (from F, O) */
    double ahead_s;                 /* track time of the solved curve ahead of the output
                                     * (the waypoints beyond it are in buffered) */
    uint64_t accepted;
    uint64_t dropped;               /* waypoints accepted that a stop or clear dropped before
                                     * the output passed them: the curve beyond where it came
                                     * to rest (the C2 local methods' to within one); a part
                                     * of accepted */
    uint64_t unjudged;              /* waypoints taken and dropped before their verdict: still
                                     * being judged at a stop or clear, or kept by a stop's
                                     * latch and dropped (past at the start, a clear, a
                                     * reload's smaller buffer; the daemon adds those); not in
                                     * accepted: the waypoints written = accepted + rejected
                                     * + duplicates + unjudged + those still being judged */
    uint64_t duplicates;
    uint64_t rejected;              /* sum of rejected_by[]: bad data only (not EFULL) */
    uint64_t rejected_by[ENGINE_ERROR_COUNT]; /* per engine_error */
    uint64_t underruns;             /* transitions into UNDERRUN */
    uint64_t underrun_ticks;        /* ticks spent in UNDERRUN, those too while a silence
                                       was judged that turned out to be the input's end
                                       (silent_ends; not in underruns) */
    uint64_t skipped_ticks;         /* ticks stepped over (caller late) */
    uint64_t gaps;                  /* trajectories ended by a gap */
    uint64_t tracks;                /* trajectories started */
    uint64_t setpoints;             /* ticks answered */
    uint64_t full;                  /* waypoints refused with ENGINE_EFULL: flow control, the
                                     * sender retries (the same waypoint offered again is not
                                     * counted again); not in rejected */
    uint32_t stalled;               /* 1: holding, and nothing can change before the next
                                     * waypoint is pushed (ticks until then are identical
                                     * holds: trajreplay skips them across a gap) but at
                                     * silence_at_ns */
    int64_t silence_at_ns;          /* stalled: the tick time at which the input's silence
                                     * closes the trajectory (a short one's: max_gap_s after
                                     * its last waypoint came, silence.h); INT64_MAX: none,
                                     * or not stalled */
    uint64_t hard_stops;            /* the solved curve ended under a moving output
                                       (the time scaling failed to brake in time):
                                       velocity set to 0 in one tick.  Should stay 0 */
    double rate;                    /* time-scaling rate ds/dt of the output (1 = as solved) */
    double override;                /* feed override, 0 .. 2 */
    uint64_t reanchors;             /* trajectories ended by `confirm` waypoints that
                                       did not continue it (not a gap) */
    uint64_t transfers;             /* transfers started */
    double transfer_s;              /* their total duration (track seconds) */
    uint64_t transfers_capped;      /* derived transfers cut to max_gap_s (faster than
                                       the object's recent motion) */
    uint64_t rejections_unreported; /* rejections pushed out of the report ring unread */
    uint32_t judging;               /* waypoints pushed and still awaiting their verdict
                                     * (judged with their neighbours: at most 8) */
    uint64_t uniform_irregular;     /* param uniform only: kept waypoints whose two intervals
                                       differ by more than ENGINE_UNIFORM_RATIO_WARN (engine.h):
                                       the velocity steps by that ratio there */
    double uniform_ratio_max;       /* param uniform: the largest ratio of a kept waypoint's two
                                       intervals (longer / shorter; 0 until there are two) */
    double uniform_ratio_t_s;       /* ... and that waypoint's time */
    uint64_t stops;                 /* runs of repeats kept as a stop: the curve rests there */
    uint64_t stop_fixes;            /* repeats kept as the dwell of a stop (in accepted) */
    uint64_t retimed;               /* fixes kept with their stamp re-estimated (jitter) */
    double retime_max_s;            /* the largest such shift, seconds */
    uint64_t silent_ends;           /* trajectories closed after a silence of the input
                                       (lib/engine/silence.h): played out to their end */
    double lag_s;                   /* relative time: how far the output trails its delay D
                                       (lib/engine/catchup.h; < 0: ahead; 0: none known) */
    uint64_t catchups;              /* lags won back (or given back) by the rate */
    double axis_lost_s;             /* time lost to the per-axis limits (issue 32): the
                                       sum of (1 - rate) x period over the ticks streamed
                                       in, or braking for, a segment they slow */
    uint64_t axis_slowed;           /* segments the per-axis limits slow */
    double axis_lag_s;              /* while the per-axis limits hold the rate: how far the
                                       output trails the newest waypoint beyond D */
    uint64_t axis_lag_stops;        /* stops because axis_lag_s passed max_lag_s */
    /* The last underrun (issue 26), for its log line; NaN before any: */
    double underrun_t_s;            /* the output's track time when it began */
    double underrun_newest_t_s;     /* the newest waypoint's stamp then */
    double underrun_next_t_s;       /* the stamp of the first waypoint after it (NaN: none
                                       yet); the silence is the difference */
    double underrun_slack_s;        /* what D held for a late waypoint then: the input's
                                       interval and the jitter slack (delay.h) */
    double underrun_curve_t_s;      /* where the solved curve ended then */
    double underrun_lookahead_s;    /* D's lookahead part then: the time the waypoints the
                                       solver needs beyond its curve may span */
    double underrun_silence_s;      /* the silence that then ended its trajectory
                                       (lib/engine/silence.h; NaN: none) */
    uint32_t underrun_judging;      /* the waypoints then awaiting their verdict (the
                                       acceptance's; 1 as usual, more while it holds fixes
                                       until a later one tells them: a run of repeats) */
    double underrun_judging_t_s;    /* the stamp of the oldest of them (NaN: none) */
    uint64_t delay_grown;           /* D stated anew, longer: the input's intervals or its
                                       top speed grew beyond what D was sized for */
    uint64_t reserve_slowed;        /* slowdowns of an object faster than the speed D's stop
                                       reserve was sized for, or with a fix lost within the
                                       lookahead: the curve ahead short of a stop while the
                                       output stood ahead of its D (which grows with the
                                       input's top speed, lib/engine/delay.h); the data came
                                       on time: not underruns */
    uint64_t transfers_moving;      /* re-anchors joined moving (lib/engine/join.c): the
                                       output met the new trajectory's curve without
                                       braking to rest; not in transfers */
    uint64_t axis_beyond;           /* stops before a segment the per-axis limits cannot
                                       follow: it would need a rate below ENGINE_CEIL_MIN
                                       (the track over 100 times faster on an axis than
                                       its limit); told as the lag is */
    double limits_lost_s;           /* time lost to the object's own speed and acceleration
                                       limits (max_speed_m_s, max_accel_m_s2: the
                                       profile's): as axis_lost_s, over the segments they
                                       slow and not the per-axis limits; the output trails
                                       its input by that much more than D, which the
                                       catch-up does not win back where they slow it */
    uint64_t limits_slowed;         /* segments those limits slow */
    /* The last re-anchor (reanchors: a new trajectory begun where nothing held
     * continued the current one: a clock stepped back or far ahead, a log
     * replayed again, a jump), for its log line: */
    double reanchor_t_s;            /* the stamp of the waypoint that began it */
    double reanchor_from_t_s;       /* the last stamp kept before it */
    uint32_t reanchor_seq;          /* that waypoint's seq */
} engine_status_t;

/* clang-format on */
#endif
