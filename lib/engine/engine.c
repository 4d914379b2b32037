/*
 * engine.c - waypoints in, fixed-rate setpoints out; see engine.h.
 *
 * Two halves joined by a queue of finished segments:
 *
 *   input  (engine_push / engine_finish): validates a waypoint, appends it as
 *          a node, pushes the row that node completes into the fragment
 *          window (frag.h), and turns every segment whose control values are
 *          all final into a cubic per axis (fdiff_seg_t), queued.  A closed
 *          trajectory queues an END entry (where it rests).
 *   output (engine_tick): walks the queued cubics with the forward-difference
 *          stepper (fdiff.h) on the period grid; waits, underruns, transfers
 *          to a new trajectory's start, finishes.
 *
 * All memory is taken in engine_new; push, tick, finish, clear never allocate.
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accept.h"
#include "cubic.h"
#include "ends.h"
#include "fdiff.h"
#include "frag.h"
#include "hoang.h"
#include "lsq.h"
#include "timescale.h"
#include "transfer.h"

/* Output and curve start closer than this need no transfer (metres). */
#define ENGINE_TRANSFER_TOL_M 1e-9
/* A transfer's or REST end's point closer than this to where the output
 * came to rest is taken as reached (rest_handover; metres). */
#define ENGINE_HANDOVER_TOL_M 1e-6
/* Timestamps closer than this are "the same time" (seconds). */
#define ENGINE_SAME_TIME_S 1e-9
/* Positions closer than this at the same time are a duplicate (metres). */
#define ENGINE_SAME_POS_M 1e-9
/* |t| above this is absurd for a track clock (about 31700 years). */
#define ENGINE_T_ABS_MAX_S 1e12
/* Below this speed (m/s) the curve's end counts as at rest. */
#define ENGINE_REST_SPEED_M_S 1e-6
/* The time scaling's limits are converted to rate units at the curve's speed,
 * but never at less than this (m/s): where the curve stands nearly still the
 * rate may change fast, but not without bound (TIMESCALE.md). */
#define ENGINE_SCALE_V_FLOOR_M_S 1.0
/* Capacity accepted at most (memory is sized from it). */
#define ENGINE_CAPACITY_MAX (1u << 20)
/* Samples of a segment's speed for its bounds (seg_speed_max). */
#define ENGINE_SPEED_SAMPLES 8

/* Upper bound on the speed |k'| over a segment (m/s): the largest of
 * ENGINE_SPEED_SAMPLES + 1 evenly spaced samples, widened by what |k''| can
 * change between a sample and the point halfway to the next (|k''(u)| <=
 * 2|c2| + 6|c3| per axis, in units of u). */
static double seg_speed_max(const fdiff_seg_t *seg)
{
    double hi = 0, b2 = 0;

    for (int k = 0; k < AX; k++) {
        double b = 2 * fabs(seg->c[k][2]) + 6 * fabs(seg->c[k][3]);
        b2 += b * b;
    }
    for (int i = 0; i <= ENGINE_SPEED_SAMPLES; i++) {
        double u = (double)i / ENGINE_SPEED_SAMPLES, v2 = 0;
        for (int k = 0; k < AX; k++) {
            double d = seg->c[k][1] + u * (2 * seg->c[k][2] + 3 * u * seg->c[k][3]);
            v2 += d * d;
        }
        hi = fmax(hi, sqrt(v2));
    }
    return (hi + sqrt(b2) / (2.0 * ENGINE_SPEED_SAMPLES)) / seg->dur_s;
}

void engine_config_default(engine_config_t *cfg)
{
    memset(cfg, 0, sizeof(*cfg));
    cfg->method = ENGINE_METHOD_CUBIC;
    cfg->param = ENGINE_PARAM_TIME;
    cfg->ends = ENGINE_ENDS_REST;
    cfg->fragment = ENGINE_AUTO;
    cfg->overlap = ENGINE_AUTO;
    cfg->accuracy = 3e-7;
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
    [ENGINE_PROFILE_ROAD] = {100.0, 30.0}, [ENGINE_PROFILE_AIR] = {400.0, 0.0},
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

static int uses_pstar(const engine_config_t *cfg)
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

/* most waypoints beyond a segment the solver needs, far from the start */
static unsigned steady_lookahead(const engine_config_t *cfg)
{
    unsigned f = cfg->fragment, o = cfg->overlap, s = f - o;
    unsigned need = uses_pstar(cfg) ? 3 : 2; /* x[j + need - 1] final for segment j */

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
    return cfg->start_slack == ENGINE_AUTO ? ENGINE_SLACK_AUTO_MIN : cfg->start_slack;
}

static unsigned frag_delta(const engine_config_t *cfg)
{
    unsigned f = cfg->fragment, dmax = frag_delta_max(f, cfg->overlap);
    unsigned want = steady_lookahead(cfg) + slack_of(cfg);
    unsigned d = f - 1 > want ? f - 1 - want : 0;

    return d < dmax ? d : dmax;
}

static unsigned smooth_extra(const engine_config_t *cfg)
{
    /* SMOOTH: the smoother holds smooth_window/2 waypoints back (lsq.h) */
    int sm = cfg->method == ENGINE_METHOD_SMOOTH && cfg->smooth_window >= 1;
    return sm ? lsq_smooth_delay(cfg->smooth_window) : 0;
}

/* engine_lookahead of a resolved configuration */
static unsigned lookahead_of(const engine_config_t *cfg)
{
    unsigned f = cfg->fragment, o = cfg->overlap, la, want;
    int sm = cfg->method == ENGINE_METHOD_SMOOTH && cfg->smooth_window >= 1;
    unsigned extra = smooth_extra(cfg);
    unsigned first = sm ? cfg->smooth_window - 1 : 0;

    if (!config_sizes_ok(cfg) || slack_of(cfg) > ENGINE_FRAGMENT_MAX)
        return 0;
    /* what the solver needs, from the start on (a few periods cover it) ... */
    la = scan_lookahead(f, o, frag_delta(cfg), uses_pstar(cfg) ? 3 : 2, 0, 4u * f, extra, first) +
         ACCEPT_LAG; /* a waypoint becomes a node once its next neighbour is in */
    /* ... and what the output waits for */
    want = steady_lookahead(cfg) + extra + slack_of(cfg);
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

int engine_config_resolve(const engine_config_t *cfg, engine_config_t *out)
{
    *out = *cfg;
    if (cfg->overlap == ENGINE_AUTO) {
        if (!(cfg->accuracy > 0) || !isfinite(cfg->accuracy))
            return -ENGINE_ECONFIG;
        out->overlap = auto_overlap(cfg->accuracy);
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
            unsigned la = lookahead_of(out);
            if (la && la - smooth_extra(out) <= cfg->max_lookahead)
                return 0;
        }
        out->fragment = o + 1;
        return -ENGINE_ECONFIG;
    }
    return 0;
}

unsigned engine_lookahead(const engine_config_t *cfg)
{
    engine_config_t r;

    if (engine_config_resolve(cfg, &r) < 0)
        return 0;
    return lookahead_of(&r);
}

int engine_config_check(const engine_config_t *cfg_in, const char **why)
{
    const char *w = NULL;
    unsigned la;
    engine_config_t r;
    const engine_config_t *cfg = &r;

    if (cfg_in->overlap == ENGINE_AUTO &&
        (!(cfg_in->accuracy > 0 && cfg_in->accuracy < 1) || !isfinite(cfg_in->accuracy)))
        w = "accuracy: must be within (0, 1)";
    else if (engine_config_resolve(cfg_in, &r) < 0)
        w = "max_lookahead: too short for the overlap accuracy asks plus start_slack: no "
            "fragment fits; raise max_lookahead or accuracy, or lower start_slack";
    if (w) {
        if (why)
            *why = w;
        return -ENGINE_ECONFIG;
    }

    if (cfg->method != ENGINE_METHOD_BSPLINE && cfg->method != ENGINE_METHOD_CUBIC &&
        cfg->method != ENGINE_METHOD_SMOOTH)
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
             !uses_pstar(cfg))
        w = "ends: held and multiple are the paper's B-spline control-polygon ends: "
            "they need method bspline with param uniform";
    else if (cfg->fragment < ENGINE_FRAGMENT_MIN || cfg->fragment > ENGINE_FRAGMENT_MAX)
        w = "fragment: must be within ENGINE_FRAGMENT_MIN..ENGINE_FRAGMENT_MAX";
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
    else if (!(cfg->max_segment_s >= 0) || !isfinite(cfg->max_segment_s))
        w = "max_segment_s: must be 0 or positive and finite";
    else if (!(cfg->scale_accel_m_s2 > 0) || !isfinite(cfg->scale_accel_m_s2))
        w = "scale_accel_m_s2: must be positive and finite";
    else if (!(cfg->scale_jerk_m_s3 > 0) || !isfinite(cfg->scale_jerk_m_s3))
        w = "scale_jerk_m_s3: must be positive and finite";
    else if (cfg->start_slack > ENGINE_FRAGMENT_MAX && cfg->start_slack != ENGINE_AUTO)
        w = "start_slack: at most ENGINE_FRAGMENT_MAX waypoints";
    else if (cfg->ends == ENGINE_ENDS_CLAMPED &&
             !(isfinite(cfg->start_vel_m_s[0]) && isfinite(cfg->start_vel_m_s[1]) &&
               isfinite(cfg->start_vel_m_s[2]) && isfinite(cfg->end_vel_m_s[0]) &&
               isfinite(cfg->end_vel_m_s[1]) && isfinite(cfg->end_vel_m_s[2])))
        w = "start_vel_m_s/end_vel_m_s: must be finite";
    else if (cfg->ends == ENGINE_ENDS_CLAMPED && !engine_ends_within_limit(cfg))
        w = "start_vel_m_s/end_vel_m_s: faster than max_speed_m_s in force (without a speed "
            "limit: than max_abs_m per second)";
    if (!w) {
        la = lookahead_of(cfg);
        if (cfg->capacity < la + cfg->fragment + 8 || cfg->capacity > ENGINE_CAPACITY_MAX)
            w = "capacity: must be at least lookahead + fragment + 8 and at most 2^20";
    }
    if (why)
        *why = w;
    return w ? -ENGINE_ECONFIG : 0;
}

/* ------------------------------------------------------------------------ */

