/*
 * join.c - transfers that keep moving (issue 32): when the trajectory the
 * output streams ends in a re-anchor (its END queued and the next
 * trajectory's first segment behind it, no gap beyond max_gap_s), the output
 * does not brake to rest at the old curve's end and then transfer rest to
 * rest: where the old curve's last interval begins (or where its end would
 * have to be braked for, if that is earlier), it leaves the old curve from
 * the state it is in (position, velocity and acceleration of the tick just
 * sent) and meets the new trajectory's curve at a time t_m on it, matching
 * its position, velocity and acceleration there.  The join is C2: three
 * cubics of constant jerk each (hermite_c2_segments), played as ordinary
 * segments of the new trajectory at rate 1 (the stepper) or at the
 * override's rate (below), spliced in at the queue's head in front of the
 * new curve cut at t_m; its setpoints carry ENGINE_SP_TRANSFER and a new
 * track.  Not where the new trajectory starts
 * where the old one ends (no transfer is needed: the curves rest there, a
 * stop as the data says).
 *
 * Its duration T is the shortest whole number of periods, from the end of
 * the new trajectory's first interval on (its curve there has left its
 * start, at rest with rest ends), for which the join keeps, on every piece:
 *   - the speed within ENGINE_SPEED_CAP x the speed limit in force (if any),
 *     and at least JOIN_KEEP of the lower of the two curves' own speeds
 *     where it leaves the old and meets the new (sampled JOIN_SAMPLES + 1
 *     times per piece);
 *   - the acceleration (linear on a piece: its ends bound it) within
 *     max(scale_accel_m_s2, |a| where it leaves the old curve): the new
 *     curve's own at t_m too (so not near its start from rest, where its
 *     own acceleration is the rest end's);
 *   - the jerk (constant on a piece) within scale_jerk_m_s3;
 *   - on each axis with per-axis limits (engine.h axis_max_*): |v_k|,
 *     |a_k| within them and |j_k| within half axis_max_jerk_m_s3, as on the
 *     curve;
 * and the new curve at t_m within its speed cap at rate 1, and the curve
 * ahead once on it (the pieces and what is queued beyond t_m) long enough
 * to stop in from rate 1.  t_m is the join's start + T, the track time it
 * covers, where the new curve is queued that far; else as far as it is
 * queued (a live sender: the new curve is solved a lookahead behind its
 * newest waypoint): the join then takes longer than the track time it
 * covers, the output falls behind its data by the difference (origin_t
 * shifted by it where the join meets the curve, qent_t shift; less than a
 * stop and transfer would), and its t_s runs from the join's start to t_m
 * (join_track_time).  The candidates grow by one period, then by
 * JOIN_GROWTH of the duration added, up to xfer.cfg.max_s (max_gap_s)
 * beyond the first; a candidate behind its data whose mean speed is below
 * the least it may keep ends the search (longer ones are slower still), and
 * it is tried again at the next tick, when more may be queued.  When none
 * fits (or the output reaches the old curve's end first), the old way is
 * the fallback: the output brakes to rest at the old curve's end and a
 * rest-to-rest transfer takes it to the new start (engine_xfer.c).
 *
 * Under a feed override rho (0 < rho <= 2, engine_set_override) the join is
 * planned at the output's path speed and played at rate rho: it leaves from
 * the commanded state as sent (the scaled velocity and acceleration) and
 * meets the new curve at rho times its velocity and rho^2 its acceleration,
 * over T seconds (whole periods) that cover rho T of track time; every
 * check above is made in m/s on that motion (the new curve's own
 * acceleration ahead at rho^2, its ceiling at least rho, the speed kept at
 * least JOIN_KEEP of the lower of rho x the two curves' speeds, the stop
 * from rho); the pieces are the same cubics with their time stretched by
 * rho, queued in track time, and the time scaling plays them at rate rho,
 * its own acceleration 0 from the join's start (the pieces hold the state
 * as sent, v / rho and a / rho^2 in track time, so nothing steps), each
 * piece's ceiling (speed cap, per-axis limits) at least rho.  Where no join
 * fits at the override's rate and the output runs slower without an
 * underrun (the curves' ceilings hold it below the override, or it brakes
 * for the old curve's end), one is sought at the rate it runs at, its
 * acceleration and jerk checked also at the rate the scaling may take it
 * to (the override within the pieces' highest ceiling: g = that / rho in
 * piece_fits); its speed the ceilings keep.  A change of the override
 * during the join is the time scaling's, as on any curve (the join is C2
 * in track time too).  At rho = 1 it is the join at rate 1 on the unit
 * grid, as before.
 *
 * A live sender (its waypoints pushed as they come) re-anchors: the new
 * curve is solved a lookahead behind its newest waypoint, and where the join
 * leaves the old curve (the start of its last interval) it must be queued
 * past the new start's first intervals, the join's own length and a stop
 * beyond; D's slack holds less than that.  The old curve's tail is then
 * played slower (join_wait_rate, the time scaling's target: the rate at
 * which the new curve is there in time, from its interval and the jump the
 * join bridges, at least JOIN_WAIT_MIN), and the join leaves from the
 * slowed state keeping JOIN_KEEP of its speed (not below what the wait
 * keeps), as in an underrun; the lag is won back after it.  Not where the
 * new track heads more than 60 degrees away from the old one (no join keeps
 * moving there: the stop), on one clock or under an override.
 *
 * In an underrun (the time scaling has slowed the output because the curve
 * ahead ran short: the re-anchor's own confirmation holds the new track's
 * first waypoints back, or the sender stalled) the join leaves from the
 * actual commanded state, the slowed velocity and its acceleration, and
 * the speed it keeps JOIN_KEEP of is the lower of the output's own there
 * and the new curve's (x rho): it does not wait for the rate to recover
 * nor brake to rest.  The underrun ends with the join (the new curve is
 * queued beyond it).  An output the underrun has brought to rest (rate 0)
 * is not joined: the transfer, as from any rest.
 *
 * On one clock (CLOCK.md) the join is played at the clock's rate (slowed
 * by an override below 1; above it has no effect) as under an override:
 * locked on the play time, the clocked step samples the pieces at the play
 * time itself (they are queued in track time), so the output stays locked
 * through the join; a join behind its data (t_m short of t_now + rho T)
 * leaves it that much behind the clock, won back by the clock's bounded
 * catch-up after it, as any lag.
 *
 * Not joined moving: during a stop or clear (a stop brakes), under a feed
 * hold (override 0), after a gap beyond max_gap_s (a new trajectory), at
 * rest.  After a gap the output has played its tail out to rest on the old
 * trajectory's last waypoint (never past the data), and from rest the
 * transfer ends on the new trajectory's first waypoint, exact through every
 * kept one, which a join meeting its curve further on would leave for time
 * (LIFECYCLE.md's precedence, 3 before 4).  The catch-up (catchup.h) does
 * not steer a join; the lag it leaves is won back after it.
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "fdiff.h"
#include "hermite.h"
#include "timescale.h"

/* Speed samples per join piece (the speed is a quadratic per axis). */
#define JOIN_SAMPLES 32
/* Shortest join, in periods. */
#define JOIN_MIN_TICKS 3
/* Candidates beyond the first JOIN_STEP_TICKS grow by this fraction of the
 * duration added so far (a few hundred candidates at most). */
