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
 * segments needed are solved, and setpoint times are t(first) + n * period
 * exactly (n counted in integers), segments entered at the fractional phase
 * left over.  Between the curve and the output sits the time scaling
 * (timescale.h): when the solved curve ahead runs short (waypoints late) the
 * output slows down along the path so that it can always come to rest
 * before the curve ends (UNDERRUN while it is held back), and speeds up
 * again as waypoints arrive; the track is delayed, never jumped, and no
 * tick changes velocity by more than the scaling's acceleration allows.  A
 * clean run that never needs it is bit-identical to the unscaled stepping.
 *
 * States: WAITING (nothing yet, or a trajectory buffering its lookahead;
 * holding: no position at all before any waypoint (flag NO_POSITION, NaN),
 * then the position given by engine_set_position, or else the first
 * waypoint),
 * STREAMING (moving, including a transfer), UNDERRUN, FINISHED (the last
 * trajectory ran to its end and rests on it, or the input ended with nothing
 * to stream; pushing again starts a new one).
 *
 * Trajectories, gaps and transfers.  A trajectory is the waypoints between
 * two ends: engine_finish/engine_stop, engine_clear, a gap (an interval
 * above max_gap_s), or a silence of the input longer than the play-out
 * delay D less its lookahead, max_gap_s for a trajectory with fewer
 * intervals than its lookahead (silence.h: counted in silent_ends; the
 * arrival is the first tick time after a push).  A gap ends the current
 * trajectory exactly as
 * engine_finish does (the configured end condition on its last waypoint; the
 * default REST stops there at rest) and the waypoint after the gap starts a
 * new one.  Setpoints never jump: when a new trajectory starts where the
 * output does not stand (after a gap, a clear, or with HELD ends), the output
 * first moves there with a rest-to-rest smoothstep k(u) = A + (B-A)(3u^2-2u^3)
 * within the object's own limits (transfer.h: transfer_speed_m_s and
 * transfer_accel_m_s2, derived from its recent motion by default; bounded
 * in time when derived), rounded up to whole periods (flags TRANSFER; the
 * first setpoint of every trajectory carries NEW_TRACK and track + 1).
 * Before any motion at all, with no position set, the output adopts the
 * first waypoint as where it stands (the last resort; see
 * engine_set_position), and reaches the curve's start from there (the same
 * point, except for HELD ends and SMOOTH).
 * Waypoint times may restart (e.g. from 0) with each new trajectory.
 *
 * Method and parameterisation (see hoang.h, cubic.h, lib/engine/DESIGN.md):
 *   (a) ENGINE_PARAM_UNIFORM  the paper: uniform B-spline, each segment
 *       mapped linearly onto its own time interval.  Physical velocity jumps
 *       at every waypoint whose neighbouring intervals differ (measured on
 *       gpxgo_visnjan: up to 9.0 m/s on a walk), by their ratio: such
 *       waypoints (ratio above ENGINE_UNIFORM_RATIO_WARN) are counted in
 *       engine_status_t uniform_irregular, and trajd and trajreplay warn.
 *       With a per-axis limit set (axis_max_*) the segments are joined in
 *       velocity instead (cubic_join): no axis holds its limits across a step.
 *   (b) ENGINE_PARAM_TIME     knots at the timestamps: C2 in physical time,
 *       but at the nodes about a fragment junction, which are joined in
 *       velocity (cubic_join) and step in acceleration by the junction's
 *       residual (before the join, they stepped in velocity: 4.0e-6 m/s on
 *       the same track with the defaults, F=28, O=24; 196 m/s on a 90 m/s
 *       zig-zag at F=6, O=2).  The default, because motion controllers follow
 *       velocity and acceleration, and real tracks are irregular.
 * METHOD_BSPLINE with PARAM_TIME is the non-uniform cubic B-spline
 * interpolant on the timestamps, which is the same curve as METHOD_CUBIC with
 * PARAM_TIME (unique C2 interpolant); it is computed in the second-derivative
 * form and checked against scipy's B-spline interpolant in test_spline.py.
 * (a) with fragments hits a waypoint exactly only where the stencil stays in
 * one fragment; near the junctions it misses by ~rho^(O/2) (rho = 2 - sqrt 3);
 * (b) hits every waypoint exactly by construction.
 */
#ifndef TRAJD_ENGINE_H
#define TRAJD_ENGINE_H
/* trajd public API: installed as <trajd/engine.h> (make install; pkg-config trajd). */
/* The #define tables are read by the tests (tests/helpers/mbsim.py,
 * tests/oracle/test_trajreplay.py) one line each: kept as written. */
/* clang-format off */

#include <stddef.h>
#include <stdint.h>

