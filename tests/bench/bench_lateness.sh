#!/bin/bash
# bench_lateness.sh - tick lateness of the real trajd at 1 kHz with 4 objects
# (the real 5 Hz figure-eight replayed into each, setpoints to CSV files),
# idle, with the other core loaded by a busy loop, and (as root) with
# SCHED_FIFO + mlockall.  Prints p50/p99/p99.9/max lateness in us, missed
# ticks, overruns and the daemon's CPU use.  Nothing is asserted.
#   DURATION_S   seconds per run (default 60; e.g. DURATION_S=5 for a quick look)
set -eu
cd "$(dirname "$0")/../.."
: "${BUILD:?BUILD must be set}"
DURATION_S=${DURATION_S:-60}
TRAJD="$BUILD/bin/trajd"
TRACK="$PWD/tests/data/n2k_furuno_figure8_src52.csv"
tmp=$(mktemp -d)
busy=""
trap '[ -n "$busy" ] && kill "$busy" 2>/dev/null; rm -rf "$tmp"' EXIT
ncpu=$(nproc)

conf() { # $1 = extra [realtime] lines
    {
        printf '[daemon]\nrate_hz = 1000\nstatus_interval_s = 0\nstop_timeout_s = 0\n'
        printf '[realtime]\n%b' "$1"
        for i in 1 2 3 4; do
            printf '[object.obj%d]\nid = %d\ninput = replay\nreplay.track = %s\noutput = csv\ncsv.path = %s/obj%d.csv\n' \
                "$i" "$i" "$TRACK" "$tmp" "$i"
        done
    } > "$tmp/bench.conf"
}

run() { # $1 = label
    # timeout sends SIGTERM after DURATION_S (stop_timeout_s = 0: exit at once);
    # `times` then gives the CPU time of the finished child.
    local out
    out=$( { timeout -s TERM "$DURATION_S" "$TRAJD" -f -c "$tmp/bench.conf" 2> "$tmp/err" || true; times; } )
    local cpu summary
    cpu=$(echo "$out" | tail -n 1 | awk '{
        split($1, u, "m"); split($2, s, "m");
        sub("s", "", u[2]); sub("s", "", s[2]);
        printf "%.2f", (u[1] * 60 + u[2] + s[1] * 60 + s[2]) }')
    summary=$(grep 'exit:' "$tmp/err" | tail -n 1)
    echo "$summary" | awk -v label="$1" -v cpu="$cpu" -v dur="$DURATION_S" '{
        match($0, /ticks [0-9]+/); ticks = substr($0, RSTART + 6, RLENGTH - 6);
        match($0, /missed [0-9]+/); missed = substr($0, RSTART + 7, RLENGTH - 7);
        match($0, /overruns [0-9]+/); over = substr($0, RSTART + 9, RLENGTH - 9);
        match($0, /p50\/p99\/p99.9\/max [0-9\/]+/); split(substr($0, RSTART + 18, RLENGTH - 18), q, "/");
        printf "| %-24s | %6s | %5s | %5s | %7s | %6s | %6s | %8s | %5.2f %% |",
            label, ticks, q[1], q[2], q[3], q[4], missed, over, 100 * cpu / dur }' > "$tmp/row"
}

# cyclictest (rt-tests, in make bench's dependencies) at the same 1 kHz for
# the same duration, one thread at the same policy: the machine's own wakeup
# latency, the floor trajd's lateness is read against.
cyclic() { # $1 = label, $2... = extra cyclictest options
    local label=$1; shift
    command -v cyclictest > /dev/null || { cat "$tmp/row"; echo " - |"; echo "| $label | cyclictest not installed (rt-tests) |"; return; }
    cyclictest -q -t 1 -i 1000 -D "$DURATION_S" -h 100000 "$@" 2> /dev/null | awk -v label="$label" \
        -v row="$(cat "$tmp/row")" '
        /^[0-9]/ { h[$1 + 0] = $2 + 0; if ($1 + 0 > top) top = $1 + 0; next }
        /^# Total:/ { total = $3 + 0 }
        /^# Max Latencies:/ { max = $4 + 0 }
        /^# Histogram Overflows:/ { over = $4 + 0 }
        END {
            if (total == 0) { printf "| %-24s | no samples |\n", label; exit }
            c = 0; p50 = p99 = p999 = -1;
            for (us = 0; us <= top; us++) {
                c += h[us];
                if (p50 < 0 && c >= 0.5 * total) p50 = us;
                if (p99 < 0 && c >= 0.99 * total) p99 = us;
                if (p999 < 0 && c >= 0.999 * total) p999 = us;
            }
            if (p99 < 0) p99 = ">100000"; if (p999 < 0) p999 = ">100000";
            # the trajd row of the same condition, with its p99 over this p99
            split(row, f, "|"); tp99 = f[5] + 0;
            printf "%s %s |\n", row, (p99 + 0 > 0) ? sprintf("%.2f", tp99 / p99) : "-";
            printf "| %-24s | %6d | %5s | %5s | %7s | %6d | %6s | %8s | %7s | %s |\n",
                label, total, p50, p99, p999, max, "-", over " ovf", "-", "1.00" }'
}

echo "trajd lateness at 1 kHz, 4 objects, ${DURATION_S} s per run, $ncpu CPUs, $(uname -r)"
echo "x cyclictest = trajd's p99 lateness over cyclictest's p99 wakeup latency in the same condition, this run"
echo "| run                      |  ticks | p50us | p99us | p99.9us | max us | missed | overruns | CPU     | x cyclictest |"
echo "|---|---|---|---|---|---|---|---|---|---|"
conf ""
run "idle"
cyclic "cyclictest, idle"
if [ "$ncpu" -ge 2 ]; then
    conf "cpu_affinity = 0\n"
    taskset -c 1 sh -c 'while :; do :; done' & busy=$!
    run "other core busy"
    cyclic "cyclictest, other busy" -a 0
    kill "$busy"; wait "$busy" 2>/dev/null || true; busy=""
fi
if [ "$(id -u)" -eq 0 ]; then
    conf "fifo_priority = 50\nmlockall = yes\n"
    run "SCHED_FIFO 50 + mlockall"
    cyclic "cyclictest, FIFO 50 + mlock" -p 50 -m
fi
