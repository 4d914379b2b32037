/*
 * engine_int.h - the engine's state, shared by the files that make up the
 * engine, one per stage (engine.c says which owns what): engine_settings.c
 * (configuration), engine_input.c (input and acceptance), engine_solve.c
 * (solver, fragments, the queue), engine_tick.c (play-out; its trajectory
 * boundaries in engine_play.c), engine_scale.c
 * (its time scaling), engine_xfer.c (transfers), engine_cmd.c (the commands
 * the lifecycle owner gives it, lifecycle.h), delay_run.c (the delay D
 * stated, delay.h), silence.c (silent ends, silence.h); engine.c creates an
 * engine.
 * Not part of the client API: only the engine's own files in lib/engine
 * include it.
 */
#ifndef TRAJD_ENGINE_INT_H
#define TRAJD_ENGINE_INT_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "accept.h"
#include "delay.h"
#include "engine.h"
#include "fdiff.h"
#include "frag.h"
#include "repeat.h"
#include "lsq.h"
#include "timescale.h"
#include "transfer.h"

#define AX ENGINE_AXES

/* Intervals of the input kept for the interval D grows to (delay.h
 * engine_delay_grow): its upper quartile, where a hole of a few lost fixes is
 * an outlier and a sender that slows down is not. */
#define ENGINE_IV_RING 64
/* The interval D grows to (delay_run.c): of the n intervals of a ring of
 * ENGINE_IV_RING written up to next (exclusive), the longest time of w in a
 * row, each with its longest interval taken as the median of the n instead,
 * over w; 0 with fewer than w. */
double engine_interval_robust(const double *iv, unsigned n, unsigned next, unsigned w);
double engine_interval_holes(const double *iv, unsigned n, unsigned next, unsigned w);
/* delay_s set: the waypoints the input's interval and speed are read from
 * before the lookahead is picked (engine_pick) */
#define ENGINE_PICK_N 3

enum { QE_SEG = 0, QE_END = 1 };

/* One queued entry: a segment to stream, or the rest point ending a trajectory. */
typedef struct {
    int kind;
    int first;       /* first entry of its trajectory */
    double t1_s;     /* segment end (absolute track time); END: rest time */
    uint64_t node;   /* SEG: index of its first node in the trajectory */
    uint64_t traj;   /* input trajectory it belongs to (engine.solve.traj) */
    fdiff_seg_t seg; /* END: c[k][0] is the rest position, t0_s = t1_s */
    double gap_s;    /* first entry: track time since the previous trajectory's
                             end when a gap separates them, else 0 */
    double vmax;     /* SEG: bound on the curve's speed |k'| over it (m/s) */
    double av;       /* SEG: the speed (m/s) at which the time scaling's
                        acceleration limit is converted on it, A = a / av:
                        max(vmax, floor), or below it where per-axis
                        acceleration limits leave the scaling more room
                        (engine_solve.c accel_speed; the jerk is converted at
                        max(vmax, floor) always) */
    double kcum;     /* SEG: braking capacity of its trajectory up to its end,
                        the sum of dur / av (see scale_remaining()) */
    double ucum;     /* SEG: the rises of 1 / av from each segment of its
                        trajectory to the next, each times the next one's
                        max(vmax, floor) / av, summed up to it
                        (scale_rise_reserve) */
    double ceil;     /* SEG: the highest rate at which it keeps the speed cap
                        (ENGINE_SPEED_CAP; INFINITY if none) */
    int ceil_axis;   /* SEG: ceil is the per-axis limits' and below 1 (issue 32) */
    int ceil_own;    /* SEG: ceil is the object's own speed or acceleration limit's
                        (max_speed_m_s, max_accel_m_s2) and below 1, not ceil_axis */
    double stop1;    /* SEG: ts_stop_dist(1, 0, A, J) at the limits converted at
                        its conv_speed (plain_window) */
    int join;        /* SEG: a piece of a join that keeps moving (join.c) */
    double shift;    /* SEG: added to the output's origin_t when it is taken: the
                        curve a join met, where the join took longer than the
                        track time it covered (join.c; 0 otherwise) */
} qent_t;

/* A built segment's own limits (engine_solve.c seg_limits): qent_t's vmax,
 * ceil, ceil_axis, and av before the next segment's is taken in. */
typedef struct {
    double vmax, ceil, av;
    int axis;
} seg_limits_t;

/* Output and curve start closer than this need no transfer (metres). */
#define ENGINE_TRANSFER_TOL_M 1e-9

/* Below this speed (m/s) the curve's end counts as at rest. */
#define ENGINE_REST_SPEED_M_S 1e-6
/* The time scaling's limits are converted to rate units at the curve's speed,
 * but never at less than this (m/s): where the curve stands nearly still the
 * rate may change fast, but not without bound (TIMESCALE.md). */
