#!/bin/bash
# bench_scale.sh - many objects on one core (issue 13: >= 1024 objects at
# 100 Hz, >= 256 at 1 kHz): trajd pinned to CPU 0, every object replaying
# the real 5 Hz figure-eight, setpoints to stdout (/dev/null: formatting
# included, no disk).  Per run: the daemon's CPU use after start-up (from
# /proc/PID/stat over the measured window), tick lateness p50/p99 and missed
# ticks (its exit line), resident memory, and cyclictest at the same rate,
# on the same CPU, for the same time, right after: trajd's p99 over
# cyclictest's p99 is the ratio printed.  Memory per object is the RSS
# difference between N objects and one, over N - 1.  Nothing is asserted.
#   DURATION_S   measured seconds per run (default 30)
set -eu
cd "$(dirname "$0")/../.."
: "${BUILD:?BUILD must be set}"
DURATION_S=${DURATION_S:-30}
TRAJD="$BUILD/bin/trajd"
TRACK="$PWD/tests/data/n2k_furuno_figure8_src52.csv"
tmp=$(mktemp -d)
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$tmp"' EXIT
hz=$(getconf CLK_TCK)

conf() { # $1 = objects, $2 = rate_hz
    {
        printf '[daemon]\nrate_hz = %s\nstatus_interval_s = 0\nstop_timeout_s = 0\n' "$2"
        printf '[realtime]\ncpu_affinity = 0\n'
        for i in $(seq 0 $(($1 - 1))); do
            printf '[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\noutput = stdout\n' \
                "$i" "$i" "$TRACK"
        done
    } > "$tmp/s.conf"
}

cpu_ticks() { awk '{ print $14 + $15 }' "/proc/$1/stat"; }
rss_kb() { awk '/^VmRSS:/ { print $2 }' "/proc/$1/status"; }

# One run: prints "cpu_percent rss_kb p50 p99 missed ticks"
run() { # $1 = objects, $2 = rate
    conf "$1" "$2"
    "$TRAJD" -f -c "$tmp/s.conf" > /dev/null 2> "$tmp/err" & pid=$!
    # start-up (loading the tracks) until the first tick: the status line
    # comes at the end, so wait for the process to settle instead
    local warm=$(( $1 / 100 + 3 ))
    sleep "$warm"
    local c0; c0=$(cpu_ticks "$pid")
    sleep "$DURATION_S"
    local c1 rss; c1=$(cpu_ticks "$pid"); rss=$(rss_kb "$pid")
    kill -TERM "$pid"; wait "$pid" 2>/dev/null || true; pid=""
    local line; line=$(grep 'exit:' "$tmp/err" | tail -n 1)
    echo "$line" | awk -v c="$((c1 - c0))" -v hz="$hz" -v dur="$DURATION_S" -v rss="$rss" '{
        match($0, /ticks [0-9]+/); ticks = substr($0, RSTART + 6, RLENGTH - 6);
        match($0, /missed [0-9]+/); missed = substr($0, RSTART + 7, RLENGTH - 7);
        match($0, /p50\/p99\/p99.9\/max [0-9\/]+/); split(substr($0, RSTART + 18, RLENGTH - 18), q, "/");
        printf "%.1f %d %s %s %s %s\n", 100 * c / hz / dur, rss, q[1], q[2], missed, ticks }'
}

cyclic_p99() { # $1 = rate: p99 wakeup latency in us on CPU 0
    command -v cyclictest > /dev/null || { echo "-"; return; }
    cyclictest -q -t 1 -a 0 -i $((1000000 / $1)) -D "$DURATION_S" -h 100000 2> /dev/null | awk '
        /^[0-9]/ { h[$1 + 0] = $2 + 0; if ($1 + 0 > top) top = $1 + 0; next }
        /^# Total:/ { total = $3 + 0 }
        END { if (!total) { print "-"; exit } c = 0;
              for (us = 0; us <= top; us++) { c += h[us]; if (c >= 0.99 * total) { print us; exit } }
              print ">100000" }'
}

echo "trajd with many objects on CPU 0, ${DURATION_S} s measured per run, $(nproc) CPUs, $(uname -r)"
echo "x cyclictest = trajd's p99 tick lateness over cyclictest's p99 wakeup latency (same rate, CPU, length; this run)"
echo "| objects | rate | CPU % | RSS MB | late p50 us | late p99 us | missed | ticks | cyclictest p99 us | x cyclictest |"
echo "|---|---|---|---|---|---|---|---|---|---|"
base=""
for spec in "1 100" "1024 100" "256 1000"; do
    set -- $spec
    r=$(run "$1" "$2")
    cy=$(cyclic_p99 "$2")
    set -- $1 $2 $r
    [ "$1" = 1 ] && base=$4
    ratio=$(awk -v a="$6" -v b="$cy" 'BEGIN { if (b + 0 > 0) printf "%.2f", a / b; else print "-" }')
    printf '| %s | %s Hz | %s | %.1f | %s | %s | %s | %s | %s | %s |\n' "$1" "$2" "$3" \
        "$(awk -v k="$4" 'BEGIN { print k / 1024 }')" "$5" "$6" "$7" "$8" "$cy" "$ratio"
    if [ "$1" != 1 ] && [ -n "$base" ]; then
        per=$(awk -v n="$1" -v a="$4" -v b="$base" 'BEGIN { printf "%.0f", (a - b) / (n - 1) }')
        echo "|   | memory per object: ${per} kB (RSS over one object's, / $(($1 - 1))) | | | | | | | | |"
    fi
done
