/*
 * engine_solve.c - the solver stage: waypoints kept (engine_input.c) become
 * nodes; each node completes a row of the spline's system, pushed into the
 * fragment window (frag.h: cubic.h's rows, or hoang.h's for control points,
 * SMOOTH through the lsq smoother first); every segment whose control
 * values are all final is turned into a cubic per axis (fdiff_seg_t), with
 * its speed bound, speed cap and braking capacity, and queued; a closed
 * trajectory queues an END entry where it rests.  It owns engine_solve_t
 * (engine_int.h: the nodes, the fragment window, the smoother) and the
 * queue of finished segments, engine_queue_t, which the play-out stage
 * (engine_tick.c) consumes.
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "cubic.h"
#include "fdiff.h"
#include "frag.h"
#include "hermite.h"
#include "hoang.h"
#include "lsq.h"
#include "timescale.h"

/* Samples of a segment's speed for its bounds (seg_speed_max). */
#define ENGINE_SPEED_SAMPLES 8

/* Upper bound on the speed |k'| over a segment (m/s): the largest of
 * ENGINE_SPEED_SAMPLES + 1 evenly spaced samples, widened by what |k''| can
 * change between a sample and the point halfway to the next (|k''(u)| <=
 * 2|c2| + 6|c3| per axis, in units of u). */
double solve_seg_speed_max(const fdiff_seg_t *seg)
{
    double m2 = 0, b2 = 0;

    for (int k = 0; k < AX; k++) {
        double b = 2 * fabs(seg->c[k][2]) + 6 * fabs(seg->c[k][3]);
        b2 += b * b;
    }
    /* the largest square, then its root: the same double as the largest
     * root (sqrt is monotonic and correctly rounded), one root instead of
     * one per sample */
    for (int i = 0; i <= ENGINE_SPEED_SAMPLES; i++) {
        double u = (double)i / ENGINE_SPEED_SAMPLES, v2 = 0;
        for (int k = 0; k < AX; k++) {
            double d = seg->c[k][1] + u * (2 * seg->c[k][2] + 3 * u * seg->c[k][3]);
            v2 += d * d;
        }
        m2 = v2 > m2 ? v2 : m2;
    }
    return (sqrt(m2) + sqrt(b2) / (2.0 * ENGINE_SPEED_SAMPLES)) / seg->dur_s;
}

static qent_t *q_push(engine_t *e)
{
    qent_t *q;

    if (e->queue.len == e->queue.cap)
        return NULL; /* cannot happen: see queue.cap */
    q = &e->queue.ent[(e->queue.head + e->queue.len) % e->queue.cap];
    e->queue.len++;
    q->first = e->solve.first_pending;
    q->traj = e->solve.traj;
    q->gap_s = q->first ? e->in.gap_s : 0;
    q->join = 0;
    q->shift = 0.0;
    e->solve.first_pending = 0;
    return q;
}

/* The largest |k''| over a segment (m/s^2 at rate 1): k'' is linear in u on
 * a cubic, so its norm peaks at an end. */
static double seg_accel_max(const fdiff_seg_t *seg)
{
    double a0 = 0, a1 = 0;
    for (int k = 0; k < AX; k++) {
        double c2 = 2 * seg->c[k][2], c3 = 6 * seg->c[k][3];
        a0 += c2 * c2;
        a1 += (c2 + c3) * (c2 + c3);
    }
    return sqrt(fmax(a0, a1)) / (seg->dur_s * seg->dur_s);
}

/* Axis k's largest speed |k_k'| over a segment at rate 1 (m/s), exactly:
 * k_k' is a quadratic in u, its largest |.| at an end or at its vertex.  (The
 * samples widened by |k''| that bound the norm, solve_seg_speed_max, doubled
 * it on a segment that turns hard: 346 for 168 m/s on a 90 m/s zig-zag,
 * which put the ceiling under ENGINE_CEIL_MIN where it is not.) */
double solve_axis_speed_max(const fdiff_seg_t *seg, int k)
{
    const double *c = seg->c[k];
    double hi = fmax(fabs(c[1]), fabs(c[1] + 2 * c[2] + 3 * c[3]));
    if (fabs(c[3]) > 0) {
        double u = -c[2] / (3 * c[3]);
        if (u > 0 && u < 1)
            hi = fmax(hi, fabs(c[1] + u * (2 * c[2] + 3 * u * c[3])));
    }
    return hi / seg->dur_s;
}

/* axis k's largest |k_k''| over seg at rate 1 (m/s^2): k'' is linear on a
 * cubic, so at an end. */
static double axis_accel_max(const fdiff_seg_t *seg, int k)
{
    double c2 = 2 * seg->c[k][2], c3 = 6 * seg->c[k][3], T = seg->dur_s;
    return fmax(fabs(c2), fabs(c2 + c3)) / (T * T);
}

/*
 * issue 32: the highest rate r at which a segment keeps the per-axis limits
 * (engine.h axis_max_*): |k_k'| r within the speed limit; |k_k''| r^2 within
 * the acceleration limit less scale_accel_m_s2 (resolved to at most a third
 * of it), which bounds the scaling's k_k' dr/dt; |k_k'''| r^3 within half the
 * jerk limit.  INFINITY where no axis is limited.
 */
