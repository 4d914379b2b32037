/* playout.c - drift estimate and play-out clock; see playout.h, CLOCK.md. */
#include "playout.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* PLAYOUT_WINDOW_S in ns */
#define PLAYOUT_WINDOW_NS ((int64_t)PLAYOUT_WINDOW_S * 1000000000)

void playout_drift_init(playout_drift_t *d, double max_ppm)
{
    memset(d, 0, sizeof *d);
    d->max_ppm = max_ppm >= 0 ? max_ppm : PLAYOUT_MAX_PPM;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Theil-Sen slope of the closed windows: the median of the pairwise slopes. */
static void refit(playout_drift_t *d)
{
    unsigned m = 0;
    double lim = d->max_ppm * 1e-6;

    for (unsigned i = 0; i < d->nwin; i++)
        for (unsigned j = i + 1; j < d->nwin; j++) {
            double da = d->wa[j] - d->wa[i];
            if (da > 0.5 * PLAYOUT_WINDOW_S || da < -0.5 * PLAYOUT_WINDOW_S)
                d->scratch[m++] = (d->wd[j] - d->wd[i]) / da;
        }
    if (d->nwin < PLAYOUT_MIN_WINDOWS || m == 0)
        return;
    /* at most 2016 slopes, once per window: a sort is plenty */
    qsort(d->scratch, m, sizeof d->scratch[0], cmp_double);
    double med = m % 2 ? d->scratch[m / 2] : 0.5 * (d->scratch[m / 2 - 1] + d->scratch[m / 2]);
    double eps = -med;
    if (!(eps < lim))
        eps = lim;
    if (!(eps > -lim))
        eps = -lim;
    d->eps = eps;
    d->valid = 1;
}

static void close_window(playout_drift_t *d)
{
    unsigned at = (d->head + d->nwin) % PLAYOUT_WINDOWS;

    if (d->nwin == PLAYOUT_WINDOWS) {
        at = d->head;
        d->head = (d->head + 1) % PLAYOUT_WINDOWS;
    } else {
        d->nwin++;
    }
    d->wa[at] = d->win_a;
    d->wd[at] = d->win_d;
    d->win_n = 0;
    refit(d);
}

void playout_drift_add(playout_drift_t *d, int64_t arrival_ns, double stamp_s)
{
    if (!isfinite(stamp_s))
        return;
    if (!d->have_ref) {
        d->have_ref = 1;
        d->ref_ns = arrival_ns;
        d->win_end_ns = arrival_ns + PLAYOUT_WINDOW_NS;
    }
    if (arrival_ns < d->win_end_ns - PLAYOUT_WINDOW_NS)
        return; /* out of order */
    if (arrival_ns >= d->win_end_ns) {
        if (d->win_n)
            close_window(d);
        /* the window holding this arrival (none in between held a sample) */
        int64_t skip = (arrival_ns - d->win_end_ns) / PLAYOUT_WINDOW_NS + 1;
        d->win_end_ns += skip * PLAYOUT_WINDOW_NS;
    }
    /* arrival and stamp relative to the reference, in long double: epoch
     * seconds in a double are only good to 2.4e-7 s, differences to better */
    double a = (double)(arrival_ns - d->ref_ns) * 1e-9;
    double dd = (double)((long double)arrival_ns * 1e-9L - (long double)stamp_s);
    d->samples++;
    if (!d->win_n || dd < d->win_d) {
        d->win_d = dd;
        d->win_a = a;
    }
    d->win_n++;
}

double playout_drift_eps(const playout_drift_t *d)
{
    return d->valid ? d->eps : 0.0;
}

void playout_clock_init(playout_clock_t *c)
{
    memset(c, 0, sizeof *c);
}

int64_t playout_clock_now(playout_clock_t *c, int64_t real_ns, double eps_target, double *rate)
{
    if (!c->started) {
        c->started = 1;
        c->last_ns = real_ns;
    }
    double dt = (double)(real_ns - c->last_ns) * 1e-9;
    if (dt < 0)
        dt = 0; /* the system clock was set back: no drift for it */
    double step = PLAYOUT_SLEW_PPM_S * 1e-6 * dt, e0 = c->eps;
    if (eps_target > c->eps + step)
        c->eps += step;
    else if (eps_target < c->eps - step)
        c->eps -= step;
    else
        c->eps = eps_target;
    /* the applied drift over the interval: trapezoid of the slewed rate */
    c->drift_ns += 0.5 * (e0 + c->eps) * dt * 1e9;
    c->last_ns = real_ns;
    if (rate)
        *rate = 1.0 + c->eps;
    return real_ns + (int64_t)llround(c->drift_ns);
}