engine_t *engine_new(const engine_config_t *cfg_in, int *err)
{
    engine_t *e;
    size_t ring = 16;
    engine_config_t r;
    const engine_config_t *cfg = &r;

    if (engine_config_check(cfg_in, NULL) < 0 || engine_config_resolve(cfg_in, &r) < 0) {
        if (err)
            *err = ENGINE_ECONFIG;
        return NULL;
    }
    e = calloc(1, sizeof(*e));
    if (!e)
        goto nomem;
    e->cfg = *cfg;
    e->lookahead = lookahead_of(cfg);
    e->la_steady = steady_lookahead(cfg) + smooth_extra(cfg);
    e->slack_auto = cfg->start_slack == ENGINE_AUTO;
    {
        /* the slack must fit the buffer: capacity >= lookahead + F + 8 (checked) */
        unsigned room = cfg->capacity - (e->lookahead + cfg->fragment + 8);
        e->slack_more = ENGINE_SLACK_AUTO_MAX - ENGINE_SLACK_AUTO_MIN;
        if (room < e->slack_more)
            e->slack_more = room;
    }
    e->pstar = uses_pstar(cfg);
    e->held = cfg->ends == ENGINE_ENDS_HELD || cfg->ends == ENGINE_ENDS_MULTIPLE;
    e->mult = cfg->ends == ENGINE_ENDS_MULTIPLE;
    e->smooth = cfg->method == ENGINE_METHOD_SMOOTH;
    if (e->smooth) {
        e->sm_mem = calloc(lsq_smooth_mem_len(cfg->smooth_window, cfg->smooth_ctrl, AX),
                           sizeof(double));
        if (!e->sm_mem ||
            lsq_smooth_init(&e->sm, cfg->smooth_window, cfg->smooth_ctrl, AX, e->sm_mem) < 0)
            goto nomem;
    }
    e->period_s = (double)cfg->period_ns * 1e-9;
    {
        accept_config_t ac = {
            .max_speed_m_s = engine_config_max_speed(cfg),
            .max_accel_m_s2 = engine_config_max_accel(cfg),
            .max_gap_s = cfg->max_gap_s,
            .learned = cfg->profile == ENGINE_PROFILE_AUTO,
            .stale = cfg->profile != ENGINE_PROFILE_MACHINE && cfg->profile != ENGINE_PROFILE_NONE,
            .window = cfg->start_slack < ACCEPT_WINDOW_MAX ? cfg->start_slack : ACCEPT_WINDOW_MAX,
            .confirm = cfg->confirm,
            .rules = ACCEPT_RULES_OF(cfg->profile == ENGINE_PROFILE_NONE), /* accept.h */
        };
        if (ac.window < ac.confirm)
            ac.window = ac.confirm;
        accept_init(&e->policy, &ac);
    }
    e->xcfg.speed_m_s = cfg->transfer_speed_m_s;
    e->xcfg.accel_m_s2 = cfg->transfer_accel_m_s2;
    e->xcfg.max_s = cfg->max_gap_s;
    e->xcfg.vmax_m_s = engine_config_max_speed(cfg);
    e->xcfg.period_s = e->period_s;
    transfer_motion_reset(&e->motion);
    /* nodes from the oldest unbuilt segment (lags the newest by the lookahead
     * plus the copies of MULTIPLE) to the newest, with margin */
    while (ring < 2 * ((size_t)cfg->fragment + e->lookahead + e->slack_more) + 16)
        ring *= 2;
    e->ring = ring;
    e->node_t = calloc(ring, sizeof(double));
    e->node_r = calloc(ring * AX, sizeof(double));
    e->fw = frag_new(cfg->fragment, cfg->overlap, frag_delta(cfg), ring);
    /* each accepted waypoint yields at most one segment, each trajectory
     * one END: twice the capacity always fits */
    e->qcap = 2 * (size_t)cfg->capacity + 8;
    e->q = calloc(e->qcap, sizeof(qent_t));
    e->slow = calloc(e->qcap, sizeof(size_t));
    if (!e->node_t || !e->node_r || !e->fw || !e->q || !e->slow)
        goto nomem;
    e->st.lookahead = e->lookahead;
    e->ts.rate = 1.0;
    e->override = 1.0;
    if (err)
        *err = 0;
    return e;
nomem:
    engine_free(e);
    if (err)
        *err = ENGINE_ENOMEM;
    return NULL;
}

void engine_free(engine_t *e)
{
    if (!e)
        return;
    free(e->node_t);
    free(e->node_r);
    frag_free(e->fw);
    free(e->q);
    free(e->slow);
    free(e->sm_mem);
    free(e);
}

/* ---- input side ---------------------------------------------------------- */

static double *nr(engine_t *e, uint64_t j)
{
    return e->node_r + (size_t)(j % e->ring) * AX;
}

static double nt(const engine_t *e, uint64_t j)
{
    return e->node_t[j % e->ring];
}

/* parameter step of interval j (M form) */
static double hpar(const engine_t *e, uint64_t j)
{
    return e->cfg.param == ENGINE_PARAM_TIME ? nt(e, j + 1) - nt(e, j) : 1.0;
}

static size_t buffered(const engine_t *e)
{
    return e->qlen + (size_t)(e->nodes - e->seg_next) +
           (e->smooth ? (size_t)lsq_smooth_pending(&e->sm) : 0) + accept_pending(&e->policy);
}

static qent_t *q_push(engine_t *e)
{
    qent_t *q;

    if (e->qlen == e->qcap)
        return NULL; /* cannot happen: see qcap */
    q = &e->q[(e->qhead + e->qlen) % e->qcap];
    e->qlen++;
    q->first = e->in_first_pending;
    q->traj = e->in_traj;
    q->gap_s = q->first ? e->in_gap_s : 0;
    e->in_first_pending = 0;
    return q;
}

/* The highest rate at which a segment whose speed is at most vmax keeps the
 * speed cap (ENGINE_SPEED_CAP x the speed limit), at least ENGINE_CEIL_MIN. */
static double seg_ceiling(const engine_t *e, double vmax)
{
    double v = engine_config_max_speed(&e->cfg);
    if (!(v > 0) || !(vmax > 0))
        return INFINITY;
    return fmax(ENGINE_SPEED_CAP * v / vmax, ENGINE_CEIL_MIN);
}

/* A queued segment whose speed cap holds the rate below TS_RATE_MAX. */
static int is_slow(const qent_t *q)
{
    return q->kind == QE_SEG && q->ceil < TS_RATE_MAX;
}

static void queue_segment(engine_t *e, const fdiff_seg_t *seg, uint64_t node)
{
    qent_t *q = q_push(e);

    if (!q)
        return;
    q->kind = QE_SEG;
    q->node = node;
    q->seg = *seg;
    q->t1_s = seg->t0_s + seg->dur_s;
    q->vmax = seg_speed_max(seg);
    q->ceil = seg_ceiling(e, q->vmax);
    if (is_slow(q)) /* every queued slot has room: so has the ring */
        e->slow[(e->slow_head + e->slow_len++) % e->qcap] = (size_t)(q - e->q);
    double inv = 1.0 / fmax(q->vmax, ENGINE_SCALE_V_FLOOR_M_S);
    if (e->in_emitted && inv > e->in_inv)
        e->in_ucum += inv - e->in_inv; /* the limits rise from the last one to this */
    e->in_inv = inv;
    q->ucum = e->in_ucum;
    e->in_kcum += seg->dur_s * inv;
    q->kcum = e->in_kcum;
    e->in_emitted = 1;
    e->end_t = q->t1_s;
    double v2 = 0;
    for (int k = 0; k < AX; k++) {
        double v = (seg->c[k][1] + 2 * seg->c[k][2] + 3 * seg->c[k][3]) / seg->dur_s;
        e->end_r[k] = seg->c[k][0] + seg->c[k][1] + seg->c[k][2] + seg->c[k][3];
        v2 += v * v;
    }
    e->end_speed = sqrt(v2);
    if (e->mode != OUT_HOLD && q->traj == e->out_traj) {
        e->avail_t = q->t1_s; /* more curve for the output (see remaining()) */
        e->avail_kcum = q->kcum;
        e->avail_ucum = q->ucum;
    }
}

static void queue_end(engine_t *e)
{
    qent_t *q = q_push(e);

    if (!q)
        return;
    q->kind = QE_END;
    e->qends++;
    memset(&q->seg, 0, sizeof(q->seg));
    q->t1_s = e->in_emitted ? e->end_t : e->last_t;
    q->seg.t0_s = q->t1_s;
    for (int k = 0; k < AX; k++)
        q->seg.c[k][0] = e->in_emitted ? e->end_r[k] : e->last_r[k];
    /* END: c[0][1] is the speed at which the curve arrives (0 at rest) */
    q->seg.c[0][1] = e->in_emitted ? e->end_speed : 0.0;
    if (e->mode != OUT_HOLD && q->traj == e->out_traj) {
        e->avail_t = q->t1_s;
        e->avail_closed = 1;
        e->avail_rest = q->seg.c[0][1] <= ENGINE_REST_SPEED_M_S;
    }
}

/* end velocities in the unknowns' parameter (dk/du for P*, dk/ds for M) */
static void end_vel_param(const engine_t *e, int at_end, double *v)
{
    const double *src = at_end ? e->cfg.end_vel_m_s : e->cfg.start_vel_m_s;
    uint64_t j = at_end ? e->nodes - 2 : 0;
    double dur = nt(e, j + 1) - nt(e, j);
    double scale = e->pstar ? dur : dur / hpar(e, j);

    for (int k = 0; k < AX; k++)
        v[k] = src[k] * scale;
}

/* Build and queue every segment whose control values are final. */
static void build_segments(engine_t *e)
{
    uint64_t fin = e->fw->final_rows, last = e->nodes - 1;
    int closed = e->fw->done;

    for (;;) {
        uint64_t j = e->seg_next;
        fdiff_seg_t seg;
        double dur;

        if (j + 1 >= e->nodes)
            break;
        if (e->pstar) {
            if (!(j + 3 <= fin || (closed && j + 2 == fin && j + 1 == last)))
                break;
        } else if (j + 2 > fin) {
            break;
        }
        e->seg_next = j + 1;
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
                hoang_ghost_start(e->cfg.ends, frag_x(e->fw, 0), frag_x(e->fw, 1), v, g0);
                p0 = g0;
            } else {
                p0 = frag_x(e->fw, j - 1);
            }
            if (j + 1 == last) {
                end_vel_param(e, 1, v);
                hoang_ghost_end(e->cfg.ends, frag_x(e->fw, last - 1), frag_x(e->fw, last), v, g1);
                p3 = g1;
            } else {
                p3 = frag_x(e->fw, j + 2);
            }
            hoang_segment(p0, frag_x(e->fw, j), frag_x(e->fw, j + 1), p3, nt(e, j), dur, &seg);
        } else {
            cubic_segment(nr(e, j), nr(e, j + 1), frag_x(e->fw, j), frag_x(e->fw, j + 1),
                          hpar(e, j), nt(e, j), dur, &seg);
        }
        queue_segment(e, &seg, j);
    }
}

