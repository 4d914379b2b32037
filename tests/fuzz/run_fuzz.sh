#!/bin/bash
# Run libFuzzer targets to a budget, FUZZ_JOBS at a time, and print one table
# (target, executions, executions/s, coverage, findings).  Called by `make fuzz`.
#   BUILD         absolute build directory
#   FUZZ_DIR      where the targets are (default $BUILD/fuzz: the depth build, UBSan;
#                 $BUILD/fuzz-asan with make fuzz FUZZ_ASAN=1)
#   FUZZ_EXECS    executions per target (libFuzzer -runs)
#   FUZZ_SECONDS  seconds per target (-max_total_time); with FUZZ_EXECS, a cap
#                 (whichever comes first); neither given: 30 s
#   FUZZ_JOBS     targets run at once (default 2)
#   FUZZ_TARGETS  target names (default: every $FUZZ_DIR/fuzz_*)
# Each target starts from tests/fuzz/corpus/<target>/ and tests/fuzz/regress/<target>/,
# copied into $FUZZ_DIR/corpus/<target>/ (the checked-in corpus is never written;
# `make fuzz-merge` minimizes what a run found back into it).  A finding (crash,
# leak, timeout, out of memory) stops that target; its input is written to
# $FUZZ_DIR/findings/<target>/ and the run exits 1.  Fix it, then keep the input
# in tests/fuzz/regress/<target>/: `make check` replays it from then on.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
FUZZ_DIR=${FUZZ_DIR:-$BUILD/fuzz}
FUZZ_EXECS=${FUZZ_EXECS:-}
FUZZ_SECONDS=${FUZZ_SECONDS:-}
FUZZ_JOBS=${FUZZ_JOBS:-2}
if [ -z "${FUZZ_TARGETS:-}" ]; then
    FUZZ_TARGETS=$(for f in "$FUZZ_DIR"/fuzz_*; do [ -x "$f" ] && [ -f "$f" ] && basename "$f"; done)
fi
budget=""
[ -n "$FUZZ_EXECS" ] && budget="-runs=$FUZZ_EXECS"
[ -n "$FUZZ_SECONDS" ] && budget="$budget -max_total_time=$FUZZ_SECONDS"
[ -z "$budget" ] && budget="-max_total_time=30"
# A small quarantine: a use after free within one input is still caught, and
# allocations reuse memory instead of faulting in fresh pages every input.
export ASAN_OPTIONS="${ASAN_OPTIONS:-quarantine_size_mb=16}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# glibc's malloc maps and unmaps every block of 128 KB or more: an engine per
# input paid for it in page faults and zeroing (fuzz_engine ran at half speed).
# Keep such blocks on the heap (the sanitizers' allocators ignore this).
export MALLOC_MMAP_THRESHOLD_="${MALLOC_MMAP_THRESHOLD_:-67108864}"
export MALLOC_TRIM_THRESHOLD_="${MALLOC_TRIM_THRESHOLD_:-134217728}"

now() { date +%s.%N; }

# After the run, every input the target kept (its grown corpus) and every
# finding is replayed through the AddressSanitizer + UBSan build of the plain
# driver ($BUILD/asan/tests/test_<target>), so that the depth build, which has
# no AddressSanitizer, still has each input it found interesting checked for
# memory errors.  A failure there is a finding.
run_target() { # name
    n=$1
    work=$FUZZ_DIR/corpus/$n; art=$FUZZ_DIR/findings/$n
    rm -rf "$art"; mkdir -p "$work" "$art"
    for d in tests/fuzz/corpus/$n tests/fuzz/regress/$n; do
        [ -d "$d" ] && find "$d" -maxdepth 1 -type f -exec cp {} "$work"/ \;
    done
    opts=""
    [ -f "tests/fuzz/$n.options" ] && opts=$(grep -v '^#' "tests/fuzz/$n.options" | tr '\n' ' ')
    t0=$(now)
    # shellcheck disable=SC2086 # $budget and $opts are lists of flags
    /usr/bin/time -f "%U %S" -o "$FUZZ_DIR/$n.cpu" \
        "$FUZZ_DIR/$n" $budget $opts -timeout=10 -print_final_stats=1 -artifact_prefix="$art/" \
        "$work" > "$FUZZ_DIR/$n.log" 2>&1
    rc=$?
    t1=$(now)
    asan=$BUILD/asan/tests/test_$n
    if [ -x "$asan" ]; then
        if ! "$asan" "$work" > "$FUZZ_DIR/$n.asan.log" 2>&1; then
            echo "asan replay failed" >> "$FUZZ_DIR/$n.log"
            cp "$FUZZ_DIR/$n.asan.log" "$art/asan-replay.log"
            rc=1
        fi
    else
        echo "  $n: no $asan: the kept inputs were not replayed under AddressSanitizer" >&2
    fi
    echo "$rc $t0 $t1" > "$FUZZ_DIR/$n.time"
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
printf '\n| %-22s | %12s | %8s | %10s | %7s | %9s | %8s |\n' target executions "exec/s" "exec/CPU-s" cov features findings
printf '|%s|%s|%s|%s|%s|%s|%s|\n' ------------------------ -------------- ---------- ------------ --------- ----------- ----------
for n in $FUZZ_TARGETS; do
    log=$FUZZ_DIR/$n.log
    read -r rc t0 t1 < "$FUZZ_DIR/$n.time"
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    last=$(grep -E '^#[0-9]+.*cov: ' "$log" | tail -n 1)
    cov=$(echo "$last" | sed -n 's/.*cov: \([0-9]*\).*/\1/p')
    ft=$(echo "$last" | sed -n 's/.*ft: \([0-9]*\).*/\1/p')
    found=$(find "$FUZZ_DIR/findings/$n" -type f | wc -l)
    rate=$(awk -v n="${execs:-0}" -v a="$t0" -v b="$t1" 'BEGIN { printf "%d", (b > a) ? n / (b - a) : 0 }')
    # executions per second of CPU the target used (user + system): what the
    # target costs, whatever else the machine was running
    cpu_rate=$(awk -v n="${execs:-0}" '{ c = $1 + $2 } END { printf "%d", (c > 0) ? n / c : 0 }' \
        "$FUZZ_DIR/$n.cpu" 2>/dev/null)
    printf '| %-22s | %12s | %8s | %10s | %7s | %9s | %8s |\n' "$n" "${execs:-?}" "$rate" "${cpu_rate:-?}" \
        "${cov:-?}" "${ft:-?}" "$found"
    if [ "$rc" -ne 0 ] || [ "$found" -ne 0 ]; then
        status=1
        grep -E 'ERROR|SUMMARY|Test unit written' "$log" | sed "s|^|    $n: |" | head -n 5
    fi
done
exit $status
