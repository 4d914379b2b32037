#!/bin/bash
# test_can_log_not_late.sh - issue 24 item 8: a late cycle's setpoints are
# dropped only on a live bus.  trajd replays a track onto a candump log_out at
# speed 1000 and 1 kHz (a wall-clock period of 1 us: every tick wakes later
# than half a period), and its exit summary counts 0 setpoints dropped late;
# the log holds one SETPOINT frame set per tick that ran; the port counts
# every tick a cycle, none of them down.  The old code
# dropped thousands (a log file has no bus to be late for).
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
{ printf '[daemon]\nrate_hz = 1000\nspeed = 1000\nexit_when_done = yes\nstatus_interval_s = 0\n'
  printf '[can]\nlog_out = %s/out.log\nmax_load_percent = 0\n' "$tmp"
  printf '[object.boat]\ninput = replay\nreplay.track = %s\noutput = can\n' \
      "$PWD/tests/data/n2k_furuno_figure8_src52.csv"; } > "$tmp/t.conf"
"$BUILD/bin/trajd" -f -c "$tmp/t.conf" 2> "$tmp/err" || { cat "$tmp/err"; fail "trajd"; }
line=$(grep "setpoints sent" "$tmp/err") || { cat "$tmp/err"; fail "no CAN summary"; }
echo "$line"
late=$(echo "$line" | sed -n 's/.*dropped late \([0-9]*\).*/\1/p')
sent=$(echo "$line" | sed -n 's/.*setpoints sent \([0-9]*\).*/\1/p')
[ "$late" = 0 ] || fail "$late setpoints dropped late writing a log file"
[ "$sent" -gt 1000 ] || fail "only $sent setpoints sent"
# the port's own counters (can_port_stats): every tick a cycle, a log file never down
port=$(grep "frames received" "$tmp/err") || { cat "$tmp/err"; fail "no CAN port summary"; }
echo "$port"
cycles=$(echo "$port" | sed -n 's/.*cycles \([0-9]*\) (0 down).*/\1/p')
[ -n "$cycles" ] && [ "$cycles" -ge "$sent" ] || fail "cycles: $port"
echo "test_can_log_not_late: ok"
