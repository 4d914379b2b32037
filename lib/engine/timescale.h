/*
 * timescale.h - the time scaling s(t) between the curve and every output.
 *
 * The engine's curve is a function of track time, k(s).  The output does not
 * evaluate it at the tick's own time but at s(t), a track time that advances
 * at the rate r = ds/dt.  r = 1 is the curve as solved; r < 1 slows down
 * along the same path, r = 0 stands still on it, r up to 2 is a feed
 * override above 100 %.  The setpoint is then (chain rule)
 *
 *     position      k(s)
 *     velocity      k'(s) r
 *     acceleration  k''(s) r^2 + k'(s) a          (a = dr/dt)
 *     jerk          k'''(s) r^3 + 3 k''(s) r a + k'(s) j   (j = da/dt)
 *
 * so the path never changes, only the speed along it.  This module keeps the
 * state (r, a) and chooses j once per tick, piecewise constant over the
 * tick, with |j| <= J and |a| <= A (J, A in rate units: 1/s^2 and 1/s).
 * The engine turns physical limits into rate units with the curve's speed
 * v = |k'(s)| at the current point: A = accel_m_s2 / max(v, v_floor),
 * J = jerk_m_s3 / max(v, v_floor), so the term k'(s) a that the scaling adds
 * to the acceleration is at most accel_m_s2 and k'(s) j adds at most
 * jerk_m_s3 to the jerk (see lib/engine/TIMESCALE.md for the whole bound).
 *
 * Every use of the scaling is one target rate and one distance:
 *   - feed override: target = override (0 .. 2);
 *   - stop now, clear: target = 0;
 *   - underrun: R = track time still available ahead (the curve's solved
 *     segments end there); the rate is capped by ts_rate_max(R), the highest
 *     rate from which the output can still come to rest within R, so it
 *     slows down smoothly as the buffer drains and speeds up again as it
 *     fills;
 *   - catch-up: target slightly above 1 until a lag is won back.
 * ts_step never lets the state leave the set from which rest within R is
 * reachable (it brakes when the move it would rather make would leave it),
 * up to the discretisation error that TS_MARGIN_TICKS of margin absorbs.
 *
 * Pure: no allocation, no I/O, no clock.  Continuous-time formulas for the
 * stopping distance (a jerk-limited "S-curve"), exact cubic integration of
 * the state over a tick.
 */
#ifndef TRAJD_TIMESCALE_H
#define TRAJD_TIMESCALE_H

#include <math.h>
#include <stddef.h>

/* Highest rate (feed override 200 %). */
#define TS_RATE_MAX 2.0
/* Track time kept in reserve before the end of the solved curve, in ticks at
 * the current rate (the engine's scale_remaining()): absorbs the discretisation of
 * the braking (the continuous-time stopping distance is exact to O(r T) per
 * tick); none at rest, so a buffer shorter than the margin cannot deadlock. */
#define TS_MARGIN_TICKS 2.0

/* Largest dead band of the rate (ts_dead_band): at long periods J T^2 can
 * exceed 1, and a target below it would never be left from rest. */
#define TS_DEAD_BAND_MAX 1e-3

typedef struct {
    double rate; /* r = ds/dt (1 = as solved) */
    double acc;  /* a = dr/dt, 1/s */
} ts_state_t;

/*
 * Track time (s-distance) needed to come to rest, r = a = 0, from (r, a)
 * with |a| <= A and |da/dt| <= J, braking as hard as the limits allow
 * (continuous time).  0 if r <= 0.  A, J > 0.
 */
double ts_stop_dist(double r, double a, double A, double J);

/*
 * Highest rate r from which rest (starting with a = 0) is reached within R:
 * the inverse of ts_stop_dist(r, 0, A, J).  0 if R <= 0, INFINITY if R is.
 */
double ts_rate_max(double R, double A, double J);

/*
 * A target rate below this is taken as 0 (rest comes exactly): J T^2, at
 * most TS_DEAD_BAND_MAX.
 */
double ts_dead_band(double J, double T);