#include "fdiff.h"
#include "motion.h"


/* Param uniform (the paper's parameterisation) maps each segment linearly
 * onto its own interval, so at a waypoint between intervals h1 and h2 the
 * physical velocity steps by the ratio h1 / h2.  Above this ratio (a 10 %
 * velocity step) the waypoint is counted in engine_status_t
 * uniform_irregular, and trajreplay and trajd warn (once) with the numbers. */
#define ENGINE_UNIFORM_RATIO_WARN 1.1

/* Limits on the configuration (checked by engine_config_check). */
#define ENGINE_FRAGMENT_MIN 4
#define ENGINE_FRAGMENT_MAX 1024
/* fragment, overlap, start_slack: picked by the engine (config text "auto") */
#define ENGINE_AUTO 0xFFFFFFFFu
/* accuracy's default.  One tighter that no fragment meets within
 * max_lookahead is refused; at this one (or a looser one) a max_lookahead
 * too short for it picks a local method (engine_config_check) */
#define ENGINE_ACCURACY_DEFAULT 3e-7
/* start_slack auto: the least and the most waypoints it adds */
#define ENGINE_SLACK_AUTO_MIN 1
#define ENGINE_SLACK_AUTO_MAX 8
#define ENGINE_PERIOD_NS_MIN 100000LL        /* 10 kHz */
#define ENGINE_PERIOD_NS_MAX 1000000000LL    /* 1 Hz */




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

/*
 * What kind of object the track belongs to (engine_config_profile).  Each sets
 * the waypoint limits; where the numbers come from:
 *   AUTO     the default, for any of the kinds below: max_speed_m_s 400 (an
 *            airliner at cruise, Mach 0.85 = 250 m/s true airspeed, plus a
 *            strong jet stream stays below it), the speed limit learned from
 *            the track (4 x its recent speed, at least 5 m/s: accept.h),
 *            max_accel_m_s2 30 for changes of speed while turns are free (a
 *            toolpath timed by feed rate turns its corners instantly), stale
 *            fixes dropped.
 *   VESSEL   40 m/s (78 kn: above high-speed craft), 30 m/s^2 (GNSS noise at
 *            5 Hz: legit fixes of the NMEA 2000 figure-8 reach 11.4), stale
 *            fixes dropped.
 *   ROAD     100 m/s (360 km/h), 30 m/s^2 (3 g: far above any road vehicle,
 *            it catches timestamp jitter, not driving), stale fixes dropped.
 *   AIR      400 m/s (as AUTO), 30 m/s^2 (about 3 g: a transport aircraft's
 *            +2.5 g limit load in a level turn is 22.5 m/s^2, an airliner
 *            stays under 0.5 g; aerobatics need it set higher), stale fixes
 *            dropped.  ADS-B stamps are the receiver's times of arrival: at
 *            222 m/s a 0.1 s error is 22 m, so a fast object's fixes are
 *            re-stamped at the pace of the path (accept.h
 *            ACCEPT_RULE_SMOOTH; lib/engine/DESIGN.md "Profiles").
 *   MACHINE  no limits, no stale rule: a feed-rate-timed toolpath changes
 *            velocity instantly at corners and may dwell on a point; every
 *            point is kept (acceleration limits are the CNC planner's job).
 *   NONE     no limits, no stale rule (time order and gaps only), none of
 *            the rules below: the solver alone.
 * Every profile keeps the time rules and the confirmation of new trajectories.
 * All but NONE (issue 27, accept.h ACCEPT_RULE_*): a run of repeats is a stop
 * (the curve rests there) unless the next new position shows the object
 * kept moving (then stale, where stale fixes are dropped); a fix refused for
 * its speed or acceleration whose position lies on the path is kept with
 * its stamp re-estimated, and so is a fast object's fix whose stamp bends
 * the pace; a repeat of a fix refused for its position is refused too; with AUTO's free turns a change of speed along the track is
 * held to max_accel_m_s2.
 */
typedef enum {
    ENGINE_PROFILE_AUTO = 0,
    ENGINE_PROFILE_VESSEL = 1,
    ENGINE_PROFILE_ROAD = 2,
    ENGINE_PROFILE_AIR = 3,
    ENGINE_PROFILE_MACHINE = 4,
    ENGINE_PROFILE_NONE = 5,
    ENGINE_PROFILE_COUNT
} engine_profile_t;

