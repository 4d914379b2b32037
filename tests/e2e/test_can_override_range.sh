#!/bin/bash
# test_can_override_range.sh - issue 24 item 2: a CAN feed override above 200 %
# is a well-formed command that is refused: counted in "commands refused" (not
# in "malformed frames") and logged with its reason.  trajd reads the command
# frames from a candump log_in (override 250 %, then 100 %).  The old code
# counted the 250 % frame as malformed, silently.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
# WAYPOINT id 0x680, mux 4 (command), seq 0, command 5 (override), percent 0xFA / 0x64
printf '(0.100000) can0 680#040005FA00000000\n(0.200000) can0 680#0400056400000000\n' > "$tmp/in.log"
printf '[daemon]\nrate_hz = 20\nspeed = 10\nexit_when_done = yes\nstatus_interval_s = 0\n' > "$tmp/t.conf"
printf '[can]\nlog_in = %s/in.log\nlog_out = %s/out.log\n' "$tmp" "$tmp" >> "$tmp/t.conf"
printf '[object.boat]\ninput = can\noutput = can\n' >> "$tmp/t.conf"
# exit 65: the log has no waypoint (what the test needs is the commands)
"$BUILD/bin/trajd" -f -c "$tmp/t.conf" 2> "$tmp/err"
grep -q "0 malformed frames; 1 commands refused" "$tmp/err" || { cat "$tmp/err"; fail "counted as"; }
grep -q "the last override on id 0x680: an override above 200 %" "$tmp/err" ||
    { cat "$tmp/err"; fail "not logged with its reason"; }
echo "test_can_override_range: ok"