#define ENGINE_SCALE_V_FLOOR_M_S 1.0

/* The lowest speed cap rate: below the time scaling's dead band (at most
 * TS_DEAD_BAND_MAX) the output would never leave rest before such a segment. */
#define ENGINE_CEIL_MIN 0.01

enum { OUT_HOLD = 0, OUT_XFER = 1, OUT_STREAM = 2 };
enum { STOP_NONE = 0, STOP_STOP = 1, STOP_CLEAR = 2 };

/* ---- input and acceptance (engine_input.c): the trajectory being received ---- */
typedef struct {
    int open;           /* a trajectory is being received */
    double first_r[AX]; /* its first waypoint */
    double last_t;      /* its last accepted waypoint */
    double last_r[AX];
    int have_prev; /* prev_t/prev_r hold the waypoint before last (same trajectory) */
    double prev_t; /* for the acceleration check */
    double prev_r[AX];
    double gap_s;         /* gap before the trajectory being received (0: none) */
    engine_repeat_t full; /* the waypoint st.full counted last (repeat.h) */
    accept_t policy;
    engine_rejection_t rej[ENGINE_REJECTIONS_KEPT];
    unsigned rej_head, rej_len;
} engine_input_t;

/* ---- solver (engine_solve.c): nodes, fragments, segments queued ---- */
typedef struct {
    uint64_t nodes;         /* nodes of the current trajectory (copies included) */
    uint64_t seg_next;      /* next segment index to build */
    size_t ring;            /* nodes kept */
    double *node_t;         /* ring */
    double *node_r;         /* ring x AX */
    double *node_v;         /* local methods: ring x AX, each node's velocity ... */
    double *node_a;         /* ... and (C2) acceleration ... */
    unsigned char *node_vk; /* ... ring: 0 none yet, 1 the source's, 2 computed */
    frag_t *fw;
    lsq_smooth_t sm; /* SMOOTH: the smoother the waypoints pass first */
    double *sm_mem;
    int emitted;       /* a segment of this trajectory was queued */
    int first_pending; /* the next queued entry is the trajectory's first */
    double end_r[AX];  /* end of the last queued segment */
    double end_t;
    double end_speed;      /* speed at the end of the last queued segment */
    double end_v[AX];      /* its velocity (m/s): the next segment starts with it */
    double kcum;           /* capacity queued so far of the trajectory (qent_t kcum) */
    double inv;            /* 1 / av of its last queued segment */
    double ucum;           /* qent_t ucum so far */
    int queued;            /* a segment of this trajectory was queued */
    int pend;              /* with per-axis acceleration limits, the newest segment
                                  built waits here until the next one is (its av takes
                                  the next one's into account: queue_segment) */
    uint64_t pend_node;    /* ... its first node */
    fdiff_seg_t pend_seg;  /* ... the segment */
    seg_limits_t pend_lim; /* ... and its limits */
    uint64_t traj;         /* +1 per trajectory opened */
    struct {               /* local backward methods: the last segment's queueing,
                                  taken back at the close to build it again with the
                                  trajectory's end condition (engine_solve.c local_end) */
        int valid;         /* the fields below are those before node's segment */
        uint64_t node;     /* its first node */
        int given;         /* its far node's velocity is the source's */
        int first_pending, queued;
        double kcum, ucum, inv;
    } tail;
    double span_max;           /* start_slack auto: longest time spanned by la_steady + 1
                         intervals of the input, decaying by 1/256 per node */
    double vmax_in;            /* start_slack auto: fastest chord speed of the input,
                         decaying the same way */
    double iv[ENGINE_IV_RING]; /* the input's last intervals (engine_delay_grow) */
    unsigned iv_n, iv_next;
} engine_solve_t;

/* ---- the queue of finished segments: the solver fills it, the play-out
 * takes from it (engine_solve.c) ---- */
typedef struct {
    qent_t *ent;
    size_t cap, head, len;
    size_t ends;  /* END entries in the queue */
    size_t *slow; /* ring (cap): the queue slots, in queue order, of the
                          segments whose speed cap holds the rate below TS_RATE_MAX */
    size_t slow_head, slow_len;
    size_t beyond; /* queued segments of ceiling 0 (beyond the per-axis
                      limits: seg_ceiling), of any trajectory */
} engine_queue_t;