static const double zero3[AX] = {0, 0, 0};

/* start_slack auto: what node j says about the input's timing and speed */
static void measure_input(engine_t *e, uint64_t j)
{
    const double decay = 1.0 - 1.0 / 256;
    double dt = nt(e, j) - nt(e, j - 1), d2 = 0;

    for (int k = 0; k < AX; k++)
        d2 += (nr(e, j)[k] - nr(e, j - 1)[k]) * (nr(e, j)[k] - nr(e, j - 1)[k]);
    if (dt > 0) {
        double v = sqrt(d2) / dt;
        e->vmax_in = fmax(v, e->vmax_in * decay);
    }
    if (j > e->la_steady) {
        /* how far ahead of the output this node must have been sent to be
         * built on time (see enough_ahead) */
        double w = nt(e, j) - nt(e, j - e->la_steady - 1);
        e->span_max = fmax(w, e->span_max * decay);
    }
}

/* Append a node; push the row it completes (row nodes-1 before it). */
static int add_node(engine_t *e, double t, const double *r)
{
    uint64_t j = e->nodes;
    frag_row_t row;
    int rc = 0;

    e->node_t[j % e->ring] = t;
    memcpy(nr(e, j), r, sizeof(double) * AX);
    e->nodes = j + 1;
    if (e->slack_auto && j >= 1)
        measure_input(e, j);
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
            rc = frag_push(e->fw, &row, nr(e, i));
        } else {
            if (i == 0) {
                double v[AX];
                end_vel_param(e, 0, v);
                cubic_row_start(e->cfg.ends, hpar(e, 0), nr(e, 0), nr(e, 1), v, &row);
            } else {
                cubic_row_interior(hpar(e, i - 1), hpar(e, i), nr(e, i - 1), nr(e, i), nr(e, i + 1),
                                   &row);
            }
            rc = frag_push(e->fw, &row, zero3);
        }
        if (rc < 0)
            return -ENGINE_ENUMERIC;
        build_segments(e);
    }
    return 0;
}

/* SMOOTH: turn every smoothed waypoint that is ready into a node. */
static int drain_smoother(engine_t *e)
{
    double t, r[AX];
    int rc;

    while (lsq_smooth_pop(&e->sm, &t, r) == 1)
        if ((rc = add_node(e, t, r)) < 0)
            return rc;
    return 0;
}

/* Close the input trajectory: end row, last segments, END entry. */
static int close_input(engine_t *e)
{
    frag_row_t row;
    int rc = 0;

    if (!e->in_open)
        return 0;
    e->in_open = 0;
    if (e->smooth) {
        lsq_smooth_finish(&e->sm);
        if ((rc = drain_smoother(e)) < 0)
            goto end;
    }
    if (e->mult) {
        /* the last point twice more (it is in already once) */
        double r[AX];
        memcpy(r, e->last_r, sizeof(r));
        if ((rc = add_node(e, e->last_t, r)) < 0 || (rc = add_node(e, e->last_t, r)) < 0)
            goto end;
    }
    if (e->nodes >= 2) {
        uint64_t l = e->nodes - 1;
        double v[AX];
        end_vel_param(e, 1, v);
        if (e->pstar)
            hoang_row_end(e->mult ? ENGINE_ENDS_HELD : e->cfg.ends, nr(e, l), v, &row);
        else
            cubic_row_end(e->cfg.ends, hpar(e, l - 1), nr(e, l - 1), nr(e, l), v, &row);
        if (frag_finish(e->fw, &row) < 0)
            rc = -ENGINE_ENUMERIC;
        else
            build_segments(e);
    }
end:
    e->seg_next = e->nodes; /* nothing pending any more */
    queue_end(e);
    return rc;
}

static void open_input(engine_t *e, const engine_waypoint_t *wp)
{
    frag_reset(e->fw);
    e->in_open = 1;
    e->nodes = 0;
    e->seg_next = 0;
    e->in_emitted = 0;
    e->in_kcum = 0.0;
    e->in_ucum = 0.0;
    e->in_first_pending = 1;
    e->in_traj++;
    e->st.tracks++;
    e->finished = 0;
    memcpy(e->first_r, wp->pos_m, sizeof(e->first_r));
    if (e->smooth)
        lsq_smooth_reset(&e->sm);
}

/*
 * Acceleration implied by the previous two waypoints and this one (dt after
 * the last): the change of mean velocity over the two intervals divided by
 * half their sum, i.e. the second divided difference times 2.  It is what
 * the C2 curve through the three has to produce somewhere near the middle
 * one, whatever the end conditions; a timestamp off by a fraction of the
 * interval makes it large because both intervals around the bad stamp are
 * divided into the same distances.  O(1), no state beyond the two.
 */
static double implied_accel(const engine_t *e, const engine_waypoint_t *wp, double dt)
{
    double d1 = e->last_t - e->prev_t, a2 = 0;

    for (int k = 0; k < AX; k++) {
        double v1 = (e->last_r[k] - e->prev_r[k]) / d1;
        double v2 = (wp->pos_m[k] - e->last_r[k]) / dt;
        double a = 2.0 * (v2 - v1) / (d1 + dt);
        a2 += a * a;
    }
    return sqrt(a2);
}

static int reject(engine_t *e, int code)
{
    if (code == ENGINE_EFULL) {
        /* flow control, not bad data: its own counter (rejected means refused) */
        e->st.full++;
        return -code;
    }
    e->st.rejected++;
    e->st.rejected_by[code]++;
    return -code;
}

/* Count a refused waypoint and keep it for engine_rejection_next. */
static int reject_wp(engine_t *e, int code, const engine_waypoint_t *wp)
{
    engine_rejection_t *r;

    if (e->rej_len == ENGINE_REJECTIONS_KEPT) {
        /* the oldest unread one makes room (its count stays in rejected_by) */
        e->rej_head = (e->rej_head + 1) % ENGINE_REJECTIONS_KEPT;
        e->rej_len--;
        e->st.rejections_unreported++;
    }
    r = &e->rej[(e->rej_head + e->rej_len) % ENGINE_REJECTIONS_KEPT];
    e->rej_len++;
    r->seq = wp->seq;
    r->reason = code;
    r->t_s = wp->t_s;
    memcpy(r->pos_m, wp->pos_m, sizeof r->pos_m);
    return reject(e, code);
}

int engine_rejection_next(engine_t *e, engine_rejection_t *r)
{
    engine_fast_close(e); /* whatever it changes, the next tick looks again */
    if (!e->rej_len)
        return 0;
    *r = e->rej[e->rej_head];
    e->rej_head = (e->rej_head + 1) % ENGINE_REJECTIONS_KEPT;
    e->rej_len--;
    return 1;
}

/* Append a waypoint the acceptance policy kept to the trajectory being received. */
/* Param uniform: the ratio of the last kept waypoint's two intervals h1, h2
 * (its velocity steps by it: ENGINE_UNIFORM_RATIO_WARN). */
static void note_uniform(engine_t *e, double h1, double h2)
{
    double r = h1 > h2 ? h1 / h2 : h2 / h1;
    if (!(r >= 1.0))
        return; /* cannot happen: kept intervals are positive */
    if (r > e->st.uniform_ratio_max) {
        e->st.uniform_ratio_max = r;
        e->st.uniform_ratio_t_s = e->last_t;
    }
    if (r > ENGINE_UNIFORM_RATIO_WARN)
        e->st.uniform_irregular++;
}

static int keep(engine_t *e, const engine_waypoint_t *wp)
{
    int rc;

    if (!e->in_open) {
        open_input(e, wp);
        e->have_prev = 0;
    } else {
        double d1 = wp->t_s - e->last_t, v2 = 0;
        for (int k = 0; k < AX; k++)
            v2 += (wp->pos_m[k] - e->last_r[k]) * (wp->pos_m[k] - e->last_r[k]);
        transfer_motion_note(&e->motion, sqrt(v2) / d1,
                             e->have_prev ? implied_accel(e, wp, d1) : 0.0);
        if (e->have_prev && e->cfg.param == ENGINE_PARAM_UNIFORM)
            note_uniform(e, e->last_t - e->prev_t, d1);
        e->have_prev = 1;
        e->prev_t = e->last_t;
        memcpy(e->prev_r, e->last_r, sizeof(e->prev_r));
    }
    e->last_t = wp->t_s;
    memcpy(e->last_r, wp->pos_m, sizeof(e->last_r));
    if (e->smooth) {
        lsq_smooth_push(&e->sm, wp->t_s, wp->pos_m);
        rc = drain_smoother(e);
    } else {
        rc = add_node(e, wp->t_s, wp->pos_m);
    }
    if (rc == 0 && e->mult && e->nodes == 1) {
        /* the first point twice more */
        if ((rc = add_node(e, wp->t_s, wp->pos_m)) == 0)
            rc = add_node(e, wp->t_s, wp->pos_m);
    }
    if (rc < 0) {
        /* cannot happen with finite data (diagonally dominant systems);
         * end the trajectory with what is queued rather than stream garbage */
        e->in_open = 0;
        e->seg_next = e->nodes;
        queue_end(e);
        accept_close(&e->policy);
        return reject_wp(e, -rc, wp);
    }
    e->st.accepted++;
    e->st.last_seq = wp->seq;
    return 0;
}

/* Carry out every verdict the acceptance policy can give now. */
static int judge(engine_t *e, int closing)
{
    accept_verdict_t v;
    int rc = 0;

    while (accept_decide_counted(&e->policy, closing, &v, &e->st)) { /* stops.c */
        switch (v.kind) {
        case ACCEPT_TAKE:
            if (keep(e, &v.wp) < 0)
                rc = -ENGINE_ENUMERIC;
            break;
        case ACCEPT_START:
            e->in_gap_s = 0;
            if (e->in_open) {
                if (v.gap) {
                    e->st.gaps++;
                    e->in_gap_s = v.wp.t_s - e->last_t;
                } else if (!v.stop) {
                    e->st.reanchors++;
                }
                if (close_input(e) < 0)
                    rc = -ENGINE_ENUMERIC;
            }
            if (v.stop != ACCEPT_STOP_HALT && keep(e, &v.wp) < 0)
                rc = -ENGINE_ENUMERIC;
            break;
        case ACCEPT_DROP: reject_wp(e, v.reason, &v.wp); break;
        }
    }
    return rc;
}

