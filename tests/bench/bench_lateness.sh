#!/bin/bash
# bench_lateness.sh - tick lateness of the real trajd against cyclictest
# (rt-tests, installed by make bench), each under the same scheduling policy
# and in the same condition (issue 28 item 4):
#   workloads   4 objects at 1 kHz, setpoints to one CSV file each;
#               1024 objects at 100 Hz, setpoints to stdout (/dev/null)
#               (every object replays the real 5 Hz figure-eight);
#   policies    SCHED_OTHER; SCHED_FIFO 50 + mlockall (as root only);
#   conditions  idle; the other core busy (trajd, or cyclictest, pinned to
#               CPU 0 and a busy loop on CPU 1).
# Per row: trajd's lateness p50/p99/p99.9/max in us (its exit line: from the
# oldest deadline not yet served), missed ticks (count and share of the
# deadlines), the tick's own CPU time at p99.9 (CLOCK_THREAD_CPUTIME_ID,
# the exit line's "tick CPU"), trajd's CPU share over the measured window
# (/proc/PID/stat), cyclictest's p99 at the same rate, policy and CPU, run
# at the same time as trajd (so both meet the same noise of a shared machine:
# one sleeping thread each, a few us of work per period), and the ratio
# trajd p99 / cyclictest p99, and the share of cyclictest's wake-ups a
# period or more late (what the host allows of the missed share).  The
# previous values (the same row of tests/bench/RESULTS.md, between its
# lateness:begin/end marks) stand beside the new ones.  Nothing is asserted.
#   DURATION_S   measured seconds per run (default 10)
#   ONLY         "4" or "1024": one workload only
#   CONDITION    a part of a condition's label ("busy", "FIFO"): those rows only
set -eu
cd "$(dirname "$0")/../.."
: "${BUILD:?BUILD must be set}"
DURATION_S=${DURATION_S:-10}
ONLY=${ONLY:-}
CONDITION=${CONDITION:-}
TRAJD="$BUILD/bin/trajd"
TRACK="$PWD/tests/data/n2k_furuno_figure8_src52.csv"
RESULTS="$PWD/tests/bench/RESULTS.md"
tmp=$(mktemp -d)
busy=""
pid=""
trap '[ -n "$busy" ] && kill "$busy" 2>/dev/null; [ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$tmp"' EXIT
ncpu=$(nproc)
hz=$(getconf CLK_TCK)

conf() { # $1 = objects, $2 = rate_hz, $3 = extra [realtime] lines
    {
        printf '[daemon]\nrate_hz = %s\nstatus_interval_s = 0\nstop_timeout_s = 0\n' "$2"
        printf '[realtime]\n%b' "$3"
        for i in $(seq 1 "$1"); do
            printf '[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\n' "$i" "$((i - 1))" "$TRACK"
            if [ "$1" -le 4 ]; then
                printf 'output = csv\ncsv.path = %s/o%d.csv\n' "$tmp" "$i"
            else
                printf 'output = stdout\n'
            fi
        done
    } > "$tmp/bench.conf"
}

# trajd for DURATION_S after its start-up, cyclictest (options $2..) at the
# same time; prints "ticks p50 p99 p999 max missed tickcpu999 cpu%" and
# leaves cyclictest's p99 in $tmp/cyc
run() { # $1 = period us, $2.. = cyclictest options
    local period=$1; shift
    rm -f "$tmp"/o*.csv
    "$TRAJD" -f -c "$tmp/bench.conf" > /dev/null 2> "$tmp/err" & pid=$!
    local i
    for i in $(seq 1 600); do
        grep -q 'started:' "$tmp/err" && break
        kill -0 "$pid" 2> /dev/null || break
        sleep 0.1
    done
    kill -0 "$pid" 2> /dev/null || { grep -v '^<6>object' "$tmp/err" | head -n 5 >&2; }
    local c0 c1
    c0=$(awk '{ print $14 + $15 }' "/proc/$pid/stat" 2> /dev/null || echo 0)
    cyclic_p99 "$period" "$@" > "$tmp/cyc" & local cyc=$!
    sleep "$DURATION_S"
    c1=$(awk '{ print $14 + $15 }' "/proc/$pid/stat" 2> /dev/null || echo 0)
    wait "$cyc" || true
    kill -TERM "$pid"; wait "$pid" 2> /dev/null || true; pid=""
    grep 'exit:' "$tmp/err" | tail -n 1 | awk -v c="$((c1 - c0))" -v hz="$hz" -v dur="$DURATION_S" '{
        match($0, /ticks [0-9]+/); ticks = substr($0, RSTART + 6, RLENGTH - 6);
        match($0, /missed [0-9]+/); missed = substr($0, RSTART + 7, RLENGTH - 7);
        match($0, /late p50\/p99\/p99.9\/max [0-9\/]+/); split(substr($0, RSTART + 23, RLENGTH - 23), q, "/");
        w = "-"; if (match($0, /tick CPU p99.9\/max [0-9]+/)) w = substr($0, RSTART + 19, RLENGTH - 19);
        printf "%s %s %s %s %s %s %s %.1f\n", ticks, q[1], q[2], q[3], q[4], missed, w, 100 * c / hz / dur }'
}

