/*
 * safety.h - the last check every setpoint passes before it leaves the
 * daemon: no step, no speed and no acceleration above an object's bounds.
 *
 * It is deliberately separate from the interpolation: it shares no code with
 * lib/engine or lib/spline and does not trust the velocity or acceleration
 * the engine reports.  It looks only at the positions that were actually
 * sent and the times of their ticks, and judges the new one by finite
 * differences:
 *   step  = |p_k - p_{k-1}|                            (Euclidean, metres)
 *   v_k   = (p_k - p_{k-1}) / dt_k,  dt_k = now_k - now_{k-1}
 *   speed = |v_k|,   accel = |v_k - v_{k-1}| / ((dt_{k-1} + dt_k) / 2)
 *   (the two velocities belong to the middles of their intervals)
 *   per axis also jerk = |a_k - a_{k-1}| / the time between the two
 *   accelerations (third differences: p_k - 3 p_{k-1} + 3 p_{k-2} - p_{k-3}
 *   over dt^3 on a regular grid)
 * dt is the time between two outputs, so skipped ticks are judged over the
 * time that really passed.
 *
 * A violation is never sent: the setpoint is replaced by the last one sent
 * (the position held, velocity and acceleration 0, flags HOLD and
 * ENGINE_SP_FAULT), the fault latches, and every later setpoint is replaced
 * the same way until safety_rearm() (after the engine was made to stand on
 * the held position again).  Holding is itself a stop within one tick: the
 * monitor is the last line of defence for what must never happen, not a way
 * to stop motion smoothly (that is the engine's job).
 *
 * Before the first position (ENGINE_SP_NO_POSITION) nothing is judged; a
 * setpoint without a position after one with a position is a violation.
 *
 * Pure: no I/O, no clock, no allocation.  The daemon logs from the counters.
 */
#ifndef TRAJD_SAFETY_H
#define TRAJD_SAFETY_H

#include <stdint.h>

#include "motion.h"

/* Setpoint flag: the safety monitor replaced this setpoint by a hold. */
#define SAFETY_SP_FAULT ENGINE_SP_FAULT

/* What was violated (the first one found, in this order). */
enum safety_fault {
    SAFETY_OK = 0,
    SAFETY_FNOTFINITE = 1, /* a position, velocity or acceleration is NaN or infinite, or
                            * the position lost after having one */
    SAFETY_FTIME = 2,      /* the tick time did not advance */
    SAFETY_FSTEP = 3,      /* step above safety_max_step_m */
    SAFETY_FSPEED = 4,     /* step / dt above safety_max_speed_m_s */
    SAFETY_FACCEL = 5,     /* change of step / dt per dt above safety_max_accel_m_s2 */
    SAFETY_FBOX = 6,       /* a position outside the box (box_min_m .. box_max_m) */
    SAFETY_FAXIS = 7,      /* one axis's speed, acceleration or jerk above its bound */
    SAFETY_FAULT_COUNT
};

/* Text for a safety_fault ("step above its bound", ...). */
const char *safety_strerror(int fault);

typedef struct {
    double max_step_m;     /* largest step between two outputs; 0 = not checked */
    double max_speed_m_s;  /* 0 = not checked */
    double max_accel_m_s2; /* 0 = not checked */
    double tol_m;          /* added to every bound after converting it to metres per
                               output (rounding of positions of up to 1e7 m: 1e-8 m
                               default, SAFETY_TOL_M_DEFAULT) */
    /* box 1: every position within box_min_m .. box_max_m per axis (soft
     * limits; +-inf: that axis free) */
    int box;
    double box_min_m[ENGINE_AXES], box_max_m[ENGINE_AXES];
    /* per axis (issue 32): |step_k| / dt, the change of it per dt and the
     * change of that per dt; 0 = that axis not checked */
    double axis_speed_m_s[ENGINE_AXES], axis_accel_m_s2[ENGINE_AXES], axis_jerk_m_s3[ENGINE_AXES];
} safety_limits_t;

#define SAFETY_TOL_M_DEFAULT 1e-8
/* The daemon's per-axis bounds: this much above the engine's per-axis limits
 * (axis_max_speed_m_s, axis_max_accel_m_s2, axis_max_jerk_m_s3), for the
 * finite differences of the setpoints the monitor measures by
 * (daemon/core/core.c, tests/fuzz). */
#define SAFETY_AXIS_MARGIN 1.1

/* lim's per-axis bounds for an engine's per-axis limits (its
 * axis_max_speed_m_s, axis_max_accel_m_s2 and axis_max_jerk_m_s3; 0: that
 * axis free): SAFETY_AXIS_MARGIN above each, as the daemon holds them. */
void safety_axis_limits(safety_limits_t *lim, const double speed_m_s[ENGINE_AXES],
                        const double accel_m_s2[ENGINE_AXES], const double jerk_m_s3[ENGINE_AXES]);

typedef struct {
    safety_limits_t lim;
    int have_pos; /* a position was sent */
    int have_vel; /* two were sent: last_vel is meaningful */
    int64_t last_ns;
    double last_pos[ENGINE_AXES];
    double last_vel[ENGINE_AXES];
    double last_dt;                  /* the interval last_vel was measured over, s (0 = unknown) */
    int have_acc;                    /* three were sent: last_acc is meaningful */
    double last_acc[ENGINE_AXES];    /* per axis, between the last two velocities */
    double last_span;                /* the time between those two velocities, s */
    int fault;                       /* latched safety_fault, 0 = none */
    uint64_t checked;                /* setpoints judged */
    uint64_t violations;             /* setpoints refused while not yet faulted + while faulted */
    uint64_t held;                   /* setpoints replaced by the hold (faulted) */
    uint64_t by[SAFETY_FAULT_COUNT]; /* first violations by reason */
    double last_value;               /* the violating value of the last violation (m, m/s, m/s^2,
                                        m/s^3) */
    double last_limit;               /* and the bound it broke */
    int last_fault;                  /* and its safety_fault (kept over safety_rearm) */
} safety_t;

/*
 * Start with no history and no fault.  lim is copied; negative or NaN
 * bounds are taken as 0 (not checked), tol_m <= 0 or NaN as the default.
 */
void safety_init(safety_t *s, const safety_limits_t *lim);

/*
 * Forget the position history (fault kept): the output's position was
 * re-established from outside (a drive's actual position) or deliberately
 * dropped (ENGINE_SP_NO_POSITION): the next position is taken as the first.
 */
void safety_forget(safety_t *s);

/* New bounds (as safety_init takes them), history and fault kept. */
void safety_set_limits(safety_t *s, const safety_limits_t *lim);

/*
 * Judge sp (in place).  Returns SAFETY_OK if sp may be sent as it is, or the
 * safety_fault found (or already latched), in which case sp was replaced by
 * the hold described above.  Counts in s.
 */
int safety_check(safety_t *s, engine_setpoint_t *sp);

/* The latched fault, 0 if none. */
int safety_fault(const safety_t *s);

/* The held position (the last one sent); 0, or -1 if none was ever sent. */
int safety_held(const safety_t *s, double pos_m[ENGINE_AXES]);

/*
 * Clear the latched fault: the next setpoint is judged against the held
 * position again, as if the output had rested there (velocity 0).  The
 * caller first makes the engine stand on safety_held() (engine_clear then
 * engine_set_position), so the motion resumes from there by a transfer.
 */
void safety_rearm(safety_t *s);

#endif
