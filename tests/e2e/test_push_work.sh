#!/bin/bash
# test_push_work.sh - no waypoint costs its push much more than the pushes
# that solve a fragment, counted in instructions by callgrind (not timed).
#   Given the real figure-eight (tests/data/n2k_furuno_figure8_src52.csv,
#   1 786 fixes at 5 Hz) replayed by trajreplay, when each engine_push is
#   counted on its own (valgrind --tool=callgrind, collecting inside
#   engine_push only, one dump after each call), then the costliest push takes
#   at most twice the instructions of the push at the 99th percentile (the
#   pushes that end a fragment and solve it are 1 in 4 of them).
# Why: in trajd every object that replays the same track takes the same push
# on the same tick, so the tick costs as many times that push as there are
# objects (1 024 in tests/bench/bench_lateness.sh).  The input's robust
# interval (engine_delay_grow, on 14 of these pushes) took 30-37 k
# instructions, three times a fragment's solve (about 10 k): the ticks of
# about 10 ms of CPU time at 1 024 objects and 100 Hz.
set -eu
cd "$(dirname "$0")/../.."
: "${BUILD:?BUILD must be set}"
command -v valgrind > /dev/null || { echo "valgrind missing (DEPS_TEST)"; exit 1; }
command -v callgrind_annotate > /dev/null || { echo "callgrind_annotate missing (valgrind)"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
track=tests/data/n2k_furuno_figure8_src52.csv
timeout 600 valgrind --tool=callgrind --toggle-collect=engine_push --dump-after=engine_push \
    --callgrind-out-file="$tmp/cg" "$BUILD/bin/trajreplay" -q -o "$tmp/out.csv" "$track" \
    > "$tmp/vg.log" 2>&1 || { cat "$tmp/vg.log"; echo "FAIL: trajreplay under callgrind"; exit 1; }
# one file per push (cg.1, cg.2, ...), its instructions on its "totals:" line
for f in "$tmp"/cg.*; do
    sed -n 's/^totals: \([0-9]*\).*/\1/p' "$f"
done | sort -n > "$tmp/counts"
n=$(wc -l < "$tmp/counts")
rows=$(($(wc -l < "$track") - 1))
[ "$n" -ge "$rows" ] || { echo "FAIL: $n pushes counted, the track has $rows fixes"; exit 1; }
p99=$(sed -n "$(( (n * 99 + 99) / 100 ))p" "$tmp/counts")
max=$(tail -n 1 "$tmp/counts")
median=$(sed -n "$(( (n + 1) / 2 ))p" "$tmp/counts")
echo "$n pushes: median $median, p99 $p99, max $max instructions"
[ "$max" -le $((2 * p99)) ] ||
    { echo "FAIL: the costliest push takes $max instructions, more than twice the 99th percentile ($p99)"; exit 1; }
echo ok