int engine_waypoint_check(const engine_config_t *cfg, const engine_waypoint_t *wp)
{
    for (int k = 0; k < AX; k++)
        if (!isfinite(wp->pos_m[k]))
            return -ENGINE_ENOTFINITE;
    if (!isfinite(wp->t_s))
        return -ENGINE_ENOTFINITE;
    for (int k = 0; k < AX; k++)
        if (fabs(wp->pos_m[k]) > cfg->max_abs_m)
            return -ENGINE_ERANGE;
    if (fabs(wp->t_s) > ENGINE_T_ABS_MAX_S)
        return -ENGINE_ERANGE;
    return 0;
}

int engine_push(engine_t *e, const engine_waypoint_t *wp)
{
    engine_fast_close(e); /* whatever it changes, the next tick looks again */
    int rc = engine_waypoint_check(&e->cfg, wp);

    if (rc < 0)
        return reject_wp(e, -rc, wp);
    /* room for this waypoint (and for the copies MULTIPLE adds) */
    if (buffered(e) + 1 + (e->mult ? 4 : 0) > e->cfg.capacity)
        return reject(e, ENGINE_EFULL);
    rc = accept_offer(&e->policy, wp);
    if (rc == ENGINE_DUPLICATE) {
        e->st.duplicates++;
        return ENGINE_DUPLICATE;
    }
    if (rc < 0)
        return reject(e, -rc); /* cannot happen: judge() empties the window below */
    return judge(e, 0);
}

int engine_finish(engine_t *e)
{
    engine_fast_close(e); /* whatever it changes, the next tick looks again */
    int rj = judge(e, 1);
    int rc = close_input(e);

    accept_close(&e->policy);
    if (!e->qlen && e->mode == OUT_HOLD && !e->in_open)
        e->finished = 1; /* nothing left to stream: the input is over */
    return rc < 0 ? rc : rj < 0 ? rj : 0;
}

/* ---- output side --------------------------------------------------------- */

static qent_t *q_head(engine_t *e)
{
    return e->qlen ? &e->q[e->qhead] : NULL;
}

static void q_pop(engine_t *e)
{
    if (e->drop_n)
        e->drop_n--;
    if (e->q[e->qhead].kind == QE_END)
        e->qends--;
    if (is_slow(&e->q[e->qhead])) { /* the ring's head */
        e->slow_head = (e->slow_head + 1) % e->qcap;
        e->slow_len--;
    }
    e->qhead = (e->qhead + 1) % e->qcap;
    e->qlen--;
}

/* The newest interval of the input (0: fewer than two nodes). */
static double last_interval(const engine_t *e)
{
    return e->nodes >= 2 ? nt(e, e->nodes - 1) - nt(e, e->nodes - 2) : 0.0;
}

/* start_slack auto: the curve kept ahead of the output beyond what the
 * solver needs, track seconds: twice a stop from full rate at the input's
 * top speed (the curve may be faster than its chords), a few ticks, and the
 * newest interval once per underrun seen. */
static double brake_s(const engine_t *e)
{
    double v = e->vmax_in > ENGINE_SCALE_V_FLOOR_M_S ? e->vmax_in : ENGINE_SCALE_V_FLOOR_M_S;
    return 2.0 * ts_stop_dist(1.0, 0.0, e->cfg.scale_accel_m_s2 / v, e->cfg.scale_jerk_m_s3 / v) +
           (TS_MARGIN_TICKS + 2) * e->period_s + e->slack_learn * last_interval(e);
}

/* Time of the newest waypoint received for the current trajectory: the
 * newest node, or a waypoint the acceptance policy still holds (-inf: none). */
static double newest_t(const engine_t *e)
{
    double t = e->nodes > 0 ? nt(e, e->nodes - 1) : -INFINITY;
    const engine_waypoint_t *held = accept_last(&e->policy);
    if (held && held->t_s > t)
        t = held->t_s;
    return t;
}

/* start_slack auto: an output stopped by an underrun at s stays stopped
 * until the curve surely built ahead of it is longer than brake_s (or the
 * buffer holds the most slack, or the input is closed).  Not span_max, as
 * at a start: after a long hole in the input that would hold it for as long
 * as the hole. */
static int rebuffering(const engine_t *e, double s)
{
    uint64_t in = e->nodes + (e->smooth ? lsq_smooth_pending(&e->sm) : 0) +
                  accept_pending(&e->policy);

    if (e->avail_closed || e->cur.kind != QE_SEG ||
        in >= e->cur.node + 2 + e->lookahead + e->slack_more)
        return 0;
    /* the curve is built at least up to the node la_steady + 1 before the
     * newest one, whatever the fragment phase */
    uint64_t back = (uint64_t)e->la_steady + 1;
    if (e->nodes <= back)
        return 1;
    return !(nt(e, e->nodes - 1 - back) - (e->origin_t + s) >=
             brake_s(e) - e->slack_learn * last_interval(e));
}

/* An underrun: counted, and (start_slack auto) the next start waits one
 * waypoint more, up to ENGINE_SLACK_AUTO_MAX: the input came later than its
 * timestamps said. */
static void count_underrun(engine_t *e)
{
    e->st.underruns++;

    if (e->slack_auto && e->slack_learn < e->slack_more) {
        e->slack_learn++;
        e->st.lookahead = e->lookahead + e->slack_learn;
    }
}

/*
 * The output may start (or resume after an underrun) on the segment h only
 * once the lookahead is buffered beyond it, or its trajectory is closed.
 */
static int enough_ahead(const engine_t *e, const qent_t *h)
{
    /* waypoints received: nodes, plus those the smoother still holds (SMOOTH) */
    /* and those the acceptance policy still judges: their verdicts come
     * within the start slack, so they count as lookahead (accept.h) */
    uint64_t in = e->nodes + (e->smooth ? lsq_smooth_pending(&e->sm) : 0) +
                  accept_pending(&e->policy);

    if (e->qends > 0 || h->kind != QE_SEG)
        return 1;
    if (in < h->node + 2 + e->lookahead + e->slack_learn)
        return 0;
    if (!e->slack_auto || in >= h->node + 2 + e->lookahead + e->slack_more)
        return 1;
    /* start_slack auto.  Starting at t0 with the newest node at t_m puts
     * the output D = t_m - t0 behind the input; the curve built ahead of it
     * is then always longer than D - span_max (span_max: the longest time of
     * la_steady + 1 intervals), and must stay longer than a stop from full
     * rate at the input's top speed, so that the time scaling can brake
     * if the input stops (timescale.h; twice that: the curve may be faster than
     * its chords).  Regular slow input: at once. */
    return newest_t(e) - h->seg.t0_s >= e->span_max + brake_s(e);
}

static void hold_here(engine_t *e)
{
    for (int k = 0; k < AX; k++)
        e->vel[k] = e->acc[k] = 0.0;
}

/* Exact comparisons of the time scaling's state (it lands on its targets
 * exactly, see ts_step), written without == for -Wfloat-equal. */
static int is_exactly(double x, double v)
{
    return !(x < v || x > v);
}

static int at_rest(const engine_t *e)
{
    return is_exactly(e->ts.rate, 0.0) && is_exactly(e->ts.acc, 0.0);
}

/* Back on the unit grid with rate 1 (every start from HOLD). */
static void unit_reset(engine_t *e)
{
    e->scaled = 0;
    e->s_off = 0.0;
    e->ts.rate = 1.0;
    e->ts.acc = 0.0;
    e->end_brake = 0;
}

/* A stop or clear has brought the output to rest: drop what was queued at
 * the request, stand here (FINISHED after a stop, WAITING after a clear). */
static void stop_at_rest(engine_t *e)
{
    while (e->drop_n && e->qlen)
        q_pop(e);
    e->drop_n = 0;
    e->mode = OUT_HOLD;
    hold_here(e);
    e->finished = e->stop_req == STOP_STOP;
    e->stop_req = STOP_NONE;
    e->underrun = 0;
    unit_reset(e);
}

/* The queue head is a trajectory's end marker: rest on its point, FINISHED. */
static void rest_at_end(engine_t *e, const qent_t *h)
{
    for (int k = 0; k < AX; k++)
        e->pos[k] = h->seg.c[k][0];
    e->out_t = h->t1_s;
    q_pop(e);
    hold_here(e);
    e->mode = OUT_HOLD;
    e->finished = 1;
    e->underrun = 0;
    if (e->stop_req)
        stop_at_rest(e);
}

/* A closed trajectory whose curve does not end at rest, braked to rest just
 * before its end: finish here, where the output stands (no jump to the end). */
static void finish_here(engine_t *e)
{
    while (e->qlen) {
        int end = q_head(e)->kind == QE_END && q_head(e)->traj == e->out_traj;
        q_pop(e);
        if (end)
            break;
    }
    e->mode = OUT_HOLD;
    hold_here(e);
    e->finished = 1;
    e->underrun = 0;
    unit_reset(e);
}

static double tick_time(const engine_t *e, int64_t n)
{
    return (double)(n * e->cfg.period_ns) * 1e-9;
}

/* Track time of tick n on the unit grid (relative to origin_t); s_off is 0
 * until the time scaling first moved the output off the grid. */
static double tau_of(const engine_t *e, int64_t n)
{
    return tick_time(e, n) + e->s_off;
}

/* The play time (now - D), absolute, and relative to origin_t: epoch
 * seconds in a double are only good to 2.4e-7 s, so the difference is taken
 * in long double from the integer nanoseconds. */
static double play_abs(const engine_t *e)
{
    return (double)((long double)e->play_ns * 1e-9L);
}

static double play_rel(const engine_t *e)
{
    return (double)((long double)e->play_ns * 1e-9L - (long double)e->origin_t);
}

static void out_eval(engine_t *e)
{
    double v2 = 0;

    fdiff_get(&e->fd, e->pos, e->vel, e->acc);
    for (int k = 0; k < AX; k++)
        v2 += e->vel[k] * e->vel[k];
    e->cspeed = sqrt(v2); /* rate 1: the curve's own speed */
}

/* Scaled output: the curve at s by Horner, then the chain rule
 * (timescale.h): v = k' r, a = k'' r^2 + k' dr/dt. */