static double axis_ceiling(const engine_t *e, const fdiff_seg_t *seg)
{
    double c = INFINITY, T = seg->dur_s;
    for (int k = 0; k < AX; k++) {
        double vl = e->cfg.axis_max_speed_m_s[k], al = e->cfg.axis_max_accel_m_s2[k];
        double jl = e->cfg.axis_max_jerk_m_s3[k];
        if (vl > 0) {
            double v = solve_axis_speed_max(seg, k);
            if (v > 0)
                c = fmin(c, vl / v);
        }
        if (al > 0) {
            double kdd = axis_accel_max(seg, k);
            if (kdd > 0)
                c = fmin(c, sqrt(fmax(al - e->cfg.scale_accel_m_s2, 0.0) / kdd));
        }
        if (jl > 0) {
            double kddd = fabs(6 * seg->c[k][3]) / (T * T * T);
            if (kddd > 0)
                c = fmin(c, cbrt(0.5 * jl / kddd));
        }
    }
    return c;
}

/* The highest rate at which a segment keeps the speed cap (ENGINE_SPEED_CAP
 * x the speed limit, vmax its speed); with the profile's acceleration limit
 * (issue 27: max_accel_m_s2 left to the profile), that limit: the output's
 * acceleration k'' r^2 + k' dr/dt stays within it when k'' r^2 keeps to the
 * limit less scale_accel_m_s2, which bounds k' dr/dt (the time scaling's
 * limits are converted at the segment's fastest speed); and the per-axis
 * limits (axis_ceiling; *axis: they are what holds it below 1).  A
 * configured max_accel_m_s2 bounds the chords only (the curve may reach 3
 * times it: engine.h).  At least ENGINE_CEIL_MIN; INFINITY with no limit; 0
 * where the per-axis limits would need less than ENGINE_CEIL_MIN. */
static double seg_ceiling(const engine_t *e, const fdiff_seg_t *seg, double vmax, int *axis)
{
    double v = engine_config_max_speed(&e->cfg), axis_c = axis_ceiling(e, seg), c = INFINITY;
    if (v > 0 && vmax > 0)
        c = ENGINE_SPEED_CAP * v / vmax;
    if (e->cfg.cap_speed_m_s > 0 && vmax > 0) /* the caller's cap (engine.h) */
        c = fmin(c, e->cfg.cap_speed_m_s / vmax);
    if (e->cfg.cap_accel_m_s2 > 0) { /* the caller's cap: the curve's share (engine.h) */
        double room = e->cfg.cap_accel_m_s2 - e->cfg.scale_accel_m_s2;
        double kdd = seg_accel_max(seg);
        if (kdd > 0) /* at any rate, a feed override's too */
            c = fmin(c, sqrt(room / kdd));
    }
    if (e->cfg.max_accel_m_s2 < 0) {
        double room = engine_config_max_accel(&e->cfg) - e->cfg.scale_accel_m_s2;
        double kdd = room > 0 ? seg_accel_max(seg) : 0.0;
        if (kdd > room)
            c = fmin(c, sqrt(room / kdd));
    }
    /* a segment the per-axis limits hold below the floor is beyond the
     * axes: at the floor it exceeded them (fuzz_engine: 2.5 m/s on a 2 m/s
     * axis), and below it the output would never leave rest before it.  Its
     * ceiling is 0: the output brakes to rest before it (scale_ceil_room)
     * and the object is stopped there (axis_beyond, engine_scale.c) */
    if (axis_c < ENGINE_CEIL_MIN) {
        *axis = 1;
        return 0.0;
    }
    *axis = axis_c < 1.0 && axis_c <= c;
    c = fmin(c, axis_c);
    return isinf(c) ? c : fmax(c, ENGINE_CEIL_MIN);
}

double solve_seg_ceiling(const engine_t *e, const fdiff_seg_t *seg, double vmax, int *axis)
{
    return seg_ceiling(e, seg, vmax, axis);
}

/* issue 32: some axis has an acceleration limit (engine.h axis_max_accel_m_s2;
 * engine_new notes it once, e->axis_accel). */
int solve_cfg_axis_accel(const engine_config_t *cfg)
{
    for (int k = 0; k < AX; k++)
        if (cfg->axis_max_accel_m_s2[k] > 0)
            return 1;
    return 0;
}

/* The most dr/dt may be on a segment for the scaling's cross term
 * 3 k_k'' r dr/dt of each axis's jerk to stay within a quarter of its jerk
 * limit at rates up to rc (the curve's own k_k''' r^3 keeps a half at the
 * ceiling, axis_ceiling; the scaling's k_k' d2r/dt2 a quarter,
 * scale_jerk_m_s3): INFINITY without a jerk limit or curvature. */
static double jerk_rate_accel(const engine_t *e, const fdiff_seg_t *seg, double rc)
{
    double A = INFINITY;
    for (int k = 0; k < AX; k++) {
        double jl = e->cfg.axis_max_jerk_m_s3[k], kdd = axis_accel_max(seg, k);
        if (jl > 0 && kdd > 0)
            A = fmin(A, 0.25 * jl / (3 * kdd * rc));
    }
    return A;
}

