/* replay_summary.c - trajreplay's --summary lines (see replay_summary.h). */
#include "replay_summary.h"

#include <inttypes.h>
#include <stdio.h>

#include "delay.h"
#include "engine_settings.h"

/* One "summary: name value" line each, so scripts can read them.  rejected
 * counts bad data only: ENGINE_EFULL refusals are flow control, retried by
 * the replay, and shown as full_retries. */
void replay_print_summary(const track_t *trk, const replay_t *r, const engine_status_t *st,
                          double max_v, double max_a, uint64_t ticks)
{
    uint64_t rejected = 0;
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++)
        if (e != ENGINE_EFULL)
            rejected += st->rejected_by[e];
    fprintf(stderr,
            "summary: waypoints %zu\n"
            "summary: skipped_lines %zu\n"
            "summary: accepted %" PRIu64 "\n"
            "summary: duplicates %" PRIu64 "\n"
            "summary: rejected %" PRIu64 "\n",
            trk->n, trk->skipped, st->accepted, st->duplicates, rejected);
    for (int e = 1; e < ENGINE_ERROR_COUNT; e++)
        if (e != ENGINE_EFULL && engine_reason_name(e))
            fprintf(stderr, "summary: rejected_%s %" PRIu64 "\n", engine_reason_name(e),
                    st->rejected_by[e]);
    fprintf(stderr,
            "summary: full_retries %" PRIu64 "\n"
            "summary: underruns %" PRIu64 "\n"
            "summary: underrun_ticks %" PRIu64 "\n"
            "summary: hard_stops %" PRIu64 "\n"
            "summary: gaps %" PRIu64 "\n"
            "summary: tracks %" PRIu64 "\n"
            "summary: setpoints %" PRIu64 "\n"
            "summary: max_speed_m_s %.6g\n"
            "summary: max_acc_m_s2 %.6g\n"
            "summary: uniform_irregular %" PRIu64 "\n"
            "summary: uniform_ratio_max %.6g\n",
            r->retries, st->underruns, st->underrun_ticks, st->hard_stops, st->gaps, st->tracks,
            ticks, max_v, max_a, st->uniform_irregular, st->uniform_ratio_max);
    fprintf(stderr,
            "summary: stops %" PRIu64 "\n"
            "summary: stop_fixes %" PRIu64 "\n"
            "summary: retimed %" PRIu64 "\n"
            "summary: retime_max_s %.6g\n"
            "summary: silent_ends %" PRIu64 "\n"
            "summary: catchups %" PRIu64 "\n"
            "summary: lag_s %.6g\n"
            "summary: axis_lost_s %.6g\n"
            "summary: axis_slowed %" PRIu64 "\n"
            "summary: axis_lag_stops %" PRIu64 "\n"
            "summary: axis_beyond %" PRIu64 "\n"
            "summary: delay_grown %" PRIu64 "\n"
            "summary: reserve_slowed %" PRIu64 "\n"
            "summary: limits_lost_s %.6g\n"
            "summary: limits_slowed %" PRIu64 "\n",
            st->stops, st->stop_fixes, st->retimed, st->retime_max_s, st->silent_ends, st->catchups,
            st->lag_s, st->axis_lost_s, st->axis_slowed, st->axis_lag_stops, st->axis_beyond,
            st->delay_grown, st->reserve_slowed, st->limits_lost_s, st->limits_slowed);
    fprintf(stderr,
            "summary: reanchors %" PRIu64 "\n"
            "summary: transfers %" PRIu64 "\n"
            "summary: transfers_moving %" PRIu64 "\n",
            st->reanchors, st->transfers, st->transfers_moving);
}

/* The play-out delay D the engine held and its parts (lib/engine/delay.h):
 * the input's interval and top speed as it measured them. */
void replay_print_delay(const engine_t *e)
{
    engine_delay_t d;
    if (!e)
        return;
    engine_delay(e, &d);
    fprintf(stderr,
            "summary: delay_s %.9g\n"
            "summary: delay_lookahead_s %.9g\n"
            "summary: delay_slack_s %.9g\n"
            "summary: delay_stop_s %.9g\n"
            "summary: delay_interval_s %.9g\n"
            "summary: delay_speed_m_s %.9g\n",
            d.delay_s, d.lookahead_s, d.slack_s, d.stop_s, d.interval_s, d.speed_m_s);
    const char *m = engine_setting_enum_name(engine_setting_find("method"), d.method);
    fprintf(stderr, "summary: method %s\n", m ? m : "?");
}

int replay_report_axis_stop(const char *input, const track_t *trk, const int *results,
                            size_t judged, const engine_status_t *st, double stop_t_s,
                            double max_lag_s)
{
    if (!st->axis_lag_stops && !st->axis_beyond)
        return 0;
    char lag[96];
    snprintf(lag, sizeof lag,
             "the per-axis limits made it lag the track by more than max_lag_s %g s", max_lag_s);
    const char *beyond = "a segment over 100 times faster on an axis than its axis_max_*";
    const char *why = !st->axis_beyond ? lag : !st->axis_lag_stops ? beyond : "the per-axis limits";
    size_t i = 0;
    while (i < trk->n && !(trk->wp[i].t_s > stop_t_s && (i >= judged || results[i] >= 0)))
        i++;
    if (i < trk->n)
        fprintf(stderr,
                "%s:%" PRIu32 ": error: the output stopped on its path at t = %.3f s, "
                "short of this waypoint",
                input, trk->line[i], stop_t_s);
    else
        fprintf(stderr, "trajreplay: %s: error: the output stopped on its path at t = %.3f s",
                input, stop_t_s);
    fprintf(stderr,
            ": %s (axis_lag_stops %" PRIu64 ", axis_beyond %" PRIu64
            "); the track was not followed there\n",
            why, st->axis_lag_stops, st->axis_beyond);
    return 1;
}