/*
 * Advance the state by one tick of T seconds towards target (clamped to
 * 0 .. TS_RATE_MAX) without ever needing more than R of track time to stop
 * (R may be INFINITY).  Writes the jerk used into *j_out (may be NULL) and
 * returns the track time advanced, ds >= 0.  Lands exactly on target
 * (rate == target, acc == 0) within two ticks' jerk of it (continuously), so the
 * caller can tell an unscaled output by rate == 1.0 && acc == 0.0.
 * *limited (may be NULL) is set to 1 when R, not target, decided the move,
 * with TS_LIM_FREE added where the move is nonetheless, bit for bit, the one
 * the same call makes with R infinite (R lowered the target, but the rate
 * rises towards it at the acceleration or jerk limit, with no release due).
 * Where the limits shrank under the state (|acc| > A: the engine converts
 * them at the speed of the segment the output is on, and the next may be
 * faster), this tick's jerk is raised by |acc| / A, so that
 * |acc| is back within A within A / J and the rate does not overshoot its
 * target (TIMESCALE.md, "Speed cap"); what comes after the tick (the
 * release of the braking, the stop, the room R) is planned at J.
 */
double ts_step(ts_state_t *st, double target, double R, double A, double J, double T, double *j_out,
               int *limited);
#define TS_LIM_FREE 2
/* ts_step_one's *limited: the move is the one with R infinite (below) */
#define TS_ONE_FREE 4
/* ts_step with this tick's jerk J_now (at least J) apart from the jerk J
 * every later tick is planned at (the release, the stop, the rooms): a
 * stop whose jerk is converted at a faster segment ahead may use the jerk of
 * the segment it is on while it is there. */
double ts_step_jerk(ts_state_t *st, double target, double R, double A, double J_now, double J,
                    double T, double *j_out, int *limited);

/*
 * The limits of a run of ts_step calls towards rate 1 with the same A, J and
 * T (the start's ramp, delay_run.c ramp_lag), and what ts_step derives from
 * them alone, each computed as ts_step computes it (ts_lims_init).
 */
typedef struct {
    double A, J, T;
    double at;         /* A T */
    double rm_cub;     /* A^3 / J^2, where ts_rate_max's two forms meet */
    double h, hh;      /* A^2 / (2 J) and h^2 */
    double db;         /* ts_dead_band(J, T) */
    double w0, w1;     /* track_jerk's -J T / 2 and (J T)^2 / 4 */
    double j2;         /* 2 J */
    double aaj, aj;    /* A^2 / J, A / J */
    double k1, k2;     /* ts_stop_dist at a = A: A t0^2 / 2 and J t0^3 / 6, t0 = A / J */
    double l4, l2;     /* the landing's bounds: 4 J T^2 and 2 J T */
    double ca;         /* A T^2 / 2 */
    double jt, cj, dj; /* J T, J T^2 / 2, J T^3 / 6 */
    double qa;         /* A^2 / (2 J) as track_jerk divides */
    int ok;            /* A, J, T > 0 and the terms above > 0, finite */
} ts_lims_t;
void ts_lims_init(ts_lims_t *l, double A, double J, double T);

/*
 * At rest (rate and acc 0), a creep towards R: the smallest of ts_step's
 * moves from rest (the jerk halved until the stop after it fits within R,
 * with a tick's travel to spare) also where R is within the dead band, where
 * ts_step stands still.  For the engine's transfer, which must end on its
 * end: at 10 Hz the braking came to rest 1.2e-4 of track time short of it,
 * 1.3 um away, and stood there for good.  Returns the advance, 0 (and st
 * unchanged) if none fits or st is not at rest.
 */
double ts_creep(ts_state_t *st, double R, double A, double J, double T);

/* ---- ts_step_one, inline: a start's ramp takes some 200 of them ---- */

/* ts_step's landing on tgt (timescale.c): rewrites the move (*j, *ds, *r1,
 * *a1) where one lands */
void ts_land_(double r, double a, double tgt, double J, double T, double *j, double *ds, double *r1,
              double *a1);

/* x == y (-0 == 0, a NaN equal to nothing) */
static inline int ts_eq_(double x, double y)
{
    return x >= y && x <= y;
}

/* timescale.c stop_dist0 with A^2 / J and A / J in hand */
static inline double ts_stop_dist0_(double r, const ts_lims_t *l)
{
    if (r <= 0)
        return 0;
    if (r >= l->aaj)
        return 0.5 * r * (r / l->A + l->aj);
    return r * sqrt(r / l->J);
}

