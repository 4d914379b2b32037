/* delay.c - the play-out delay D, stated (see delay.h). */
#include "delay.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "accept.h"
#include "engine_int.h"
#include "engine_settings.h"
#include "timescale.h"

/* The time scaling's limits are converted at no less than this speed (m/s):
 * engine_int.h's ENGINE_SCALE_V_FLOOR_M_S. */
#define DELAY_V_FLOOR_M_S 1.0

double engine_delay_stop_s(const engine_config_t *cfg, double speed_m_s)
{
    double v = speed_m_s > DELAY_V_FLOOR_M_S ? speed_m_s : DELAY_V_FLOOR_M_S;
    double T = (double)cfg->period_ns * 1e-9;
    return ts_stop_dist(1.0, 0.0, cfg->scale_accel_m_s2 / v, cfg->scale_jerk_m_s3 / v) +
           TS_MARGIN_TICKS * T;
}

int engine_delay_of(const engine_config_t *cfg, double interval_s, double speed_m_s,
                    engine_delay_t *d)
{
    engine_config_t r;
    unsigned la;

    memset(d, 0, sizeof *d);
    if (engine_config_resolve(cfg, &r) < 0 || !(la = engine_lookahead(&r)))
        return -ENGINE_ECONFIG;
    engine_delay_parts(&r, la, interval_s, speed_m_s, d);
    return 0;
}

void engine_delay_parts(const engine_config_t *r, unsigned la, double interval_s, double speed_m_s,
                        engine_delay_t *d)
{
    memset(d, 0, sizeof *d);
    d->interval_s = interval_s > 0 && isfinite(interval_s) ? interval_s : 0.0;
    if (r->start_slack == ENGINE_AUTO) {
        /* the lookahead (the acceptance's verdict in it) and a slack in
         * time, an interval at most ENGINE_DELAY_TICKS periods (the
         * fragments' at least, below: delay.h) */
        d->lookahead_n = la;
        d->slack_ticks = ENGINE_DELAY_TICKS;
        d->slack_s = ENGINE_DELAY_TICKS * (double)r->period_ns * 1e-9;
        if (d->interval_s > 0 && d->interval_s < d->slack_s)
            d->slack_s = d->interval_s;
    } else {
        d->slack_n = r->start_slack; /* counted */
        d->lookahead_n = la - (d->slack_n < la ? d->slack_n : la) + 1;
        d->slack_s = d->slack_n * d->interval_s;
    }
    if (!(speed_m_s > 0)) {
        speed_m_s = engine_config_max_speed(r);
        if (!(speed_m_s > 0))
            speed_m_s = DELAY_V_FLOOR_M_S;
    }
    d->speed_m_s = speed_m_s;
    d->lookahead_s = d->lookahead_n * d->interval_s;
    d->stop_s = engine_delay_stop_s(r, speed_m_s);
    if (d->slack_ticks && !engine_cfg_local(r) && d->interval_s > d->slack_s) {
        /* the fragments: an interval, less what the stop reserve holds
         * beyond v / (2 scale_accel_m_s2) (its jerk term and margin), so
         * D = (L + 1) h + v / (2 scale_accel_m_s2) where that fits */
        double held = d->stop_s - 0.5 * speed_m_s / r->scale_accel_m_s2;
        d->slack_s = fmax(d->slack_s, d->interval_s - fmax(held, 0.0));
    }
    d->need_s = d->lookahead_s + d->slack_s + d->stop_s;
    d->delay_s = r->delay_s > d->need_s ? r->delay_s : d->need_s;
    d->asked_s = r->delay_s > 0 ? r->delay_s : 0.0;
    d->method = (int)r->method;
}

unsigned engine_lookahead_for_delay(const engine_config_t *cfg, double interval_s, double speed_m_s)
{
    engine_delay_t d;
    if (!(cfg->delay_s > 0) || !(interval_s > 0))
        return cfg->max_lookahead;
    for (unsigned la = cfg->max_lookahead; la >= 1; la--) {
        engine_config_t c = *cfg;
        c.max_lookahead = la;
        c.delay_s = 0.0; /* the need alone (a max_lookahead that does not resolve: none) */
        if (engine_delay_of(&c, interval_s, speed_m_s, &d) == 0 && d.need_s <= cfg->delay_s)
            return la;
    }
    return cfg->max_lookahead;
}

