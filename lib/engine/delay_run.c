/*
 * delay_run.c - the engine's own play-out delay (delay.h, issue 26): D from
 * its settings and what it measured of the input, the start it holds until
 * the output will stand D behind the newest waypoint, and the D it stated.
 */
#include "delay.h"
#include "engine_int.h"

#include <math.h>
#include <string.h>

#include "accept.h"
#include "catchup.h"
#include "timescale.h"

/* Steps of the start's ramp simulated at most (ramp_lag). */
#define DELAY_RAMP_STEPS_MAX 100000
/* Ticks of the start's ramp taken at once where it rises at A, at most
 * (ramp_lag), and those taken one by one after a run that failed (ramp_lag
 * on bench_engine --start's ramps: 16 and 16, 20.6 M instructions; 32 and
 * 16, 19.9 M; 64 and 16, 19.3 M). */
#define DELAY_RISE_RUN 64
#define DELAY_RISE_RETRY 16
/* Queue entries looked at for the fastest segment ahead (head_vmax). */
#define DELAY_HEAD_SCAN 256

/* The input's interval as measured: span_max (the longest time of
 * la_steady + 1 intervals) over their count; 0 before it is measured. */
static double input_interval(const engine_t *e)
{
    return e->solve.span_max > 0 ? e->solve.span_max / (e->la_steady + 1) : 0.0;
}

/* D for the input's interval h and top speed v, with the slack learnt so
 * far. */
static void delay_at(const engine_t *e, double h, double v, engine_delay_t *d)
{
    /* e->cfg is resolved and e->lookahead its lookahead (engine_new): not
     * resolved again at every tick that asks */
    engine_delay_parts(&e->cfg, e->lookahead, h, v, d);
    if (e->slack_auto) {
        /* the slack in time (delay.h): the parts' least, the arrivals'
         * lateness (J, catchup.c) and the intervals learnt from underruns */
        if (!e->clk.on)
            d->jitter_s = e->lag.jit_s;
        d->slack_n = e->slack_learn;
        d->slack_s += d->jitter_s + e->slack_learn * d->interval_s;
    }
    d->need_s = d->lookahead_s + d->slack_s + d->stop_s;
    /* on the caller's clock (CLOCK.md) the output stands at its D, the
     * daemon's delay_s: that is this object's D, its need the parts */
    double fixed = e->clk.on ? (double)e->clk.delay_ns * 1e-9 : e->cfg.delay_s;
    d->delay_s = fixed > d->need_s ? fixed : d->need_s;
    d->asked_s = fixed > 0 ? fixed : 0.0;
}

/* D now: the settings with the input's interval and top speed as measured
 * (span_max, the longest time of la_steady + 1 intervals, and vmax_in, its
 * fastest chord, both decaying; measured whatever start_slack is). */
static void delay_measured(const engine_t *e, engine_delay_t *d)
{
    delay_at(e, input_interval(e), e->solve.vmax_in, d);
}

/* Time of the newest waypoint received for the current trajectory (as
 * enough_ahead in engine_tick.c, now play_enough_ahead in engine_play.c,
 * did before issue 26): the newest node, or one the acceptance policy
 * holds. */
static double newest(const engine_t *e)
{
    double t = e->solve.nodes > 0 ? nt(e, e->solve.nodes - 1) : -INFINITY;
    const engine_waypoint_t *held = accept_last(&e->in.policy);
    if (held && held->t_s > t)
        t = held->t_s;
    return t;
}

/* The fastest queued segment of the head's trajectory (m/s, at least 1). */
static double head_vmax(const engine_t *e)
{
    double v = 1.0;
    for (size_t i = 0; i < e->queue.len && i < DELAY_HEAD_SCAN; i++) {
        const qent_t *q = queue_at(e, i);
        if (q->kind != QE_SEG || q->traj != queue_at(e, 0)->traj)
            break;
        v = fmax(v, q->vmax);
    }
    return v;
}