#define JOIN_STEP_TICKS 50
#define JOIN_GROWTH 0.05
/* The new curve is met beyond its first intervals: its start from rest
 * shapes the curve there (with rest ends a C2 spline's start decays by
 * 2 - sqrt(3) per node: to 2 % after 3). */
#define JOIN_SETTLE_INTERVALS 3
/* ... and where its own acceleration stays within the join's limit for
 * this long (track seconds, of what is queued). */
#define JOIN_AHEAD_S 1.0
/* A join keeps at least this fraction of the lower of the two curves'
 * speeds (issue 32: "it does not drop below 50 %"); one that would not is
 * no join that keeps moving: the stop and transfer. */
#define JOIN_KEEP 0.5
/* Under an override, a rate below this fraction of it is held by the
 * curves' ceilings (join_try). */
#define JOIN_HELD 0.999
/* The least rate join_wait_rate slows an old curve's tail to, waiting for the
 * new one (above JOIN_KEEP: the join starts from it). */
#define JOIN_WAIT_MIN 0.6

/* What the queue holds for a join: the old trajectory's END at index iend,
 * the new trajectory's first entry after it. */
typedef struct {
    size_t iend, inew; /* queue indices */
    double t_end;      /* the old curve's end */
    double t_last_ivl; /* where its last interval begins */
    double t_first;    /* the end of the new trajectory's first intervals */
    double t_last;     /* the end of the new trajectory's queued curve */
    int closed;        /* the new trajectory's END is queued */
} join_find_t;

int join_wanted(const engine_t *e)
{
    return e->out.mode == OUT_STREAM && e->scale.avail_closed && e->queue.ends > 0 &&
           e->out.join_refused != e->out.traj + 1 && !e->scale.stop_req && e->scale.override > 0 &&
           e->out.have_pos;
}

/* The rate a join is played at: the override's; on one clock the clock's,
 * slowed by an override below 1 (above it has no effect: CLOCK.md). */
