/*
 * safety.c - the last check before a setpoint leaves (see safety.h).
 * Shares nothing with the engine: positions and tick times only.
 */
#include "safety.h"

#include <math.h>
#include <string.h>

#define AX ENGINE_AXES

const char *safety_strerror(int fault)
{
    switch (fault < 0 ? -fault : fault) {
    case SAFETY_OK: return "ok";
    case SAFETY_FNOTFINITE:
        return "position, velocity or acceleration not finite (or the position lost after "
               "having one)";
    case SAFETY_FTIME: return "tick time did not advance";
    case SAFETY_FSTEP: return "step above safety_max_step_m";
    case SAFETY_FSPEED: return "speed above safety_max_speed_m_s";
    case SAFETY_FACCEL: return "acceleration above safety_max_accel_m_s2";
    case SAFETY_FBOX: return "position outside position_min_m .. position_max_m";
    case SAFETY_FAXIS: return "one axis's speed, acceleration or jerk above its per-axis bound";
    default: return "unknown safety fault";
    }
}

/* A bound that is not a positive finite number is "not checked" (0). */
static double bound(double v)
{
    return v > 0 && isfinite(v) ? v : 0.0;
}

void safety_axis_limits(safety_limits_t *lim, const double speed_m_s[ENGINE_AXES],
                        const double accel_m_s2[ENGINE_AXES], const double jerk_m_s3[ENGINE_AXES])
{
    for (int k = 0; k < ENGINE_AXES; k++) {
        lim->axis_speed_m_s[k] = SAFETY_AXIS_MARGIN * speed_m_s[k];
        lim->axis_accel_m_s2[k] = SAFETY_AXIS_MARGIN * accel_m_s2[k];
        lim->axis_jerk_m_s3[k] = SAFETY_AXIS_MARGIN * jerk_m_s3[k];
    }
}

void safety_init(safety_t *s, const safety_limits_t *lim)
{
    memset(s, 0, sizeof *s);
    safety_set_limits(s, lim);
}

void safety_set_limits(safety_t *s, const safety_limits_t *lim)
{
    s->lim.max_step_m = bound(lim->max_step_m);
    s->lim.max_speed_m_s = bound(lim->max_speed_m_s);
    s->lim.max_accel_m_s2 = bound(lim->max_accel_m_s2);
    s->lim.tol_m = bound(lim->tol_m) > 0 ? lim->tol_m : SAFETY_TOL_M_DEFAULT;
    s->lim.box = lim->box;
    memcpy(s->lim.box_min_m, lim->box_min_m, sizeof s->lim.box_min_m);
    memcpy(s->lim.box_max_m, lim->box_max_m, sizeof s->lim.box_max_m);
    for (int k = 0; k < ENGINE_AXES; k++) {
        s->lim.axis_speed_m_s[k] = bound(lim->axis_speed_m_s[k]);
        s->lim.axis_accel_m_s2[k] = bound(lim->axis_accel_m_s2[k]);
        s->lim.axis_jerk_m_s3[k] = bound(lim->axis_jerk_m_s3[k]);
    }
}

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

/* Replace sp by the hold on the last position sent. */
static void hold(safety_t *s, engine_setpoint_t *sp)
{
    for (int k = 0; k < AX; k++) {
        sp->pos_m[k] = s->last_pos[k];
        sp->vel_m_s[k] = 0.0;
        sp->acc_m_s2[k] = 0.0;
    }
    sp->flags |= ENGINE_SP_HOLD | ENGINE_SP_FAULT;
    sp->flags &= ~(uint32_t)(ENGINE_SP_NO_POSITION | ENGINE_SP_TRANSFER);
    s->held++;
    if (sp->now_ns > s->last_ns)
        s->last_ns = sp->now_ns;
    memset(s->last_vel, 0, sizeof s->last_vel);
    s->last_dt = 0;
    s->have_acc = 0;
}

/* 1 if a finite position of sp is outside the box: *value the coordinate,
 * *limit the bound it passed. */