/*
 * issue 32: the speed at which the time scaling's acceleration limit is
 * converted on a segment (qent_t av): A = a / av, a = scale_accel_m_s2.
 * Without a per-axis acceleration limit max(vmax, floor), as the jerk's.
 * With them, what the segment's axes leave at its ceiling c (rc = min(c,
 * TS_RATE_MAX), the highest rate on it): the scaling's term k_k' dr/dt may
 * take what the curve's own k_k'' r^2 leaves of the axis's limit,
 *
 *     A = min over the axes that move of room_k / max|k_k'|,
 *     room_k = axis_max_accel_m_s2[k] - max|k_k''| rc^2   (a on a free axis),
 *
 * and likewise for the norm with the profile's acceleration limit
 * (max_accel_m_s2 left to it, seg_ceiling).  The ceiling leaves every limited
 * axis at least a (axis_ceiling), so A is at least a / max(vmax, floor), the
 * share as without; at most |(l_x, l_y, l_z)| / max(vmax, floor), l_k the
 * axis's limit or a on a free axis: the share that all the axes' rooms make
 * together where they all move, and no more where some barely do (A = room /
 * max|k_k'| grows without bound as max|k_k'| vanishes) or the curve is slower
 * than the floor.  On a straight, where k'' is small, the braking into a
 * corner has the whole limit (the time-optimal traversal's), where
 * a / max(vmax, floor) gave it a third.  The jerk stays converted at
 * max(vmax, floor): the scaling's own k' d2r/dt2 within scale_jerk_m_s3.
 */
static double accel_speed(const engine_t *e, const fdiff_seg_t *seg, double vmax, double ceil)
{
    double v = vmax > ENGINE_SCALE_V_FLOOR_M_S ? vmax : ENGINE_SCALE_V_FLOOR_M_S;
    if (!(ceil > 0) || (!e->axis_accel && !e->axis_jerk))
        return v;
    double a = e->cfg.scale_accel_m_s2, rc = fmin(ceil, TS_RATE_MAX), n2 = 0;
    double Aj = jerk_rate_accel(e, seg, rc);
    if (!e->axis_accel)
        return a / fmin(a / v, Aj);
    for (int k = 0; k < AX; k++) {
        double al = e->cfg.axis_max_accel_m_s2[k];
        n2 += al > 0 ? al * al : a * a;
    }
    double A = sqrt(n2) / v;
    for (int k = 0; k < AX; k++) {
        double vk = solve_axis_speed_max(seg, k), al = e->cfg.axis_max_accel_m_s2[k];
        if (!(vk > 0))
            continue;
        double room = a;
        if (al > 0)
            room = al - axis_accel_max(seg, k) * rc * rc;
        A = fmin(A, room / vk);
    }
    double lim = engine_config_max_accel(&e->cfg);
    if (e->cfg.max_accel_m_s2 < 0 && lim > 0 && vmax > 0)
        A = fmin(A, (lim - seg_accel_max(seg) * rc * rc) / vmax);
    return a / fmin(fmax(A, a / v), Aj);
}

/* A built segment's own limits, worked out once. */
static void seg_limits(const engine_t *e, const fdiff_seg_t *seg, seg_limits_t *l)
{
    l->vmax = solve_seg_speed_max(seg);
    l->ceil = seg_ceiling(e, seg, l->vmax, &l->axis);
    l->av = accel_speed(e, seg, l->vmax, l->ceil);
}

/* Queue a built segment with its limits l, its av at least av_next (the
 * next segment's, 0 if none): see queue_segment. */
static void queue_now(engine_t *e, const fdiff_seg_t *seg, uint64_t node, const seg_limits_t *l,
                      double av_next)
{
    qent_t *q = q_push(e);

    if (!q)
        return;
    q->kind = QE_SEG;
    q->node = node;
    q->seg = *seg;
    q->t1_s = seg->t0_s + seg->dur_s;
    q->vmax = l->vmax;
    q->ceil = l->ceil;
    q->ceil_axis = l->axis;
    q->ceil_own = !l->axis && q->ceil < 1.0;
    q->av = fmax(l->av, av_next);
    e->st.axis_slowed += (uint64_t)q->ceil_axis;
    e->st.limits_slowed += (uint64_t)q->ceil_own;
    /* the jerk's conversion speed (scale_jerk_speed) */
    double v = q->vmax > ENGINE_SCALE_V_FLOOR_M_S ? q->vmax : ENGINE_SCALE_V_FLOOR_M_S;
    /* the stop from rate 1 at its limits, as the tick would work it out
     * (plain_window: scale_conv_speed, scale_limits) */
    q->stop1 = ts_stop_dist(1.0, 0.0, e->cfg.scale_accel_m_s2 / q->av, e->cfg.scale_jerk_m_s3 / v);
    if (queue_is_slow(q)) /* every queued slot has room: so has the ring */
        e->queue.slow[(e->queue.slow_head + e->queue.slow_len++) % e->queue.cap] =
            (size_t)(q - e->queue.ent);
    e->queue.beyond += queue_is_slow(q) && !(q->ceil > 0);
    double inv = 1.0 / q->av;
    if (e->solve.queued && inv > e->solve.inv) /* the limits rise from the last one to this: */
        e->solve.ucum += (inv - e->solve.inv) * (v / q->av); /* its A / J against a / j */
    e->solve.inv = inv;
    q->ucum = e->solve.ucum;
    e->solve.kcum += seg->dur_s * inv;
    q->kcum = e->solve.kcum;
    e->solve.queued = 1;
    if (e->out.mode != OUT_HOLD && q->traj == e->out.traj) {
        e->scale.avail_t = q->t1_s; /* more curve for the output (see scale_remaining()) */
        e->scale.avail_kcum = q->kcum;
        e->scale.avail_ucum = q->ucum;
    }
}

