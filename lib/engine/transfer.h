/*
 * transfer.h - how the output moves to a trajectory's start when it does not
 * stand there: after a gap, a re-anchor, a clear, or from the initial
 * position (a re-anchor met while moving is joined without resting where a
 * join fits: lib/engine/join.c).  One rest-to-rest smoothstep per transfer,
 *     k(u) = A + (B - A)(3u^2 - 2u^3),  u in [0, 1] over T seconds,
 * whose peak speed is 1.5 D / T and peak acceleration 6 D / T^2 (D = |B - A|).
 *
 * The duration T follows the object's own limits:
 *     T = max(TRANSFER_MIN_S, 1.5 D / v, sqrt(6 D / a)), rounded up to whole
 * output periods, with
 *   v = transfer_speed_m_s if configured, else derived: the fastest of the
 *       object's recent chord speeds (the trajectory it leaves, the one it
 *       joins), TRANSFER_SPEED_UNKNOWN_M_S if none is known (no interval
 *       kept yet: single-waypoint trajectories), and across a gap at least
 *       D / gap (the object itself covered D in that time);
 *   a = transfer_accel_m_s2 if configured, else derived: the largest recent
 *       implied acceleration of the waypoints kept, or
 *       TRANSFER_ACCEL_UNKNOWN_M_S2 if none is known, and at least v /
 *       TRANSFER_REACH_S.
 * Bounded in time: a derived transfer never lasts longer than max_s (the
 * engine passes max_gap_s: it never spends longer moving between two
 * trajectories than it would wait for a gap) or, across a gap, 1.5 x the gap
 * (the object's own pace) up to TRANSFER_GAP_CAP x max_s, unless
 * TRANSFER_MIN_S is longer or its peak speed would exceed the object's
 * speed limit (vmax_m_s: that comes first, the duration is then
 * 1.5 D / vmax_m_s).  So a derived transfer lasts at most
 * max(TRANSFER_MIN_S, TRANSFER_GAP_CAP x max_s, 1.5 D / vmax_m_s); when cut so its peak speed is 1.5 D / max_s, the one case where a derived
 * transfer outruns the object's recent motion, and transfer_duration says so
 * (*capped).  With both limits configured the duration is not capped: the
 * configured limits are the machine's, and the engine still finishes, in
 * 1.5 D / v + sqrt(6 D / a) at most.
 *
 * Lead (issue 26): an output resting off the start of the input's newest
 * trajectory sets off to it once two of its waypoints are kept (the curve
 * starts on the first: not held or multiple ends, no smoother; and not on a
 * caller's clock, which leads by its own play time), not once that
 * trajectory's output is due, a lookahead and a ramp later.  It then rests
 * on the start until its output is due, and starts from there on the same
 * output track.  The wait for the lookahead and the transfer overlap, so
 * the lag a trajectory after a silence starts with is the transfer's excess
 * over that wait, not the transfer's whole duration.
 */
#ifndef TRAJD_TRANSFER_H
#define TRAJD_TRANSFER_H

#include "fdiff.h"

/* Shortest transfer (seconds). */
#define TRANSFER_MIN_S 1.0
/* Derived speed and acceleration when nothing of the object's motion is
 * known yet (m/s, m/s^2): a walking pace, gentle for any machine that can
 * follow a track at all.  Only then: a known slow object (a toolpath at
 * mm/s) transfers at its own speed. */
#define TRANSFER_SPEED_UNKNOWN_M_S 1.0
#define TRANSFER_ACCEL_UNKNOWN_M_S2 1.0
/* Below these a known speed or acceleration is taken as zero (no division
 * by it): the duration is then capped (max_s). */
#define TRANSFER_SPEED_TINY_M_S 1e-9
#define TRANSFER_ACCEL_TINY_M_S2 1e-9
/* A derived acceleration is at least the transfer's speed over this (s): the
 * object reaches the speed it moves at within it.  Its recent motion may show
 * no acceleration at all (a straight line at constant speed: a rounding
 * residue), which is no limit of the object. */
#define TRANSFER_REACH_S 2.0
/* Across a gap a derived transfer may take 1.5 x the gap, at most this many
 * times max_s (1 h with max_gap_s = 60 s: cerknicko's 894 s gap gives 1341 s). */
#define TRANSFER_GAP_CAP 60.0
/* Kept waypoints whose motion the derived limits look back on. */
#define TRANSFER_HIST 16

typedef struct {
    double speed_m_s;  /* configured transfer speed, 0 = derive */
    double accel_m_s2; /* configured transfer acceleration, 0 = derive */
    double max_s;      /* a derived transfer lasts at most this, > 0 */
    double vmax_m_s;   /* the object's speed limit (max_speed_m_s in force, 0 =
                           none): a derived transfer's peak never exceeds it,
                           before and above max_s */
    double period_s;   /* output period, > 0 */
} transfer_config_t;

/* The object's recent motion, from the waypoints kept. */
typedef struct {
    double v[TRANSFER_HIST], a[TRANSFER_HIST];
    unsigned n, next;
} transfer_motion_t;

void transfer_motion_reset(transfer_motion_t *m);
/* One kept interval: its chord speed and (0 if unknown) implied acceleration. */
void transfer_motion_note(transfer_motion_t *m, double speed_m_s, double accel_m_s2);
double transfer_motion_speed(const transfer_motion_t *m);
double transfer_motion_accel(const transfer_motion_t *m);

/*
 * Duration of a transfer over dist_m (see above), a whole number of periods.
 * v_obj, a_obj: the object's recent speed and acceleration (0 = unknown);
 * gap_s: track time between the two ends when they are across a gap (0 =
 * not a gap).  *capped (may be NULL) is set to 1 when max_s cut it short.
 */
double transfer_duration(const transfer_config_t *c, double dist_m, double v_obj, double a_obj,
                         double gap_s, int *capped);

/* The smoothstep from `from` to `to` over dur_s (> 0), starting at t0_s = 0. */
void transfer_segment(fdiff_seg_t *seg, const double *from, const double *to, double dur_s);

#endif