typedef enum {
    ENGINE_METHOD_BSPLINE = 0, /* exact interpolation, Hoang control points */
    ENGINE_METHOD_CUBIC = 1,   /* exact interpolation, second-derivative system (seed 002) */
    ENGINE_METHOD_SMOOTH = 2,  /* least-squares B-spline over the window (not exact) */
    ENGINE_METHOD_HERMITE = 3, /* exact, local: C1 cubic Hermite, velocities from the
                                  source or from each waypoint and the two before */
    ENGINE_METHOD_HERMITE_CENTRED = 4, /* exact, local: as HERMITE, velocities estimated
                                          from the waypoints either side */
    ENGINE_METHOD_HERMITE_C2 = 5,      /* exact, local, C2: position, velocity and
                                          acceleration at each waypoint (hermite.h) */
    ENGINE_METHOD_HERMITE_C2_CENTRED = 6, /* as HERMITE_C2, estimates from either side */
} engine_method_t;

/*
 * The local methods (lib/engine/hermite.h, issue 31): each segment is the
 * cubic Hermite between its two waypoints and their velocities, the
 * source's (engine_waypoint_t has_vel) or estimated; no system is solved,
 * so a segment is final once its end waypoint (HERMITE) or the one after it
 * (HERMITE_CENTRED) is kept: 2 and 3 waypoints of lookahead with the
 * acceptance's 1, instead of the fragments' 8 or more.  Exact through every
 * waypoint, velocity continuous, acceleration not (C1).  HERMITE_C2 and
 * HERMITE_C2_CENTRED also match an acceleration at each waypoint (the
 * parabola's through the same three), continuous (C2): three cubics per
 * interval in place of the quintic Hermite.  A max_lookahead too short for
 * any fragment picks one (engine_config_resolve): 1 or 2 HERMITE_C2, 3 or
 * more HERMITE_C2_CENTRED.  max_lookahead 1 (a local method): a waypoint
 * that follows the one kept before is kept as it arrives, not once its next
 * neighbour is in (accept.h at_arrival), and start_slack auto starts at 0.  ends: rest and clamped start and, for
 * HERMITE_CENTRED, end at the given velocity; natural with zero
 * acceleration; HERMITE's last segment is final before the input is known
 * to end, so its end is braked to along the path (the time scaling).
 */

/*
 * ENGINE_METHOD_SMOOTH (lib/spline/lsq.h, lsq_smooth_*): each waypoint's position
 * is replaced by the value, at its own time, of the least-squares cubic
 * B-spline with smooth_ctrl control points fitted to the smooth_window
 * waypoints around it; the smoothed waypoints then go through the CUBIC
 * path (fragments, end condition, forward differences) unchanged.  The
 * curve no longer passes through the waypoints; it adds smooth_window/2
 * waypoints of lookahead.  For noisy positions (a GNSS fix standing still).
 */
#define ENGINE_SMOOTH_WINDOW_MAX 1024