/*
 * A segment built: queued, or with per-axis acceleration limits held until
 * the next one is built, and then queued with the av of whichever of the two
 * gives the scaling less (A_i = min(A_i, A_i+1)).  The rate's dr/dt then
 * enters every segment within the A its own axes leave room for
 * (accel_speed): a braking at a straight's A into a corner, where k'' steps
 * at a knot the C2 spline does not smooth (cubic_join, the local methods),
 * would otherwise carry that A onto the corner's k'' r^2.  A segment's A,
 * queued, never changes: the braking capacity ahead (kcum) only grows.  The
 * price is one segment of the curve later to the output.
 */
static void queue_segment(engine_t *e, const fdiff_seg_t *seg, uint64_t node)
{
    seg_limits_t l;
    seg_limits(e, seg, &l);
    if (e->axis_accel || e->axis_jerk) {
        if (e->solve.pend)
            queue_now(e, &e->solve.pend_seg, e->solve.pend_node, &e->solve.pend_lim, l.av);
        e->solve.pend = 1;
        e->solve.pend_seg = *seg;
        e->solve.pend_node = node;
        e->solve.pend_lim = l;
    } else {
        queue_now(e, seg, node, &l, 0.0);
    }
    e->solve.emitted = 1;
    e->solve.end_t = seg->t0_s + seg->dur_s;
    double v2 = 0;
    for (int k = 0; k < AX; k++) {
        double v = (seg->c[k][1] + 2 * seg->c[k][2] + 3 * seg->c[k][3]) / seg->dur_s;
        e->solve.end_r[k] = seg->c[k][0] + seg->c[k][1] + seg->c[k][2] + seg->c[k][3];
        e->solve.end_v[k] = v;
        v2 += v * v;
    }
    e->solve.end_speed = sqrt(v2);
}

static void queue_end(engine_t *e)
{
    if (e->solve.pend) { /* the last segment: its own av (the output rests at its end) */
        e->solve.pend = 0;
        queue_now(e, &e->solve.pend_seg, e->solve.pend_node, &e->solve.pend_lim, 0.0);
    }
    qent_t *q = q_push(e);

    if (!q)
        return;
    q->kind = QE_END;
    q->av = ENGINE_SCALE_V_FLOOR_M_S; /* (read by nothing: not left unset) */
    e->queue.ends++;
    memset(&q->seg, 0, sizeof(q->seg));
    q->t1_s = e->solve.emitted ? e->solve.end_t : e->in.last_t;
    q->seg.t0_s = q->t1_s;
    for (int k = 0; k < AX; k++)
        q->seg.c[k][0] = e->solve.emitted ? e->solve.end_r[k] : e->in.last_r[k];
    /* END: c[0][1] is the speed at which the curve arrives (0 at rest) */
    q->seg.c[0][1] = e->solve.emitted ? e->solve.end_speed : 0.0;
    if (e->out.mode != OUT_HOLD && q->traj == e->out.traj) {
        e->scale.avail_t = q->t1_s;
        e->scale.avail_closed = 1;
        e->scale.avail_rest = q->seg.c[0][1] <= ENGINE_REST_SPEED_M_S;
    }
}

uint64_t queue_waypoints(const engine_t *e, size_t i0, size_t i1)
{
    uint64_t n = 0;
    for (size_t i = i0; i < i1 && i < e->queue.len; i++)
        n += queue_at(e, i)->kind == QE_SEG;
    return e->local >= 3 ? (n + 2) / 3 : n;
}

/* end velocities in the unknowns' parameter (dk/du for P*, dk/ds for M) */
static void end_vel_param(const engine_t *e, int at_end, double *v)
{
    const double *src = at_end ? e->cfg.end_vel_m_s : e->cfg.start_vel_m_s;
    uint64_t j = at_end ? e->solve.nodes - 2 : 0;
    double dur = nt(e, j + 1) - nt(e, j);
    double scale = e->pstar ? dur : dur / hpar(e, j);

    for (int k = 0; k < AX; k++)
        v[k] = src[k] * scale;
}

/* issue 32: a per-axis limit is set in cfg (engine.h axis_max_*). */
int solve_cfg_axis_limited(const engine_config_t *cfg)
{
    for (int k = 0; k < AX; k++)
        if (cfg->axis_max_speed_m_s[k] > 0 || cfg->axis_max_accel_m_s2[k] > 0 ||
            cfg->axis_max_jerk_m_s3[k] > 0)
            return 1;
    return 0;
}