/* timescale.c track_jerk's release: for a tick of jerk j that leaves the
 * acceleration a1 = a + j T below 0: the smallest jerk >= j after which a
 * release at full jerk does not take the rate below tgt (r1 - a1^2 / (2 J)
 * >= tgt, r1 the rate after the tick); J if none does.  The law of
 * track_jerk alone, sqrt(2 J |e|) from the error now, releases up to a few
 * ticks late and lands with the acceleration still at several J T, which
 * the landing then cleared in one tick. */
static inline double ts_release_in_time_(double r, double a, double tgt, double j, double J,
                                         double T)
{
    double a1 = a + j * T, r1 = r + a * T + 0.5 * j * T * T;

    if (!(a1 < 0 && r1 - a1 * a1 / (2.0 * J) < tgt))
        return j;
    /* r + a T + x T^2/2 - (a + x T)^2 / (2 J) = tgt, a downward parabola in
     * x: the root left of its vertex (where the final rate rises with x) */
    double c0 = r + a * T - tgt;
    double b = 2.0 * a / T - J, c = -(2.0 * J / (T * T)) * (c0 - a * a / (2.0 * J));
    double disc = b * b - 4.0 * c;
    double x = disc >= 0 ? 0.5 * (-b - sqrt(disc)) : J;
    if (x > J)
        x = J;
    return x > j ? x : j;
}

/*
 * ts_step_jerk's operations, in its order and on its operands, where J_now
 * is J, target is 1 and j_out NULL, on the path that applies when:
 *   0 <= a <= A: this tick's jerk is J (not raised);
 *   R > 0: ts_rate_max(R) is its root form or its cube root (INFINITY for R
 *     INFINITY, as ts_rate_max returns, and no stop is then beyond R);
 *   tgt (1, or R's lower rate) above the dead band (> 0) and the rate:
 *     e > 0 (so tgt > 0), and track_jerk's want is not negated;
 *   track_jerk's releases (release_in_time; the second, on the negated
 *     state, tests r1 + a1^2 / (2 J) > tgt with a1 > 0) are taken where one
 *     may be due (a1 < 0, or that test), but at A (then ts_step's); else they
 *     return the jerk as it was;
 *   r1 > 0 and the stop after the tick fits within R: no braking (nor creep),
 *     and none of the tests of a rate at or through 0 holds;
 *   the landing, where its test holds, as ts_step makes it.
 * The terms in j of the tick's integration are taken in hand where j is 0
 * at A or J: the next tick's state then waits on no root or quotient of
 * this one (those decide branches only), so that ticks overlap.
 * Returns 0 with *st unchanged where one fails.
 */