/* The room at tick n of the start's ramp, s of track advanced: what the
 * queue holds ahead, and the curve grows as the input comes, a fragment's S
 * segments at a time: at worst S intervals late (g > 0 ? g : 0 is
 * fmax(g, 0) but for -0, which gives R as +0 does: T > 0 is subtracted
 * from it), less TS_MARGIN_TICKS + 1 ticks. */
static inline double ramp_room(double ahead, double lag_grow, int n, double T, double s)
{
    double g = n * T - lag_grow, grown = g > 0 ? g : 0.0;
    return ahead + grown - s - (TS_MARGIN_TICKS + 1) * T;
}

/*
 * Track time the start's ramp from rest to rate 1 loses against the clock:
 * the time scaling's steps (ts_step) from rate 0 with the limits converted
 * at each queued segment's speed bound, as the output will make them, with
 * the curve solved ahead growing as the input keeps coming (one second of
 * track a second).  A ramp from rest loses what a stop from rate 1 at
 * the speeds of the curve where it ramps needs: it builds the stop reserve
 * (a REST start's curve overshoots the waypoints' speed to catch up with
 * them, so the reserve is often more than a stop at their top speed).
 * strict: INFINITY if the curve ahead would hold the ramp back on the way:
 * the start waits until it does not, so that the ramp, and the track-time grid
 * after it, do not depend on the tick at which each waypoint arrives.
 */
static double ramp_lag(const engine_t *e, int strict)
{
    ts_state_t st = {0.0, 0.0};
    size_t i = 0;
    const qent_t *q = queue_at(e, 0);
    double t0 = q->seg.t0_s, s = 0.0, lag = 0.0, T = e->period_s, ahead = t0;
    double h = input_interval(e);
    double lag_grow = (double)(e->cfg.fragment - e->cfg.overlap) * h;

    for (size_t k = 0; k < e->queue.len; k++) {
        const qent_t *p = queue_at(e, k);
        if (p->traj != q->traj)
            break;
        ahead = p->t1_s;
    }
    ahead -= t0;
    /* the limits at q (A, J and what ts_step derives from them) */
    const qent_t *lq = NULL;
    ts_lims_t l;
    int rise_at = 0; /* the first tick a run at A is tried on */
    for (int n = 0; n < DELAY_RAMP_STEPS_MAX; n++) {
        while (s >= q->t1_s - t0 && i + 1 < e->queue.len) {
            const qent_t *nq = queue_at(e, i + 1);
            if (nq->kind != QE_SEG || nq->traj != q->traj)
                break;
            i++;
            q = nq;
        }
        if (q != lq) {
            double v = fmax(q->vmax, 1.0);
            ts_lims_init(&l, e->cfg.scale_accel_m_s2 / q->av, e->cfg.scale_jerk_m_s3 / v, T);
            lq = q;
        }
        /* a run of ticks rising at A on q, ts_step_one's plainest: taken
         * as it takes them (rate + A T, advance rate T + A T^2 / 2), then
         * checked at once on the run's least room and highest rate
         * (ts_rise_holds: no free step is due in it either); undone, and
         * DELAY_RISE_RETRY ticks taken one by one, where it fails */
        if (n >= rise_at && l.ok && st.acc >= l.A && st.acc <= l.A) {
            double r = st.rate, r_last = r, R_min = INFINITY, s_was = s, lag_was = lag;
            double s_end = q->t1_s - t0;
            int k = 0, k_max = DELAY_RAMP_STEPS_MAX - n;
            k_max = k_max < DELAY_RISE_RUN ? k_max : DELAY_RISE_RUN;
            for (; k < k_max && !(s >= s_end); k++) {
                double R = ramp_room(ahead, lag_grow, n + k, T, s), ds = r * T + l.ca;
                R_min = R >= R_min ? R_min : R; /* a NaN taken */
                r_last = r;
                r = r + l.at;
                s += ds;
                lag += T - ds;
            }
            if (k > 0 && ts_rise_holds(&l, R_min, st.rate, r_last)) {
                st.rate = r;
                n += k - 1;
                continue;
            }
            s = s_was;
            lag = lag_was;
            rise_at = n + DELAY_RISE_RETRY;
        }
        double R = ramp_room(ahead, lag_grow, n, T, s);
        ts_state_t free_st = st;
        int lim = 0;
        double ds = ts_step_one(&st, &l, R, &lim);
        /* the step without the curve's end differs only where the end
         * limited it, or in a landing on rate 1 (within A T of it), which
         * ts_step makes only if it leaves room: the free step is taken
         * there alone, and not where ts_step made it already (TS_LIM_FREE:
         * the end lowered the target of a ramp still rising at its
         * acceleration or jerk limit; TS_ONE_FREE: the end neither limited
         * ts_step_one's move nor refused its landing).  With both on every
         * step, and the ramp simulated twice on the start's tick, that tick
         * took 28 us per object (tests/bench/bench_engine --start,
         * tests/bench/RESULTS.md) */
        if (strict && !(lim & (TS_LIM_FREE | TS_ONE_FREE)) &&
            ((lim & 1) || fabs(1.0 - free_st.rate) <= l.at) &&
            ds < ts_step(&free_st, 1.0, INFINITY, l.A, l.J, T, NULL, NULL))
            return INFINITY; /* held back by the curve ahead: the ramp would
                              * depend on when each waypoint comes (wait) */
        s += ds;
        lag += T - ds;
        if (!(st.rate < 1.0 || st.rate > 1.0) && !(st.acc < 0.0 || st.acc > 0.0))
            break;
    }
    return lag;
}