static void out_eval_scaled(engine_t *e)
{
    double u = (e->s - e->cur_t0) / e->cur.seg.dur_s, cv[AX], ca[AX], v2 = 0;
    double r = e->ts.rate, ra = e->ts.acc;

    if (u < 0)
        u = 0;
    if (u > 1)
        u = 1;
    fdiff_eval(&e->cur.seg, u, e->pos, cv, ca);
    for (int k = 0; k < AX; k++) {
        e->vel[k] = cv[k] * r;
        e->acc[k] = ca[k] * r * r + cv[k] * ra;
        v2 += cv[k] * cv[k];
    }
    e->cspeed = sqrt(v2);
}

/* Seed cur at tick n (relative time tau in [cur_t0, cur_t1)). */
static void seed_cur(engine_t *e, int64_t n)
{
    double tau = tau_of(e, n);
    double u0 = (tau - e->cur_t0) / e->cur.seg.dur_s;
    fdiff_seed(&e->fd, &e->cur.seg, u0, e->period_s / e->cur.seg.dur_s);
}

/* Make the queue head (a SEG) the current segment, relative to origin_t. */
static void take_segment(engine_t *e)
{
    e->cur = *q_head(e);
    q_pop(e);
    e->cur_t0 = e->cur.seg.t0_s - e->origin_t;
    e->cur_t1 = e->cur.t1_s - e->origin_t;
}

/* Where the solved curve of the output's trajectory ends, from the queue
 * (once per trajectory; queue_segment and queue_end keep it up to date). */
static void find_avail(engine_t *e)
{
    e->avail_t = e->cur.t1_s;
    e->avail_kcum = e->cur.kcum;
    e->avail_ucum = e->cur.ucum;
    e->avail_closed = 0;
    e->avail_rest = 0;
    for (size_t i = 0; i < e->qlen; i++) {
        const qent_t *q = &e->q[(e->qhead + i) % e->qcap];
        if (q->traj != e->out_traj)
            break;
        e->avail_t = q->t1_s;
        if (q->kind == QE_SEG) {
            e->avail_kcum = q->kcum;
            e->avail_ucum = q->ucum;
        }
        if (q->kind == QE_END) {
            e->avail_closed = 1;
            e->avail_rest = q->seg.c[0][1] <= ENGINE_REST_SPEED_M_S;
            break;
        }
    }
}

static void scaled_rest(engine_t *e);

/* One clock: a trajectory is entered at rate 0 like every other
 * (scaled_rest, TIMESCALE.md "Handovers": locked at once, its acceleration
 * would step by k''(0) rho^2), behind the play time by the sub-tick phase
 * past its first waypoint (and by what the waypoints came late); the
 * catch-up of clocked_step wins the lag back and locks on the clock. */
static void clock_start(engine_t *e)
{
    scaled_rest(e);
    e->locked = 0;
    out_eval_scaled(e);
    e->out_t = e->origin_t;
}

/* Begin streaming the trajectory at the queue head (tick 0 of it). */
static void start_trajectory(engine_t *e, int new_flag)
{
    qent_t *h = q_head(e);

    if (new_flag) {
        e->out_track++;
        e->flags_pending |= ENGINE_SP_NEW_TRACK;
    }
    e->have_pos = 1;
    e->underrun = 0;
    if (h->kind == QE_END) {
        /* a trajectory with no segment: rest on its point */
        rest_at_end(e, h);
        return;
    }
    e->origin_t = h->seg.t0_s;
    e->out_traj = h->traj;
    take_segment(e);
    find_avail(e);
    e->n = 0;
    e->seg_n0 = 0;
    e->s_off = 0.0;
    seed_cur(e, 0);
    out_eval(e);
    e->out_t = e->origin_t;
    e->mode = OUT_STREAM;
    if (e->clocked) {
        clock_start(e);
    } else if (e->scaled) {
        /* from a scaled transfer: go on scaled from the start */
        e->s = 0.0;
        out_eval_scaled(e);
    }
}

/* Fastest chord speed of the first queued segments of the trajectory at the
 * queue head: how the object moves where the transfer takes it. */
static double head_speed(const engine_t *e)
{
    double v = 0;

    for (size_t i = 0; i < e->qlen && i < TRANSFER_HIST; i++) {
        const qent_t *q = &e->q[(e->qhead + i) % e->qcap];
        double d2 = 0;
        if (q->kind != QE_SEG || (i > 0 && q->first))
            break;
        for (int k = 0; k < AX; k++) {
            double d = q->seg.c[k][1] + q->seg.c[k][2] + q->seg.c[k][3];
            d2 += d * d;
        }
        v = fmax(v, sqrt(d2) / q->seg.dur_s);
    }
    return v;
}

/* How long a transfer from the output position to target takes (transfer.h). */
static double xfer_duration(const engine_t *e, const double *target, double gap_s, int *capped)
{
    double dist = 0, v_obj;

    for (int i = 0; i < AX; i++)
        dist += (target[i] - e->pos[i]) * (target[i] - e->pos[i]);
    dist = sqrt(dist);
    v_obj = fmax(transfer_motion_speed(&e->motion), head_speed(e));
    return transfer_duration(&e->xcfg, dist, v_obj, transfer_motion_accel(&e->motion), gap_s,
                             capped);
}

/* Start a transfer from the output position to target (transfer.h). */
static void start_transfer(engine_t *e, const double *target, double gap_s)
{
    int capped = 0;
    double dur = xfer_duration(e, target, gap_s, &capped);

    memset(&e->cur, 0, sizeof(e->cur));
    e->xfer_from_t = e->out_track ? e->out_t : NAN;
    e->cur.kind = QE_SEG;
    transfer_segment(&e->cur.seg, e->pos, target, dur);
    e->cur.vmax = seg_speed_max(&e->cur.seg);
    e->cur_t0 = 0;
    e->cur_t1 = e->cur.seg.dur_s;
    e->n = 0;
    e->seg_n0 = 0;
    e->s_off = 0.0;
    e->out_track++;
    e->flags_pending |= ENGINE_SP_NEW_TRACK;
    e->mode = OUT_XFER;
    e->st.transfers++;
    e->st.transfer_s += dur;
    e->st.transfers_capped += (uint64_t)capped;
    seed_cur(e, 0);
}

/* One forward step of cur (with a re-seed at deterministic ticks). */
static void step_cur(engine_t *e, int64_t n)
{
    if ((uint64_t)(n - e->seg_n0) % FDIFF_RESEED_STEPS == 0)
        seed_cur(e, n);
    else
        fdiff_step(&e->fd);
    out_eval(e);
}

/* The speed (m/s) at which the scaling's limits are converted outside a
 * stop: the largest the curve reaches on the current segment (seg_speed_max;
 * a transfer's: 1.5 D / T_x), at least the floor.  (Converted at the speed
 * here, the limits shrink as a ramp speeds up along a transfer faster than
 * the jerk can take the rate's acceleration back: the rate overshot 1.) */
static double conv_speed(const engine_t *e)
{
    return fmax(e->cur.vmax, ENGINE_SCALE_V_FLOOR_M_S);
}

/* Track time (per unit of rate, in the units of the limits converted at v)
 * kept for the rises of the limits ahead.  Where the output brakes into a
 * segment with larger limits (a slower one: A = a / v), its deceleration must
 * ramp up to the new A at the jerk J: a stop then needs up to
 * r (A_new - A_old)^2 / (2 J_new) <= r dA a / (2 j) of capacity more than
 * r^2/2; so much per rise of A ahead, summed (ucum), is kept in reserve. */
static double rise_reserve(const engine_t *e, double v)
{
    double du = e->avail_ucum - e->cur.ucum;
    return du > 0 ? 0.5 * e->cfg.scale_accel_m_s2 / e->cfg.scale_jerk_m_s3 * v * du : 0.0;
}

/*
 * Track time still available ahead of s (relative) before the output must
 * be at rest, with TS_MARGIN_TICKS in reserve; INFINITY when the curve ahead
 * ends at rest anyway (a transfer, a closed trajectory with rest ends).
 *
 * Not the plain track time left: the limits are a / v in rate units, so
 * braking on a part of the curve at speed v removes r^2/2 at a / v per unit
 * of track time (d(r^2/2)/ds = dr/dt).  What the curve ahead can absorb is
 * the capacity K = sum of dur / v over it (each segment at its fastest,
 * seg_speed_max, so K is a lower bound), and the output can stop within
 * it from r iff r^2/2 <= a K.  Expressed for ts_step, whose limits are
 * converted at the speed here, that is track time v_here K: more than is
 * left where the curve ahead is slower, less where it is faster.  With the
 * plain track time, a curve speeding up 8x in its last solved segment
 * (bspline + uniform on gpxpy_cerknicko-jezero.csv) was reached at 0.8 of
 * its rate and ended under the moving output (a hard stop).
 */
static double remaining(const engine_t *e, double s)
{
    if (e->mode == OUT_XFER)
        return e->cur_t1 - s; /* left at rate 0 (handover) */
    /* the braking capacity left, in the units of the limits here */
    double in_cur = e->cur_t1 - s, v = conv_speed(e), k;
    k = (in_cur > 0 ? in_cur / v : 0.0) + (e->avail_kcum - e->cur.kcum);
    /* the margin scales with the rate: standing still needs none, so a
     * buffer shorter than the margin never deadlocks the output */
    return v * k - e->ts.rate * (rise_reserve(e, v) + TS_MARGIN_TICKS * e->period_s);
}

/*
 * The speed cap ahead (ENGINE_SPEED_CAP, TIMESCALE.md "Speed cap"), as a
 * distance for ts_step like remaining(): the output must enter each slow
 * segment ahead (rate ceiling c) at a rate of at most c.  The braking that
 * comes to rest within the track time D to its start plus what a braking at
 * -A from c still needs, ts_stop_dist(c, -A), passes c within D (it passes c
 * decelerating at most at A, and needs at least that much more from there).
 * D as in remaining(): the capacity to the segment's start at the limits
 * here, less the same reserve.  INFINITY if no slow segment is ahead.
 */
static double ceil_room(const engine_t *e, double s, double A, double J)
{
    double R = INFINITY;

    if (e->mode != OUT_STREAM || !e->slow_len)
        return R;
    double in_cur = e->cur_t1 - s, v = conv_speed(e);
    double k0 = (in_cur > 0 ? in_cur / v : 0.0) - e->cur.kcum;
    double res = e->ts.rate * (rise_reserve(e, v) + TS_MARGIN_TICKS * e->period_s);
    for (size_t i = 0; i < e->slow_len; i++) {
        const qent_t *q = &e->q[e->slow[(e->slow_head + i) % e->qcap]];
        if (q->traj != e->out_traj)
            break;
        double kstart = q->kcum - q->seg.dur_s / fmax(q->vmax, ENGINE_SCALE_V_FLOOR_M_S);
        R = fmin(R, v * (k0 + kstart) - res + ts_stop_dist(q->ceil, -A, A, J));
    }
    return R;
}