static double join_rate(const engine_t *e)
{
    return e->clk.on ? e->clk.rate * fmin(e->scale.override, 1.0) : e->scale.override;
}

/* A join on the unit grid (else scaled at its rate). */
static int join_unit(const engine_t *e, double rho)
{
    return is_exactly(rho, 1.0) && !e->clk.on;
}

/* The first queue index at or after i0 whose trajectory is past traj (the
 * queue holds the trajectories in order): a binary search. */
static size_t traj_past(const engine_t *e, size_t i0, uint64_t traj)
{
    size_t lo = i0, hi = e->queue.len;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (queue_at(e, mid)->traj > traj)
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* Where the old trajectory's last interval (its node's pieces) begins, its
 * END at queue index iend. */
static double join_last_ivl(const engine_t *e, size_t iend)
{
    if (iend == 0)
        return e->out.cur.seg.t0_s;
    uint64_t node = queue_at(e, iend - 1)->node;
    size_t j = iend;
    while (j > 0 && queue_at(e, j - 1)->node == node)
        j--;
    return j > 0 || e->out.cur.node != node ? queue_at(e, j)->seg.t0_s : e->out.cur.seg.t0_s;
}

/* The old trajectory's end and the new one behind it (0: no join possible
 * now; *never: not for this trajectory). */
static int join_find(const engine_t *e, join_find_t *f, int *never)
{
    *never = 0;
    if (!queue_later_traj(e))
        return 0;
    size_t i = traj_past(e, 0, e->out.traj);
    if (i == 0 || i >= e->queue.len || queue_at(e, i - 1)->kind != QE_END)
        return 0; /* not closed, or the next trajectory may still come */
    f->iend = i - 1;
    f->inew = i;
    f->t_end = queue_at(e, i - 1)->t1_s;
    f->t_last_ivl = join_last_ivl(e, f->iend);
    const qent_t *n = queue_at(e, i), *end = queue_at(e, i - 1);
    double d2 = 0;
    for (int k = 0; k < AX; k++)
        d2 += (n->seg.c[k][0] - end->seg.c[k][0]) * (n->seg.c[k][0] - end->seg.c[k][0]);
    /* a gap beyond max_gap_s still rests (TIMESCALE.md), and so does a
     * trajectory with no segment or one whose time does not run on; one
     * that starts where the old one ends needs no transfer: the curves rest
     * there (a stop, issue 27), as the data says */
    if (n->kind != QE_SEG || !n->first || n->gap_s > 0 || n->seg.t0_s < f->t_end - 1e-9 ||
        n->seg.t0_s - f->t_end > e->cfg.max_gap_s || !(sqrt(d2) > ENGINE_TRANSFER_TOL_M)) {
        *never = 1;
        return 0;
    }
    size_t k = traj_past(e, i, n->traj); /* past the new trajectory's queued entries */
    const qent_t *l = queue_at(e, k - 1);
    f->closed = l->kind == QE_END;
    f->t_last = l->t1_s;
    /* the end of its first JOIN_SETTLE_INTERVALS intervals */
    int settled = 0;
    f->t_first = n->t1_s;
    for (size_t j = i; j < k && queue_at(e, j)->kind == QE_SEG; j++) {
        if (queue_at(e, j)->node >= n->node + JOIN_SETTLE_INTERVALS) {
            settled = 1;
            break;
        }
        f->t_first = queue_at(e, j)->t1_s;
    }
    if (!settled) { /* not queued yet; or too short a trajectory to join */
        *never = f->closed;
        return 0;
    }
    return 1;
}

/* 1 if the piece keeps the join's limits (see above); its acceleration and
 * jerk also where the time scaling plays it g >= 1 times faster than it
 * was planned for (join_search). */
static int piece_fits(const engine_t *e, const fdiff_seg_t *s, double vlim, double vmin,
                      double alim, double jlim, double g)
{
    double id = 1.0 / s->dur_s, j2 = 0, a02 = 0, a12 = 0;

    for (int k = 0; k < AX; k++) {
        const double *c = s->c[k];
        /* played up to g times faster: acceleration g^2, jerk g^3 */
        double jk = 6.0 * c[3] * id * id * id * (g * g * g), a0 = 2.0 * c[2] * id * id * (g * g),
               a1 = (2.0 * c[2] + 6.0 * c[3]) * id * id * (g * g);
        j2 += jk * jk;
        a02 += a0 * a0;
        a12 += a1 * a1;
        if (e->cfg.axis_max_jerk_m_s3[k] > 0 && fabs(jk) > 0.5 * e->cfg.axis_max_jerk_m_s3[k])
            return 0;
        if (e->cfg.axis_max_accel_m_s2[k] > 0 &&
            fmax(fabs(a0), fabs(a1)) > e->cfg.axis_max_accel_m_s2[k])
            return 0;
        if (e->cfg.axis_max_speed_m_s[k] > 0 &&
            solve_axis_speed_max(s, k) > e->cfg.axis_max_speed_m_s[k])
            return 0;
    }
    if (sqrt(j2) > jlim || sqrt(fmax(a02, a12)) > alim)
        return 0;
    double v[AX];
    for (int i = 0; i <= JOIN_SAMPLES; i++) {
        double v2 = 0;
        fdiff_eval(s, (double)i / JOIN_SAMPLES, NULL, v, NULL);
        for (int k = 0; k < AX; k++)
            v2 += v[k] * v[k];
        if ((vlim > 0 && v2 > vlim * vlim) || v2 < vmin * vmin)
            return 0;
    }
    return 1;
}

