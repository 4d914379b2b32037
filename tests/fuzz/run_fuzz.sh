#!/bin/bash
# Run libFuzzer targets to a budget, FUZZ_JOBS at a time, and print one table
# (target, executions, executions/s, coverage, findings).  Called by `make fuzz`.
#   BUILD         absolute build directory (binaries in $BUILD/fuzz/<target>)
#   FUZZ_EXECS    executions per target (libFuzzer -runs)
#   FUZZ_SECONDS  seconds per target (-max_total_time); with FUZZ_EXECS, a cap
#                 (whichever comes first); neither given: 30 s
#   FUZZ_JOBS     targets run at once (default 2)
#   FUZZ_TARGETS  target names (default: every $BUILD/fuzz/fuzz_*)
# Each target starts from tests/fuzz/corpus/<target>/ and tests/fuzz/regress/<target>/,
# copied into $BUILD/fuzz/corpus/<target>/ (the checked-in corpus is never written;
# `make fuzz-merge` minimizes what a run found back into it).  A finding (crash,
# leak, timeout, out of memory) stops that target; its input is written to
# $BUILD/fuzz/findings/<target>/ and the run exits 1.  Fix it, then keep the input
# in tests/fuzz/regress/<target>/: `make check` replays it from then on.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
FUZZ_EXECS=${FUZZ_EXECS:-}
FUZZ_SECONDS=${FUZZ_SECONDS:-}
FUZZ_JOBS=${FUZZ_JOBS:-2}
if [ -z "${FUZZ_TARGETS:-}" ]; then
    FUZZ_TARGETS=$(for f in "$BUILD"/fuzz/fuzz_*; do [ -x "$f" ] && [ -f "$f" ] && basename "$f"; done)
fi
budget=""
[ -n "$FUZZ_EXECS" ] && budget="-runs=$FUZZ_EXECS"
[ -n "$FUZZ_SECONDS" ] && budget="$budget -max_total_time=$FUZZ_SECONDS"
[ -z "$budget" ] && budget="-max_total_time=30"
# A small quarantine: a use after free within one input is still caught, and
# allocations reuse memory instead of faulting in fresh pages every input.
export ASAN_OPTIONS="${ASAN_OPTIONS:-quarantine_size_mb=16}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

now() { date +%s.%N; }

run_target() { # name
    n=$1
    work=$BUILD/fuzz/corpus/$n; art=$BUILD/fuzz/findings/$n
    rm -rf "$art"; mkdir -p "$work" "$art"
    for d in tests/fuzz/corpus/$n tests/fuzz/regress/$n; do
        [ -d "$d" ] && find "$d" -maxdepth 1 -type f -exec cp {} "$work"/ \;
    done
    t0=$(now)
    "$BUILD/fuzz/$n" $budget -timeout=10 -print_final_stats=1 -artifact_prefix="$art/" \
        "$work" > "$BUILD/fuzz/$n.log" 2>&1
    rc=$?
    t1=$(now)
    echo "$rc $t0 $t1" > "$BUILD/fuzz/$n.time"
}

# FUZZ_JOBS at a time: a new target starts as soon as one ends.
running=0
for n in $FUZZ_TARGETS; do
    if [ "$running" -ge "$FUZZ_JOBS" ]; then
        wait -n
        running=$((running - 1))
    fi
    echo "== $n ($budget)"
    run_target "$n" &
    running=$((running + 1))
done
wait

status=0
printf '\n| %-22s | %12s | %8s | %7s | %9s | %8s |\n' target executions "exec/s" cov features findings
printf '|%s|%s|%s|%s|%s|%s|\n' ------------------------ -------------- ---------- --------- ----------- ----------
for n in $FUZZ_TARGETS; do
    log=$BUILD/fuzz/$n.log
    read -r rc t0 t1 < "$BUILD/fuzz/$n.time"
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    last=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -n 1)
    cov=$(echo "$last" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.*ft: \([0-9]*\).*/\1/p')
    found=$(find "$BUILD/fuzz/findings/$n" -type f | wc -l)
    rate=$(awk -v n="${execs:-0}" -v a="$t0" -v b="$t1" 'BEGIN { printf "%d", (b > a) ? n / (b - a) : 0 }')
    printf '| %-22s | %12s | %8s | %7s | %9s | %8s |\n' "$n" "${execs:-?}" "$rate" "${cov:-?}" "${ft:-?}" "$found"
    if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
        status=1
        grep -E 'ERROR|SUMMARY|Test unit written' "$log" | sed "s|^|    $n: |" | head -n 5
    fi
done
exit $status