typedef struct {
    engine_method_t method; /* default CUBIC (see (b) above) */
    engine_param_t param;   /* default TIME: C2 in physical time, see above */
    engine_ends_t ends;     /* default REST: start and stop with zero velocity,
                               no velocity step when the output starts or stops */
    double start_vel_m_s[ENGINE_AXES]; /* ENGINE_ENDS_CLAMPED only (default 0) */
    double end_vel_m_s[ENGINE_AXES];   /* ENGINE_ENDS_CLAMPED only (default 0) */
    unsigned fragment;      /* F: waypoints per fragment, or ENGINE_AUTO (the
                               default): picked with overlap from accuracy and
                               max_lookahead (engine_config_resolve) */
    unsigned overlap;       /* O: waypoints shared by consecutive fragments, even,
                               2 <= O < F, or ENGINE_AUTO (the default).  The
                               error against one global solve is at most
                               2 rho^(O/2) of the curvature scale max|k''|/6
                               (rho = 2 - sqrt(3)); F - O sets the lookahead
                               and the work: see lib/engine/DESIGN.md */
    double accuracy;        /* overlap auto: the smallest even O with
                               2 rho^(O/2) <= accuracy, the error bound
                               against one global solve relative to the
                               curvature scale.  Default 3e-7: O = 24,
                               measured 2e-9 .. 3e-9 of a random walk's
                               extent (lib/engine/DESIGN.md) */
    unsigned max_lookahead; /* fragment auto: the largest S = F - O (the least
                               work per waypoint) whose lookahead, with one
                               waypoint of slack, is at most this many
                               waypoints (regular input; start_slack auto adds
                               what irregular input needs).  Default 18: F = 28
                               with O = 24 */
    int64_t period_ns;      /* output period.  Default 10 ms (100 Hz) */
    unsigned capacity;      /* waypoints buffered at most (lookahead + fragment
                               + 8 .. 2^20; about 272 bytes each).  Default
                               4096: 68 min at 1 Hz, 1.1 MB */
    double max_gap_s;       /* a longer interval ends the trajectory at rest and
                               starts a new one; so does a silence this long,
                               whatever the trajectory's length (silence.h).
                               Default 60 s */
    double max_abs_m;       /* |coordinate| above this is rejected.  Default 1e7 m
                               (beyond the Earth's radius from any ENU origin) */
    engine_profile_t profile; /* what kind of object: the limits below when
                               they are left at ENGINE_LIMIT_PROFILE, and the
                               rules (learned, stale).  Default AUTO */
    double max_speed_m_s;   /* chord speed above this is refused (0 = no
                               limit, ENGINE_LIMIT_PROFILE = the profile's:
                               AUTO 400 m/s); the output never moves faster
                               than ENGINE_SPEED_CAP times it (the time
                               scaling slows down where the curve between
                               the waypoints is faster than their chords).
                               Default ENGINE_LIMIT_PROFILE */
    double max_accel_m_s2;  /* implied acceleration above this is refused (0 =
                               no limit): the change of mean velocity over two
                               intervals, 2 |v2 - v1| / (dt1 + dt2).  Catches
                               timestamp jitter (a fix stamped late or early
                               by a fraction of the interval), which the
                               curve, forced through every waypoint at its
                               time, would turn into an acceleration spike.
                               ENGINE_LIMIT_PROFILE = the profile's (AUTO
                               30 m/s^2, with free turns: see accept.h).
                               Default ENGINE_LIMIT_PROFILE.  Measured on the real
                               tracks: legit samples reach 11.4 at 5 Hz, the
                               figure-8's jittered ones 117 and 44 (lib/engine/DESIGN.md
                               "Jitter and outliers").  Position noise alone
                               implies ~4 noise / dt^2 */
    unsigned confirm;       /* mutually consistent waypoints needed before a
                               waypoint far from the current trajectory (in
                               time, space or at odds with its neighbours)
                               abandons it for a new one, 1..8.  Default 3 */
    double transfer_speed_m_s; /* speed of the rest-to-rest transfers to a new
                               trajectory's start (after a gap, a re-anchor, a
                               clear); 0 = derived from the object's own recent
                               motion (transfer.h).  Default 0 */
    double transfer_accel_m_s2; /* their acceleration; 0 = derived.  Default 0 */
    double max_segment_s;   /* longest segment the stepper is tested for
                               (informational: the stepper re-seeds every
                               FDIFF_RESEED_STEPS, so drift does not grow with
                               the segment).  Default 60 s (= max_gap_s) */
    unsigned start_slack;   /* waypoints buffered beyond what the solver needs
                               before a trajectory's output starts; adds to
                               engine_lookahead.  ENGINE_AUTO (default): from
                               the input's timing, ENGINE_SLACK_AUTO_MIN ..
                               _MAX (lib/engine/DESIGN.md "start_slack
                               auto"); a number fixes it */
    unsigned smooth_window; /* SMOOTH only: waypoints per local least-squares fit,
                               4 .. ENGINE_SMOOTH_WINDOW_MAX.  Default 24 */
    unsigned smooth_ctrl;   /* SMOOTH only: control points per fit,
                               4 .. smooth_window.  Default 6 */
    double scale_accel_m_s2; /* time scaling (timescale.h): the most it adds to
                               the acceleration along the path when it slows
                               down or speeds up (start, end, transfer, stop,
                               clear, underrun, feed override).  Default 5 m/s^2 */
    double scale_jerk_m_s3; /* ... and to the jerk.  Default 50 m/s^3: a stop
                               from v takes v^2/(2 a) + v T (T the
                               period) of path, see lib/engine/TIMESCALE.md.
                               Every output then changes its acceleration
                               per tick by at most T times the jerk bound
                               J_c r^3 + 3 A_c r a / (1 m/s) + j (J_c, A_c the
                               curve's own largest |k'''|, |k''|, r <= 2 the
                               rate, j this or, in a stop, max(j, a / T)):
                               every trajectory and transfer is entered and
                               left at rate 0 (TIMESCALE.md, "Handovers") */
    double delay_s;         /* play-out delay D, s (delay.h): 0 (the default)
                               = what the settings and the input need
                               (lookahead + jitter slack + stop reserve,
                               measured on the input); above 0, the output is
                               held this far behind the newest waypoint
                               (engine_delay_check refuses less than the
                               settings need), and max_lookahead is the most
                               lookahead the solver may take: the longest up
                               to it whose D fits within delay_s at the
                               interval of the first waypoints is taken
                               (engine_input.c engine_pick, issue 31) */
    /* Per-axis limits (issue 32), each x, y, z; 0 = that axis free (the
     * default).  The time scaling slows the output along its path so that
     * |v_k| <= axis_max_speed_m_s[k], |a_k| <= axis_max_accel_m_s2[k] and the
     * curve's own jerk |k_k'''| r^3 <= axis_max_jerk_m_s3[k] / 2: each queued
     * segment's rate is capped (engine_solve.c seg_ceiling), and with an
     * acceleration (jerk) limit the scaling's own scale_accel_m_s2
     * (scale_jerk_m_s3) is taken down to a third (a quarter) of the smallest
     * (resolve), the share its dr/dt term keeps on every segment (a stop's,
     * whose jerk is then scale_jerk_m_s3 too); with a jerk limit each
     * segment's dr/dt also keeps 3 |k_k''| r |dr/dt| within a quarter of it
     * (engine_solve.c jerk_rate_accel): the jerk of every axis within its
     * limit (a C2 curve: on a C1 one engine_config_check refuses it);
     * outside a stop its dr/dt may take, per segment, what the curve's own
     * k_k'' r^2 leaves of each axis's acceleration limit (engine_solve.c
     * accel_speed; lib/engine/TIMESCALE.md "Per-axis limits").  Transfers last
     * long enough for every axis.  The path is never left; the time lost is axis_lost_s
     * (engine_status_t).  A segment that would need a rate below 1/100 (over 100
     * times faster on an axis than its limit) is not entered: the output rests
     * before it and the owner is told to stop (engine_axis_lag_over, axis_beyond). */
    double axis_max_speed_m_s[ENGINE_AXES];
    double axis_max_accel_m_s2[ENGINE_AXES];
    double axis_max_jerk_m_s3[ENGINE_AXES];
    double max_lag_s; /* the most the per-axis limits may make a trajectory's output
                         lag: trail its newest waypoint beyond D (axis_lag_s,
                         engine_status_t, while its input is open): beyond it the object
                         stops on its path and holds, latched until start or clear
                         (engine_axis_lag_over; the lifecycle's "lag" event).  0 (the
                         default): not bounded, counted and warned of only */
    double cap_speed_m_s; /* the output's speed never exceeds it (0, the default: no such
                             cap): each segment faster gets a rate ceiling, so the time
                             scaling slows along the path; transfers and joins keep within
                             it too; the waypoints are kept and passed exactly, their timing
                             yields (limits_lost_s).  Not a setting: the caller's bound
                             (trajd: 95 % of a configured safety_max_speed_m_s where that
                             is below ENGINE_SPEED_CAP x its speed limit, so the monitor
                             never has to hold the motion the engine plans) */
    double cap_accel_m_s2; /* the output's acceleration never exceeds it (0, the default:
                              no such cap): the time scaling's own share is at most
                              ENGINE_CAP_SCALE_SHARE of it (scale_accel_m_s2 is lowered to
                              that where above: engine_config_resolve), each segment whose
                              curve asks more than the rest gets a rate ceiling, transfers
                              last long enough; waypoints kept and passed exactly, their
                              timing yields.  Not a setting: the caller's bound (trajd: 95 %
                              of a configured safety_max_accel_m_s2 where that is below
                              what the engine's own limits let the output reach) */
} engine_config_t;

