/*
 * engine_int.h - the engine's state, shared by the files that make up the
 * engine (engine.c: input, queue and output; engine_cmd.c: the commands the
 * lifecycle owner gives it, lifecycle.h).  Not part of the client API: only
 * the engine's own files in lib/engine include it.
 */
#ifndef TRAJD_ENGINE_INT_H
#define TRAJD_ENGINE_INT_H

#include <stddef.h>
#include <stdint.h>

#include "accept.h"
#include "engine.h"
#include "fdiff.h"
#include "frag.h"
#include "lsq.h"
#include "timescale.h"
#include "transfer.h"

#define AX ENGINE_AXES

enum { QE_SEG = 0, QE_END = 1 };

/* One queued entry: a segment to stream, or the rest point ending a trajectory. */
typedef struct {
    int kind;
    int first;       /* first entry of its trajectory */
    double t1_s;     /* segment end (absolute track time); END: rest time */
    uint64_t node;   /* SEG: index of its first node in the trajectory */
    uint64_t traj;   /* input trajectory it belongs to (engine.in_traj) */
    fdiff_seg_t seg; /* END: c[k][0] is the rest position, t0_s = t1_s */
    double gap_s;    /* first entry: track time since the previous trajectory's
                             end when a gap separates them, else 0 */
    double vmax;     /* SEG: bound on the curve's speed |k'| over it (m/s) */
    double kcum;     /* SEG: braking capacity of its trajectory up to its end,
                        the sum of dur / max(vmax, floor) (see remaining()) */
    double ucum;     /* SEG: the rises of 1 / max(vmax, floor) from each segment
                          of its trajectory to the next, summed up to it */
    double ceil;     /* SEG: the highest rate at which it keeps the speed cap
                        (ENGINE_SPEED_CAP; INFINITY if none) */
} qent_t;

/* The lowest speed cap rate: below the time scaling's dead band (at most
 * TS_DEAD_BAND_MAX) the output would never leave rest before such a segment. */
#define ENGINE_CEIL_MIN 0.01

enum { OUT_HOLD = 0, OUT_XFER = 1, OUT_STREAM = 2 };
enum { STOP_NONE = 0, STOP_STOP = 1, STOP_CLEAR = 2 };

struct engine {
    engine_config_t cfg; /* resolved: fragment and overlap never ENGINE_AUTO */
    unsigned lookahead;
    unsigned la_steady;   /* what the solver needs far from the start (steady_lookahead) */
    int slack_auto;       /* start_slack auto (engine.h) */
    unsigned slack_learn; /* start_slack auto: one more per underrun seen */
    unsigned slack_more;  /* start_slack auto: the most it adds to lookahead
                             (ENGINE_SLACK_AUTO_MAX - MIN, less if capacity is short) */
    double span_max;      /* start_slack auto: longest time spanned by la_steady + 1
                           intervals of the input, decaying by 1/256 per node */
    double vmax_in;       /* start_slack auto: fastest chord speed of the input,
                           decaying the same way */
    int pstar;            /* unknowns are Hoang control points (BSPLINE + UNIFORM) */
    int held;             /* HELD or MULTIPLE: first and last segments not emitted */
    int mult;             /* MULTIPLE: end points entered three times */
    int smooth;           /* SMOOTH: waypoints pass through the lsq smoother first */
    lsq_smooth_t sm;
    double *sm_mem;
    double first_r[AX]; /* first waypoint of the current trajectory */
    double period_s;

    /* ---- input: the trajectory being received ---- */
    int in_open;
    uint64_t nodes;    /* nodes of the current trajectory (copies included) */
    uint64_t seg_next; /* next segment index to build */
    size_t ring;       /* nodes kept */
    double *node_t;    /* ring */
    double *node_r;    /* ring x AX */
    frag_t *fw;
    int in_emitted;       /* a segment of this trajectory was queued */
    int in_first_pending; /* the next queued entry is the trajectory's first */
    double last_t;        /* last accepted waypoint of the current trajectory */
    double last_r[AX];
    int have_prev; /* prev_t/prev_r hold the waypoint before last (same trajectory) */
    double prev_t; /* for the acceleration check */
    double prev_r[AX];
    double end_r[AX]; /* end of the last queued segment */
    double end_t;
    double end_speed; /* speed at the end of the last queued segment */
    double in_kcum;   /* capacity queued so far of the trajectory (qent_t kcum) */
    double in_inv;    /* 1 / max(vmax, floor) of its last queued segment */
    double in_ucum;   /* qent_t ucum so far */
    uint64_t in_traj; /* +1 per trajectory opened */
    double in_gap_s;  /* gap before the trajectory being received (0: none) */