static double norm3(const double *x)
{
    return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
}

/* The queued segment of the new trajectory holding track time t. */
static const qent_t *seg_at(const engine_t *e, const join_find_t *f, double t, size_t *idx)
{
    for (size_t j = f->inew; j < e->queue.len; j++) {
        const qent_t *q = queue_at(e, j);
        if (q->kind != QE_SEG || q->traj != queue_at(e, f->inew)->traj)
            break;
        if (t < q->t1_s) {
            *idx = j;
            return q;
        }
    }
    return NULL;
}

/* The largest |k''| of the new curve from t (in the queued segment idx) on,
 * over the segments that begin before t + h (k'' is linear on a segment:
 * its ends bound it). */
static double acc_ahead(const engine_t *e, size_t idx, double t, double h)
{
    double amax = 0, a[AX];
    uint64_t traj = queue_at(e, idx)->traj;
    for (size_t j = idx; j < e->queue.len; j++) {
        const qent_t *q = queue_at(e, j);
        if (q->kind != QE_SEG || q->traj != traj || (j > idx && q->seg.t0_s >= t + h))
            break;
        fdiff_eval(&q->seg, j == idx ? (t - q->seg.t0_s) / q->seg.dur_s : 0.0, NULL, NULL, a);
        amax = fmax(amax, norm3(a));
        fdiff_eval(&q->seg, 1.0, NULL, NULL, a);
        amax = fmax(amax, norm3(a));
    }
    return amax;
}

/* The cubic s restricted to its u in [u0, 1], as a cubic over that part. */
static void seg_cut(fdiff_seg_t *s, double u0)
{
    double w = 1.0 - u0;
    for (int k = 0; k < AX; k++) {
        double *c = s->c[k];
        double d0 = c[0] + u0 * (c[1] + u0 * (c[2] + u0 * c[3]));
        double d1 = w * (c[1] + u0 * (2.0 * c[2] + 3.0 * c[3] * u0));
        double d2 = w * w * (c[2] + 3.0 * c[3] * u0);
        double d3 = w * w * w * c[3];
        c[0] = d0;
        c[1] = d1;
        c[2] = d2;
        c[3] = d3;
    }
}

/* The join in the queue: the old trajectory's rest and the new one's curve
 * before t_m dropped, the segment holding t_m cut there, the pieces in
 * front of it (their capacities and rises as queue_segment counts them). */
