/*
 * summary.c - the status and exit lines (core_summary, core.h): the daemon's
 * counters, each transport's, and each object's motion, lifecycle and faults.
 */
#include "core.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "log.h"

/* core_summary's part of an object's motion: stops and re-stamps (issue 27),
 * lags won back and silent ends (issue 26), time lost to the per-axis limits
 * (issue 32); n characters are in buf already, the new count returned. */
static size_t summary_motion(const obj_t *o, char *buf, size_t len, size_t n)
{
    int m;
    if ((o->status.stops || o->status.retimed) && n < len) { /* issue 27 */
        m = snprintf(buf + n, len - n, ", %llu stops, %llu re-stamped (largest %.3f s)",
                     (unsigned long long)o->status.stops, (unsigned long long)o->status.retimed,
                     o->status.retime_max_s);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.catchups && n < len) { /* issue 26: lib/engine/catchup.h */
        m = snprintf(buf + n, len - n, ", %llu lags won back (now %+.3f s)",
                     (unsigned long long)o->status.catchups, o->status.lag_s);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.silent_ends && n < len) { /* issue 26: lib/engine/silence.h */
        m = snprintf(buf + n, len - n, ", %llu silent ends",
                     (unsigned long long)o->status.silent_ends);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.axis_slowed && n < len) { /* issue 32: per-axis limits */
        m = snprintf(buf + n, len - n, ", %.1f s lost to the per-axis limits (%llu segments)",
                     o->status.axis_lost_s, (unsigned long long)o->status.axis_slowed);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if ((o->status.dropped || o->status.unjudged) && n < len) { /* taken, dropped unplayed */
        m = snprintf(buf + n, len - n,
                     ", %llu waypoints dropped by a stop, clear or reload (and %llu before their "
                     "verdict)",
                     (unsigned long long)o->status.dropped, (unsigned long long)o->status.unjudged);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->stop_refused && n < len) { /* obj_push_from while the daemon stops */
        m = snprintf(buf + n, len - n, ", %llu waypoints refused while stopping",
                     (unsigned long long)o->stop_refused);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.limits_lost_s >= 0.05 && n < len) { /* its own speed/acceleration limits */
        m = snprintf(buf + n, len - n, ", %.1f s lost to its speed/acceleration limits",
                     o->status.limits_lost_s);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.transfers_moving && n < len) { /* issue 32: lib/engine/join.c */
        m = snprintf(buf + n, len - n, ", %llu re-anchors joined moving",
                     (unsigned long long)o->status.transfers_moving);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.reserve_slowed && n < len) { /* issue 26: delay.h */
        m = snprintf(buf + n, len - n, ", slowed %llu times for D's stop reserve",
                     (unsigned long long)o->status.reserve_slowed);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    if (o->status.delay_grown && n < len) { /* issue 26: engine_delay_grow */
        m = snprintf(buf + n, len - n, ", D grown %llu times",
                     (unsigned long long)o->status.delay_grown);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    return n;
}

int core_summary(const core_t *c, char *buf, size_t len)
{
    const stats_t *s = c->stats;
    int64_t up_s = (core_mono_ns() - s->start_mono_ns) / 1000000000;
    size_t n = 0;
    int m = snprintf(buf, len,
                     "up %lld s%s, ticks %llu, missed %llu, overruns %llu, late p50/p99/p99.9/max "
                     "%u/%u/%u/%u us, tick CPU p99.9/max %u/%u us",
                     (long long)up_s, c->stopping ? " (stopping)" : "",
                     (unsigned long long)s->ticks, (unsigned long long)s->missed_ticks,
                     (unsigned long long)s->overruns, s->late.p50_us, s->late.p99_us,
                     s->late.p999_us, s->late.max_us, s->work.p999_us, s->work.max_us);
    if (m < 0)
        return m;
    n = (size_t)m < len ? (size_t)m : len;
    /* every transport's counters, open or not (a reload may have closed it) */
    for (unsigned t = 0; transport_table[t] && n < len; t++)
        if (transport_table[t]->summary) {
            m = transport_table[t]->summary(c, buf + n, len - n);
            n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
        }
    if (s->out_fault && n < len) {
        m = snprintf(buf + n, len - n, ", OUTPUT FAULT (%llu failed writes, last: %s)",
                     (unsigned long long)s->out_errors, strerror(s->out_errno));
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    unsigned long long dropped = log_dropped_count(); /* never silent: log.h */
    if (dropped && n < len) {
        m = snprintf(buf + n, len - n, ", log lines dropped %llu", dropped);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
    }
    for (unsigned i = 0; i < c->nobj && n < len; i++) {
        const obj_t *o = &c->obj[i];
        m = snprintf(buf + n, len - n,
                     "; %s %s%s t=%.1f s, wp %llu ok %llu rejected %llu full, %llu underruns",
                     o->name, engine_state_name(o->status.state),
                     safety_fault(&o->safety) ? " SAFETY FAULT (holding)" : "", o->sp.t_s,
                     (unsigned long long)o->status.accepted, (unsigned long long)o->status.rejected,
                     (unsigned long long)o->status.full, (unsigned long long)o->status.underruns);
        n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
        if (o->clocked == 1 && isfinite(o->sp.age_s) && n < len) { /* lib/engine/CLOCK.md */
            m = snprintf(buf + n, len - n, ", data age %.3f s", o->sp.age_s);
            n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
        }
        lc_state_t ls = lc_state(&o->lc);
        if ((ls == LC_STOPPED || ls == LC_STOPPING || ls == LC_HELD || o->lc.n.stalled_periods) &&
            n < len) { /* lib/engine/LIFECYCLE.md */
            m = snprintf(buf + n, len - n, ", %s, %u waypoints buffered, %llu stalled periods",
                         lc_state_name(ls), lc_buffered(&o->lc),
                         (unsigned long long)o->lc.n.stalled_periods);
            n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
            if (o->clocked != 1 && o->lc.n.lag_s > 0 && n < len) {
                m = snprintf(buf + n, len - n, ", lag %.3f s", o->lc.n.lag_s);
                n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
            }
        }
        n = summary_motion(o, buf, len, n);
        if (o->lc.n.refused && n < len) { /* by the owner or the gate (objlife.c) */
            m = snprintf(buf + n, len - n, ", %llu commands refused",
                         (unsigned long long)o->lc.n.refused);
            n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
        }
        if (o->out_lost && n < len) {
            m = snprintf(buf + n, len - n, ", %s%llu lines lost by outputs",
                         o->out_fault ? "FAULT, " : "", (unsigned long long)o->out_lost);
            n += m > 0 ? ((size_t)m < len - n ? (size_t)m : len - n) : 0;
        }
    }
    return (int)n;
}