/* Fill cfg with working defaults (each one commented above; documented in
 * config/trajd.conf). */
void engine_config_default(engine_config_t *cfg);

/* max_speed_m_s or max_accel_m_s2 left to the profile (any value in
 * [-1, 0) means the same). */
#define ENGINE_LIMIT_PROFILE (-1.0)

/* The output's speed |k'(s)| x rate never exceeds ENGINE_SPEED_CAP times the
 * speed limit in force (engine_config_max_speed; none if 0): the acceptance
 * policy bounds the chords between waypoints, the curve between them may be
 * faster (a cubic 1.5 times its chord on a rest-to-rest segment, a uniform
 * B-spline by the ratio of neighbouring intervals), and the time scaling
 * slows down there (lib/engine/TIMESCALE.md, "Speed cap").  Below the
 * daemon's default safety bound, twice the limit. */
#define ENGINE_SPEED_CAP 1.5
/* The time scaling's share of cap_accel_m_s2 at most (engine_config_t): the
 * curve's own acceleration, held by the segments' rate ceilings, has the rest. */
#define ENGINE_CAP_SCALE_SHARE 0.5

/* The limits in force: the field, or the profile's if ENGINE_LIMIT_PROFILE
 * (0 = no limit). */
double engine_config_max_speed(const engine_config_t *cfg);
double engine_config_max_accel(const engine_config_t *cfg);


