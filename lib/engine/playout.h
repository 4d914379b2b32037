/*
 * playout.h - one clock for every object (issue 16 item 2): the sender's
 * clock rate estimated from arrivals, and the play-out clock that the
 * daemon passes to every engine (engine_set_clock).  Pure: arrival times are
 * passed in, no clock is read here.  See lib/engine/CLOCK.md.
 *
 * Drift.  A sender stamps waypoints with its own clock; trajd receives them
 * at arrival times on its CLOCK_REALTIME.  With the sender's clock running
 * at (1 + eps) times ours, d = arrival - stamp = c - eps * arrival + delay,
 * where delay >= 0 is the transport's variable latency.  The estimator keeps,
 * per window of PLAYOUT_WINDOW_S of arrival time, the sample of least d (the
 * least-delayed one: latency only ever adds), and fits a line through the
 * last PLAYOUT_WINDOWS window minima by Theil-Sen (the median of the slopes
 * of every pair: robust to up to 29 % of windows with a wrong floor, e.g. a
 * sender whose clock stepped, or an object that stopped sending).  eps is
 * minus that slope, clamped to +-max_ppm, and valid from PLAYOUT_MIN_WINDOWS
 * windows on (0 before).
 *
 * Play-out clock.  now_sender(t) = t + drift(t), where t is trajd's clock and
 * drift integrates the applied estimate: d drift/dt = eps_applied.  The
 * applied estimate follows the estimator at PLAYOUT_SLEW_PPM_S at most, so
 * the play-out rate 1 + eps_applied changes smoothly (an object locked on
 * the clock then gains at most k'(s) * 1e-6 m/s^2 of acceleration from it).
 * The offset between the sender's clock and trajd's is not estimated (it
 * cannot be told from the mean latency): it is taken as 0 when the clock
 * starts, and the play-out delay D covers it.
 */
#ifndef TRAJD_PLAYOUT_H
#define TRAJD_PLAYOUT_H

#include <stdint.h>

#define PLAYOUT_WINDOW_S 60.0  /* arrival time per window minimum */
#define PLAYOUT_WINDOWS 64     /* window minima kept: the fit spans about an hour */
#define PLAYOUT_MIN_WINDOWS 3  /* windows before the estimate is used */
#define PLAYOUT_SLEW_PPM_S 1.0 /* the applied drift moves at most this fast, ppm per second */
#define PLAYOUT_MAX_PPM 500.0  /* default bound on the drift absorbed */

typedef struct {
    double max_ppm; /* |eps| absorbed at most, ppm */
    int64_t ref_ns; /* arrival time origin (the first sample) */
    int have_ref;
    int64_t win_end_ns;  /* the current window ends here */
    int win_n;           /* samples in the current window */
    double win_a, win_d; /* its least d and that sample's arrival (s from ref) */
    double wa[PLAYOUT_WINDOWS], wd[PLAYOUT_WINDOWS]; /* closed windows, ring */
    unsigned nwin, head;
    double eps; /* current estimate (fraction, + = sender fast) */
    int valid;
    uint64_t samples;
    double scratch[PLAYOUT_WINDOWS * (PLAYOUT_WINDOWS - 1) / 2];
} playout_drift_t;

/* Start with no sample; max_ppm >= 0 bounds the estimate (0: no drift is
 * absorbed; negative: PLAYOUT_MAX_PPM).  A zeroed struct is the same with
 * max_ppm 0. */
void playout_drift_init(playout_drift_t *d, double max_ppm);

/* One waypoint: received at arrival_ns (trajd's clock, ns since the epoch),
 * stamped stamp_s by the sender (seconds since the epoch).  Samples must come
 * in arrival order (a sample earlier than the current window is ignored). */
void playout_drift_add(playout_drift_t *d, int64_t arrival_ns, double stamp_s);

/* The estimate: the sender's clock rate minus 1 (100e-6 = 100 ppm fast), 0
 * until valid; within +-max_ppm. */
double playout_drift_eps(const playout_drift_t *d);

typedef struct {
    int started;
    int64_t last_ns; /* trajd's clock at the last advance */
    double drift_ns; /* now_sender - trajd's clock, integrated */
    double eps;      /* applied drift (slewed) */
} playout_clock_t;

/* Not started: the first playout_clock_now starts it at offset 0. */
void playout_clock_init(playout_clock_t *c);

/*
 * The sender's time base at trajd's time real_ns (ns since the epoch), with
 * the drift applied moving towards eps_target at PLAYOUT_SLEW_PPM_S at most.
 * real_ns should not go backwards: a step back (the system clock was set)
 * is passed through with no drift accrued for it.  *rate (may be NULL)
 * receives 1 + the applied drift: d now_sender / dt.
 */
int64_t playout_clock_now(playout_clock_t *c, int64_t real_ns, double eps_target, double *rate);

#endif