/* ---- play-out (engine_tick.c): the output ---- */
typedef struct {
    int mode;                          /* OUT_* */
    double join_t0, join_tm, join_dur; /* the join under way (cur.join): its start
                                          and meeting track times, its duration */
    uint64_t join_refused;             /* traj + 1 of a trajectory whose end joins the next
                              one by the stop and transfer, not moving (join.c) */
    int have_pos; /* the output stands somewhere real: set by engine_set_position,
                     or the first waypoint adopted as the last resort.  From then on
                     the output only moves by streaming or by a transfer */
    int need_pos; /* engine_require_position: no first-waypoint fallback */
    int finished; /* the last trajectory ran to its end */
    int underrun;
    int reserve_slow;      /* issue 26: slowed, on data that came on time, for a stop reserve
                         longer than the output stood at (catchup.h engine_lag_ahead):
                         counted in reserve_slowed, not an underrun */
    uint64_t traj;         /* trajectory the output streams */
    qent_t cur;            /* segment (or transfer) being stepped */
    double cur_t0, cur_t1; /* its start and end relative to origin_t */
    fdiff_t fd;
    int64_t n;       /* ticks since origin_t */
    int64_t seg_n0;  /* tick at which cur was seeded */
    double origin_t; /* absolute track time of tick 0 of the trajectory */
    /* The output's position, velocity and acceleration: on the unit grid
     * (on_fd, out_eval) they are the stepper's values (fd.f), copied
     * here only when something needs them here (out_sync: a hold keeps the
     * position); else (scaled, held) here.  Read them through out_pos,
     * out_vel, out_acc; whoever writes them here clears on_fd. */
    double pos[AX], vel[AX], acc[AX];
    int on_fd;
    /* The rate decision of step_once kept for the ticks ahead (plain_window,
     * engine_tick.c): the steps from a tick n below plain_last are plain
     * unit-grid steps while the key below still matches the engine
     * (plain_holds).  seg_last is the last tick on the grid inside cur
     * (tau_of(seg_last) < cur_t1); the kept steps from a tick n below
     * kept_last, the lesser of the two, stay inside cur (engine_tick makes
     * them itself), and those from below fast_last besides are no re-seed
     * (nor checked by the test hook) and follow a plain setpoint (on_fd, no
     * underrun, last_plain: fill_sp_flags closes it): plain_tick */
    int64_t plain_last, seg_last, kept_last, fast_last;
    /* the stepper's f held a -0.0 at the last plain setpoint (fill_plain,
     * made at every seed and re-seed of a kept or plain step): plain_tick,
     * which stores f's sums without put_sp's + 0.0, is not taken (fill_plain
     * closes fast_last, fast_bound keeps it closed) until one without.  A
     * step adds d1 to f, and a sum is -0.0 only where both terms are: an f
     * with none keeps none */
    int f_negz;
    size_t plain_qlen;                /* key: queue.len then */
    int64_t plain_seen;               /* key: lag.seen_ns then (a push since: a new sample) */
    int plain_check;                  /* test hook (engine_plain_check) */
    uint64_t plain_kept, plain_wrong; /* test hook: kept ticks, and those wrong */
    double t;                         /* track time of the output */
    uint32_t track;
    uint32_t cycle;
    uint32_t flags_pending;
    int have_now;
    int64_t last_now;
    /* the setpoint of the last call that stepped, for a call at the same
     * time or before: a plain one (streaming on the unit grid, no flags) is
     * rebuilt from the stepper (last_setpoint), any other kept here */
    int last_plain;
    engine_setpoint_t last_sp;
    /* the underrun under way began with the newest waypoint at und_t of the
     * input trajectory und_traj (silence.h).  While the input's silence may
     * still turn out to be its end (engine_silence_pending) it is counted
     * only once a newer waypoint comes (und_pending): a silent end with
     * nothing newer is the input's end, not a late waypoint
     * (engine_silence_tick), and a counter never goes back */
    double und_t;
    uint64_t und_traj;
    int und_pending;
} engine_out_t;

/* ---- time scaling of the play-out (engine_scale.c, timescale.h, TIMESCALE.md) ---- */
typedef struct {
    ts_state_t ts;     /* rate ds/dt and its derivative */
    double stop_dv;    /* this tick: the rate it may stop from within the limits (A T) */
    int on;            /* off the unit grid: the output's track time is s */
    double s;          /* on: track time of the output, relative to origin_t */
    double s_off;      /* unit grid: track time = tick_time(n) + s_off */
    double cspeed;     /* |k'(s)|: the curve's own speed at the output */
    double override;   /* feed override 0 .. 2 */
    int stop_req;      /* STOP_*: braking to rest, then drop */
    size_t drop_n;     /* queue entries to drop once at rest */
    double avail_t;    /* end of the output trajectory's solved curve (absolute track time) */
    double avail_kcum; /* braking capacity up to there (qent_t kcum) */
    double avail_ucum; /* ... and the rises of the limits (qent_t ucum) */
    int avail_closed;  /* its END is queued */
    int avail_rest;    /* ... and the curve ends at rest there */
    int end_brake;     /* braking to rest before an end that is not at rest */
} engine_scale_t;