static void join_splice(engine_t *e, size_t ihead, double t_m, double t_j, const fdiff_seg_t pc[3])
{
    for (size_t i = 0; i < ihead; i++)
        queue_pop(e);
    qent_t *h = q_head(e);
    double u0 = (t_m - h->seg.t0_s) / h->seg.dur_s;
    if (u0 > 0) {
        seg_cut(&h->seg, u0);
        h->seg.dur_s = h->t1_s - t_m;
        h->seg.t0_s = t_m;
    }
    h->first = 0;
    h->gap_s = 0;
    h->shift = t_m - t_j; /* the join's end, t_j on its pieces, is t_m on the curve */
    uint64_t traj = h->traj, node = h->node;
    /* capacity (kcum) and rises (ucum) back from the head, as queued */
    double kcum = h->kcum - h->seg.dur_s / h->av;
    double ucum = h->ucum, inv_next = 1.0 / h->av;
    /* a rise into the next entry counts its A / J against a / j (queue_now) */
    double g_next = fmax(h->vmax, ENGINE_SCALE_V_FLOOR_M_S) / h->av;
    for (int i = 2; i >= 0; i--) {
        e->queue.head = (e->queue.head + e->queue.cap - 1) % e->queue.cap;
        e->queue.len++;
        qent_t *q = &e->queue.ent[e->queue.head];
        memset(q, 0, sizeof(*q));
        q->kind = QE_SEG;
        q->join = 1;
        q->node = node;
        q->traj = traj;
        q->seg = pc[i];
        q->t1_s = pc[i].t0_s + pc[i].dur_s;
        q->vmax = solve_seg_speed_max(&pc[i]);
        q->ceil = solve_seg_ceiling(e, &pc[i], q->vmax, &q->ceil_axis);
        double v = fmax(q->vmax, ENGINE_SCALE_V_FLOOR_M_S), inv = 1.0 / v;
        q->av = v; /* a piece's limits: converted at its speed */
        q->stop1 = ts_stop_dist(1.0, 0.0, e->cfg.scale_accel_m_s2 / v, e->cfg.scale_jerk_m_s3 / v);
        q->kcum = kcum;
        kcum -= pc[i].dur_s * inv;
        if (inv_next > inv)
            ucum -= (inv_next - inv) * g_next;
        q->ucum = ucum;
        inv_next = inv;
        g_next = 1.0;
        if (q->ceil < TS_RATE_MAX) { /* the slow ring, in queue order */
            e->queue.slow_head = (e->queue.slow_head + e->queue.cap - 1) % e->queue.cap;
            e->queue.slow[e->queue.slow_head] = e->queue.head;
            e->queue.slow_len++;
            e->queue.beyond += !(q->ceil > 0);
        }
    }
}

/* The output on the join's first piece from this tick on (n: the tick just
 * sent, the join's start), streaming the new trajectory: a new track, as a
 * transfer's.  At rate 1 on the unit grid; at another rate rho (an
 * override) scaled at rho, the rate's own acceleration 0: the pieces hold
 * the output's state in track time (v / rho, a / rho^2), so v and a go on
 * as they were sent. */
static void join_begin(engine_t *e, double t0, double t_m, double Tt, double rho)
{
    double s = out_s(e);
    e->out.join_t0 = t0;
    e->out.join_tm = t_m;
    e->out.join_dur = Tt;
    int unit = join_unit(e, rho);
    if (unit && e->scale.on) { /* the grid through the track time reached */
        e->scale.s_off = s - tick_time(e, e->out.n);
        e->scale.on = 0;
    }
    e->scale.ts.rate = rho;
    e->scale.ts.acc = 0.0;
    e->scale.end_brake = 0;
    e->out.traj = q_head(e)->traj;
    play_take_segment(e);
    if (unit) {
        e->out.seg_n0 = e->out.n;
        play_seed_cur(e, e->out.n);
        e->out.on_fd = 1;
    } else {
        e->scale.on = 1;
        e->scale.s = s;
        scale_eval(e);
    }
    play_find_avail(e);
    e->out.finished = 0;
    e->out.underrun = 0; /* the new curve is queued beyond the join */
    e->out.reserve_slow = 0;
    e->out.track++;
    e->out.flags_pending |= ENGINE_SP_NEW_TRACK;
    e->st.transfers_moving++;
    e->out.flags_pending |= ENGINE_SP_TRANSFER;
}

/* The lowest and highest ceiling of the pieces in track time (queue_segment's,
 * from the bound on their speed: the speed cap and per-axis limits). */
static void ceilings(const engine_t *e, const fdiff_seg_t pc[3], double *cmin, double *cmax)
{
    *cmin = INFINITY;
    *cmax = 0.0;
    for (int i = 0; i < 3; i++) {
        int ax;
        double c = solve_seg_ceiling(e, &pc[i], solve_seg_speed_max(&pc[i]), &ax);
        *cmin = fmin(*cmin, c);
        *cmax = fmax(*cmax, c);
    }
}

/* Track time a stop from rate r needs on segment q, within the time
 * scaling's limits converted at its speeds, with its margin: the curve a
 * join must leave queued beyond where it begins. */
static double stop_room(const engine_t *e, const qent_t *q, double r)
{
    double vq = fmax(q->vmax, ENGINE_SCALE_V_FLOOR_M_S);
    return ts_stop_dist(r, 0.0, e->cfg.scale_accel_m_s2 / q->av, e->cfg.scale_jerk_m_s3 / vq) +
           (TS_MARGIN_TICKS + 2) * e->period_s * r;
}

int join_may_wait_here(const engine_t *e)
{
    return !e->clk.on && is_exactly(e->scale.override, 1.0) && join_wanted(e);
}

static int join_wait_plan(const engine_t *e, double *r);

/* The shortest join at rate rho from the output's state at track time
 * t_now (see above): spliced in and begun (1), or none (0; *short_queue: one
 * may fit once more of the new curve is queued). */