/* delay_if_started's D of a start from the wait and the ramp's loss. */
static void delay_started(const engine_t *e, engine_delay_t *d, double *lag, double known,
                          double waited, int counted)
{
    /* the ramp loses at most a stop at the fastest speed ahead */
    if (!counted && waited < d->delay_s - engine_delay_stop_s(&e->cfg, head_vmax(e)))
        return;
    /* a batch written ahead of its stamps (an upload) is not steered
     * (catchup.h): its output stands further behind than any D, and D is
     * what its input needs, not where the batch left the start */
    if (e->lag.ahead)
        return;
    *lag = isfinite(known) ? known : ramp_lag(e, 1);
    /* what the ramp loses if it started now anyway (held back: more) */
    double loss = isfinite(*lag) ? *lag : ramp_lag(e, 0);
    /* on a clock the start's ramp is a lag the clock wins back (CLOCK.md
     * "Behind"), not a longer D: age_s returns to the clock's D */
    if (e->clk.on)
        return;
    if (counted || (!d->slack_ticks && waited + loss > d->delay_s + 0.5 * d->interval_s)) {
        /* the wait the lookahead needs plus the ramp exceed D (by more than
         * the half interval a start is rounded to): D is that */
        d->delay_s = waited + loss;
        d->stop_s = d->delay_s - d->lookahead_s - d->slack_s;
        d->need_s = d->delay_s;
    }
}

/* The output of the head's trajectory starting now: the D it will hold
 * (the time waited plus the ramp's loss, *lag; NAN: not simulated, the wait
 * short of D by more than any ramp loses) into d; returns the time waited.
 * A ramp that loses more than D less the wait (a REST start's curve faster
 * than its waypoints) sets D: the output stands there after it, and that is
 * no lag to win back (catchup.h): the track-time grid after a start does not
 * depend on when each waypoint came.  An upload's D is not raised so.  A
 * fixed start_slack's D is the wait plus the loss, less or more. */