/* The rate the speed cap allows on the current segment. */
static double ceil_here(const engine_t *e)
{
    return e->mode == OUT_STREAM ? e->cur.ceil : INFINITY;
}

/* The jerk of a stop or clear (m/s^3): at least a / T, so that the braking
 * reaches its full deceleration within one tick and the stop ends within
 * v^2/(2 a) + v T of path (a jerk j adds v a/(2 j) of onset: TIMESCALE.md,
 * "Stop distance"). */
static double stop_jerk(const engine_t *e)
{
    return fmax(e->cfg.scale_jerk_m_s3, e->cfg.scale_accel_m_s2 / e->period_s);
}

/* The time scaling's limits in rate units at the curve's speed: outside a
 * stop at the largest speed the curve reaches on the current segment and the
 * next one (conv_speed), so that k' dr/dt stays within a over the ticks ahead
 * also where the curve speeds up (a REST start, entered at rate 0).  A stop
 * converts them at the curve's speed here, down to a T (not the 1 m/s floor):
 * below the floor a slow object would brake at less than a, and a stop from v
 * must end within v^2/(2 a) + v T. */
static void scale_limits(const engine_t *e, double *A, double *J)
{
    double v, jerk = e->cfg.scale_jerk_m_s3;

    if (e->stop_req) {
        double floor = fmin(ENGINE_SCALE_V_FLOOR_M_S, e->cfg.scale_accel_m_s2 * e->period_s);
        jerk = stop_jerk(e);
        v = e->cspeed > floor ? e->cspeed : floor;
    } else {
        v = conv_speed(e);
    }
    *A = e->cfg.scale_accel_m_s2 / v;
    *J = jerk / v;
}

/* The rate the output is asked for, before the buffer's limit. */
static double scale_target(const engine_t *e)
{
    return e->stop_req || e->end_brake ? 0.0 : fmin(e->override, ceil_here(e));
}

/* 1 if the time scaling's next tick would set the output moving (tried on a
 * copy of its state): it advances and is not back at rest at the tick's end
 * (a tick that brakes back to rest within itself, or advances by less than
 * the track time's last bit, repeats for ever on a curve that cannot grow). */
static int moves(const engine_t *e, double R, double A, double J)
{
    ts_state_t ts = e->ts;
    int lim = 0;
    double ds = ts_step(&ts, scale_target(e), R, A, J, e->period_s, NULL, &lim);
    return e->s + ds > e->s && !(is_exactly(ts.rate, 0.0) && is_exactly(ts.acc, 0.0));
}

/* Scaled, at rate 0 at the start of cur (s = 0).  Every transfer and every
 * trajectory is entered at rate 0 and every transfer and REST end left at
 * rate 0: there the curve rests (k' = 0) with its own k'' != 0 (the
 * smoothstep's 6 D / T_x^2, a REST end's M), and the output's acceleration
 * k'' r^2 + k' dr/dt is 0 on both sides of the handover instead of stepping
 * by k'' (TIMESCALE.md, "Handovers"). */
static void scaled_rest(engine_t *e)
{
    e->scaled = 1;
    e->s = 0.0;
    e->ts.rate = 0.0;
    e->ts.acc = 0.0;
}

/* The output stands within ENGINE_HANDOVER_TOL_M of p. */
static int near_here(const engine_t *e, const double *p)
{
    double d2 = 0;
    for (int k = 0; k < AX; k++)
        d2 += (p[k] - e->pos[k]) * (p[k] - e->pos[k]);
    return d2 <= ENGINE_HANDOVER_TOL_M * ENGINE_HANDOVER_TOL_M;
}

/* At rest (rate 0) within the dead band of the end of a transfer or of a
 * trajectory's REST end (asked to move, the next tick could not: no move of
 * one tick would leave room to stop, ts_step's creep included): the curve is
 * as good as there.  A closed trajectory whose end is not at rest finishes
 * where it stands (finish_here, as its end braking does) (its speed
 * vanishes at the end, the position within k'' d^2 / 2 of it, d the track
 * time left): hand over from its end. */
static void rest_handover(engine_t *e)
{
    double A, J, target = scale_target(e), end[AX];
    ts_state_t probe = e->ts;

    if (!(target > 0))
        return; /* at rest by the override */
    scale_limits(e, &A, &J);
    (void)ts_step(&probe, target, remaining(e, e->s), A, J, e->period_s, NULL, NULL);
    if (probe.rate > 0)
        return; /* the next tick moves on (its advance from rest alone may be a
                 * rounding residue of 1e-22: not a move) */
    if (e->mode == OUT_XFER) {
        fdiff_eval(&e->cur.seg, 1.0, end, NULL, NULL);
        if (near_here(e, end))
            start_trajectory(e, 0);
        return;
    }
    if (e->mode != OUT_STREAM || !e->avail_closed)
        return; /* an underrun: resumes when waypoints come */
    const qent_t *h = NULL;
    for (size_t i = 0; i < e->qlen && !h; i++) {
        const qent_t *q = &e->q[(e->qhead + i) % e->qcap];
        if (q->traj != e->out_traj)
            break;
        if (q->kind == QE_END)
            h = q;
    }
    for (int k = 0; k < AX; k++)
        end[k] = h ? h->seg.c[k][0] : NAN;
    if (!e->avail_rest || !near_here(e, end)) {
        /* an end not at rest (as end_brake would), or one that the braking
         * cannot reach (the curve ahead too fast to stop on from any move):
         * finish where the output stands, never a jump */
        finish_here(e);
        return;
    }
    while (q_head(e)->kind == QE_SEG)
        q_pop(e);
    rest_at_end(e, q_head(e));
}

/* One tick on the unit grid (rate 1): the forward-difference stepper. */
static void unit_step(engine_t *e)
{
    if (e->mode == OUT_XFER) {
        int64_t n = e->n + 1;
        if (tau_of(e, n) >= e->cur_t1) {
            /* not reached: remaining() brakes the transfer to rate 0 before its
             * end; should it be, the trajectory is entered at rate 0 as well */
            scaled_rest(e);
            start_trajectory(e, 0); /* the transfer ends exactly on its start */
        } else {
            e->n = n;
            step_cur(e, n);
        }
        return;
    }
    int64_t n = e->n + 1;
    double tau = tau_of(e, n);
    if (tau < e->cur_t1) {
        e->n = n;
        step_cur(e, n);
        e->out_t = e->origin_t + tau;
        e->underrun = 0;
        return;
    }
    for (;;) {
        qent_t *h = q_head(e);
        if (h && h->traj != e->out_traj)
            h = NULL;
        if (!h) {
            /* the solved curve ended under a moving output: cannot happen
             * while remaining() is right (the scaling brakes before); hold
             * and go on scaled from rest */
            if (!e->underrun)
                count_underrun(e);
            e->underrun = 1;
            e->st.underrun_ticks++;
            e->st.hard_stops++;
            hold_here(e);
            e->scaled = 1;
            e->s = tau_of(e, e->n);
            e->ts.rate = 0.0;
            e->ts.acc = 0.0;
            return;
        }
        if (h->kind == QE_END) {
            rest_at_end(e, h);
            return;
        }
        take_segment(e);
        if (tau < e->cur_t1)
            break;
        /* shorter than a period: no tick falls in it */
    }
    e->n = n;
    e->seg_n0 = n;
    seed_cur(e, n);
    out_eval(e);
    e->out_t = e->origin_t + tau;
    e->underrun = 0;
}

static void scaled_advance(engine_t *e, double s1, double target, int lim);

/* One tick off the unit grid: the time scaling chooses the advance. */
static void scaled_step(engine_t *e, double target, double R, double A, double J)
{
    int lim = 0;
    double s = e->scaled ? e->s : tau_of(e, e->n), Rc = ceil_room(e, s, A, J);
    double ds = ts_step(&e->ts, target, fmin(R, Rc), A, J, e->period_s, NULL, &lim);

    /* held back by the speed cap ahead, not by the curve running short */
    scaled_advance(e, s + ds, target, lim && !(Rc < R));
}

/* Move the scaled output to track time s1 (relative to origin_t), through
 * the queued segments, and update the states that depend on it. */
static void scaled_advance(engine_t *e, double s1, double target, int lim)
{
    e->scaled = 1;
    e->n++;
    while (s1 >= e->cur_t1) {
        if (e->mode == OUT_XFER) {
            /* a transfer ends at rest, braked to rate 0 (remaining()) */
            s1 = e->cur_t1;
            e->ts.rate = e->ts.acc = 0.0;
            if (e->stop_req)
                break; /* stop on its end */
            start_trajectory(e, 0);
            if (e->mode != OUT_STREAM)
                return;
            s1 = 0.0;
            continue;
        }
        qent_t *h = q_head(e);
        if (h && h->traj == e->out_traj && h->kind == QE_END) {
            rest_at_end(e, h);
            return;
        }
        if (!h || h->traj != e->out_traj) {
            /* cannot happen while remaining() is right: see unit_step */
            s1 = e->cur_t1;
            if (e->ts.rate > 0)
                e->st.hard_stops++;
            e->ts.rate = e->ts.acc = 0.0;
            break;
        }
        take_segment(e);
    }
    e->s = s1;
    out_eval_scaled(e);
    e->out_t = e->origin_t + s1;

    if (lim && !e->stop_req && !e->avail_closed && e->mode == OUT_STREAM) {
        if (!e->underrun)
            count_underrun(e);
        e->underrun = 1;
    } else if (e->underrun && !lim && e->ts.rate >= target) {
        e->underrun = 0;
    }
    if (e->underrun)
        e->st.underrun_ticks++;

    if (at_rest(e)) {
        if (e->stop_req)
            stop_at_rest(e);
        else if (e->end_brake)
            finish_here(e);
        else
            rest_handover(e);
        return;
    }
    if (!e->clocked && is_exactly(e->ts.rate, 1.0) && is_exactly(e->ts.acc, 0.0) &&
        is_exactly(target, 1.0)) {
        /* back on a grid of whole periods, shifted by the time lost */
        e->s_off = e->s - tick_time(e, e->n);
        e->seg_n0 = e->n;
        seed_cur(e, e->n);
        e->scaled = 0;
    }
}

/*
 * One tick of a clocked trajectory (CLOCK.md): locked on the play time while
 * it advances by one tick and the curve ahead is long enough to stop in;
 * else the time scaling with the target rate + GAIN * lag, the lag's part
 * bounded by catchup above (a bounded catch-up) and by rest below.
 */