static int join_search(engine_t *e, const join_find_t *fp, double t_now, double rho,
                       int *short_queue)
{
    const join_find_t f = *fp;
    /* r_max: the rate the scaling takes the new curve to after it (the
     * override's: a join at a rate the ceilings held is followed by it) */
    double P = e->period_s, r_max = fmax(rho, join_rate(e)), r_hi = fmax(1.0, r_max);
    int unit = join_unit(e, rho);
    double p0[AX], v0[AX], a0[AX];
    memcpy(p0, out_pos(e), sizeof(p0));
    memcpy(v0, out_vel(e), sizeof(v0));
    memcpy(a0, out_acc(e), sizeof(a0));
    double vlim = engine_config_max_speed(&e->cfg);
    vlim = vlim > 0 ? ENGINE_SPEED_CAP * vlim : 0.0;
    if (e->cfg.cap_speed_m_s > 0 && (!(vlim > 0) || vlim > e->cfg.cap_speed_m_s))
        vlim = e->cfg.cap_speed_m_s; /* the caller's cap (engine.h) */
    /* the old motion's speed it keeps half of: the old curve's at rho; in
     * an underrun the output's own (the time scaling has slowed it); slowed
     * to wait for the new curve (join_wait_rate), its own, but not below
     * what the wait keeps, JOIN_WAIT_MIN of the curve's */
    double v_old = rho * out_cspeed(e);
    if (e->out.underrun)
        v_old = norm3(v0);
    else if (e->scale.on && join_wait_plan(e, NULL))
        v_old = fmin(v_old, fmax(norm3(v0), JOIN_WAIT_MIN * v_old));
    double T0 = ceil((f.t_first - t_now) / (rho * P) - 1e-9) * P;
    if (T0 < JOIN_MIN_TICKS * P)
        T0 = JOIN_MIN_TICKS * P;
    double T_hi = T0 + e->xfer.cfg.max_s;
    int64_t ticks = llround(T0 / P), step = 1;

    for (int c = 0;; c++) {
        double T = (double)ticks * P, Tt = rho * T; /* seconds; track time at rho */
        if (T > T_hi)
            break;
        /* on the new curve as far as its track time ran (t_now + Tt), or
         * as far as it is queued: then the join takes longer than the
         * track time it covers (the output falls behind its data by the
         * difference, less than a stop and transfer would) */
        double t_m = fmin(t_now + Tt, f.t_last - P);
        size_t idx;
        const qent_t *q = t_m >= f.t_first ? seg_at(e, &f, t_m, &idx) : NULL;
        if (!q) {
            *short_queue = !f.closed;
            break;
        }
        /* the curve ahead once on it (the pieces, and the new curve queued
         * beyond t_m) long enough to stop in from rho */
        double need = stop_room(e, q, r_hi);
        int fits = (f.closed || Tt + (f.t_last - t_m) >= need) &&
                   e->queue.len + 3 <= e->queue.cap + idx; /* room for the pieces */
        /* the new curve's state at t_m as the output meets it at rho:
         * velocity rho k', acceleration rho^2 k'' */
        double p1[AX], v1[AX], a1[AX];
        fdiff_seg_t pc[3];
        fdiff_eval(&q->seg, (t_m - q->seg.t0_s) / q->seg.dur_s, p1, v1, a1);
        for (int k = 0; k < AX; k++) {
            v1[k] *= rho;
            a1[k] *= rho * rho;
        }
        hermite_c2_segments(p0, v0, a0, p1, v1, a1, t_now, T, pc);
        /* not the new curve's own where it is larger, at t_m (the piece's
         * end) and for JOIN_AHEAD_S after it: near its start from rest the
         * scaling would have ramped through it; t_m moves on to where it
         * has settled */
        double alim = fmax(e->cfg.scale_accel_m_s2, norm3(a0));
        int settled = r_max * r_max * acc_ahead(e, idx, t_m, JOIN_AHEAD_S) <= alim;
        fits = fits && settled && q->ceil >= rho;
        /* it keeps moving: at least JOIN_KEEP of the lower of the two
         * motions' speeds, where it leaves the old and meets the new */
        double vmin = JOIN_KEEP * fmin(v_old, norm3(v1));
        /* in track time: the pieces played at rho (their cubics are the
         * same, their time stretched by rho), each piece's ceiling at
         * least rho; the scaling plays them at up to the override within
         * their highest ceiling: g times faster than planned (a join at a
         * rate the ceilings held: its acceleration and jerk checked at
         * that rate too; its speed the ceilings keep) */
        double g = 1.0;
        fdiff_seg_t tk[3] = {pc[0], pc[1], pc[2]};
        for (int i = 0; i < 3 && !unit; i++) {
            tk[i].t0_s = t_now + rho * (pc[i].t0_s - t_now);
            tk[i].dur_s = rho * pc[i].dur_s;
        }
        if (!unit) {
            double cmin, cmax;
            ceilings(e, tk, &cmin, &cmax);
            fits = fits && cmin >= rho;
            g = fmax(1.0, fmin(join_rate(e), cmax) / rho);
        }
        for (int i = 0; i < 3 && fits; i++)
            fits = piece_fits(e, &pc[i], vlim, vmin, alim, e->cfg.scale_jerk_m_s3, g);
        if (fits) {
            join_splice(e, idx, t_m, t_now + Tt, tk);
            join_begin(e, t_now, t_m, Tt, rho);
            return 1;
        }
        double d[AX] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        if (t_m < t_now + Tt && (norm3(d) < vmin * T || !settled)) {
            /* behind its data, a longer join only covers the same track
             * more slowly (and meets the curve at the same t_m), and this
             * one's mean speed is below the least it may keep already (or
             * the curve there has not settled); more of the new curve may
             * come by the next tick */
            *short_queue = !f.closed;
            break;
        }
        if (c >= JOIN_STEP_TICKS) {
            step = llround(JOIN_GROWTH * (T - T0) / P);
            step = step < 1 ? 1 : step;
        }
        ticks += step;
    }
    return 0;
}

