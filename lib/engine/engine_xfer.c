/*
 * engine_xfer.c - the transfer stage: a trajectory that does not start where
 * the output stands is reached by a rest-to-rest transfer (transfer.h).  Its
 * duration from the distance, the object's recent motion (noted by the
 * input stage) and the speed of the trajectory it joins; its start as the
 * output's current segment; and the track time a transfer reports.  It owns
 * engine_xfer_t (engine_int.h): the transfers' configuration, the object's
 * recent motion and where the transfer under way began.
 */
#include "engine.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "fdiff.h"
#include "transfer.h"

/* Fastest chord speed of the first queued segments of the trajectory at the
 * queue head: how the object moves where the transfer takes it. */
static double head_speed(const engine_t *e)
{
    double v = 0;

    for (size_t i = 0; i < e->queue.len && i < TRANSFER_HIST; i++) {
        const qent_t *q = queue_at(e, i);
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
double xfer_duration(const engine_t *e, const double *target, double gap_s, int *capped)
{
    double dist = 0, v_obj;

    for (int i = 0; i < AX; i++)
        dist += (target[i] - out_pos(e)[i]) * (target[i] - out_pos(e)[i]);
    dist = sqrt(dist);
    v_obj = fmax(transfer_motion_speed(&e->xfer.motion), head_speed(e));
    double dur = transfer_duration(&e->xfer.cfg, dist, v_obj,
                                   transfer_motion_accel(&e->xfer.motion), gap_s, capped);
    /* issue 32: long enough for every axis's limits (engine.h axis_max_*):
     * the smoothstep's peak speed 1.5 D/T, acceleration 6 D/T^2, jerk 12 D/T^3
     * per axis, the jerk within half the limit as on the curve */
    double dur0 = dur;
    if (e->cfg.cap_accel_m_s2 > 0) /* the caller's cap (engine.h): the peak 6 D/T^2 within
                                      what the time scaling's share leaves, at rate 1 at most
                                      (scale_ceil_here) */
        dur = fmax(dur, sqrt(6.0 * dist / (e->cfg.cap_accel_m_s2 - e->cfg.scale_accel_m_s2)));
    for (int k = 0; k < AX; k++) {
        double d = fabs(target[k] - out_pos(e)[k]);
        if (e->cfg.axis_max_speed_m_s[k] > 0)
            dur = fmax(dur, 1.5 * d / e->cfg.axis_max_speed_m_s[k]);
        if (e->cfg.axis_max_accel_m_s2[k] > 0)
            dur = fmax(dur, sqrt(6.0 * d / e->cfg.axis_max_accel_m_s2[k]));
        if (e->cfg.axis_max_jerk_m_s3[k] > 0)
            dur = fmax(dur, cbrt(24.0 * d / e->cfg.axis_max_jerk_m_s3[k]));
    }
    if (dur > dur0) /* whole periods, as transfer_duration's */
        dur = ceil(dur / e->period_s) * e->period_s;
    return dur;
}

int xfer_lead_target(const engine_t *e, double *target, double *t0_s, double *gap_s)
{
    /* a resting output, off a clock (which leads by its own play time:
     * CLOCK.md), with a curve that starts on its first waypoint (not held
     * or multiple ends, no smoother moving it) */
    if (e->clk.on || e->out.mode != OUT_HOLD || !e->out.have_pos || e->scale.stop_req || e->held ||
        e->smooth)
        return 0;
    if (e->queue.len) {
        const qent_t *h = queue_at(e, 0);
        if (h->kind != QE_SEG || !h->first || h->traj == e->out.traj)
            return 0;
        for (int k = 0; k < AX; k++)
            target[k] = h->seg.c[k][0];
        *t0_s = h->seg.t0_s;
        *gap_s = h->gap_s;
    } else {
        /* none queued yet: the input's open trajectory, once two of its
         * waypoints are kept (a chord: the pace it moves at, transfer.h) */
        if (!e->in.open || e->solve.traj == e->out.traj || e->solve.nodes < 2 ||
            e->solve.nodes > e->solve.ring)
            return 0;
        const double *r = e->solve.node_r + 0; /* node 0 (nr), read only */
        for (int k = 0; k < AX; k++)
            target[k] = r[k];
        *t0_s = nt(e, 0);
        *gap_s = e->in.gap_s;
    }
    double d2 = 0;
    for (int k = 0; k < AX; k++)
        d2 += (target[k] - out_pos(e)[k]) * (target[k] - out_pos(e)[k]);
    return sqrt(d2) > ENGINE_TRANSFER_TOL_M;
}

/* Start a transfer from the output position to target (transfer.h). */
void xfer_start(engine_t *e, const double *target, double gap_s, double lead_t_s)
{
    int capped = 0;
    double dur = xfer_duration(e, target, gap_s, &capped);

    memset(&e->out.cur, 0, sizeof(e->out.cur));
    e->xfer.from_t = e->out.track ? e->out.t : NAN;
    e->xfer.lead = isfinite(lead_t_s);
    e->xfer.to_t = lead_t_s;
    e->out.cur.kind = QE_SEG;
    transfer_segment(&e->out.cur.seg, out_pos(e), target, dur);
    e->out.cur.vmax = solve_seg_speed_max(&e->out.cur.seg);
    e->out.cur.av = 0.0; /* its limits converted at its speed (scale_conv_speed) */
    e->out.cur_t0 = 0;
    e->out.cur_t1 = e->out.cur.seg.dur_s;
    e->out.n = 0;
    e->out.seg_n0 = 0;
    e->scale.s_off = 0.0;
    e->out.track++;
    e->out.flags_pending |= ENGINE_SP_NEW_TRACK;
    e->out.mode = OUT_XFER;
    e->st.transfers++;
    e->st.transfer_s += dur;
    e->st.transfers_capped += (uint64_t)capped;
    play_seed_cur(e, 0);
}

/* A transfer's track time: from where the output's time stood when it began
 * to the start of the trajectory it joins, in proportion to the transfer
 * done (from that start less the transfer's duration if the output had no
 * time before), so t_s and the data age say what the object does and reach
 * that start as it does. */
void xfer_track_time(engine_t *e)
{
    const qent_t *h = e->queue.len ? &e->queue.ent[e->queue.head] : NULL; /* q_head, read only */
    if ((!h && !e->xfer.lead) || !(e->out.cur_t1 > 0))
        return;
    double t = out_s(e), u = t / e->out.cur_t1;
    double to = e->xfer.lead ? e->xfer.to_t : h->kind == QE_END ? h->t1_s : h->seg.t0_s;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    if (isnan(e->xfer.from_t))
        e->out.t = to - (1.0 - u) * e->out.cur_t1;
    else
        e->out.t = e->xfer.from_t + (to - e->xfer.from_t) * u;
}