/* Build and queue every segment whose control values are final. */
static void build_segments(engine_t *e)
{
    uint64_t fin = e->solve.fw->final_rows, last = e->solve.nodes - 1;
    int closed = e->solve.fw->done;

    for (;;) {
        uint64_t j = e->solve.seg_next;
        fdiff_seg_t seg;
        double dur;

        if (j + 1 >= e->solve.nodes)
            break;
        if (e->pstar) {
            if (!(j + 3 <= fin || (closed && j + 2 == fin && j + 1 == last)))
                break;
        } else if (j + 2 > fin) {
            break;
        }
        e->solve.seg_next = j + 1;
        dur = nt(e, j + 1) - nt(e, j);
        if (!(dur > 0))
            continue; /* between copies of one point (MULTIPLE): a loop, never motion */
        if (e->held && (j == 0 || (closed && j + 1 == last)))
            continue; /* held ends: not part of the curve */
        if (e->pstar) {
            double g0[AX], g1[AX], v[AX];
            const double *p0, *p3;
            if (j == 0) {
                end_vel_param(e, 0, v);
                hoang_ghost_start(e->cfg.ends, frag_x(e->solve.fw, 0), frag_x(e->solve.fw, 1), v,
                                  g0);
                p0 = g0;
            } else {
                p0 = frag_x(e->solve.fw, j - 1);
            }
            if (j + 1 == last) {
                end_vel_param(e, 1, v);
                hoang_ghost_end(e->cfg.ends, frag_x(e->solve.fw, last - 1),
                                frag_x(e->solve.fw, last), v, g1);
                p3 = g1;
            } else {
                p3 = frag_x(e->solve.fw, j + 2);
            }
            hoang_segment(p0, frag_x(e->solve.fw, j), frag_x(e->solve.fw, j + 1), p3, nt(e, j), dur,
                          &seg);
        } else {
            cubic_segment(nr(e, j), nr(e, j + 1), frag_x(e->solve.fw, j),
                          frag_x(e->solve.fw, j + 1), hpar(e, j), nt(e, j), dur, &seg);
        }
        /* continuous in velocity where fragments meet (cubic_join): with knots
         * at the timestamps; and with per-axis limits at every knot of the
         * uniform parameterisation too, which steps there by design (DESIGN.md
         * (a)), for no axis holds its acceleration across a step */
        if (e->solve.emitted && (e->cfg.param == ENGINE_PARAM_TIME || solve_axis_limited(e)))
            (void)cubic_join(&seg, e->solve.end_v);
        queue_segment(e, &seg, j);
    }
}

/*
 * Local methods (hermite.h): node i's velocity (and, C2, acceleration), the
 * source's velocity or computed once it can be, and kept so that both
 * segments at the node share them (C1, C2); 0 while they cannot be yet.
 * Backward (local 1, 3): from nodes i-2..i (the chord and no acceleration at
 * node 1); centred (2, 4): from nodes i-1..i+1, the last node's from the end
 * condition once the trajectory is closed.  Node 0: the start condition
 * (rest 0, clamped start_vel_m_s, natural zero acceleration); the C2
 * methods' acceleration is 0 at either end.
 */
static int local_state(engine_t *e, uint64_t i, int closed, const double **vout,
                       const double **aout)
{
    size_t slot = (size_t)(i % e->solve.ring);
    double *v = e->solve.node_v + slot * AX, *a = e->solve.node_a + slot * AX;
    uint64_t last = e->solve.nodes - 1;
    int centred = e->local % 2 == 0, given = e->solve.node_vk[slot] == 1;

    *vout = v;
    *aout = a;
    if (e->solve.node_vk[slot] == 2 || (given && e->local < 3 && i > 0))
        return 1;
    if (i == 0 || (centred && i == last)) { /* an end of the trajectory */
        if ((i == 0 && last < 1) || (i == last && !closed))
            return 0;
        memset(a, 0, sizeof(double) * AX);
        const double *src = i == 0 ? e->cfg.start_vel_m_s : e->cfg.end_vel_m_s;
        int fixed = e->cfg.ends == ENGINE_ENDS_REST || e->cfg.ends == ENGINE_ENDS_CLAMPED;
        if (fixed && (i == 0 || !given)) { /* a start at the condition, even past the source */
            for (int k = 0; k < AX; k++)
                v[k] = e->cfg.ends == ENGINE_ENDS_REST ? 0.0 : src[k];
        } else if (given) {
            /* the source's velocity as sent */
        } else if (last == 1 && (centred || i == 1)) {
            hermite_vel_chord(nt(e, 0), nr(e, 0), nt(e, 1), nr(e, 1), v); /* both ends natural */
        } else {
            const double *vo, *ao;
            uint64_t o = i == 0 ? 1 : i - 1; /* the segment's other node */
            if (!local_state(e, o, closed, &vo, &ao))
                return 0;
            hermite_vel_natural(nt(e, i), nr(e, i), nt(e, o), nr(e, o), vo, v);
        }
    } else if (!centred) {
        if (i == 1) {
            if (!given)
                hermite_vel_chord(nt(e, 0), nr(e, 0), nt(e, 1), nr(e, 1), v);
            memset(a, 0, sizeof(double) * AX);
        } else {
            if (!given)
                hermite_vel_backward(nt(e, i - 2), nr(e, i - 2), nt(e, i - 1), nr(e, i - 1),
                                     nt(e, i), nr(e, i), v);
            hermite_acc_parabola(nt(e, i - 2), nr(e, i - 2), nt(e, i - 1), nr(e, i - 1), nt(e, i),
                                 nr(e, i), a);
        }
    } else {
        if (!given)
            hermite_vel_centred(nt(e, i - 1), nr(e, i - 1), nt(e, i), nr(e, i), nt(e, i + 1),
                                nr(e, i + 1), v);
        hermite_acc_parabola(nt(e, i - 1), nr(e, i - 1), nt(e, i), nr(e, i), nt(e, i + 1),
                             nr(e, i + 1), a);
    }
    e->solve.node_vk[slot] = 2;
    return 1;
}