/*
 * Check a configuration.  Returns 0 or -ENGINE_ECONFIG; if why is not NULL
 * it receives a static string naming the offending field and the rule (NULL
 * when valid).  Refused: METHOD_SMOOTH with smooth_window or smooth_ctrl
 * out of range, HELD or MULTIPLE with
 * anything but BSPLINE + UNIFORM (they are the paper's ends of the
 * control polygon, meaningless in the second-derivative form), F, O, period
 * or capacity out of range, non-finite or non-positive limits, a per-axis
 * jerk limit on a C1 curve (method HERMITE, HERMITE_CENTRED: their
 * acceleration steps at every waypoint).
 */
int engine_config_check(const engine_config_t *cfg, const char **why);

/* One engine per moving object; not thread-safe: push, tick and the commands
 * of one engine must come from one thread (or be serialised by the caller). */
typedef struct engine engine_t;

/*
 * Allocate an engine for cfg (all memory it will ever use is taken here).
 * err (may be NULL) receives 0, ENGINE_ECONFIG or ENGINE_ENOMEM.
 */
engine_t *engine_new(const engine_config_t *cfg, int *err);

/* 1 once each time a trajectory's lag from the per-axis limits passes
 * max_lag_s (issue 32), or its output stands at rest before a segment the
 * per-axis limits cannot follow (engine_status_t axis_beyond: it would need a
 * rate below 1/100), then 0 until the next: the caller stops the object
 * (the lifecycle: LC_EV_LAG; trajreplay: engine_stop). */
int engine_axis_lag_over(engine_t *e);

/* Free; NULL is a no-op. */
void engine_free(engine_t *e);

/*
 * Offer a waypoint.  Returns at once:
 *   0                   taken for judgement (the verdict may come later)
 *   ENGINE_DUPLICATE    same time, to 1 ns, and position, to 1 nm, as the
 *                       previous one: dropped, counted
 *   -ENGINE_ENOTFINITE  NaN or infinite time or coordinate (counted)
 *   -ENGINE_ERANGE      |coordinate| > max_abs_m, or |t_s| > 1e12 s (counted)
 *   -ENGINE_EFULL       capacity waypoints buffered: offer it again later
 *                       (flow control: counted in status.full, not in
 *                       rejected; nothing
 *                       accepted is ever dropped)
 *   -ENGINE_ENUMERIC    the solver refused (cannot happen with finite data:
 *                       the systems are diagonally dominant); the trajectory
 *                       is ended where it was
 * Every other verdict is given with the waypoint's neighbours (accept.h: the
 * waypoints after it are the lookahead the solver buffers anyway, so a clean
 * track waits for nothing extra), within `confirm`..8 waypoints or at
 * engine_finish; a refused waypoint is counted in status.rejected_by and
 * reported by engine_rejection_next with its reason:
 *   ENGINE_EBACKWARDS   earlier than the waypoint kept before it
 *   ENGINE_ESAMETIME    same time as it, different position
 *   ENGINE_ESPEED       chord speed above the limit (max_speed_m_s; learned
 *                       under profile AUTO)
 *   ENGINE_EACCEL       with the two waypoints kept before it (r0, r1 at t0,
 *                       t1), 2 |(r - r1)/(t - t1) - (r1 - r0)/(t1 - t0)| / (t - t0)
 *                       > max_accel_m_s2 (timestamp jitter, position jump)
 *   ENGINE_ESTALE       the same position again while the object was moving
 *   ENGINE_EUNCONFIRMED far from the trajectory in time or space (e.g. one
 *                       waypoint at t = 1e9, or a burst of fewer than
 *                       `confirm` fixes 1 km off, consistent among
 *                       themselves), or at odds with its neighbours, and not
 *                       confirmed by `confirm` consistent waypoints (a lone
 *                       spike is ESPEED or EACCEL)
 * A bad waypoint is dropped when its neighbours agree without it, so it
 * never condemns the good ones after it.  `confirm` mutually consistent
 * waypoints that do not continue the trajectory end it at rest (a gap if
 * the interval exceeds max_gap_s, else a re-anchor) and start a new one,
 * reached by a transfer.
 */
int engine_push(engine_t *e, const engine_waypoint_t *wp);

/*
 * The checks engine_push makes on wp alone, before any neighbour is seen:
 * 0, -ENGINE_ENOTFINITE or -ENGINE_ERANGE (cfg->max_abs_m, |t_s| > 1e12 s),
 * or, for the source's velocity (has_vel), -ENGINE_ENOTFINITE or
 * -ENGINE_ESPEED (faster than the speed limit in force; without one, than
 * max_abs_m per second).
 * A waypoint that fails them is refused by every engine with cfg; one that
 * passes may still be refused with its neighbours.  Pure (config checks:
 * a track none of whose waypoints passes has nothing usable).
 */
int engine_waypoint_check(const engine_config_t *cfg, const engine_waypoint_t *wp);

