/* timescale.c - the time scaling s(t); see timescale.h and TIMESCALE.md. */
#include "timescale.h"

#include <math.h>
#include <stddef.h>

/* Stopping distance from (r, 0): a symmetric S-curve.  With r >= A^2/J the
 * deceleration reaches -A (ramps of A/J each side, total time r/A + A/J),
 * otherwise it peaks at sqrt(r J) (total time 2 sqrt(r/J)); the rate falls
 * symmetrically, so the distance is r/2 times the total time. */
static double stop_dist0(double r, double A, double J)
{
    if (r <= 0)
        return 0;
    if (r >= A * A / J)
        return 0.5 * r * (r / A + A / J);
    return r * sqrt(r / J);
}

double ts_stop_dist(double r, double a, double A, double J)
{
    if (r <= 0)
        return 0;
    if (a > 0) {
        /* first bring a down to 0 at full jerk: t0 = a/J, the rate still
         * rises by a^2/(2J) */
        double t0 = a / J;
        double s0 = r * t0 + 0.5 * a * t0 * t0 - J * t0 * t0 * t0 / 6.0;
        return s0 + stop_dist0(r + 0.5 * a * a / J, A, J);
    }
    if (a < 0) {
        double m = a < -A ? A : -a; /* |a| (a beyond -A is brought back) */
        if (0.5 * m * m / J >= r) {
            /* releasing now at full jerk, the rate still reaches 0 before
             * the deceleration does (a state the braking itself never
             * enters; the limits may have shrunk): the distance until
             * r + a t + J t^2/2 = 0 */
            double t = (m - sqrt(fmax(m * m - 2.0 * J * r, 0.0))) / J;
            return r * t - 0.5 * m * t * t + J * t * t * t / 6.0;
        }
        /* (r, a) lies on the braking profile that started from (rv, 0)
         * tb = m/J ago: subtract what that profile covered before now */
        double tb = m / J, rv = r + 0.5 * m * m / J;
        double d = stop_dist0(rv, A, J) - (rv * tb - J * tb * tb * tb / 6.0);
        return d > 0 ? d : 0;
    }
    return stop_dist0(r, A, J);
}

double ts_rate_max(double R, double A, double J)
{
    if (isinf(R) && R > 0)
        return INFINITY;
    if (!(R > 0))
        return 0;
    if (R >= A * A * A / (J * J)) {
        /* r^2/(2A) + r A/(2J) = R */
        double h = 0.5 * A * A / J;
        return -h + sqrt(h * h + 2.0 * R * A);
    }
    /* r^1.5 / sqrt(J) = R */
    return cbrt(R * R * J);
}

/* Jerk that drives the rate towards tgt as fast as the limits allow: the
 * acceleration wanted for an error e is the one from which, released at
 * full jerk, the rate lands on tgt (sqrt(2 J |e|), corrected for the
 * discrete tick), at most A.  *up (may be NULL): 1 if every higher tgt
 * gives the same jerk, bit for bit: the rate rises towards tgt at the
 * acceleration or the jerk limit, with no release due (each operation is
 * monotonic in tgt, so a higher one is as saturated and releases later). */
static double track_jerk(double r, double a, double tgt, double A, double J, double Jr, double T,
                         int *up)
{
    double e = tgt - r, ae = fabs(e);
    double want = -0.5 * Jr * T + sqrt(0.25 * Jr * Jr * T * T + 2.0 * Jr * ae);
    double j;

    if (want > A)
        want = A;
    if (e < 0)
        want = -want;
    j = (want - a) / T;
    if (j > J)
        j = J;
    if (j < -J)
        j = -J;
    if (up) {
        double a1 = a + j * T, r1 = r + a * T + 0.5 * j * T * T;
        *up = e > 0 && (want >= A || j >= J) && !(a1 < 0) && !(r1 + a1 * a1 / (2.0 * Jr) > tgt);
    }
    /* and no later release than lands on tgt (both directions), planned at
     * Jr, the jerk the release will have (J may be raised for this tick) */
    j = ts_release_in_time_(r, a, tgt, j, Jr, T);
    j = -ts_release_in_time_(-r, -a, -tgt, -j, Jr, T);
    return j > J ? J : j < -J ? -J : j;
}