/* A live sender's re-anchor ended the trajectory the output streams, and the
 * new trajectory's curve is not yet solved far enough to be joined where the
 * join leaves the old one (the start of its last interval, t_j): there the
 * new curve must be queued JOIN_SETTLE_INTERVALS intervals past its start, and
 * the join's least duration (a quintic's across the jump within the scaling's
 * acceleration and jerk) and a stop from rate 1 beyond t_j.  The new curve
 * grows with its waypoints, a second of track time a second; the old curve
 * played at rate r reaches t_j in (t_j - t_now) / r.  Returns 1 if the join
 * waits so (no gap, time that runs on, the new track heading within 60
 * degrees of the old one's: a turn back is no join that keeps moving), with
 * *r (r may be NULL) the rate at which the curve is there by t_j (INFINITY:
 * no need to slow, or past t_j). */
static int join_wait_plan(const engine_t *e, double *r)
{
    if (r)
        *r = INFINITY;
    if (!join_may_wait(e) || e->solve.nodes < 2 || e->solve.nodes > e->solve.ring ||
        e->out.cur.join)
        return 0;
    size_t i = traj_past(e, 0, e->out.traj);
    if (i == 0 || queue_at(e, i - 1)->kind != QE_END)
        return 0;
    const qent_t *end = queue_at(e, i - 1);
    double t_end = end->t1_s, t_n0 = nt(e, 0), t_nw = nt(e, e->solve.nodes - 1);
    if (t_n0 < t_end - 1e-9 || t_n0 - t_end > e->cfg.max_gap_s)
        return 0; /* no join: a gap, or time that does not run on */
    const qent_t *last = i < e->queue.len ? queue_at(e, traj_past(e, i, queue_at(e, i)->traj) - 1)
                                          : NULL; /* the new trajectory's queued end */
    if (last && last->kind == QE_END)
        return 0; /* the new trajectory is whole: join_try's own */
    const double *r0 = e->solve.node_r, *r1 = e->solve.node_r + AX; /* nodes 0, 1 (nr) */
    double d2 = 0, dot = 0, vn2 = 0, vo2 = 0;
    for (int k = 0; k < AX; k++) {
        double vn = r1[k] - r0[k], vo = out_vel(e)[k];
        d2 += (r0[k] - end->seg.c[k][0]) * (r0[k] - end->seg.c[k][0]);
        dot += vn * vo;
        vn2 += vn * vn;
        vo2 += vo * vo;
    }
    if (!(dot > 0.5 * sqrt(vn2 * vo2)))
        return 0;
    if (!r)
        return 1;
    double t_j = join_last_ivl(e, i - 1), t_now = e->out.origin_t + out_s(e), P = e->period_s;
    double h = e->solve.span_max > 0 ? e->solve.span_max / (e->la_steady + 1) : 0.0;
    if (!(h > 0) || !(t_j > t_now))
        return 1;
    double d = sqrt(d2), A = e->cfg.scale_accel_m_s2, Jm = e->cfg.scale_jerk_m_s3;
    double T_j = fmax(sqrt(5.78 * d / A), cbrt(60.0 * d / Jm));
    double t_req = fmax(t_n0 + (JOIN_SETTLE_INTERVALS + 1) * h, t_j + T_j) +
                   stop_room(e, &e->out.cur, 1.0) + 2 * P;
    double t_grow = t_nw - (e->la_steady + 1) * h; /* the solved curve's end, growing */
    if (last)
        t_grow = fmax(t_grow, last->t1_s);
    if (t_req > t_grow)
        *r = (t_j - t_now) / (t_req - t_grow);
    return 1;
}