static double delay_if_started(const engine_t *e, engine_delay_t *d, double *lag, double known)
{
    /* a fixed start_slack starts by count and is not steered to D after
     * (catchup.h): its D is where that start leaves the output */
    int counted = !(e->slack_auto || e->cfg.delay_s > 0);
    /* the D a trajectory before this one stated (d may be e->delay.d) */
    double before = e->delay.noted && !counted ? e->delay.d.delay_s : 0.0;
    delay_measured(e, d);
    double need = d->delay_s;
    *lag = NAN;
    if (!e->queue.len || queue_at(e, 0)->kind != QE_SEG)
        return 0.0;
    double waited = newest(e) - queue_at(e, 0)->seg.t0_s;
    delay_started(e, d, lag, known, waited, counted);
    /* a trajectory after a silence, a gap or a re-anchor: its start makes D
     * no longer than the D stated before it (or what its input needs, if
     * more): where the start leaves the output beyond that (the input
     * buffered while the output played out the last one and transferred)
     * is lag, won back (catchup.h), not a longer D for good (a 1 s hole at
     * 10 Hz made D 1 s longer for the rest of the track) */
    double cap = fmax(before, need);
    if (before > 0 && !e->lag.ahead && d->delay_s > cap) {
        d->delay_s = d->need_s = cap;
        d->stop_s = d->delay_s - d->lookahead_s - d->slack_s;
    }
    return waited;
}

int engine_delay_ready(const engine_t *e, double *lag_out)
{
    engine_delay_t d;
    double lag;

    if (lag_out)
        *lag_out = NAN;
    if (!e->queue.len || queue_at(e, 0)->kind != QE_SEG)
        return 1;
    /* a buffer that cannot take the input D needs: start, rather than wait
     * for waypoints the sender cannot give (ENGINE_EFULL) */
    if (input_buffered(e) + e->cfg.fragment + 8 >= e->cfg.capacity)
        return 1;
    delay_measured(e, &d);
    double waited = newest(e) - queue_at(e, 0)->seg.t0_s;
    if (waited >= d.delay_s)
        return 1;
    /* the ramp loses at most a stop at the fastest speed ahead */
    if (waited < d.delay_s - engine_delay_stop_s(&e->cfg, head_vmax(e)))
        return 0;
    /* the first tick at which the output, after a ramp the curve ahead does
     * not hold back, stands within half an interval of D */
    lag = ramp_lag(e, 1);
    if (lag_out)
        *lag_out = lag;
    return isfinite(lag) && waited + lag >= d.delay_s - 0.5 * d.interval_s;
}

void engine_delay_note(engine_t *e, double known)
{
    double lag;
    (void)delay_if_started(e, &e->delay.d, &lag, known);
    e->delay.noted = 1;
    e->delay.learnt = e->slack_learn;
}

/* How far from a whole number of the median interval a regular sender's
 * interval may be (engine_interval_holes): its stamps' jitter. */
#define REGULAR_TOL 0.05

/* The k-th smallest (from 0) of v[0 .. n) (Hoare's FIND: v is reordered). */
static double kth_smallest(double *v, unsigned n, unsigned k)
{
    int l = 0, m = (int)n - 1, ki = (int)k;
    while (l < m) {
        double x = v[ki];
        int i = l, j = m;
        do {
            while (v[i] < x)
                i++;
            while (x < v[j])
                j--;
            if (i <= j) {
                double t = v[i];
                v[i] = v[j];
                v[j] = t;
                i++;
                j--;
            }
        } while (i <= j);
        if (j < ki)
            l = i;
        if (ki < i)
            m = j;
    }
    return v[ki];
}

/* The ring's n intervals written up to next, oldest first, into a; returns
 * their median (the (n/2)-th smallest). */
static double ring_read(const double *iv, unsigned n, unsigned next, double *a)
{
    double v[ENGINE_IV_RING];
    for (unsigned i = 0; i < n; i++)
        a[i] = iv[(next + ENGINE_IV_RING - n + i) % ENGINE_IV_RING];
    memcpy(v, a, n * sizeof v[0]);
    return kth_smallest(v, n, n / 2);
}

/* The input's interval as D is grown to it (engine_delay_grow): of the
 * last intervals (engine_solve_t iv), the longest time of la_steady + 1 in a
 * row, each with its longest interval taken as the median instead, over
 * their count: a sender that slows down counts, a hole of a few lost
 * fixes does not (it is an underrun once, logged, not a longer D for good).
 * 0 before there are enough.  On the push path, and on the same push for
 * every object that replays the same track: the median by a selection of
 * expected linear work (kth_smallest), the windows over the ring laid out in
 * arrival order, each window summed in its own order as before (the same
 * result, bit for bit: test_delay_robust). */