    /* ---- acceptance (accept.h) and transfers (transfer.h) ---- */
    accept_t policy;
    transfer_config_t xcfg;
    transfer_motion_t motion;
    engine_rejection_t rej[ENGINE_REJECTIONS_KEPT];
    unsigned rej_head, rej_len;

    /* ---- the queue ---- */
    qent_t *q;
    size_t qcap, qhead, qlen;
    size_t qends; /* END entries in the queue */

    /* ---- output ---- */
    int mode;
    int have_pos; /* the output stands somewhere real: set by engine_set_position,
                             or the first waypoint adopted as the last resort.  From then on
                             the output only moves by streaming or by a transfer */
    int need_pos; /* engine_require_position: no first-waypoint fallback */
    int finished; /* the last trajectory ran to its end */
    int underrun;
    qent_t cur;            /* segment (or transfer) being stepped */
    double cur_t0, cur_t1; /* its start and end relative to base */
    fdiff_t fd;
    int64_t n;       /* ticks since base */
    int64_t seg_n0;  /* tick at which cur was seeded */
    double origin_t; /* absolute track time of tick 0 of the trajectory */
    double pos[AX], vel[AX], acc[AX];
    double out_t;       /* track time of the output */
    double xfer_from_t; /* out_t when the transfer under way began (NAN: none before) */
    uint32_t out_track;
    uint32_t cycle;
    uint32_t flags_pending;
    int have_now;
    int64_t last_now;
    engine_setpoint_t last_sp;

    /* ---- time scaling (timescale.h, TIMESCALE.md) ---- */
    ts_state_t ts;     /* rate ds/dt and its derivative */
    int scaled;        /* off the unit grid: the output's track time is s */
    double s;          /* scaled: track time of the output, relative to origin_t */
    double s_off;      /* unit grid: track time = tick_time(n) + s_off */
    double cspeed;     /* |k'(s)|: the curve's own speed at the output */
    double override;   /* feed override 0 .. 2 */
    int stop_req;      /* STOP_*: braking to rest, then drop */
    size_t drop_n;     /* queue entries to drop once at rest */
    uint64_t out_traj; /* trajectory the output streams */
    double avail_t;    /* end of its solved curve (absolute track time) */
    double avail_kcum; /* braking capacity up to there (qent_t kcum) */
    double avail_ucum; /* ... and the rises of the limits (qent_t ucum) */
    int avail_closed;  /* its END is queued */
    int avail_rest;    /* ... and the curve ends at rest there */
    int end_brake;     /* braking to rest before an end that is not at rest */
    size_t *slow;      /* ring (qcap): the queue slots, in queue order, of the
                     segments whose speed cap holds the rate below TS_RATE_MAX */
    size_t slow_head, slow_len;

    /* ---- one clock (engine_set_clock, CLOCK.md) ---- */
    int clocked;          /* the output follows the caller's clock */
    int locked;           /* its track time is exactly the play time */
    int64_t clk_now_ns;   /* now on the sender's time base (last call) */
    int64_t clk_delay_ns; /* play-out delay D */
    double clk_rate;      /* d now / dt */
    double clk_catchup;   /* most the rate rises above clk_rate */
    int64_t play_ns;      /* now - D at the step being made */

    /* ---- fast ticks (fast_window, fast_tick) ---- */
    int64_t fast_left; /* ticks ahead that are certainly plain unit-grid steps */
    int fast_off;      /* engine_set_fast_ticks(e, 0): every tick the full way */
    int fast_last;     /* the last tick was fast: last_sp and cspeed not yet written */

    engine_status_t st;
};

/* The fast-tick window closed and its deferred copies made (engine.c):
 * every call that changes the engine makes it first. */
void engine_fast_close(engine_t *e);

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

#endif