/* The rate the output keeps on such an old curve (join_wait_plan): the rate
 * at which the new curve is there by t_j, at least JOIN_WAIT_MIN (the join
 * keeps at least JOIN_KEEP of the speed it leaves from, as in an underrun);
 * INFINITY where nothing waits (no later trajectory open, on one clock,
 * under an override, no need). */
double join_wait_rate(const engine_t *e)
{
    double r;
    if (!join_wait_plan(e, &r) || !(r < 1.0))
        return INFINITY;
    return r > JOIN_WAIT_MIN ? r : JOIN_WAIT_MIN;
}

int join_try(engine_t *e)
{
    join_find_t f;
    int never;

    if (!queue_later_traj(e))
        return 0; /* join_find finds none, and never is 0 */
    if (!join_find(e, &f, &never)) {
        if (never)
            e->out.join_refused = e->out.traj + 1;
        return 0;
    }
    /* rho: the rate the join is played at and the new curve entered at,
     * the override (1 on the unit grid) */
    double P = e->period_s, s = out_s(e);
    double t_now = e->out.origin_t + s, A, J, rho = join_rate(e);
    if (e->scale.on && !(e->scale.ts.rate > 0))
        return 0; /* at rest: the transfer's (or the old curve's own end) */
    /* the lead a catch-up allows: on one clock, or to a rate speeding up */
    double acc = e->scale.ts.acc, lead = acc > 0 || e->clk.on ? e->clk.catchup : 0.0;
    if (e->scale.on && !e->out.underrun && (acc < 0 || acc > 0) &&
        e->scale.ts.rate > rho / JOIN_HELD + lead)
        return 0; /* still braking to the join's rate (an override lowered;
                   * on one clock beyond the lead its catch-up allows), or
                   * still speeding up beyond it and the lead any catch-up
                   * allows (a steady rate there is a catch-up's, joined as
                   * before): a join planned at rho from a state braking from
                   * 8 times rho started with 2.9 m/s^3 on a 2 m/s^3 axis,
                   * and one from 9 times rho still speeding up, its
                   * acceleration not yet turned by the jerk, with 3.38
                   * (fuzz_lifecycle); tried again once the rate is there,
                   * else the old curve's end brakes it as it would (not
                   * refused) */
    scale_limits(e, &A, &J);
    /* leave the old curve where its last interval begins, or where the
     * time scaling begins to brake for its end (decide's test, a few ticks
     * early, at rate 1 or the override's if higher), whichever is first */
    double r_hi = fmax(1.0, rho);
    if (t_now < f.t_last_ivl && !e->scale.end_brake &&
        ts_stop_dist(r_hi, 0.0, A, J) < scale_remaining(e, s) - (TS_MARGIN_TICKS + 2) * P * r_hi)
        return 0;
    if (t_now >= f.t_end)
        return 0;
    int short_queue = 0, sq2 = 0;
    if (join_search(e, &f, t_now, rho, &short_queue))
        return 1;
    /* under an override the curves' ceilings (the speed cap, per-axis
     * limits) hold below (the output's rate lower, not by an underrun): at
     * that rate */
    double r = e->scale.ts.rate;
    if (!join_unit(e, rho) && !e->out.underrun && e->scale.on && r > 0 && r < JOIN_HELD * rho &&
        join_search(e, &f, t_now, r, &sq2))
        return 1;
    if (!short_queue && !sq2)
        e->out.join_refused = e->out.traj + 1; /* the stop's, as before */
    return 0;
}

int64_t join_ticks_left(const engine_t *e)
{
    join_find_t f;
    int never;

    if (!queue_later_traj(e) || !join_wanted(e) || !join_find(e, &f, &never))
        return INT64_MAX; /* a push that brings one ends the window (its key) */
    /* the braking for the end: plain_window keeps no decision beyond its
     * start already (decide's test) */
    double x = (f.t_last_ivl - (e->out.origin_t + tau_of(e, e->out.n))) / e->period_s;
    if (!(x > 2))
        return 0;
    return x < 0x1p62 ? (int64_t)x - 2 : INT64_MAX / 2;
}

void join_track_time(engine_t *e)
{
    double s = out_s(e);
    double u = (e->out.origin_t + s - e->out.join_t0) / e->out.join_dur;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    e->out.t = e->out.join_t0 + (e->out.join_tm - e->out.join_t0) * u;
}