int engine_delay_check(const engine_config_t *cfg, double interval_s, char *why, size_t whylen)
{
    engine_delay_t d;

    if (!(cfg->delay_s > 0))
        return 0;
    if (engine_delay_of(cfg, interval_s, 0.0, &d) < 0)
        return 0; /* engine_config_check says why */
    if (cfg->delay_s >= d.need_s)
        return 0;
    if (why && whylen)
        snprintf(why, whylen,
                 "delay_s %g s is shorter than the settings need: %.3g s = stop reserve %.3g s "
                 "(from %g m/s at scale_accel_m_s2 %g) + %u input intervals (lookahead %u, "
                 "slack %u)%s%s; raise delay_s, or lower max_speed_m_s",
                 cfg->delay_s, d.need_s, d.stop_s, d.speed_m_s, cfg->scale_accel_m_s2,
                 d.lookahead_n + d.slack_n, d.lookahead_n, d.slack_n,
                 d.interval_s > 0 ? "" : " x the interval", d.slack_ticks ? " + a few ticks" : "");
    return -ENGINE_ECONFIG;
}

int engine_underrun_due(const engine_status_t *st, double told_t_s, int at_end)
{
    double t = st->underrun_t_s;
    return (st->underruns || isfinite(st->underrun_silence_s)) && isfinite(t) &&
           (isnan(told_t_s) || t < told_t_s || t > told_t_s) &&
           (at_end || isfinite(st->underrun_next_t_s) || isfinite(st->underrun_silence_s));
}

int engine_underrun_format(const engine_status_t *st, char *buf, size_t len)
{
    if (len)
        buf[0] = 0;
    if (!isfinite(st->underrun_t_s) || !isfinite(st->underrun_newest_t_s))
        return 0;
    double hold = st->underrun_slack_s, newest = st->underrun_newest_t_s;
    double gap = st->underrun_next_t_s - newest, span = newest - st->underrun_curve_t_s;
    int n = snprintf(buf, len, "underrun at t = %.3f s: ", st->underrun_t_s);
    size_t off = n > 0 && (size_t)n < len ? (size_t)n : len;
    if (isfinite(st->underrun_silence_s))
        n = snprintf(buf + off, len - off,
                     "no waypoint after t = %.3f s: the input fell silent, and after %.3g s of "
                     "silence (D holds %.3g s for a late one; the silence that ends a "
                     "trajectory is longer: lib/engine/silence.h) that was taken as its end, "
                     "not a late waypoint (not counted): the output plays on to its last "
                     "waypoint",
                     newest, st->underrun_silence_s, hold);
    else if (gap > hold) /* (NaN: none came yet) */
        n = snprintf(buf + off, len - off,
                     "no waypoint after t = %.3f s until t = %.3f s, a silence of %.3g s, longer "
                     "than the %.3g s D holds for a late one (the interval and the jitter slack)",
                     newest, st->underrun_next_t_s, gap, hold);
    else if (st->underrun_judging > ACCEPT_LAG && isfinite(st->underrun_judging_t_s))
        n = snprintf(buf + off, len - off,
                     "the %u waypoints from t = %.3f s to t = %.3f s were still being judged "
                     "(the acceptance holds a fix until a later one tells it good: a run of "
                     "repeats of one position, a stop too hard for the object's recent pace, "
                     "waits for the next new position, as a frozen receiver's copies must; "
                     "lib/engine/accept.h)",
                     (unsigned)st->underrun_judging, st->underrun_judging_t_s, newest);
    else if (span > st->underrun_lookahead_s)
        n = snprintf(buf + off, len - off,
                     "the waypoints the solver needs beyond its curve (t = %.3f .. %.3f s) spanned "
                     "%.3g s, more than the %.3g s of lookahead D was sized for (intervals "
                     "longer than measured at the start)",
                     st->underrun_curve_t_s, newest, span, st->underrun_lookahead_s);
    else if (isfinite(gap))
        n = snprintf(buf + off, len - off,
                     "no waypoint after t = %.3f s until t = %.3f s, a silence of %.3g s, within "
                     "the %.3g s D holds for a late one: the output was late on its D",
                     newest, st->underrun_next_t_s, gap, hold);
    else
        n = snprintf(buf + off, len - off,
                     "no waypoint after t = %.3f s until the input's end (D holds %.3g s for a "
                     "late one)",
                     newest, hold);
    return n < 0 ? n : (int)off + n;
}