double engine_interval_robust(const double *iv, unsigned n, unsigned next, unsigned w)
{
    double a[ENGINE_IV_RING], med;
    if (n > ENGINE_IV_RING || n < w || w == 0)
        return 0.0;
    med = ring_read(iv, n, next, a);
    /* each window's sum from its oldest interval on (0 + x is x), its
     * longest by comparison (fmax: the intervals are > 0, measure_input);
     * four windows at a time, each in its own order */
    double best = 0.0;
    unsigned s = 0, m = n - w + 1;
    for (; s + 4 <= m; s += 4) {
        double s0 = a[s], s1 = a[s + 1], s2 = a[s + 2], s3 = a[s + 3];
        double m0 = s0, m1 = s1, m2 = s2, m3 = s3;
        for (unsigned i = 1; i < w; i++) {
            double x0 = a[s + i], x1 = a[s + i + 1], x2 = a[s + i + 2], x3 = a[s + i + 3];
            s0 += x0;
            s1 += x1;
            s2 += x2;
            s3 += x3;
            m0 = x0 > m0 ? x0 : m0;
            m1 = x1 > m1 ? x1 : m1;
            m2 = x2 > m2 ? x2 : m2;
            m3 = x3 > m3 ? x3 : m3;
        }
        best = fmax(best, s0 - m0 + med);
        best = fmax(best, s1 - m1 + med);
        best = fmax(best, s2 - m2 + med);
        best = fmax(best, s3 - m3 + med);
    }
    for (; s < m; s++) {
        double sum = a[s], mx = a[s];
        for (unsigned i = 1; i < w; i++) {
            sum += a[s + i];
            mx = a[s + i] > mx ? a[s + i] : mx;
        }
        best = fmax(best, sum - mx + med);
    }
    return best / w;
}

/* A regular sender's interval with its lost fixes filled in: every
 * interval of the ring within REGULAR_TOL of a whole number k >= 1 of their
 * median (a fix lost is a slot of the sender's clock left empty), each taken
 * as its k-th part; the longest time of w slots in a row over w.  0 when an
 * interval is not such a multiple (a sender whose timing varies: its holes
 * are its timing, engine_interval_robust) or with fewer than w. */
double engine_interval_holes(const double *iv, unsigned n, unsigned next, unsigned w)
{
    double a[ENGINE_IV_RING];
    if (n > ENGINE_IV_RING || n < w || w == 0)
        return 0.0;
    double med = ring_read(iv, n, next, a);
    for (unsigned i = 0; i < n; i++) {
        double k = round(a[i] / med);
        if (!(k >= 1.0) || fabs(a[i] - k * med) > REGULAR_TOL * med)
            return 0.0;
        a[i] /= k;
    }
    double best = 0.0;
    for (unsigned s = 0; s + w <= n; s++) {
        double sum = 0.0;
        for (unsigned i = 0; i < w; i++)
            sum += a[s + i];
        best = fmax(best, sum);
    }
    return best / w;
}

static double interval_holes(const engine_t *e)
{
    return engine_interval_holes(e->solve.iv, e->solve.iv_n, e->solve.iv_next, e->la_steady + 1);
}

int engine_input_regular(const engine_t *e)
{
    return interval_holes(e) > 0.0;
}

int engine_input_hole(const engine_t *e, double gap_s)
{
    double h = interval_holes(e), k = h > 0.0 ? round(gap_s / h) : 0.0;
    return k >= 2.0 && fabs(gap_s - k * h) <= REGULAR_TOL * h;
}

/* A regular sender's lost fixes are holes, slowed for and won back
 * (engine_delay_reserve_short), not a longer D for good: the 24 h run of
 * issue 26 (1 % lost) ends with its starting lag. */