/* ---- transfers (engine_xfer.c, transfer.h) ---- */
typedef struct {
    transfer_config_t cfg;
    transfer_motion_t motion; /* the object's recent motion (noted by the input) */
    double from_t;            /* out.t when the transfer under way began (NAN: none before) */
    int lead;                 /* the transfer under way, or the rest after it, leads to
                                 the start of a trajectory not due yet (xfer_lead_target) */
    double to_t;              /* ... that start's track time */
} engine_xfer_t;

/* ---- one clock (engine_set_clock, CLOCK.md; engine_scale.c) ---- */
typedef struct {
    int on;           /* the output follows the caller's clock */
    int locked;       /* its track time is exactly the play time */
    int64_t now_ns;   /* now on the sender's time base (last call) */
    int64_t delay_ns; /* play-out delay D */
    double rate;      /* d now / dt */
    double catchup;   /* most the rate rises above rate */
    int64_t play_ns;  /* now - D at the step being made */
} engine_clk_t;

/* ---- the play-out delay D stated (delay_run.c, delay.h; issue 26) ---- */
typedef struct {
    engine_delay_t d; /* D at the last start of an output */
    int noted;        /* d holds one */
    unsigned learnt;  /* slack_learn then (start_slack auto) */
} engine_delay_state_t;

/* ---- silent ends of the input (silence.c, silence.h; issue 26) ---- */
typedef struct {
    int arrived;        /* arrival_ns holds the newest waypoint's arrival */
    int64_t arrival_ns; /* the first tick time after its push */
    int fresh;          /* pushed since the last tick */
    int closed;         /* the input trajectory was closed by a silence */
    uint64_t traj;      /* the trajectory the fields below measure (solve.traj) */
    uint64_t n;         /* its waypoints pushed */
    double last_t;      /* its newest waypoint time */
    double int_max;     /* its longest interval */
} engine_silence_t;

/* ---- the lag won back (catchup.c, catchup.h; issue 26) ---- */
typedef struct {
    int pending;       /* waypoints pushed since the last tick: */
    double pend_max;   /* ... their newest stamp */
    double pend_min;   /* ... and their oldest */
    uint64_t traj;     /* the input trajectory sampled (solve.traj) */
    int have;          /* off_s holds a sample of traj */
    double off_s;      /* the sender's time less ours, least-delayed arrival */
    int64_t off_at_ns; /* when that sample came */
    int64_t seen_ns;   /* the last tick that brought a sample */
    double off_first;  /* the trajectory's first sample */
    int64_t first_ns;  /* ... and when it came */
    int ahead;         /* the trajectory's stamps came ahead of time (an upload) */
    int steer;         /* winning back (or giving back) a lag */
    double jit_s;      /* the latest an arrival came after the least-delayed sample said
                          (beyond a period: catchup.h), over the object's life */
} engine_lag_t;

struct engine {
    /* ---- configuration (engine_settings.c) and what it implies ---- */
    engine_config_t cfg; /* resolved: fragment and overlap never ENGINE_AUTO */
    unsigned lookahead;
    unsigned la_steady;      /* what the solver needs far from the start (steady_lookahead) */
    int slack_auto;          /* start_slack auto (engine.h) */
    unsigned slack_learn;    /* start_slack auto: one more per underrun seen */
    unsigned slack_more;     /* start_slack auto: the most it adds to lookahead
                             (ENGINE_SLACK_AUTO_MAX - MIN, less if capacity is short) */
    int pstar;               /* unknowns are Hoang control points (BSPLINE + UNIFORM) */
    int held;                /* HELD or MULTIPLE: first and last segments not emitted */
    int mult;                /* MULTIPLE: end points entered three times */
    int smooth;              /* SMOOTH: waypoints pass through the lsq smoother first */
    int axis_lim;            /* issue 32: a per-axis limit is set (solve_axis_limited) */
    int axis_jerk;           /* ... a per-axis jerk limit (engine_cfg_axis_jerk) */
    int axis_accel;          /* ... a per-axis acceleration limit (solve_cfg_axis_accel) */
    uint32_t axis_lag_track; /* issue 32: the output track axis_lag_s counts for ... */
    int axis_lag_over;       /* ... and its max_lag_s passed, not yet told */
    int axis_lag_told;       /* ... and told (once per trajectory) */
    int axis_episode;        /* the per-axis limits hold the rate below 1 */
    int own_episode;         /* the object's own speed/acceleration limits hold it */
    int local;               /* local method (engine_cfg_local): 1, 3 backward, 2, 4 centred;
                             3, 4 C2 (three queued pieces per interval) */
    double period_s;
    int64_t period_lo; /* cfg.period_ns - cfg.period_ns / 2: the least time since
                          the last tick that rounds to one period (engine_tick) */

