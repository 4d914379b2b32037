/* transfer.c - rest-to-rest transfers within the object's limits; see transfer.h. */
#include "transfer.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

void transfer_motion_reset(transfer_motion_t *m)
{
    memset(m, 0, sizeof *m);
}

void transfer_motion_note(transfer_motion_t *m, double speed_m_s, double accel_m_s2)
{
    m->v[m->next] = isfinite(speed_m_s) ? speed_m_s : 0;
    m->a[m->next] = isfinite(accel_m_s2) ? accel_m_s2 : 0;
    m->next = (m->next + 1) % TRANSFER_HIST;
    if (m->n < TRANSFER_HIST)
        m->n++;
}

static double ring_max(const double *x, unsigned n)
{
    double m = 0;
    for (unsigned i = 0; i < n; i++)
        if (x[i] > m)
            m = x[i];
    return m;
}

double transfer_motion_speed(const transfer_motion_t *m)
{
    return ring_max(m->v, m->n);
}

double transfer_motion_accel(const transfer_motion_t *m)
{
    return ring_max(m->a, m->n);
}

double transfer_duration(const transfer_config_t *c, double dist_m, double v_obj, double a_obj,
                         double gap_s, int *capped)
{
    double v = c->speed_m_s, a = c->accel_m_s2, dur, cap;
    int derived = !(v > 0 && a > 0);

    if (!(v > 0)) {
        /* the object's own speed; across a gap at least what it needed to
         * cover it (never slower than the object was) */
        v = v_obj > 0 ? v_obj : TRANSFER_SPEED_UNKNOWN_M_S;
        if (gap_s > 0)
            v = fmax(v, dist_m / gap_s);
        v = fmax(v, TRANSFER_SPEED_TINY_M_S);
    }
    if (!(a > 0)) {
        /* the object's own, at least what reaches its speed within
         * TRANSFER_REACH_S: a straight line at constant speed shows none (a
         * rounding residue of 1e-14 m/s^2 made a 1 m transfer last max_s) */
        a = fmax(a_obj > 0 ? a_obj : TRANSFER_ACCEL_UNKNOWN_M_S2, v / TRANSFER_REACH_S);
        a = fmax(a, TRANSFER_ACCEL_TINY_M_S2);
    }
    /* smoothstep: peak speed 1.5 D / T, peak acceleration 6 D / T^2 */
    dur = fmax(1.5 * dist_m / v, sqrt(6.0 * dist_m / a));
    if (capped)
        *capped = 0;
    /* across a gap the object itself took gap_s: 1.5 gap_s is its own pace,
     * up to TRANSFER_GAP_CAP x max_s (a gap of days is not a pace) */
    cap = fmax(c->max_s, fmin(1.5 * gap_s, TRANSFER_GAP_CAP * c->max_s));
    if (derived && dur > cap) {
        dur = cap;
        if (capped)
            *capped = 1;
    }
    /* never faster than the object may go: its speed limit comes first */
    if (derived && c->vmax_m_s > 0 && dur < 1.5 * dist_m / c->vmax_m_s) {
        dur = 1.5 * dist_m / c->vmax_m_s;
        if (capped)
            *capped = 0;
    }
    if (dur < TRANSFER_MIN_S)
        dur = TRANSFER_MIN_S;
    /* whole periods: the transfer ends exactly on a tick (period_s > 0) */
    return (double)(int64_t)ceil(dur / c->period_s) * c->period_s;
}

void transfer_segment(fdiff_seg_t *seg, const double *from, const double *to, double dur_s)
{
    memset(seg, 0, sizeof *seg);
    seg->t0_s = 0;
    seg->dur_s = dur_s;
    for (int i = 0; i < FDIFF_AXES; i++) {
        double d = to[i] - from[i];
        seg->c[i][0] = from[i];
        seg->c[i][1] = 0.0;
        seg->c[i][2] = 3.0 * d;
        seg->c[i][3] = -2.0 * d;
    }
}