int engine_delay_format(const engine_delay_t *d, char *buf, size_t len)
{
    char need[320], slack[120];
    /* the local methods (issue 31) are named: max_lookahead may have picked
     * them (the settings table's names) */
    char m[48] = "";
    if (d->method >= ENGINE_METHOD_HERMITE)
        snprintf(m, sizeof m, " (method %s)",
                 engine_setting_enum_name(engine_setting_find("method"), d->method));
    if (d->slack_ticks) { /* in time: ticks, the arrivals' lateness, intervals learnt */
        /* the fragments' an interval less the stop's jerk term and margin, at
         * least the ticks; the local methods' at most the ticks (delay.h) */
        int n = d->method >= ENGINE_METHOD_HERMITE
                    ? snprintf(slack, sizeof slack, "slack %.3f s (an interval, at most %u ticks",
                               d->slack_s, d->slack_ticks)
                    : snprintf(slack, sizeof slack,
                               "slack %.3f s (an interval less the stop's a/(2j) and margin, at "
                               "least %u ticks",
                               d->slack_s, d->slack_ticks);
        if (d->jitter_s > 0 && n > 0 && (size_t)n < sizeof slack)
            n += snprintf(slack + n, sizeof slack - (size_t)n, ", arrivals up to %.3f s late",
                          d->jitter_s);
        if (d->slack_n && n > 0 && (size_t)n < sizeof slack)
            n += snprintf(slack + n, sizeof slack - (size_t)n, ", %u intervals learnt", d->slack_n);
        if (n > 0 && (size_t)n < sizeof slack)
            snprintf(slack + n, sizeof slack - (size_t)n, ")");
    } else if (d->interval_s > 0 && d->jitter_s > 0) {
        snprintf(slack, sizeof slack,
                 "slack %.3f s (arrivals up to %.3f s late, %u intervals learnt)", d->slack_s,
                 d->jitter_s, (unsigned)llround((d->slack_s - d->jitter_s) / d->interval_s));
    } else {
        snprintf(slack, sizeof slack, "slack %u x %.3g s", d->slack_n, d->interval_s);
    }
    if (d->interval_s > 0)
        snprintf(need, sizeof need,
                 "lookahead %u x %.3g s%s + %s + stop reserve %.3f s (from %.3g m/s)",
                 d->lookahead_n, d->interval_s, m, slack, d->stop_s, d->speed_m_s);
    else
        snprintf(need, sizeof need,
                 "%u input intervals (lookahead %u%s, slack %u)%s + stop reserve at most %.3f s "
                 "(from the speed limit, %.3g m/s; the input's own top speed sets it once "
                 "waypoints come)",
                 d->lookahead_n + d->slack_n, d->lookahead_n, m, d->slack_n,
                 d->slack_ticks ? " + a few ticks" : "", d->stop_s, d->speed_m_s);
    if (d->delay_s > d->need_s)
        return snprintf(buf, len, "D %.3f s (delay_s; the settings need %s)", d->delay_s, need);
    if (d->asked_s > 0 && d->delay_s > d->asked_s + 1e-9 && d->interval_s > 0)
        return snprintf(buf, len,
                        "D %.3f s (delay_s %.3g s is short of what this input needs: the "
                        "lookahead max_lookahead allows at its interval, and a start's ramp "
                        "from rest) = %s",
                        d->delay_s, d->asked_s, need);
    if (d->interval_s > 0)
        return snprintf(buf, len, "D %.3f s = %s", d->delay_s, need);
    return snprintf(buf, len, "D = %s", need);
}