/* Local methods: build and queue every segment whose two end states are
 * known (C2: as its three pieces). */
static void build_local(engine_t *e, int closed)
{
    for (;;) {
        uint64_t j = e->solve.seg_next;
        const double *v0, *v1, *a0, *a1;
        fdiff_seg_t seg[3];

        int given = j + 1 < e->solve.nodes &&
                    e->solve.node_vk[(size_t)((j + 1) % e->solve.ring)] == 1;
        if (j + 1 >= e->solve.nodes || !local_state(e, j + 1, closed, &v1, &a1) ||
            !local_state(e, j, closed, &v0, &a0))
            break;
        e->solve.seg_next = j + 1;
        /* (the state local_end takes back to) */
        e->solve.tail.valid = !e->solve.pend && !e->axis_accel && !e->axis_jerk;
        e->solve.tail.node = j;
        e->solve.tail.given = given;
        e->solve.tail.first_pending = e->solve.first_pending;
        e->solve.tail.queued = e->solve.queued;
        e->solve.tail.kcum = e->solve.kcum;
        e->solve.tail.ucum = e->solve.ucum;
        e->solve.tail.inv = e->solve.inv;
        if (e->local < 3) {
            hermite_segment(nr(e, j), v0, nr(e, j + 1), v1, nt(e, j), nt(e, j + 1) - nt(e, j),
                            &seg[0]);
            queue_segment(e, &seg[0], j);
            continue;
        }
        hermite_c2_segments(nr(e, j), v0, a0, nr(e, j + 1), v1, a1, nt(e, j),
                            nt(e, j + 1) - nt(e, j), seg);
        for (int k = 0; k < 3; k++)
            queue_segment(e, &seg[k], j);
    }
}

static const double zero3[AX] = {0, 0, 0};

/* The last segment of a local backward method, queued as node j + 1 came,
 * built: its pieces (C1: one, C2: three) into seg, their count returned. */
static int local_pieces(engine_t *e, uint64_t j, const double *v0, const double *a0,
                        const double *v1, const double *a1, fdiff_seg_t seg[3])
{
    double dur = nt(e, j + 1) - nt(e, j);
    if (e->local < 3) {
        hermite_segment(nr(e, j), v0, nr(e, j + 1), v1, nt(e, j), dur, &seg[0]);
        return 1;
    }
    hermite_c2_segments(nr(e, j), v0, a0, nr(e, j + 1), v1, a1, nt(e, j), dur, seg);
    return 3;
}

/* The queue's k-th entry from its tail (k = 0: the newest). */
static qent_t *q_from_tail(engine_t *e, size_t k)
{
    return &e->queue.ent[(e->queue.head + e->queue.len - 1 - k) % e->queue.cap];
}

/*
 * A closed trajectory of a local backward method (HERMITE, HERMITE_C2): its
 * last segment was built as its last node came, with that node's backward
 * estimate, so the curve ended moving, and the output braked before its
 * end and stood short of the last waypoint (2.3 cm on a line at 1 m/s,
 * 0.13 m on the bundled figure-8: tests/oracle/test_hermite.py
 * test_ends_on_last_waypoint; and a trajectory of two waypoints, whose one
 * segment is its last: 3.2 cm of 0.5 m).  While that segment is still queued, whole,
 * it is built again with the trajectory's end condition at the last node
 * (as the centred methods have it there: rest, clamped, or natural; the
 * acceleration 0), and queued in its place.  Not where the output already
 * entered it, nor where the new segment would leave the moving output less
 * room to stop than it stands in (scale_remaining): the old end is kept
 * then, and braked for as before.
 */
