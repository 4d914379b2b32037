/* trajreplay_help.c - trajreplay's --help text: its options, the track formats and
 * the engine settings (from their table, one source), and the exit statuses; and
 * what it tells of the engine settings it is given. */
#include "trajreplay_help.h"

#include <stdio.h>

#include "delay.h"
#include "engine_settings.h"
#include "track.h"

static void usage_engine(FILE *f)
{
    engine_config_t d;
    engine_config_default(&d);
    fputs("\nEngine settings (lib/engine/engine_settings.c; the key is the same setting\n"
          "in an [object.NAME] section of trajd.conf):\n",
          f);
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        if (!s->option)
            continue;
        char opt[64], def[96];
        snprintf(opt, sizeof opt, "--%s %s", s->option, s->arg);
        engine_setting_format(s, &d, def, sizeof def);
        fprintf(f, "  %-20s %s\n  %-20s (key %s, default %s)\n", opt, s->help, "", s->name, def);
    }
}

void trajreplay_usage(FILE *f)
{
    fputs(
        "usage: trajreplay [options] TRACK\n"
        "       trajreplay -c trajd.conf [--object NAME] [options] [TRACK]\n"
        "Replay a logged track (CSV, GPX, NMEA 2000 candump, NMEA 0183, IGC or a path:\n"
        "the formats below) through the trajd engine on a virtual clock and write the\n"
        "setpoints as CSV.\n"
        "\n"
        "  -c, --config FILE    take the engine settings, rate_hz, replay.track,\n"
        "                       replay.format, replay.skip_bad, replay.start_s and\n"
        "                       initial_position of object NAME in a trajd config (the\n"
        "                       only object if --object is not given), and [daemon]\n"
        "                       catchup: the output is the rows trajd writes for it\n"
        "                       (from initial_position, by a transfer to the first\n"
        "                       waypoint).  Not can.cia402 = feedback or managed (where\n"
        "                       the drives stand: a notice says so), nor the safety\n"
        "                       monitor.  Options given too override the file's\n"
        "                       settings; a TRACK given replaces replay.track\n"
        "  --rate HZ            output rate (default 100, or -c's rate_hz)\n"
        "  --format F           track format, default auto (the list below)\n"
        "  --skip-bad           skip and count malformed lines instead of failing\n"
        "  --strict             exit 6 if any waypoint was rejected or line skipped\n"
        "                       (each is reported as file:line: rejected (reason))\n"
        "  --keep-gaps          write hold rows through gaps longer than max_gap_s too\n"
        "                       (default: skip them; the row after a skipped gap has\n"
        "                       flag 4, ENGINE_SP_SKIPPED)\n"
        "  --override PCT       feed override, 1..200 % of the track's pace (default\n"
        "                       100): the time scaling plays the curve at that rate, as\n"
        "                       trajd's Modbus and CAN override command\n"
        "  --max-rows N         stop with exit 5 after N setpoint rows (default\n"
        "                       50000000; 0 = no limit)\n"
        "  --object NAME        value of the object column (default \"replay\"); with -c,\n"
        "                       the object of the config to replay\n"
        "  -o, --output FILE    setpoint CSV (default stdout; \"-\" = stdout)\n"
        "  --precision N        numbers in fixed notation with N decimals (0..17, e.g. 9:\n"
        "                       nanometres), exactly printf's %.Nf, by a fast formatter;\n"
        "                       g17: printf's %.17g (17 digits always, the former default)\n"
        "                       (default: the shortest decimal that reads back to the\n"
        "                       same double, as Python's repr writes it)\n"
        "  --geo                append the columns lat_deg,lon_deg,alt_m (a geographic\n"
        "                       track's setpoint in WGS84) and heading_deg (a heading\n"
        "                       column's axis, wrapped), as trajd's csv.geo = yes\n"
        "  --binary             write little-endian binary records instead of CSV: a\n"
        "                       64-byte header then 112 bytes per setpoint (layout and\n"
        "                       numpy dtype in trajreplay(1), BINARY FORMAT)\n"
        "  --svg FILE           draw waypoints, curve and speed profile\n"
        "  --summary            counters on stderr at the end\n"
        "  -q, --quiet          no progress line\n"
        "  --progress-after MS  progress line (stderr a terminal only) after MS ms (default 500)\n"
        "  -h, --help           this text\n"
        "  -V, --version        version\n",
        f);
    fputs("\nTrack formats (--format, replay.format; daemon/replay/track.h):\n", f);
    for (int k = 0; k < TRACK_FMT_COUNT; k++)
        fprintf(f, "  %-20s %s\n", track_format_name((track_format_t)k),
                track_format_help((track_format_t)k));
    usage_engine(f);
    fputs("\n"
          "Exit status: 0 ok, 1 track not loadable or no usable waypoint in it, 2 usage\n"
          "or configuration, 3 output write failed, 4 out of memory, 5 --max-rows\n"
          "reached, 6 --strict and something was rejected, 7 internal fault (a defect:\n"
          "a solver refused finite data; please report it), 8 the per-axis limits\n"
          "stopped the output on its path (--max-lag passed, or a segment over 100 times\n"
          "faster on an axis than its --axis-max-*; file:line names the waypoint).\n",
          f);
}

int trajreplay_check_config(const engine_config_t *cfg)
{
    char err[512];
    const char *why = NULL;
    if (engine_config_check(cfg, &why)) {
        fprintf(stderr, "trajreplay: invalid engine configuration: %s\n", why ? why : "?");
        return -1;
    }
    if (engine_delay_check(cfg, 0.0, err, sizeof err) ||
        engine_axis_jerk_check(cfg, err, sizeof err)) {
        fprintf(stderr, "trajreplay: invalid engine configuration: %s\n", err);
        return -1;
    }
    return 0;
}