static int outside_box(const safety_limits_t *l, const engine_setpoint_t *sp, double *value,
                       double *limit)
{
    for (int k = 0; l->box && k < AX; k++)
        if (sp->pos_m[k] < l->box_min_m[k] || sp->pos_m[k] > l->box_max_m[k]) {
            *value = sp->pos_m[k];
            *limit = sp->pos_m[k] < l->box_min_m[k] ? l->box_min_m[k] : l->box_max_m[k];
            return 1;
        }
    return 0;
}

/* What judge works out of a new position against the last output: the
 * velocity over the interval dt since it, and (with a velocity before) its
 * change dv, over span, the time between the two velocities' middles. */
typedef struct {
    double vel[AX], dv[AX], dt, span;
} motion_t;

/* The per-axis bounds (issue 32), as the norms: speed, acceleration between
 * the last two velocities (span apart), jerk between the last two
 * accelerations (the mean of their spans apart); in metres of change per
 * output, with the rounding tolerance (twice it for the third differences). */
static int judge_axes(const safety_t *s, const double *d, const motion_t *m, double *value,
                      double *limit)
{
    const safety_limits_t *l = &s->lim;
    double dt = m->dt, span = m->span, js = 0.5 * (s->last_span + span);
    for (int k = 0; k < AX; k++) {
        if (l->axis_speed_m_s[k] > 0 && fabs(d[k]) > l->axis_speed_m_s[k] * dt + l->tol_m) {
            *value = fabs(d[k]) / dt;
            *limit = l->axis_speed_m_s[k];
            return SAFETY_FAXIS;
        }
        if (!s->have_vel)
            continue;
        double dv = m->dv[k];
        if (l->axis_accel_m_s2[k] > 0 &&
            fabs(dv) * span > l->axis_accel_m_s2[k] * span * span + l->tol_m) {
            *value = fabs(dv) / span;
            *limit = l->axis_accel_m_s2[k];
            return SAFETY_FAXIS;
        }
        if (l->axis_jerk_m_s3[k] > 0 && s->have_acc &&
            fabs(dv / span - s->last_acc[k]) * span * js >
                l->axis_jerk_m_s3[k] * span * js * js + 2.0 * l->tol_m) {
            *value = fabs(dv / span - s->last_acc[k]) / js;
            *limit = l->axis_jerk_m_s3[k];
            return SAFETY_FAXIS;
        }
    }
    return SAFETY_OK;
}

/* First violation of sp against the last output, with its value and bound. */
static int judge(const safety_t *s, const engine_setpoint_t *sp, double *value, double *limit,
                 motion_t *m)
{
    const safety_limits_t *l = &s->lim;
    double d[AX], dt, step;

    if (sp->flags & ENGINE_SP_NO_POSITION) {
        *value = NAN;
        *limit = 0;
        return SAFETY_FNOTFINITE; /* a position was sent before: it cannot be lost */
    }
    for (int k = 0; k < AX; k++)
        if (!isfinite(sp->pos_m[k]) || !isfinite(sp->vel_m_s[k]) || !isfinite(sp->acc_m_s2[k])) {
            /* a NaN velocity or acceleration goes out too (csv, Modbus): never unflagged */
            *value = !isfinite(sp->pos_m[k])     ? sp->pos_m[k]
                     : !isfinite(sp->vel_m_s[k]) ? sp->vel_m_s[k]
                                                 : sp->acc_m_s2[k];
            *limit = 0;
            return SAFETY_FNOTFINITE;
        }
    if (outside_box(l, sp, value, limit))
        return SAFETY_FBOX;
    if (sp->now_ns <= s->last_ns) {
        *value = (double)(sp->now_ns - s->last_ns) * 1e-9;
        *limit = 0;
        return SAFETY_FTIME;
    }
    dt = (double)(sp->now_ns - s->last_ns) * 1e-9; /* > 0 */
    /* the velocities belong to the middles of their intervals: after a
     * skipped tick they are (dt_prev + dt)/2 apart, not dt */
    m->dt = dt;
    m->span = s->last_dt > 0 ? 0.5 * (s->last_dt + dt) : dt;
    for (int k = 0; k < AX; k++) {
        d[k] = sp->pos_m[k] - s->last_pos[k];
        m->vel[k] = d[k] / dt;
        m->dv[k] = m->vel[k] - s->last_vel[k];
    }
    step = norm3(d);
    if (l->max_step_m > 0 && step > l->max_step_m + l->tol_m) {
        *value = step;
        *limit = l->max_step_m;
        return SAFETY_FSTEP;
    }
    if (l->max_speed_m_s > 0 && step > l->max_speed_m_s * dt + l->tol_m) {
        *value = step / dt;
        *limit = l->max_speed_m_s;
        return SAFETY_FSPEED;
    }
    int f = judge_axes(s, d, m, value, limit);
    if (f)
        return f;
    /* |dv| * span is the change of step a constant acceleration bound allows, in metres */
    double span = m->span;
    if (l->max_accel_m_s2 > 0 && s->have_vel &&
        norm3(m->dv) * span > l->max_accel_m_s2 * span * span + l->tol_m) {
        *value = norm3(m->dv) / span;
        *limit = l->max_accel_m_s2;
        return SAFETY_FACCEL;
    }
    return SAFETY_OK;
}

