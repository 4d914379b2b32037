#!/bin/bash
# [can] log_out stamps are wall-clock epoch times by default (log_time = wall):
#   - trajd replays a track onto a candump log; its first stamp lies between
#     the epoch times taken just before trajd started and just after it ended,
#     and the stamps never go backwards;
#   - can-utils' log2asc (independent reader) converts the log with one
#     header ("date" once: with stamps from 0 s it repeated the header), as
#     many frame lines as the log has frames, and times relative to the first
#     frame equal to the log's own differences (to the microsecond);
#   - log_time = engine keeps the engine-time stamps (from 0 s, not epoch).
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
command -v log2asc > /dev/null || { echo "FAIL: log2asc (can-utils) not installed (make deps installs it)"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run() { # log_time value ("" = default) -> $tmp/out.log
    { printf '[daemon]\nrate_hz = 20\nspeed = 100\nexit_when_done = yes\nstatus_interval_s = 0\n'
      printf '[can]\nlog_out = %s/out.log\nmax_load_percent = 0\n' "$tmp"
      [ -n "$1" ] && printf 'log_time = %s\n' "$1"
      printf '[object.boat]\ninput = replay\nreplay.track = %s\noutput = can\n' \
          "$PWD/tests/data/n2k_furuno_figure8_src52.csv"; } > "$tmp/t.conf"
    "$BUILD/bin/trajd" -f -c "$tmp/t.conf" 2> "$tmp/err" || { cat "$tmp/err"; fail "trajd ($1)"; }
}
t0=$(date +%s.%N)
run ""
t1=$(date +%s.%N)
n=$(wc -l < "$tmp/out.log")
start=$(head -1 "$tmp/out.log" | cut -d" " -f1)
[ "$n" -gt 1000 ] || fail "only $n frames logged"
awk -v t0="$t0" -v t1="$t1" '
    { ts = substr($1, 2, length($1) - 2) + 0 }
    NR == 1 && (ts < t0 - 0.001 || ts > t1) { print "first stamp " ts " outside " t0 " .. " t1; bad = 1 }
    NR > 1 && ts < last { print "line " NR ": stamp goes back"; bad = 1 }
    { last = ts }
    END { exit bad }' "$tmp/out.log" || fail "wall-clock stamps"
log2asc -I "$tmp/out.log" -O "$tmp/out.asc" can0 || fail "log2asc"
[ "$(grep -c '^date ' "$tmp/out.asc")" = 1 ] || fail "log2asc wrote $(grep -c '^date ' "$tmp/out.asc") headers"
frames=$(grep -cE '^ +[0-9]+\.[0-9]+ 1 ' "$tmp/out.asc")
[ "$frames" = "$n" ] || fail "log2asc: $frames frame lines for $n frames"
# relative times in the ASC against the log's differences, line by line
paste <(awk '{ ts = substr($1, 2, length($1) - 2); split(ts, p, "."); us = p[1] * 1000000 + p[2]
               if (NR == 1) first = us; print us - first }' "$tmp/out.log") \
      <(awk '/^ +[0-9]+\.[0-9]+ 1 / { split($1, p, "."); print p[1] * 1000000 + p[2] }' "$tmp/out.asc") |
    awk '$1 != $2 { print "frame " NR ": log +" $1 " us, asc +" $2 " us"; bad = 1; exit } END { exit bad }' ||
    fail "log2asc times"
run engine
first=$(head -1 "$tmp/out.log" | sed 's/^(\([0-9.]*\)).*/\1/')
awk -v f="$first" 'BEGIN { exit !(f < 1000) }' || fail "log_time = engine: first stamp $first"
echo "PASS: $n frames, epoch stamps from $start, log2asc agrees"