static inline int ts_step_one_(ts_state_t *st, const ts_lims_t *l, double R, double *ds_out,
                               int *limited)
{
    double r = st->rate, a = st->acc, A = l->A, J = l->J, T = l->T, tgt = 1.0;
    int lim = 0;

    if (!(R > 0) || !(a >= 0 && a <= A) || !l->ok)
        return 0;
    double rm = R >= l->rm_cub ? -l->h + sqrt(l->hh + 2.0 * R * A) : cbrt(R * R * J);
    if (rm < tgt) {
        tgt = rm;
        lim = 1;
    }
    double e = tgt - r;
    if (!(e > 0) || tgt < l->db)
        return 0;
    /* track_jerk: want at most A; j = (want - a) / T within +-J */
    double want = l->w0 + sqrt(l->w1 + l->j2 * e);
    int at_a = want >= A;
    double j, a1, r1, ds, sd;
    int up;
    if (at_a && ts_eq_(a, A)) {
        /* j = (A - A) / T = +0: its terms are +0, added to sums that are
         * not -0 (A T, A T^2 / 2 > 0 in them); no release (else
         * ts_step's); the stop after the tick is ts_stop_dist's a > 0 case
         * with t0 = A / J */
        j = 0.0;
        a1 = A;
        r1 = r + l->at;
        ds = r * T + l->ca;
        if (!(r1 > 0) || r1 + l->qa > tgt)
            return 0;
        up = 1;
        double s0 = r1 * l->aj + l->k1 - l->k2;
        sd = s0 + ts_stop_dist0_(r1 + l->h, l);
    } else {
        j = ((at_a ? A : want) - a) / T;
        if (j > J)
            j = J;
        if (j < -J)
            j = -J;
        if (ts_eq_(j, J)) {
            a1 = a + l->jt;
            r1 = r + a * T + l->cj;
            ds = r * T + 0.5 * a * T * T + l->dj;
        } else {
            a1 = a + j * T;
            r1 = r + a * T + 0.5 * j * T * T;
            ds = r * T + 0.5 * a * T * T + j * T * T * T / 6.0;
        }
        int late = r1 + a1 * a1 / l->j2 > tgt;
        up = (at_a || j >= J) && !(a1 < 0) && !late; /* before the releases */
        if (a1 < 0 || (a1 > 0 && late)) {
            /* a release may be due: track_jerk's two, then its clamp */
            j = ts_release_in_time_(r, a, tgt, j, J, T);
            j = -ts_release_in_time_(-r, -a, -tgt, -j, J, T);
            j = j > J ? J : j < -J ? -J : j;
            a1 = a + j * T;
            r1 = r + a * T + 0.5 * j * T * T;
            ds = r * T + 0.5 * a * T * T + j * T * T * T / 6.0;
        }
        if (!(r1 > 0))
            return 0;
        if (ts_eq_(a1, A)) {
            double s0 = r1 * l->aj + l->k1 - l->k2;
            sd = s0 + ts_stop_dist0_(r1 + l->h, l);
        } else if (a1 > 0) {
            double t0 = a1 / J;
            double s0 = r1 * t0 + 0.5 * a1 * t0 * t0 - J * t0 * t0 * t0 / 6.0;
            sd = s0 + ts_stop_dist0_(r1 + 0.5 * a1 * a1 / J, l);
        } else {
            sd = ts_stop_dist(r1, a1, A, J);
        }
    }
    if (sd + r1 * T > R - ds)
        return 0;
    if (ds < 0)
        ds = 0;
    /* the landing (fabs(tgt - r) is e, fabs(a) is a); one it makes is the
     * one with R infinite, which makes every one */
    int refused = 0;
    if (!lim && e <= l->at && e <= l->l4 && a <= l->l2) {
        double lj = j, lds = ds, lr = r1, la = a1;
        ts_land_(r, a, tgt, J, T, &lj, &lds, &lr, &la);
        if (isinf(R) || (lds <= R && (!(lr > 0) || ts_stop_dist(lr, la, A, J) <= R - lds))) {
            ds = lds;
            r1 = lr;
            a1 = la;
        } else {
            refused = 1;
        }
    }
    if (limited) {
        int same = lim && up &&
                   !(fabs(1.0 - r) <= l->at && fabs(1.0 - r) <= l->l4 && fabs(a) <= l->l2);
        /* R did not decide (tgt 1 as with R infinite, no braking) and no
         * landing was refused: the move with R infinite */
        *limited = lim ? lim | (same ? TS_LIM_FREE : 0) : refused ? 0 : TS_ONE_FREE;
    }
    st->rate = r1;
    st->acc = a1;
    *ds_out = ds;
    return 1;
}

/*
 * A run of ticks rising at A, each from rate r (r_first <= r <= r_last,
 * each the one before plus l->at: r_first, r_first + A T, ...) with room
 * R >= R_min: 1 where every one is, in ts_step_one, the rise from (r, A) to
 * (r + A T, A) with the advance r T + A T^2 / 2 (l->ca), and *limited has
 * TS_LIM_FREE or TS_ONE_FREE; 0 where that is not shown for every one.
 */
int ts_rise_holds(const ts_lims_t *l, double R_min, double r_first, double r_last);

/*
 * ts_step(st, 1.0, R, l->A, l->J, l->T, NULL, limited), bit for bit: the
 * state, the advance and *limited, but for TS_ONE_FREE in place of 0 where
 * the move is also, bit for bit, the one with R infinite (R did not decide
 * it, and no landing was refused for want of room).  A tick that rises
 * towards its target (the rate below it, 0 <= acc <= A) with no braking
 * due takes ts_step_one_, the limits' terms in hand; any other is ts_step's.
 */
static inline double ts_step_one(ts_state_t *st, const ts_lims_t *l, double R, int *limited)
{
    double ds;
    if (ts_step_one_(st, l, R, &ds, limited))
        return ds;
    return ts_step(st, 1.0, R, l->A, l->J, l->T, NULL, limited);
}

#endif