    engine_input_t in;
    engine_solve_t solve;
    engine_xfer_t xfer;
    engine_clk_t clk;
    engine_queue_t queue;
    engine_out_t out;
    engine_scale_t scale;
    engine_delay_state_t delay;
    engine_silence_t sil;
    engine_lag_t lag;
    struct {                   /* delay_s picks the lookahead (engine_input.c engine_pick) */
        int pending;           /* the first waypoints are held for it */
        unsigned n;            /* held */
        int64_t first_ns;      /* the tick time the first of them came by */
        engine_config_t asked; /* the caller's configuration, unresolved */
        engine_waypoint_t wp[ENGINE_PICK_N];
    } pick;

    engine_status_t st;
};

/* No underrun yet: its record NaN (engine_status_t underrun_*). */
static inline void engine_status_underrun_none(engine_status_t *st)
{
    st->underrun_t_s = st->underrun_newest_t_s = st->underrun_next_t_s = NAN;
    st->underrun_slack_s = st->underrun_curve_t_s = st->underrun_lookahead_s = NAN;
    st->underrun_silence_s = st->underrun_judging_t_s = NAN;
    st->underrun_judging = 0;
}

/* ---- configuration (engine_settings.c): what a resolved one implies ---- */

/* engine_lookahead of a resolved configuration */
unsigned engine_cfg_lookahead(const engine_config_t *cfg);
/* engine_config_check, and where it passes the configuration resolved
 * (engine_config_resolve) into *out: one resolution, not two */
int engine_config_check_resolve(const engine_config_t *cfg_in, engine_config_t *out,
                                const char **why);
/* most waypoints beyond a segment the solver needs, far from the start */
unsigned engine_cfg_steady_lookahead(const engine_config_t *cfg);
int engine_cfg_local(const engine_config_t *cfg);
/* issue 32: some axis has a jerk limit (axis_max_jerk_m_s3). */
int engine_cfg_axis_jerk(const engine_config_t *cfg);
/* waypoints after a fix its verdict waits for: ACCEPT_LAG, or 0 for a local
 * method with max_lookahead 1 (accept.h at_arrival, issue 31) */
unsigned engine_cfg_accept_lag(const engine_config_t *cfg);
/* start_slack auto's least: ENGINE_SLACK_AUTO_MIN, or 0 with no accept lag
 * (the slack is learnt from underruns from 0 then) */
unsigned engine_cfg_slack_min(const engine_config_t *cfg);
/* SMOOTH: the waypoints the smoother holds back (0 otherwise) */
unsigned engine_cfg_smooth_extra(const engine_config_t *cfg);
/* start offset of the fragment grid (frag.h) */
unsigned engine_cfg_frag_delta(const engine_config_t *cfg);
/* 1: the unknowns are Hoang control points (BSPLINE + UNIFORM) */
int engine_cfg_uses_pstar(const engine_config_t *cfg);

/* ---- input (engine_input.c) ---- */

/* Waypoints held anywhere between engine_push and the queue, and entries
 * queued: what the capacity counts. */
size_t input_buffered(const engine_t *e);
/* engine.c: (re)make what the resolved configuration r implies (the solver's
 * rings, the fragment window, the queue, the acceptance policy) for an engine
 * that has taken no waypoint; 0, or -1 (out of memory: e unchanged). */
int engine_setup(engine_t *e, const engine_config_t *r);
/* engine_input.c: the held waypoints offered, the lookahead picked first
 * where delay_s asks (engine_pick); at once by a finish, a clear, a halt */
void engine_pick_flush(engine_t *e);

/* ---- solver and queue (engine_solve.c) ---- */

/* Upper bound on the speed |k'| over a segment (m/s). */
double solve_seg_speed_max(const fdiff_seg_t *seg);
/* axis k's largest speed |k_k'| over seg at rate 1 (m/s), exactly */
double solve_axis_speed_max(const fdiff_seg_t *seg, int k);
/* issue 32: a per-axis limit is set (engine.h axis_max_*; the settings are
 * the engine's for its life, so engine_new notes it once). */
static inline int solve_axis_limited(const engine_t *e)
{
    return e->axis_lim;
}
int solve_cfg_axis_limited(const engine_config_t *cfg);
int solve_cfg_axis_accel(const engine_config_t *cfg);
/* The highest rate at which a segment keeps the speed cap and the
 * per-axis limits (qent_t ceil; *axis: qent_t ceil_axis). */