/* Exact integration over one tick with constant jerk. */
static double integrate(double r, double a, double j, double T, double *r1, double *a1)
{
    *r1 = r + a * T + 0.5 * j * T * T;
    *a1 = a + j * T;
    return r * T + 0.5 * a * T * T + j * T * T * T / 6.0;
}

/* At rest, asked to move, but a tick at full jerk would need more than R to
 * stop again (a long period: the distance grows as J T^3): a smaller jerk,
 * halved up to TS_CREEP_HALVINGS times, that does leave room, so that the
 * output creeps on instead of standing still for good with room ahead.
 * Returns the advance (0 and nothing changed if none fits). */
#define TS_CREEP_HALVINGS 30
static double creep(double R, double A, double J, double T, double *j, double *r1, double *a1)
{
    /* first with a tick's travel at the new rate to spare (the stop it
     * plans is continuous, the ticks are not: without it the creep up to
     * the end of the solved curve could reach it moving, issue 27), else
     * without (so that a long period still creeps on) */
    for (int spare = 1; spare >= 0; spare--) {
        double jj = J;
        for (int i = 0; i < TS_CREEP_HALVINGS; i++) {
            double rr, aa, dd;
            jj *= 0.5;
            dd = integrate(0.0, 0.0, jj, T, &rr, &aa);
            if (ts_stop_dist(rr, aa, A, J) + spare * rr * T <= R - dd) {
                *j = jj;
                *r1 = rr;
                *a1 = aa;
                return dd;
            }
        }
    }
    return 0.0;
}

double ts_creep(ts_state_t *st, double R, double A, double J, double T)
{
    double j, r1, a1, ds;

    if (st->rate > 0 || st->acc < 0 || st->acc > 0 || !(R > 0) || isinf(R))
        return 0.0;
    ds = creep(R, A, J, T, &j, &r1, &a1);
    if (ds > 0) {
        st->rate = r1;
        st->acc = a1;
    }
    return ds;
}

/* Near the target (within a few ticks' jerk): land on it exactly, rate =
 * target and acceleration 0, with no step of either.  One tick lands when
 * the error is a T / 2 (jerk -a / T); else two ticks do (jerk j1 now, then
 * the one-tick landing), if both jerks are within J: the rate then reaches
 * the target continuously instead of being set to it (which stepped the
 * velocity by up to k' J T^2: 0.125 m/s at 20 Hz).  Leaves the move as it
 * was otherwise. */
void ts_land_(double r, double a, double tgt, double J, double T, double *j, double *ds, double *r1,
              double *a1)
{
    double e = tgt - r, j1 = -a / T;

    if (fabs(e - 0.5 * a * T) <= 1e-12 * (1.0 + fabs(tgt)) && fabs(j1) <= J) {
        *j = j1;
        *ds = integrate(r, a, j1, T, r1, a1);
        if (*ds < 0)
            *ds = 0;
        *r1 = tgt; /* equal to 1e-12: exact, for the engine's r == 1 test */
        *a1 = 0;
        return;
    }
    j1 = e / (T * T) - 1.5 * a / T;
    double j2 = -a / T - j1;
    if (fabs(j1) <= J && fabs(j2) <= J) {
        *j = j1;
        *ds = integrate(r, a, j1, T, r1, a1);
        if (*ds < 0)
            *ds = 0;
    }
}

double ts_dead_band(double J, double T)
{
    double d = J * T * T;
    return d < TS_DEAD_BAND_MAX ? d : TS_DEAD_BAND_MAX;
}

double ts_step(ts_state_t *st, double target, double R, double A, double J, double T, double *j_out,
               int *limited)
{
    return ts_step_jerk(st, target, R, A, J, J, T, j_out, limited);
}