static void clocked_step(engine_t *e, double R, double A, double J)
{
    double s = e->scaled ? e->s : tau_of(e, e->n), p = play_rel(e), rho = e->clk_rate;
    double T = e->period_s;
    int free_run = !e->stop_req && !e->end_brake && e->override >= 1.0;

    double Rm = fmin(R, ceil_room(e, s, A, J));
    if (e->locked && free_run && fabs(p - s - rho * T) <= ENGINE_CLOCK_LOCK_S && p > s &&
        rho <= ceil_here(e) && (isinf(Rm) || ts_stop_dist(rho, 0.0, A, J) < Rm - rho * T)) {
        e->ts.rate = rho;
        e->ts.acc = 0.0;
        e->n++;
        scaled_advance(e, p, rho, 0);
        if (e->mode == OUT_STREAM)
            e->out_t = play_abs(e);
        return;
    }
    e->locked = 0;
    double target = 0.0;
    if (!e->stop_req && !e->end_brake) {
        /* the lag left after this tick if it ran at the clock's rate */
        double lead = ENGINE_CLOCK_GAIN * (p - s - rho * T);
        if (lead > e->clk_catchup)
            lead = e->clk_catchup;
        target = rho + lead;
        if (target < 0)
            target = 0;
        if (e->override < 1.0)
            target *= e->override;
        target = fmin(target, ceil_here(e));
    }
    scaled_step(e, target, R, A, J);
    if (e->mode == OUT_STREAM && free_run && fabs(p - e->s) <= ENGINE_CLOCK_LOCK_S &&
        fabs(e->ts.rate - rho) <= ENGINE_CLOCK_LOCK_S * ENGINE_CLOCK_GAIN + 1e-9)
        e->locked = 1;
}

/* One tick of the output state machine. */
static void step_once(engine_t *e)
{
    e->cycle++;
    if (e->mode == OUT_HOLD) {
        qent_t *h = q_head(e);
        if (!h || !h->first || !enough_ahead(e, h) || (!e->have_pos && e->need_pos)) {
            hold_here(e);
            return;
        }
        if (!e->have_pos) {
            /* no position known and none required: the start is the last resort */
            for (int k = 0; k < AX; k++)
                e->pos[k] = h->seg.c[k][0];
            e->out_t = h->seg.t0_s;
            e->have_pos = 1;
        }
        double d2 = 0;
        for (int k = 0; k < AX; k++)
            d2 += (h->seg.c[k][0] - e->pos[k]) * (h->seg.c[k][0] - e->pos[k]);
        int xfer = sqrt(d2) > ENGINE_TRANSFER_TOL_M;
        if (e->clocked) {
            /* one clock: not before the play time reaches the start, less
             * the transfer that leads there */
            double lead = 0.0, target[AX];
            int capped = 0;
            for (int k = 0; k < AX; k++)
                target[k] = h->seg.c[k][0];
            if (xfer)
                lead = xfer_duration(e, target, h->gap_s, &capped);
            if ((long double)e->play_ns * 1e-9L < (long double)h->seg.t0_s - lead) {
                hold_here(e);
                return;
            }
        }
        unit_reset(e);
        if (xfer) {
            double target[AX];
            for (int k = 0; k < AX; k++)
                target[k] = h->seg.c[k][0];
            start_transfer(e, target, h->gap_s);
            scaled_rest(e);
            e->n++;
            out_eval_scaled(e);
        } else {
            if (!e->clocked)
                scaled_rest(e);
            start_trajectory(e, 1);
        }
        return;
    }
    /* moving (a transfer or a trajectory): on the unit grid while nothing
     * asks for another rate and the curve ahead is long enough to stop in */
    double A, J, s = e->scaled ? e->s : tau_of(e, e->n), R;
    scale_limits(e, &A, &J);
    R = remaining(e, s);
    if (e->mode == OUT_STREAM && e->avail_closed && !e->avail_rest && !e->end_brake &&
        (ts_stop_dist(e->ts.rate, e->ts.acc, A, J) >= R - e->ts.rate * e->period_s ||
         (e->scaled && at_rest(e) && !moves(e, R, A, J))))
        /* the curve does not end at rest: brake before its end; at rest with
         * less curve left than one tick of motion and its stop need, no input
         * can come to lengthen it: finish here, not wait for ever */
        e->end_brake = 1;
    if (e->clocked && e->mode == OUT_STREAM) {
        clocked_step(e, R, A, J);
        return;
    }
    double target = scale_target(e);
    /* start_slack auto: an output stopped by an underrun resumes once it is
     * as far behind the newest waypoint as at the start (enough_ahead) */
    if (e->slack_auto && e->underrun && e->mode == OUT_STREAM && !(e->ts.rate > 0) && target > 0 &&
        rebuffering(e, s)) {
        scaled_step(e, 0.0, R, A, J);
        if (!e->underrun) { /* still in the same underrun */
            e->underrun = 1;
            e->st.underrun_ticks++;
        }
        return;
    }
    double Rm = fmin(R, ceil_room(e, s, A, J)); /* the speed cap ahead too */
    if (!e->scaled && is_exactly(target, 1.0) &&
        (isinf(Rm) || ts_stop_dist(1.0, 0.0, A, J) < Rm - e->period_s)) {
        unit_step(e);
        return;
    }
    scaled_step(e, target, R, A, J);
}

static engine_state_t out_state(const engine_t *e)
{
    if (e->mode == OUT_STREAM)
        return e->underrun ? ENGINE_STATE_UNDERRUN : ENGINE_STATE_STREAMING;
    if (e->mode == OUT_XFER)
        return ENGINE_STATE_STREAMING;
    if (e->in_open || e->qlen || accept_pending(&e->policy))
        return ENGINE_STATE_WAITING;
    return e->finished ? ENGINE_STATE_FINISHED : ENGINE_STATE_WAITING;
}

/* A transfer's track time: from where the output's time stood when it began
 * to the start of the trajectory it joins, in proportion to the transfer
 * done (from that start less the transfer's duration if the output had no
 * time before), so t_s and the data age say what the object does and reach
 * that start as it does. */
static void xfer_track_time(engine_t *e)
{
    const qent_t *h = e->qlen ? &e->q[e->qhead] : NULL; /* q_head, read only */
    if (!h || !(e->cur_t1 > 0))
        return;
    double t = e->scaled ? e->s : tau_of(e, e->n), u = t / e->cur_t1;
    double to = h->kind == QE_END ? h->t1_s : h->seg.t0_s;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    if (isnan(e->xfer_from_t))
        e->out_t = to - (1.0 - u) * e->cur_t1;
    else
        e->out_t = e->xfer_from_t + (to - e->xfer_from_t) * u;
}

static void fill_sp(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    engine_state_t s = out_state(e);

    sp->now_ns = now_ns;
    /* No position known yet: the first waypoint is the last resort (unless a
     * position is required), adopted once and for all, so the output never
     * jumps from it to somewhere else (a new start is reached by a transfer). */
    if (!e->have_pos && e->mode == OUT_HOLD && !e->need_pos) {
        qent_t *h = q_head(e);
        if (h)
            for (int k = 0; k < AX; k++)
                e->pos[k] = h->seg.c[k][0];
        else if (e->in_open && e->nodes)
            memcpy(e->pos, nr(e, 0), sizeof(e->pos));
        else if (e->in_open) /* SMOOTH: no node yet, the first waypoint as received */
            memcpy(e->pos, e->first_r, sizeof(e->pos));
        if (h)
            e->out_t = h->seg.t0_s;
        else if (e->in_open && e->nodes)
            e->out_t = nt(e, 0);
        if (h || e->in_open)
            e->have_pos = 1;
    }
    if (e->mode == OUT_XFER)
        xfer_track_time(e);
    sp->t_s = e->out_t;
    memcpy(sp->pos_m, e->pos, sizeof(sp->pos_m));
    if (!e->have_pos)
        for (int k = 0; k < AX; k++)
            sp->pos_m[k] = NAN; /* not a position: see ENGINE_SP_NO_POSITION */
    memcpy(sp->vel_m_s, e->vel, sizeof(sp->vel_m_s));
    memcpy(sp->acc_m_s2, e->acc, sizeof(sp->acc_m_s2));
    sp->state = s;
    sp->flags = e->flags_pending;
    e->flags_pending = 0;
    if (e->mode == OUT_HOLD || (e->scaled && at_rest(e)))
        sp->flags |= ENGINE_SP_HOLD;
    else if (s != ENGINE_STATE_STREAMING && s != ENGINE_STATE_UNDERRUN)
        sp->flags |= ENGINE_SP_HOLD;
    if (e->mode == OUT_XFER)
        sp->flags |= ENGINE_SP_TRANSFER;
    if (!e->have_pos)
        sp->flags |= ENGINE_SP_NO_POSITION;
    if (e->mode != OUT_HOLD && e->scaled)
        sp->flags |= ENGINE_SP_SCALED;
    sp->cycle = e->cycle;
    sp->track = e->out_track;
    sp->age_s = NAN;
    if (e->clocked && e->have_pos)
        sp->age_s = (double)((long double)e->clk_now_ns * 1e-9L - (long double)e->out_t);
}

/* 1 if further steps cannot change anything until new input arrives. */
static int stalled(const engine_t *e)
{
    const qent_t *h = e->qlen ? &e->q[e->qhead] : NULL; /* q_head, read only */

    if (e->mode == OUT_HOLD)
        return !h || !h->first || !enough_ahead(e, h);
    if (e->mode == OUT_STREAM && e->scaled && at_rest(e) && !e->stop_req && !e->end_brake) {
        double A, J, target = scale_target(e);
        if (!(target > 0))
            return 1;
        scale_limits(e, &A, &J);
        return ts_rate_max(remaining(e, e->s), A, J) < ts_dead_band(J, e->period_s);
    }
    return 0;
}

/*
 * Fast ticks.  Most ticks are a plain step on the unit grid inside the
 * current segment: step_once then only re-derives, every tick, that nothing
 * asks for another rate (two divisions, the stopping distance ts_stop_dist
 * against the buffer's remaining time) and engine_tick divides for the
 * number of periods.  fast_window decides once, after a full tick, for how
 * many ticks ahead that answer cannot change: until the next re-seed, and
 * while the stopping distance stays short of the remaining capacity
 * (remaining()) with two ticks to spare, at the segment's lower bound on the
 * curve's speed (seg_speed_max): the check each of those ticks would make
 * passes at any speed above it (see fast_window).  Every public call that
 * changes the engine (push, finish, stop, clear, override, clock, position)
 * closes the window.
 * fast_tick then does what the full path does for such a tick, to the same
 * doubles in the same order: tests/unit/test_engine_fast.c compares both
 * paths setpoint for setpoint (engine_set_fast_ticks).
 */