double solve_seg_ceiling(const engine_t *e, const fdiff_seg_t *seg, double vmax, int *axis);
/* A new trajectory; a node appended (0 or -ENGINE_ENUMERIC); SMOOTH's ready
 * waypoints turned into nodes; the trajectory closed (end row, last
 * segments, END entry); or ended on a failure with what is queued. */
void solve_open(engine_t *e);
int solve_add_node(engine_t *e, double t, const double *r, const double *vel);
int solve_drain(engine_t *e);
int solve_close(engine_t *e);
void solve_abort(engine_t *e);
/* A queued segment whose speed cap holds the rate below TS_RATE_MAX (the
 * queue's ring slow). */
static inline int queue_is_slow(const qent_t *q)
{
    return q->kind == QE_SEG && q->ceil < TS_RATE_MAX;
}

/* The queue head taken off (inline: a tick takes a segment here). */
static inline void queue_pop(engine_t *e)
{
    const qent_t *h = &e->queue.ent[e->queue.head];
    if (e->scale.drop_n)
        e->scale.drop_n--;
    if (h->kind == QE_END)
        e->queue.ends--;
    if (queue_is_slow(h)) { /* the ring's head */
        e->queue.slow_head = e->queue.slow_head + 1 == e->queue.cap ? 0 : e->queue.slow_head + 1;
        e->queue.slow_len--;
        e->queue.beyond -= !(h->ceil > 0);
    }
    /* (h + 1) % cap without the division */
    e->queue.head = e->queue.head + 1 == e->queue.cap ? 0 : e->queue.head + 1;
    e->queue.len--;
}
/* The waypoints queue entries i0 .. i1 - 1 end on (segments: the C2 local
 * methods queue three pieces an interval). */
uint64_t queue_waypoints(const engine_t *e, size_t i0, size_t i1);

/* ---- play-out (engine_tick.c; its trajectory boundaries: engine_play.c) ---- */

engine_state_t play_state(const engine_t *e);
/* 1 if further steps cannot change anything until new input arrives. */
int play_stalled(const engine_t *e);
/* The output may start (or resume after an underrun) on the queued segment
 * h: the lookahead is buffered beyond it, or its trajectory is closed
 * (engine_play.c; *lag, may be NULL: engine_delay_ready's). */
int play_enough_ahead(const engine_t *e, const qent_t *h, double *lag);
/* start_slack auto: an output stopped by an underrun at s stays stopped
 * (engine_play.c). */
int play_rebuffering(const engine_t *e, double s);
void play_count_underrun(engine_t *e);
/* D grows as the input now needs, and (start_slack auto) the slack learns
 * an interval more: after an underrun, or fixes lost within the lookahead. */
void play_slack_learn(engine_t *e);
void play_underrun_counted(engine_t *e);
void play_seed_cur(engine_t *e, int64_t n);
/* The queue head (a SEG) made cur; its segment as the freed slot holds it
 * until the next push. */
const fdiff_seg_t *play_take_segment(engine_t *e);
void play_start(engine_t *e, int new_flag);
/* A transfer has ended on its target: the trajectory there starts, or, a
 * lead transfer's not due yet, the output rests there until it is. */
void play_xfer_end(engine_t *e);
void play_stop_at_rest(engine_t *e);
void play_rest_at_end(engine_t *e, const qent_t *h);
void play_finish_here(engine_t *e);
/* The output stands where it is, at rest (its position out of the stepper). */
void play_hold_here(engine_t *e);
/* Back on the unit grid with rate 1 (every start from HOLD). */
void play_unit_reset(engine_t *e);
/* Where the solved curve of the output's trajectory ends (scale.avail_*). */
void play_find_avail(engine_t *e);
/* The output's pos, vel, acc copied out of the stepper (on_fd cleared). */
void out_sync(engine_t *e);
/* The output is the stepper's (engine_out_t): no copies, and the curve's
 * speed only where it is read (out_cspeed). */
static inline void out_eval(engine_t *e)
{
    e->out.on_fd = 1;
}
/* |k'|: the curve's own speed at the output (scale.cspeed off the grid). */
double out_cspeed(const engine_t *e);
/* Test hook (tests/unit/test_engine_tick.c): on 1, every tick whose rate
 * decision is kept (plain_window) recomputes it too (undoing its side
 * effects); on 2, makes it anyway and follows it; 0 as in use.  *kept and *wrong (either may be NULL)
 * count the kept ticks checked and those where the recomputed one differs. */
void engine_plain_check(engine_t *e, int on, uint64_t *kept, uint64_t *wrong);

/* ---- time scaling of the play-out (engine_scale.c) ---- */

