#!/bin/bash
# tests/run.sh itself: three outcomes (PASS, FAIL, SKIP by exit 77 or a first
# line "SKIP:"), a hung program failed by its timeout, the closing line counting
# each, the skipped listed with their reasons, the same verdicts whether the
# programs run one at a time or side by side, and COUNTS appended.
set -u
unset TESTS COUNTS JOBS ONLY  # run.sh itself may have set them for this program
cd "$(dirname "$0")/../.." || exit 1
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
mkdir -p "$tmp/tests"
prog() { printf '#!/bin/sh\n%s\n' "$2" > "$tmp/tests/$1"; chmod +x "$tmp/tests/$1"; }
prog test_pass 'echo fine; exit 0'
prog test_fail 'echo broken; exit 3'
prog test_skip77 'echo "no peer here"; exit 77'
prog test_skipline 'echo "SKIP: nothing to talk to"; exit 0'
prog test_hang 'sleep 60'
prog test_pyskips 'echo "Ran 5 tests in 0.1s"; echo "OK (skipped=2)"'
for jobs in 1 4; do
    rm -f "$tmp/counts"
    out=$(BUILD="$tmp" ONLY=c JOBS=$jobs TEST_TIMEOUT_S=2 COUNTS="$tmp/counts" sh tests/run.sh 2>&1)
    rc=$?
    [ $rc -ne 0 ] || fail "JOBS=$jobs: exit 0 with failures:$(printf '\n%s' "$out")"
    last=$(printf '%s\n' "$out" | tail -n 1)
    [ "$last" = "check: 2 passed, 2 failed, 2 skipped" ] || fail "JOBS=$jobs: closing line '$last'"
    printf '%s\n' "$out" | grep -q '^failed: test_fail test_hang$' ||
        printf '%s\n' "$out" | grep -q '^failed: test_hang test_fail$' ||
        fail "JOBS=$jobs: the failed are not named:$(printf '\n%s' "$out")"
    printf '%s\n' "$out" | grep -q '^  test_skip77: no peer here$' || fail "JOBS=$jobs: exit 77 reason missing"
    printf '%s\n' "$out" | grep -q '^  test_skipline: nothing to talk to$' || fail "JOBS=$jobs: SKIP: reason missing"
    printf '%s\n' "$out" | grep -q '^  test_pyskips: 2 of 5 cases skipped' || fail "JOBS=$jobs: skipped cases not listed"
    printf '%s\n' "$out" | grep -q '^FAIL test_hang (.*exit 124' || fail "JOBS=$jobs: the hung program is not failed by its timeout"
    [ "$(cat "$tmp/counts")" = "2 2 2" ] || fail "JOBS=$jobs: COUNTS holds '$(cat "$tmp/counts")'"
done
# TESTS= picks by name; a pass alone exits 0
out=$(BUILD="$tmp" ONLY=c TESTS="test_pass test_skip77" sh tests/run.sh 2>&1) || fail "TESTS=: exit $?"
[ "$(printf '%s\n' "$out" | tail -n 1)" = "check: 1 passed, 0 failed, 1 skipped" ] || fail "TESTS=: $out"
echo "run.sh: PASS, FAIL, SKIP, timeout and counts as stated, one at a time and side by side"