/*
 * The oldest unread refused waypoint (reason and all), 1, or 0 if none.
 * The engine keeps the last ENGINE_REJECTIONS_KEPT; older unread ones are
 * counted in status.rejections_unreported (the counters stay exact).
 */
#define ENGINE_REJECTIONS_KEPT 64
int engine_rejection_next(engine_t *e, engine_rejection_t *r);

/*
 * End of input for the current trajectory: every waypoint still held is
 * judged, the last fragment is closed with
 * the configured end condition and the output runs to the last waypoint and
 * stops there (FINISHED).  Pushing again afterwards starts a new trajectory.
 * Returns 0 (also when there is nothing to finish), or -ENGINE_ENUMERIC.
 */
int engine_finish(engine_t *e);

/*
 * Produce the setpoint for now_ns (the scheduled tick).  Never allocates,
 * never fails on data: bad waypoints were refused at push.  Returns 0, or
 * -ENGINE_ESTATE if now_ns went backwards (sp then repeats the last setpoint).
 */
int engine_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp);

/* Commands (Modbus holding registers, CAN, the daemon on SIGTERM).
 * Stop and clear are controlled stops by the time scaling (timescale.h,
 * lib/engine/TIMESCALE.md): the output slows down along the path it is on,
 * within scale_accel_m_s2 and scale_jerk_m_s3, to rest within
 * v^2/(2 a) + v T of path (the stop's jerk is max(scale_jerk_m_s3, a/T)),
 * and only then is anything dropped.
 * Waypoints pushed meanwhile start a new trajectory, kept. */
/* Stop, then drop every waypoint and segment buffered at the time of the
 * call; the output rests where it stopped, WAITING; the next waypoint starts
 * a new trajectory, reached by a transfer. */
void engine_clear(engine_t *e);
/* Stop now (category 1): as engine_clear, but the state at rest is FINISHED.
 * Of a clear and a stop given while the output brakes, the later one decides
 * the state at rest.  (To run on to the last waypoint received, use
 * engine_finish.)  Returns 0. */
int engine_stop(engine_t *e);
/*
 * Where the object really stands (drive feedback, a config key), before the
 * output moves it: the output holds there and reaches the first trajectory's
 * start by a transfer instead of taking it as its position.  Valid while the
 * output holds (WAITING, FINISHED, after engine_clear), not while it streams,
 * transfers or underruns.  Returns 0, -ENGINE_ENOTFINITE, -ENGINE_ERANGE
 * (|coordinate| > max_abs_m), or -ENGINE_ESTATE (the output is moving).
 *
 * Without it the engine's last resort is the first waypoint: the output
 * adopts it as its position when it is received (ENGINE_SP_NO_POSITION, and
 * NaN positions, until then).  Once the output has a position it never
 * leaves it except by streaming or a transfer: no setpoint ever jumps.
 */
int engine_set_position(engine_t *e, const double pos_m[ENGINE_AXES]);

/*
 * Stand at pos_m at rest now, whatever the output was doing: every
 * waypoint and segment buffered is dropped, the state is WAITING and the
 * next waypoint starts a new trajectory, reached by a transfer.  Only for
 * an output that was not sent (the lifecycle owner froze it: a safety or
 * drive hold, lifecycle.h), so stopping it is no step of what went out.
 * Returns 0, -ENGINE_ENOTFINITE or -ENGINE_ERANGE (|coordinate| >
 * max_abs_m; the engine is then unchanged).
 */
int engine_halt(engine_t *e, const double pos_m[ENGINE_AXES]);

/*
 * on = 1: no first-waypoint fallback; the output stays without a position
 * (ENGINE_SP_NO_POSITION, WAITING) and buffers waypoints until
 * engine_set_position gives one (e.g. the drive's position actual value is
 * awaited).  If the output holds, the position it had is dropped too (its
 * drive faulted: where it stands must come from the drive again).  on = 0:
 * the default.
 */
void engine_require_position(engine_t *e, int on);

/* 1 once the output has a position (set, or the first waypoint adopted). */
int engine_has_position(const engine_t *e);

/*
 * Feed override: the output runs along the same path at ratio times the
 * solved speed (0 = stand still on the path, 2 = 200 %), ramped within the
 * time scaling's limits; positions stay on the curve (it is evaluated at the
 * scaled track time, reported in the setpoint's t_s).  Kept across
 * trajectories.  Returns 0, or -ENGINE_ERANGE (NaN, below 0 or above 2).
 */