static void local_end(engine_t *e)
{
    uint64_t last = e->solve.nodes - 1, j = last - 1;
    size_t sl = (size_t)(last % e->solve.ring), sj = (size_t)(j % e->solve.ring);
    double *vl = e->solve.node_v + sl * AX, *al = e->solve.node_a + sl * AX;
    double v1[AX], a1[AX] = {0, 0, 0};
    fdiff_seg_t seg[3];

    if (e->local % 2 == 0 || e->solve.nodes < 2 || !e->solve.tail.valid ||
        e->solve.tail.node != j || e->solve.seg_next != last || e->solve.pend ||
        e->solve.node_vk[sj] != 2)
        return;
    if ((e->cfg.ends == ENGINE_ENDS_REST || e->cfg.ends == ENGINE_ENDS_CLAMPED) &&
        !e->solve.tail.given) {
        for (int k = 0; k < AX; k++)
            v1[k] = e->cfg.ends == ENGINE_ENDS_REST ? 0.0 : e->cfg.end_vel_m_s[k];
    } else if (e->solve.tail.given) {
        memcpy(v1, vl, sizeof v1); /* the source's velocity, as sent */
    } else {
        hermite_vel_natural(nt(e, last), nr(e, last), nt(e, j), nr(e, j), e->solve.node_v + sj * AX,
                            v1);
    }
    if (!memcmp(v1, vl, sizeof v1) && (e->local < 3 || !memcmp(a1, al, sizeof a1)))
        return; /* the same segment */
    int n = local_pieces(e, j, e->solve.node_v + sj * AX, e->solve.node_a + sj * AX, v1, a1, seg);
    if (e->queue.len < (size_t)n)
        return;
    for (int i = 0; i < n; i++) {
        const qent_t *q = q_from_tail(e, (size_t)i);
        if (q->kind != QE_SEG || q->traj != e->solve.traj || q->node != j || q->join ||
            q->shift < 0 || q->shift > 0)
            return; /* the output entered it (or its first pieces), or a join that ends in
                       it cut it and stands in front (join.c join_splice) */
    }
    if (q_from_tail(e, (size_t)(n - 1))->seg.t0_s < nt(e, j) ||
        q_from_tail(e, (size_t)(n - 1))->seg.t0_s > nt(e, j))
        return; /* (cut) */

    /* what is taken back, kept to be put back as it was */
    qent_t old[3] = {0};
    size_t slow_old[3] = {0}, slow_len = e->queue.slow_len, beyond = e->queue.beyond;
    engine_solve_t solve = e->solve;
    engine_scale_t scale = e->scale;
    uint64_t axis_slowed = e->st.axis_slowed, limits_slowed = e->st.limits_slowed;
    double vl_old[AX], al_old[AX];
    memcpy(vl_old, vl, sizeof vl_old);
    memcpy(al_old, al, sizeof al_old);
    for (int i = 0; i < n; i++)
        old[i] = *q_from_tail(e, (size_t)(n - 1 - i)); /* in queue order */
    for (int i = 0; i < 3 && (size_t)i < slow_len; i++)
        slow_old[i] = e->queue.slow[(e->queue.slow_head + slow_len - 1 - (size_t)i) % e->queue.cap];

    for (int i = n - 1; i >= 0; i--) { /* off the tail */
        const qent_t *q = &old[i];
        if (queue_is_slow(q)) {
            e->queue.slow_len--;
            e->queue.beyond -= !(q->ceil > 0);
        }
        e->st.axis_slowed -= (uint64_t)q->ceil_axis;
        e->st.limits_slowed -= (uint64_t)q->ceil_own;
        e->queue.len--;
    }
    e->solve.first_pending = e->solve.tail.first_pending;
    e->solve.queued = e->solve.tail.queued;
    e->solve.kcum = e->solve.tail.kcum;
    e->solve.ucum = e->solve.tail.ucum;
    e->solve.inv = e->solve.tail.inv;
    memcpy(vl, v1, sizeof v1);
    memcpy(al, a1, sizeof a1);
    for (int i = 0; i < n; i++)
        queue_segment(e, &seg[i], j);
    q_from_tail(e, (size_t)(n - 1))->gap_s = old[0].gap_s;

    if (e->out.mode == OUT_STREAM && e->out.traj == e->solve.traj && !at_rest(e)) {
        double A, J;
        scale_limits(e, &A, &J);
        if (ts_stop_dist(e->scale.ts.rate, e->scale.ts.acc, A, J) + e->scale.ts.rate * e->period_s <
            scale_remaining(e, out_s(e)))
            return;
    } else {
        return;
    }
    /* less room than the output stands in: the old end, as it was */
    for (int i = 0; i < n; i++)
        *q_from_tail(e, (size_t)(n - 1 - i)) = old[i];
    for (int i = 0; i < 3 && (size_t)i < slow_len; i++)
        e->queue.slow[(e->queue.slow_head + slow_len - 1 - (size_t)i) % e->queue.cap] = slow_old[i];
    e->queue.slow_len = slow_len;
    e->queue.beyond = beyond;
    e->st.axis_slowed = axis_slowed;
    e->st.limits_slowed = limits_slowed;
    e->solve = solve;
    e->scale = scale;
    memcpy(vl, vl_old, sizeof vl_old);
    memcpy(al, al_old, sizeof al_old);
}

/* What node j says about the input's timing and speed */
static void measure_input(engine_t *e, uint64_t j)
{
    const double decay = 1.0 - 1.0 / 256;
    double dt = nt(e, j) - nt(e, j - 1), d2 = 0;

    for (int k = 0; k < AX; k++)
        d2 += (nr(e, j)[k] - nr(e, j - 1)[k]) * (nr(e, j)[k] - nr(e, j - 1)[k]);
    if (dt > 0) {
        double v = sqrt(d2) / dt;
        e->solve.vmax_in = fmax(v, e->solve.vmax_in * decay);
        e->solve.iv[e->solve.iv_next] = dt;
        e->solve.iv_next = (e->solve.iv_next + 1) % ENGINE_IV_RING;
        if (e->solve.iv_n < ENGINE_IV_RING)
            e->solve.iv_n++;
    }
    if (j > e->la_steady) {
        /* how far ahead of the output this node must have been sent to be
         * built on time (see play_enough_ahead) */
        double w = nt(e, j) - nt(e, j - e->la_steady - 1);
        e->solve.span_max = fmax(w, e->solve.span_max * decay);
        if (w >= e->solve.span_max && (e->slack_auto || e->cfg.delay_s > 0))
            engine_delay_grow(e); /* longer than any kept: D may need more (delay.h) */
    }
}