# cyclictest's p99 wake-up latency (us), and the share (%) of its wake-ups a
# period or more late (each one a deadline a tick would have missed): one
# thread at the period, for DURATION_S
cyclic_p99() { # $1 = period us, $2... = cyclictest options (policy, CPU)
    local period=$1; shift
    command -v cyclictest > /dev/null || { echo "- -"; return; }
    cyclictest -q -t 1 -i "$period" -D "$DURATION_S" -h 100000 "$@" 2> /dev/null | awk -v per="$period" '
        /^[0-9]/ { h[$1 + 0] = $2 + 0; if ($1 + 0 > top) top = $1 + 0; next }
        /^# Total:/ { total = $3 + 0 }
        /^# Histogram Overflows:/ { ovf = $4 + 0 }
        END {
            if (total == 0) { print "- -"; exit }
            late = ovf; for (us = per; us <= top; us++) late += h[us]
            share = sprintf("%.3f", 100 * late / total)
            c = 0; for (us = 0; us <= top; us++) { c += h[us]; if (c >= 0.99 * total) { print us, share; exit } }
            print ">100000", share }'
}

# The previous row's ratio, missed share and tick CPU, from RESULTS.md
prev() { # $1 = workload label, $2 = condition label
    awk -v w="$1" -v c="$2" '
        /lateness:begin/ { on = 1; next } /lateness:end/ { on = 0 }
        on && /^\|/ { n = split($0, f, "|"); for (i = 1; i <= n; i++) gsub(/^ +| +$/, "", f[i]);
            if (f[2] == w && f[3] == c) { print f[6], f[10], f[12]; found = 1; exit } }
        END { if (!found) print "- - -" }' "$RESULTS" 2> /dev/null || echo "- - -"
}

row() { # $1 = objects, $2 = rate, $3 = condition label, $4 = [realtime] lines, $5 = CPU list for cyclictest, $6.. cyclictest policy
    local objs=$1 rate=$2 label=$3 rt=$4 cpu=$5; shift 5
    case "$label" in *"$CONDITION"*) ;; *) return 0 ;; esac
    conf "$objs" "$rate" "$rt"
    local r c p
    if [ -n "$cpu" ]; then r=$(run $((1000000 / rate)) -a "$cpu" "$@"); else r=$(run $((1000000 / rate)) "$@"); fi
    c=$(cat "$tmp/cyc")
    p=$(prev "$objs x $rate Hz" "$label")
    set -- $c
    echo "$r $1 $p $2" | awk -v w="$objs x $rate Hz" -v l="$label" '{
        ticks = $1; p99 = $3; missed = $6; ratio = ($9 + 0 > 0) ? sprintf("%.2f", p99 / $9) : "-";
        share = (ticks + missed > 0) ? sprintf("%.3f", 100 * missed / (ticks + missed)) : "-";
        printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n",
            w, l, $3, $9, ratio, $10, $2 "/" $4 "/" $5, missed, share, $11, $7, $12, $8, $13 }'
}

busy_on() { taskset -c 1 sh -c 'while :; do :; done' & busy=$!; }
busy_off() { kill "$busy"; wait "$busy" 2> /dev/null || true; busy=""; }

echo "trajd tick lateness against cyclictest, ${DURATION_S} s per run, $ncpu CPUs, $(uname -r)"
echo "x cyclictest: trajd's p99 over cyclictest's p99, run at the same time, same policy and CPUs;"
echo "was: the same row of tests/bench/RESULTS.md"
echo "<!-- lateness:begin -->"
echo "| workload | condition | trajd p99 us | cyclictest p99 us | x cyclictest | was | trajd p50/p99.9/max us | missed | missed % | was | tick CPU p99.9 us | was | trajd CPU % | cyclictest a period late % |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for w in "4 1000" "1024 100"; do
    set -- $w
    [ -n "$ONLY" ] && [ "$ONLY" != "$1" ] && continue
    row "$1" "$2" "SCHED_OTHER, idle" "" ""
    if [ "$ncpu" -ge 2 ]; then
        busy_on
        row "$1" "$2" "SCHED_OTHER, other core busy" "cpu_affinity = 0\n" 0
        busy_off
    fi
    if [ "$(id -u)" -eq 0 ]; then
        row "$1" "$2" "SCHED_FIFO 50 + mlockall, idle" "fifo_priority = 50\nmlockall = yes\n" "" -p 50 -m
        if [ "$ncpu" -ge 2 ]; then
            busy_on
            row "$1" "$2" "SCHED_FIFO 50 + mlockall, other core busy" \
                "fifo_priority = 50\nmlockall = yes\ncpu_affinity = 0\n" 0 -p 50 -m
            busy_off
        fi
    fi
done
echo "<!-- lateness:end -->"