int engine_set_override(engine_t *e, double ratio);
/*
 * One clock (issue 16 item 2, lib/engine/CLOCK.md).  For tracks stamped in
 * absolute time (seconds since the epoch), the caller passes, before every
 * engine_tick, the time now on the sender's time base (its CLOCK_REALTIME
 * with the sender's drift absorbed: playout.h) and the play-out delay D.
 * The output then stands at track time now - D, the same instant for every
 * engine given the same clock, instead of an origin of its own:
 *   - a trajectory starts when now - D reaches its first waypoint's time
 *     (a transfer to it starts early enough to arrive by then), at rate 0
 *     like every start (its acceleration never steps), so behind now - D
 *     by the sub-tick phase of that moment and the ramp; it catches up as
 *     below and locks: its track time is then exactly now - D at every
 *     tick (the curve evaluated there, velocity k' * rate);
 *   - when the solved curve runs short (waypoints late) the time scaling
 *     slows it down as without a clock; behind the clock by a lag L, the
 *     output runs at rate + min(ENGINE_CLOCK_GAIN * L, catchup) (a bounded
 *     catch-up within scale_accel_m_s2 and scale_jerk_m_s3), and locks
 *     again once within ENGINE_CLOCK_LOCK_S of now - D;
 *   - a feed override below 100 % slows it down (the lag is won back
 *     afterwards); above 100 % it cannot run ahead of the clock.
 * The setpoint's age_s is now - t_s.  Without engine_set_clock the engine
 * keeps its own origin per trajectory exactly as before (relative time).
 * Once called, the engine stays clocked: call it before every tick.
 * Returns 0, or -ENGINE_ERANGE (delay_ns < 0, rate outside 1 +- 1e-3,
 * catchup outside 0 .. 1, or now_ns before the previous call's).
 */
#define ENGINE_CLOCK_GAIN 1.0        /* 1/s: a lag decays with a time constant of 1 s */
#define ENGINE_CLOCK_LOCK_S 1e-6     /* lag within which the output locks on the clock */
#define ENGINE_CLOCK_RATE_TOL 1e-3   /* |rate - 1| accepted at most */
typedef struct {
    int64_t now_ns;   /* now on the sender's time base, ns since the epoch */
    int64_t delay_ns; /* play-out delay D: the output stands at now - D */
    double rate;      /* d now / dt: 1 + the sender's drift */
    double catchup;   /* most the rate rises above `rate` to win back a lag
                         (0.05: 5 %) */
} engine_clock_t;
int engine_set_clock(engine_t *e, const engine_clock_t *clk);

/*
 * Relative time (no engine_set_clock): the output follows its own estimate
 * of the sender's time from the arrivals of its waypoints, and wins back a
 * lag beyond D (an underrun, a transfer) or follows a sender whose clock
 * runs fast or slow at most `catchup` faster or slower than the curve
 * (lib/engine/catchup.h; default 0.05; 0: never steered).  Also the
 * catch-up of engine_set_clock until that is called.  Returns 0, or
 * -ENGINE_ERANGE (outside 0 .. 1).
 */
int engine_set_catchup(engine_t *e, double catchup);

/* Zero every counter of engine_status (state and last_seq are kept). */
void engine_reset_counters(engine_t *e);

/* Snapshot of state and counters. */
void engine_status(const engine_t *e, engine_status_t *st);

/* A hint, no effect on any result: start loading the parts of e that a tick,
 * engine_status and engine_rejection_next read (about 45 cache lines of its
 * 17 KB), so that a caller that ticks many engines in turn can ask for the
 * next one's while it works on this one: each engine's first touch in a tick
 * is otherwise a run of cache misses one after another. */
void engine_prefetch(const engine_t *e);

/* Add the counters of more (an engine's that another took over from: a reload
 * that changed its object's settings) into st: the counts summed, the
 * largest values (uniform_ratio_max, retime_max_s) the larger; state and the
 * values of the moment (buffered, rate, lag_s, the last underrun's ...) left. */
void engine_status_add_counts(engine_status_t *st, const engine_status_t *more);

/*
 * Waypoints of lookahead this configuration needs (depends on F, O and
 * whether the unknowns are control points): the most waypoints beyond a
 * segment's end that must have arrived before it is final.  The output waits
 * for it at the start (and after an underrun), so the delay between receiving
 * a waypoint and passing through it is about (lookahead + 1) waypoint
 * intervals.  About S + O/2 + start_slack (S = F - O); 0 if F, O invalid.
 */
unsigned engine_lookahead(const engine_config_t *cfg);

/*
 * cfg with fragment and overlap ENGINE_AUTO replaced by what accuracy and
 * max_lookahead pick (the others copied).  Returns 0, or -ENGINE_ECONFIG
 * when no fragment fits within max_lookahead (engine_config_check says why).
 */
int engine_config_resolve(const engine_config_t *cfg, engine_config_t *out);

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

/* clang-format on */
#endif