double ts_step_jerk(ts_state_t *st, double target, double R, double A, double J_now, double J,
                    double T, double *j_out, int *limited)
{
    double r = st->rate, a = st->acc, tgt = target, r1, a1, ds, j, Jr = J;
    J = J_now > J ? J_now : J;
    int lim = 0, crept = 0, up = 0;

    /* the limits shrank (timescale.h): back within A in A/J.  Only this
     * tick's jerk is raised: what the rate will do after it (its release,
     * its stop) is planned at J, the jerk it will have then.  Planned at the
     * raised one, a release that began as a stop's braking met a segment
     * with a 2.5 % lower A started a tick late and came to rest with its
     * deceleration left (2.38 m/s^3 on a 2 m/s^3 axis, fuzz_lifecycle). */
    if (fabs(a) > A)
        J *= fabs(a) / A;
    if (!(tgt > 0))
        tgt = 0;
    if (tgt > TS_RATE_MAX)
        tgt = TS_RATE_MAX;
    double tfree = tgt; /* the target with R infinite */
    if (!isinf(R)) {
        double rm = ts_rate_max(R, A, Jr);
        if (rm < tgt) {
            tgt = rm;
            lim = 1;
        }
    }
    if (tgt < ts_dead_band(J, T))
        tgt = 0; /* dead band: a rate this low comes to rest exactly */
    j = track_jerk(r, a, tgt, A, J, Jr, T, lim ? &up : NULL);
    ds = integrate(r, a, j, T, &r1, &a1);
    if (!isinf(R) && r1 > 0 && ts_stop_dist(r1, a1, A, Jr) + r1 * T > R - ds) {
        /* the move would leave too little to stop: brake as hard as allowed.
         * With a tick's travel at the new rate to spare, as creep() keeps:
         * the stop planned is continuous, the ticks are not, and a creep
         * towards the end of the solved curve reached it at 0.13 m/s (issue 27) */
        tgt = 0;
        j = track_jerk(r, a, tgt, A, J, Jr, T, NULL);
        ds = integrate(r, a, j, T, &r1, &a1);
        lim = 1;
        if (!(r > 0) && !(a < 0 || a > 0) && target > 0) {
            ds = creep(R, A, J, T, &j, &r1, &a1);
            crept = ds > 0;
        }
    }
    if (r1 <= 0 && r > A * T) {
        /* the jerk would take the rate through 0 within the tick, from
         * further than one tick at A: brake at -A instead (|j| <= J still),
         * so that no tick changes the rate by more than A T */
        j = (-A - a) / T;
        if (j > J)
            j = J;
        if (j < -J)
            j = -J;
        ds = integrate(r, a, j, T, &r1, &a1);
    }
    if (!(tgt > 0) && r1 > 0 && r1 <= 1e-15 && fabs(a1) <= 1e-12 * J * T)
        r1 = 0; /* rounding residue of a landing on rest (1e-19): at rest */
    if (r1 <= 0) {
        /* came to rest within the tick (the release of the braking ends
         * here): rest exactly; a is within one tick's jerk of 0 */
        r1 = 0;
        a1 = 0;
    }
    if (ds < 0)
        ds = 0;
    if (!crept && !lim && fabs(tgt - r) <= A * T && fabs(tgt - r) <= 4.0 * J * T * T &&
        fabs(a) <= 2.0 * J * T) {
        double lj = j, lds = ds, lr = r1, la = a1;
        ts_land_(r, a, tgt, J, T, &lj, &lds, &lr, &la);
        if (isinf(R) || (lds <= R && (!(lr > 0) || ts_stop_dist(lr, la, A, Jr) <= R - lds))) {
            j = lj; /* a landing that leaves room to stop */
            ds = lds;
            r1 = lr;
            a1 = la;
        }
    }
    st->rate = r1;
    st->acc = a1;
    if (j_out)
        *j_out = j;
    if (limited) {
        /* R lowered the target (tgt > 0: not the stop's braking) and the
         * move is the one a higher target makes (up), not a landing with R
         * infinite */
        int same = lim && up && tgt > 0 &&
                   !(fabs(tfree - r) <= A * T && fabs(tfree - r) <= 4.0 * J * T * T &&
                     fabs(a) <= 2.0 * J * T);
        *limited = lim | (same ? TS_LIM_FREE : 0);
    }
    return ds;
}