void scale_eval(engine_t *e);
void scale_rest(engine_t *e);
double scale_remaining(const engine_t *e, double s);
double scale_slowing_reserve(const engine_t *e, double v);
double scale_ceil_room(const engine_t *e, double s, double A, double J);
/* scale_remaining and scale_ceil_room before scale_slowing_reserve at
 * scale_conv_speed is taken off (a decision works that out once for both) */
double scale_remaining_gross(const engine_t *e, double s);
double scale_ceil_room_gross(const engine_t *e, double s, double A, double J);
void scale_limits(const engine_t *e, double *A, double *J);
double scale_target(const engine_t *e);
int scale_moves(const engine_t *e, double R, double A, double J);
void scale_step(engine_t *e, double target, double R, double Rc, double A, double J);
void scale_clocked_step(engine_t *e, double R, double A, double J);

/* ---- transfers (engine_xfer.c) ---- */

double xfer_duration(const engine_t *e, const double *target, double gap_s, int *capped);
/* lead_t_s: the track time of the start it leads to (transfer.h "Lead"),
 * NAN for a transfer to a start due now. */
void xfer_start(engine_t *e, const double *target, double gap_s, double lead_t_s);
void xfer_track_time(engine_t *e);
/* issue 26: the start of the input's newest trajectory, where a resting
 * output that is not there may move before that trajectory's output is due
 * (transfer.h "Lead"): its position, track time and the gap before it.
 * Returns 1 if there is one to lead to now. */
int xfer_lead_target(const engine_t *e, double *target, double *t0_s, double *gap_s);

/* ---- transfers that keep moving (join.c) ---- */

/* 1 if the output may join the next trajectory moving (cheap checks only). */
int join_wanted(const engine_t *e);
/* Join the next trajectory moving from this tick if it is due and a join
 * fits (1: the output is on it); else 0, and the old way goes on. */
int join_try(engine_t *e);
/* The rate an old curve's tail keeps while a live re-anchor's new curve is
 * solved far enough to join (join.c); INFINITY where nothing waits. */
double join_wait_rate(const engine_t *e);
/* join_may_wait's tests beyond the later trajectory (join.c). */
int join_may_wait_here(const engine_t *e);
/* 1 if join_wait_rate may be below 1 now or later without a call between
 * ticks (a later trajectory open behind a re-anchor): no kept decision. */
static inline int join_may_wait(const engine_t *e)
{
    return e->in.open && e->solve.traj != e->out.traj && join_may_wait_here(e);
}
/* Unit-grid ticks before a join may be due (plain_window keeps no
 * decision beyond them); INT64_MAX if none can be (always without
 * queue_later_traj). */
int64_t join_ticks_left(const engine_t *e);
/* The output's track time on a join: from its start to the meeting time on
 * the new curve, in proportion to the join done. */
void join_track_time(engine_t *e);

/* ---- shared small helpers ---- */

/* node j of the ring: its position and its time */
static inline double *nr(engine_t *e, uint64_t j)
{
    return e->solve.node_r + (size_t)(j % e->solve.ring) * AX;
}

static inline double nt(const engine_t *e, uint64_t j)
{
    return e->solve.node_t[j % e->solve.ring];
}

/* parameter step of interval j (M form) */
static inline double hpar(const engine_t *e, uint64_t j)
{
    return e->cfg.param == ENGINE_PARAM_TIME ? nt(e, j + 1) - nt(e, j) : 1.0;
}

/* the i-th queued entry from the head (i < queue.len <= queue.cap, so
 * head + i < 2 cap: the ring's wrap without the division) */
static inline const qent_t *queue_at(const engine_t *e, size_t i)
{
    size_t j = e->queue.head + i;
    return &e->queue.ent[j >= e->queue.cap ? j - e->queue.cap : j];
}

/* A later trajectory than the output's is queued: else there is none to
 * join (join.c join_find; the usual case, asked at every segment's end). */
static inline int queue_later_traj(const engine_t *e)
{
    return e->queue.len && queue_at(e, e->queue.len - 1)->traj > e->out.traj;
}

static inline qent_t *q_head(engine_t *e)
{
    return e->queue.len ? &e->queue.ent[e->queue.head] : NULL;
}

/* Exact comparisons of the time scaling's state (it lands on its targets
 * exactly, see ts_step), written without == for -Wfloat-equal. */
static inline int is_exactly(double x, double v)
{
    return !(x < v || x > v);
}

static inline int at_rest(const engine_t *e)
{
    return is_exactly(e->scale.ts.rate, 0.0) && is_exactly(e->scale.ts.acc, 0.0);
}