int safety_check(safety_t *s, engine_setpoint_t *sp)
{
    double value = 0, limit = 0;
    motion_t m;
    int f;

    if (!s->have_pos) {
        /* nothing sent yet: no position is fine, a first position is taken as is */
        if (sp->flags & ENGINE_SP_NO_POSITION)
            return SAFETY_OK;
        s->checked++;
        f = SAFETY_OK;
        for (int k = 0; k < AX && !f; k++)
            if (!isfinite(sp->pos_m[k])) {
                f = SAFETY_FNOTFINITE;
                value = sp->pos_m[k];
            }
        if (!f && outside_box(&s->lim, sp, &value, &limit))
            f = SAFETY_FBOX;
        if (f) { /* nothing to hold on: send it as "no position" */
            s->violations++;
            s->by[f]++;
            s->last_value = value;
            s->last_limit = limit;
            s->last_fault = f;
            for (int j = 0; j < AX; j++)
                sp->pos_m[j] = NAN;
            sp->flags |= ENGINE_SP_NO_POSITION | ENGINE_SP_FAULT | ENGINE_SP_HOLD;
            return f;
        }
        s->have_pos = 1;
        s->last_ns = sp->now_ns;
        memcpy(s->last_pos, sp->pos_m, sizeof s->last_pos);
        return SAFETY_OK;
    }
    s->checked++;
    if (s->fault) {
        s->violations++;
        hold(s, sp);
        return s->fault;
    }
    f = judge(s, sp, &value, &limit, &m);
    if (f != SAFETY_OK) {
        s->fault = f;
        s->violations++;
        s->by[f]++;
        s->last_value = value;
        s->last_limit = limit;
        s->last_fault = f;
        hold(s, sp);
        return f;
    }
    if (s->have_vel) { /* the acceleration between the last two velocities */
        for (int k = 0; k < AX; k++)
            s->last_acc[k] = m.dv[k] / m.span;
        s->last_span = m.span;
        s->have_acc = 1;
    }
    memcpy(s->last_pos, sp->pos_m, sizeof s->last_pos);
    memcpy(s->last_vel, m.vel, sizeof s->last_vel);
    s->last_dt = m.dt;
    s->have_vel = 1;
    s->last_ns = sp->now_ns;
    return SAFETY_OK;
}

void safety_forget(safety_t *s)
{
    s->have_pos = 0;
    s->have_vel = 0;
    s->have_acc = 0;
    memset(s->last_vel, 0, sizeof s->last_vel);
    s->last_dt = 0;
}

int safety_fault(const safety_t *s)
{
    return s->fault;
}

int safety_held(const safety_t *s, double pos_m[ENGINE_AXES])
{
    if (!s->have_pos)
        return -1;
    memcpy(pos_m, s->last_pos, sizeof s->last_pos);
    return 0;
}

void safety_rearm(safety_t *s)
{
    s->fault = SAFETY_OK;
    memset(s->last_vel, 0, sizeof s->last_vel);
    s->have_vel = s->have_pos;
    s->have_acc = 0; /* the jerk judged from the next two accelerations on */
}