/* Each term written as the expression ts_step evaluates, the same
 * operations on the same operands in the same order (0.5 * A * A / J is
 * ((0.5 A) A) / J), so that it is that value bit for bit. */
void ts_lims_init(ts_lims_t *l, double A, double J, double T)
{
    l->A = A;
    l->J = J;
    l->T = T;
    l->at = A * T;
    l->rm_cub = A * A * A / (J * J);
    l->h = 0.5 * A * A / J;
    l->hh = l->h * l->h;
    l->db = ts_dead_band(J, T);
    l->w0 = -0.5 * J * T;
    l->w1 = 0.25 * J * J * T * T;
    l->j2 = 2.0 * J;
    l->aaj = A * A / J;
    l->aj = A / J;
    l->k1 = 0.5 * A * l->aj * l->aj;
    l->k2 = J * l->aj * l->aj * l->aj / 6.0;
    l->l4 = 4.0 * J * T * T;
    l->l2 = 2.0 * J * T;
    l->ca = 0.5 * A * T * T;
    l->jt = J * T;
    l->cj = 0.5 * J * T * T;
    l->dj = J * T * T * T / 6.0;
    l->qa = A * A / (2.0 * J);
    l->ok = A > 0 && J > 0 && T > 0 && l->at > 0 && l->ca > 0 && isfinite(l->ca) &&
            isfinite(l->dj) && l->dj > 0 && l->db > 0;
}

/*
 * Every operation of ts_step_one_'s rise at A is monotonic in the rate r
 * and in R (sums, products and quotients of terms >= 0 or with constants
 * > 0, roots; correctly rounded, so monotonic in floating point too): each
 * of its tests, taken at the run's highest rate and least room, holds for
 * every tick of the run.  stop_dist0's two forms are one where the run
 * stays on one side of A^2 / J (they may differ by a rounding at it), and
 * ts_rate_max's root form is the one where the least room is past A^3 / J^2.
 */
int ts_rise_holds(const ts_lims_t *l, double R_min, double r_first, double r_last)
{
    if (!l->ok || !(R_min > 0) || !(R_min >= l->rm_cub) || !(r_first <= r_last))
        return 0;
    double rm = -l->h + sqrt(l->hh + 2.0 * R_min * l->A);
    if (!(rm > 0))
        return 0;
    double tgt = rm < 1.0 ? rm : 1.0, e = tgt - r_last;
    /* the target (the lowest), the rate below it, want at A */
    if (!(e > 0) || tgt < l->db || !(l->w0 + sqrt(l->w1 + l->j2 * e) >= l->A))
        return 0;
    /* no release; r1 > 0 and the advance >= 0 from the first tick on */
    double r1f = r_first + l->at, r1l = r_last + l->at;
    if (!(r1f > 0) || r1l + l->qa > tgt || !(r_first * l->T + l->ca >= 0))
        return 0;
    /* the stop after the last tick within the least room, less the last
     * (largest) advance */
    double xf = r1f + l->h, xl = r1l + l->h;
    if (!(xf > 0) || (xf >= l->aaj) != (xl >= l->aaj))
        return 0;
    double s0 = r1l * l->aj + l->k1 - l->k2;
    double sd = s0 + ts_stop_dist0_(xl, l), dsl = r_last * l->T + l->ca;
    if (sd + r1l * l->T > R_min - dsl)
        return 0;
    /* further than A T from rate 1: no landing is tested, and where R lowers
     * the target the move is the free one (TS_LIM_FREE) */
    return 1.0 - r_last > l->at;
}