/* The output's position, velocity, acceleration (see engine_out_t). */
static inline const double *out_pos(const engine_t *e)
{
    return e->out.on_fd ? e->out.fd.f + FDIFF_POS : e->out.pos;
}

static inline const double *out_vel(const engine_t *e)
{
    return e->out.on_fd ? e->out.fd.f + FDIFF_VEL : e->out.vel;
}

static inline const double *out_acc(const engine_t *e)
{
    return e->out.on_fd ? e->out.fd.f + FDIFF_ACC : e->out.acc;
}

static inline double tick_time(const engine_t *e, int64_t n)
{
    return (double)(n * e->cfg.period_ns) * 1e-9;
}

/* Track time of tick n on the unit grid (relative to origin_t); s_off is 0
 * until the time scaling first moved the output off the grid. */
static inline double tau_of(const engine_t *e, int64_t n)
{
    return tick_time(e, n) + e->scale.s_off;
}

/* The output's track time now (relative to origin_t): the time scaling's s
 * while it is on, else the unit grid's at the current tick. */
static inline double out_s(const engine_t *e)
{
    return e->scale.on ? e->scale.s : tau_of(e, e->out.n);
}

/* A zero is +0.0 (-0.0 + 0.0 = +0.0): a setpoint at rest reads 0, not -0, in
 * every output (CSV, binary, Modbus, CAN), all of them alike.  Returns rc. */
static inline int positive_zeros(engine_setpoint_t *sp, int rc)
{
    for (int a = 0; a < ENGINE_AXES; a++) {
        sp->pos_m[a] += 0.0;
        sp->vel_m_s[a] += 0.0;
        sp->acc_m_s2[a] += 0.0;
    }
    return rc;
}

/* ---- the time scaling's conversions at the current segment (engine_scale.c;
 * inline: plain_window reads them at every segment's end) ---- */

/* The speed (m/s) at which the scaling's jerk limit is converted outside a
 * stop: the largest the curve reaches on the current segment (seg_speed_max;
 * a transfer's: 1.5 D / T_x), at least the floor.  (Not the speed here:
 * converted there, the limits would shrink as a ramp speeds up along a
 * transfer faster than the jerk can take the rate's acceleration back.) */
static inline double scale_jerk_speed(const engine_t *e)
{
    /* fmax without the libm call (x86-64 baseline): the same for every
     * vmax, NaN included (the floor) */
    double v = e->out.cur.vmax;
    return v > ENGINE_SCALE_V_FLOOR_M_S ? v : ENGINE_SCALE_V_FLOOR_M_S;
}

/* ... and its acceleration limit, in whose units the braking capacity is
 * expressed (scale_remaining): the segment's av (qent_t), the same speed
 * unless per-axis acceleration limits leave the scaling more (issue 32,
 * engine_solve.c accel_speed); a transfer's is its jerk's. */
static inline double scale_conv_speed(const engine_t *e)
{
    double v = e->out.cur.av;
    return v > 0 ? v : scale_jerk_speed(e);
}

/* Track time (per unit of rate, in the units of the limits converted at v)
 * kept for the rises of the limits ahead.  Where the output brakes into a
 * segment with larger limits (a slower one: A = a / v), its deceleration must
 * ramp up to the new A at the jerk J: a stop then needs up to
 * r (A_new - A_old)^2 / (2 J_new) <= r dA a / (2 j) of capacity more than
 * r^2/2; so much per rise of A ahead, summed (ucum), is kept in reserve:
 * scale_rise_per_u(e, r, v) per unit of ucum, at rate r (scale_rise_reserve's
 * r 1, times the rate where it is used). */
static inline double scale_rise_per_u(const engine_t *e, double r, double v)
{
    return r * 0.5 * e->cfg.scale_accel_m_s2 / e->cfg.scale_jerk_m_s3 * v;
}

static inline double scale_rise_reserve(const engine_t *e, double v)
{
    double du = e->scale.avail_ucum - e->out.cur.ucum;
    return du > 0 ? scale_rise_per_u(e, 1.0, v) * du : 0.0;
}

/* The rate the speed cap allows on the current segment.  A transfer lasts
 * long enough for every axis, and for the caller's acceleration cap, at rate
 * 1 (engine_xfer.c xfer_duration): with per-axis limits or that cap a feed
 * override above 100 % does not speed it up, which would take an axis past
 * its limit (tests/unit/test_axis_share.c) or the output past the cap. */
static inline double scale_ceil_here(const engine_t *e)
{
    if (e->out.mode == OUT_STREAM)
        return e->out.cur.ceil;
    return e->out.mode == OUT_XFER && (solve_axis_limited(e) || e->cfg.cap_accel_m_s2 > 0)
               ? 1.0
               : INFINITY;
}

#endif