static void fast_window(engine_t *e)
{
    e->fast_left = 0;
    if (e->fast_off || e->mode != OUT_STREAM || e->scaled || e->clocked || e->underrun ||
        !e->have_pos || e->stop_req || e->end_brake || e->flags_pending ||
        !is_exactly(e->override, 1.0) || !is_exactly(e->ts.rate, 1.0) ||
        !is_exactly(e->ts.acc, 0.0) || ceil_here(e) < 1.0)
        return;
    /* the ticks before the next re-seed (step_cur) */
    int64_t m = (int64_t)(FDIFF_RESEED_STEPS - (uint64_t)(e->n - e->seg_n0) % FDIFF_RESEED_STEPS) -
                1;
    { /* remaining() is finite: a REST end too is left at rate 0 */
        /* step_once's check, ts_stop_dist(1, 0, a/v, j/v) < v K - (margin + 1) T
         * with v = conv_speed (the same on every tick of the window: a push
         * closes it) and K the capacity left (remaining()) */
        double v = conv_speed(e);

        double A = e->cfg.scale_accel_m_s2 / v, J = e->cfg.scale_jerk_m_s3 / v;
        double d = ts_stop_dist(1.0, 0.0, A, J) * (1 + 1e-9);
        double in_cur = e->cur_t1 - tau_of(e, e->n);
        double k = (in_cur > 0 ? in_cur / v : 0.0) + (e->avail_kcum - e->cur.kcum);
        /* K falls by T / v per tick: the ticks for which it stays above */
        double room = (k - (d + rise_reserve(e, v) + (TS_MARGIN_TICKS + 1) * e->period_s) / v) * v;
        /* and the speed cap ahead (ceil_room), which falls by T per tick too */
        room = fmin(room, ceil_room(e, tau_of(e, e->n), A, J) - d - e->period_s);
        if (!(room > 0) || !isfinite(d))
            return;
        double mr = floor(room / e->period_s) - 2;
        if (mr < (double)m)
            m = (int64_t)mr;
    }
    e->fast_left = m > 0 ? m : 0;
}

/* One tick as step_once + fill_sp would make it inside the window; 0 (and
 * nothing changed) at the end of the segment. */
static void fast_fill_from(const engine_t *e, int64_t now_ns, engine_setpoint_t *sp,
                           const double *pos, const double *vel, const double *acc)
{
    sp->now_ns = now_ns; /* fill_sp: streaming, no flags */
    sp->t_s = e->out_t;
    memcpy(sp->pos_m, pos, sizeof(sp->pos_m));
    memcpy(sp->vel_m_s, vel, sizeof(sp->vel_m_s));
    memcpy(sp->acc_m_s2, acc, sizeof(sp->acc_m_s2));
    sp->state = ENGINE_STATE_STREAMING;
    sp->flags = 0;
    sp->cycle = e->cycle;
    sp->track = e->out_track;
    sp->age_s = NAN;
}

/* What a fast tick left for later: the setpoint kept for a repeated call
 * (last_sp, 120 bytes copied every tick otherwise) and the curve's speed
 * (a square root only the full path reads), both from the same doubles. */
static void fast_sync(engine_t *e)
{
    if (!e->fast_last)
        return;
    for (int k = 0; k < AX; k++) { /* out_eval, deferred by fast_tick */
        e->pos[k] = e->fd.p0[k];
        e->vel[k] = e->fd.v0[k];
        e->acc[k] = e->fd.a0[k];
    }
    double v2 = 0;
    for (int k = 0; k < AX; k++) /* as out_eval */
        v2 += e->vel[k] * e->vel[k];
    e->cspeed = sqrt(v2);
    fast_fill_from(e, e->last_now, &e->last_sp, e->pos, e->vel, e->acc);
    e->fast_last = 0;
}

/*
 * One tick as step_once + fill_sp would make it inside the window; 0 (and
 * nothing changed) at the end of the segment.  What is left per setpoint
 * (gcc -O2, x86-64 baseline SSE2): the tick's time (an integer multiply and
 * two floating additions), one compare with the segment's end, the step as
 * 12 packed addpd over the fdiff_t rows, and 18 stores of the 9 doubles into
 * the engine and the setpoint; the full path added two divisions and
 * ts_stop_dist's branches (step_once), a 64-bit idiv (engine_tick's count of
 * periods), out_state/fill_sp's flag logic, a sqrt and a 120-byte copy.
 */
static int fast_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    int64_t n = e->n + 1;
    double tau = tau_of(e, n);
    if (!(tau < e->cur_t1)) {
        e->fast_left = 0;
        return 0;
    }
    e->fast_left--;
    e->fast_last = 1;
    e->cycle++;
    e->n = n;
    e->last_now = now_ns;
    fdiff_step(&e->fd);
    /* out_eval's copies into e->pos, vel, acc wait for fast_sync: the
     * setpoint is filled from the stepper itself (9 stores a tick fewer) */
    e->out_t = e->origin_t + tau;
    fast_fill_from(e, now_ns, sp, e->fd.p0, e->fd.v0, e->fd.a0);
    e->st.setpoints++;
    return 1;
}

void engine_fast_close(engine_t *e)
{
    e->fast_left = 0;
    fast_sync(e);
}

void engine_set_fast_ticks(engine_t *e, int on)
{
    engine_fast_close(e);
    e->fast_off = !on;
}

static int tick_full(engine_t *e, int64_t now_ns, engine_setpoint_t *sp);

/*
 * The fast tick stays out of the full tick's frame: with both in one
 * function the compiler saved six registers and set up a 200-byte frame
 * (push x6, sub $0xc8,%rsp at the entry of engine_tick, objdump -d) before
 * the fast path's first test; apart, a fast tick is a leaf-like run of
 * loads, one imul, cvtsi2sd, mulsd, the step's addpd and the setpoint's
 * stores: 9.5 -> 7.9 ns per setpoint at 1 kHz with the copies fast_sync now
 * defers (the fastest chunk of 10000 ticks, tests/bench/RESULTS.md).
 */
int engine_tick(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    if (e->fast_left > 0) {
        /* one period since the last call, as the division below would round */
        int64_t d = now_ns - e->last_now, p = e->cfg.period_ns;
        if (d >= p - p / 2 && d < 2 * p - p / 2 && fast_tick(e, now_ns, sp))
            return positive_zeros(sp, 0);
        e->fast_left = 0;
    }
    return positive_zeros(sp, tick_full(e, now_ns, sp));
}

__attribute__((noinline)) static int tick_full(engine_t *e, int64_t now_ns, engine_setpoint_t *sp)
{
    int64_t k = 1, i;

    fast_sync(e);
    if (e->have_now) {
        if (now_ns < e->last_now) {
            *sp = e->last_sp;
            return -ENGINE_ESTATE;
        }
        /* ticks on the period grid since the last call (rounded) */
        k = (now_ns - e->last_now + e->cfg.period_ns / 2) / e->cfg.period_ns;
        if (k == 0) {
            *sp = e->last_sp;
            sp->now_ns = now_ns;
            e->st.setpoints++;
            return 0;
        }
    }
    e->have_now = 1;
    e->last_now = now_ns;
    for (i = 0; i < k; i++) {
        if (e->clocked) /* the play time of each step, the last one's given */
            e->play_ns = e->clk_now_ns - e->clk_delay_ns -
                         (int64_t)llround((double)(k - 1 - i) * e->clk_rate *
                                          (double)e->cfg.period_ns);
        step_once(e);
        if (i + 1 < k && stalled(e)) {
            /* Nothing can change before the next push: the remaining steps
             * are identical holds.  Count them instead of looping (a clock
             * jump of hours must not cost hours of steps). */
            int64_t rest = k - 1 - i;
            e->cycle += (uint32_t)rest;
            if (e->mode != OUT_HOLD && e->scaled)
                e->n += rest; /* as each scaled step at rest would (the grid of s_off) */
            if (e->mode == OUT_STREAM && e->underrun)
                e->st.underrun_ticks += (uint64_t)rest;
            break;
        }
    }
    if (k > 1) {
        e->st.skipped_ticks += (uint64_t)(k - 1);
        e->flags_pending |= ENGINE_SP_SKIPPED;
    }
    fill_sp(e, now_ns, sp);
    e->st.setpoints++;
    e->last_sp = *sp;
    fast_window(e);
    return 0;
}

void engine_status(const engine_t *e, engine_status_t *st)
{
    size_t b = buffered(e);

    *st = e->st;
    st->state = out_state(e);
    st->buffered = (uint32_t)b;
    st->free = b >= e->cfg.capacity ? 0 : (uint32_t)(e->cfg.capacity - b);
    st->lookahead = e->lookahead + e->slack_learn;
    st->stalled = (uint32_t)stalled(e);
    st->rate = e->mode == OUT_HOLD ? 0.0 : e->ts.rate;
    st->override = e->override;
    st->judging = accept_pending(&e->policy);
    st->ahead_s = 0;
    if (e->qlen) {
        const qent_t *tail = &e->q[(e->qhead + e->qlen - 1) % e->qcap];
        double ahead = tail->t1_s - e->out_t;
        st->ahead_s = ahead > 0 ? ahead : 0;
    }
}

/* ---- offline ------------------------------------------------------------- */

int engine_curve(const engine_config_t *cfg, const engine_waypoint_t *wp, size_t n,
                 fdiff_seg_t *seg, size_t max_seg, size_t *nseg)
{
    int err = 0, rc = 0;
    engine_t *e = engine_new(cfg, &err);
    size_t i, out = 0;

    *nseg = 0;
    if (!e)
        return -err;
    for (i = 0; i <= n; i++) {
        if (i < n) {
            rc = engine_push(e, &wp[i]);
            if (rc == -ENGINE_EFULL) {
                rc = -ENGINE_ENUMERIC; /* cannot happen: the queue is drained below */
                break;
            }
        } else {
            engine_finish(e);
        }
        while (e->qlen) {
            qent_t *h = q_head(e);
            if (h->kind == QE_SEG) {
                if (out == max_seg) {
                    rc = -ENGINE_ECONFIG;
                    goto out;
                }
                seg[out++] = h->seg;
            }
            q_pop(e);
        }
    }
    rc = 0;
out:
    *nseg = out;
    engine_free(e);
    return rc;
}