static double interval_robust(const engine_t *e)
{
    double h = engine_interval_robust(e->solve.iv, e->solve.iv_n, e->solve.iv_next,
                                      e->la_steady + 1);
    double r = interval_holes(e);
    return r > 0.0 ? fmin(h, r) : h;
}

void engine_delay_grow(engine_t *e)
{
    engine_delay_t d;
    if (!e->delay.noted)
        return;
    /* the interval D is sized for: the one measured, its longest interval
     * the median's (interval_robust).  D rises with the interval and the
     * robust one is at most the measured one: if that does not grow D, the
     * robust one (a selection over the ring, on the push path) is not needed */
    double h = input_interval(e);
    /* a D that grows keeps the top speed it stated: the measured one
     * decays while the object moves slower, and a reserve shrunk to it
     * would be short once the object is back at that speed (a slowdown for
     * it, then D grown again: tests/unit/test_delay_grow.c) */
    double v = fmax(e->solve.vmax_in, e->delay.d.speed_m_s);
    delay_at(e, h, v, &d);
    if (!(d.delay_s > e->delay.d.delay_s + 1e-9))
        return;
    delay_at(e, fmin(h, interval_robust(e)), v, &d);
    if (d.delay_s > e->delay.d.delay_s + 1e-9) {
        e->delay.d = d;
        e->delay.learnt = e->slack_learn;
        e->st.delay_grown++;
    }
}

void engine_delay_restate(engine_t *e)
{
    if (e->slack_auto || e->cfg.delay_s > 0 || !e->delay.noted)
        return;
    double at = engine_lag_trailing(e);
    if (!isfinite(at))
        return;
    e->delay.d.delay_s = e->delay.d.need_s = at;
    e->delay.d.stop_s = at - e->delay.d.lookahead_s - e->delay.d.slack_s;
}

int engine_delay_reserve_short(const engine_t *e)
{
    engine_delay_t d;
    if (!e->sil.arrived || e->sil.traj != e->out.traj || !e->out.have_now)
        return 0;
    engine_delay(e, &d);
    if (!(d.interval_s > 0))
        return 0;
    double since = (double)(e->out.last_now - e->sil.arrival_ns) * 1e-9;
    if (!(since <= d.interval_s + d.slack_s + e->period_s))
        return 0;
    if (e->sil.last_t - e->scale.avail_t <= d.lookahead_s + e->period_s)
        return 1;
    /* longer in time than D's lookahead, the same in waypoints: fixes lost
     * within it (each a hole of an interval more, the next on time).  The
     * curve then ends as far as the waypoints received let the solver take
     * it, at most la_steady nodes before the newest, and the acceptance
     * judges no more than a refused fix's verdict holds (the fix after it,
     * ACCEPT_LAG + 1; a run it judges, a re-anchor's confirm or a dead stop's
     * repeats, stays an underrun, told as such); two lost within one
     * lookahead at 2 Hz were an underrun of an input on time (issue 26's
     * 24 h run) */
    unsigned after = 0;
    for (uint64_t j = e->solve.nodes; j-- > 0 && after <= e->la_steady;) {
        if (!(nt(e, j) > e->scale.avail_t))
            break;
        after++;
    }
    return after <= e->la_steady && accept_pending(&e->in.policy) <= ACCEPT_LAG + 1 ? 2 : 0;
}

void engine_delay(const engine_t *e, engine_delay_t *d)
{
    if (!e->delay.noted) {
        delay_measured(e, d);
        return;
    }
    /* D as stated at the start, and an interval more for each underrun
     * since (start_slack auto learns them: the input came later than its
     * stamps said, the slack it kept was too short): what the output is
     * steered to (catchup.h), so stated (the summary, the log, Modbus) as
     * well; it stood an interval beyond the D it stated */
    *d = e->delay.d;
    if (e->slack_learn > e->delay.learnt) {
        unsigned more = e->slack_learn - e->delay.learnt;
        double s = (double)more * d->interval_s;
        d->slack_n += more;
        d->slack_s += s;
        d->need_s += s;
        d->delay_s += s;
    }
}