/* Append a node; push the row it completes (row nodes-1 before it). */
int solve_add_node(engine_t *e, double t, const double *r, const double *vel)
{
    uint64_t j = e->solve.nodes;
    frag_row_t row;
    int rc = 0;

    e->solve.node_t[j % e->solve.ring] = t;
    memcpy(nr(e, j), r, sizeof(double) * AX);
    e->solve.nodes = j + 1;
    /* D is measured and stated whatever start_slack is (a fixed one keeps
     * the count-based start, but the silence that ends a trajectory is
     * judged by D: engine_silence_limit_s) */
    if (j >= 1)
        measure_input(e, j);
    if (e->local) {
        size_t slot = (size_t)(j % e->solve.ring);
        e->solve.node_vk[slot] = vel != NULL;
        if (vel)
            memcpy(e->solve.node_v + slot * AX, vel, sizeof(double) * AX);
        build_local(e, 0);
        return 0;
    }
    if (j >= 1) {
        uint64_t i = j - 1; /* the row now complete */
        if (e->pstar) {
            if (i == 0) {
                double v[AX];
                end_vel_param(e, 0, v);
                hoang_row_start(e->cfg.ends == ENGINE_ENDS_MULTIPLE ? ENGINE_ENDS_HELD
                                                                    : e->cfg.ends,
                                nr(e, 0), v, &row);
            } else {
                hoang_row_interior(nr(e, i), &row);
            }
            rc = frag_push(e->solve.fw, &row, nr(e, i));
        } else {
            if (i == 0) {
                double v[AX];
                end_vel_param(e, 0, v);
                cubic_row_start(e->cfg.ends, hpar(e, 0), nr(e, 0), nr(e, 1), v, &row);
            } else {
                cubic_row_interior(hpar(e, i - 1), hpar(e, i), nr(e, i - 1), nr(e, i), nr(e, i + 1),
                                   &row);
            }
            rc = frag_push(e->solve.fw, &row, zero3);
        }
        if (rc < 0)
            return -ENGINE_ENUMERIC;
        build_segments(e);
    }
    return 0;
}

/* SMOOTH: turn every smoothed waypoint that is ready into a node. */
int solve_drain(engine_t *e)
{
    double t, r[AX];
    int rc;

    while (lsq_smooth_pop(&e->solve.sm, &t, r) == 1)
        if ((rc = solve_add_node(e, t, r, NULL)) < 0)
            return rc;
    return 0;
}

/* The trajectory being received is closed: end row, last segments, END entry. */
int solve_close(engine_t *e)
{
    frag_row_t row;
    int rc = 0;

    if (e->smooth) {
        lsq_smooth_finish(&e->solve.sm);
        if ((rc = solve_drain(e)) < 0)
            goto end;
    }
    if (e->mult) {
        /* the last point twice more (it is in already once) */
        double r[AX];
        memcpy(r, e->in.last_r, sizeof(r));
        if ((rc = solve_add_node(e, e->in.last_t, r, NULL)) < 0 ||
            (rc = solve_add_node(e, e->in.last_t, r, NULL)) < 0)
            goto end;
    }
    if (e->local) {
        build_local(e, 1);
        local_end(e);
    } else if (e->solve.nodes >= 2) {
        uint64_t l = e->solve.nodes - 1;
        double v[AX];
        end_vel_param(e, 1, v);
        if (e->pstar)
            hoang_row_end(e->mult ? ENGINE_ENDS_HELD : e->cfg.ends, nr(e, l), v, &row);
        else
            cubic_row_end(e->cfg.ends, hpar(e, l - 1), nr(e, l - 1), nr(e, l), v, &row);
        if (frag_finish(e->solve.fw, &row) < 0)
            rc = -ENGINE_ENUMERIC;
        else
            build_segments(e);
    }
end:
    e->solve.seg_next = e->solve.nodes; /* nothing pending any more */
    queue_end(e);
    return rc;
}

/* A new trajectory: no node yet, its first queued entry marked as such. */
void solve_open(engine_t *e)
{
    frag_reset(e->solve.fw);
    e->solve.nodes = 0;
    e->solve.seg_next = 0;
    e->solve.emitted = 0;
    e->solve.queued = 0;
    e->solve.pend = 0;
    e->solve.kcum = 0.0;
    e->solve.ucum = 0.0;
    e->solve.first_pending = 1;
    e->solve.traj++;
    if (e->smooth)
        lsq_smooth_reset(&e->solve.sm);
}

/* The solver failed (cannot happen with finite data): the trajectory ends
 * with what is queued, nothing more built of it. */
void solve_abort(engine_t *e)
{
    e->solve.seg_next = e->solve.nodes;
    queue_end(e);
}
