#!/bin/sh
# Run every test program and print one closing line "check: N passed, M failed".
#   BUILD   absolute path of the build directory (binaries in $BUILD/bin, tests in $BUILD/tests)
#   PYTHON  interpreter that sees Debian's scipy (default /usr/bin/python3)
#   ONLY    "c" to run only the cmocka binaries (the sanitizer pass)
#   TESTS   space-separated names to run only those (e.g. TESTS="test_tridiag test_replay.py")
# Each test program is one unit here; cmocka prints its own per-case lines.
set -u
cd "$(dirname "$0")/.." || exit 1
: "${BUILD:?BUILD must be set}"
PYTHON=${PYTHON:-/usr/bin/python3}
ONLY=${ONLY:-}
export BUILD PYTHON
passed=0; failed=0; failures=""
log_dir="$BUILD/test-logs"; mkdir -p "$log_dir"

want() { [ -z "${TESTS:-}" ] && return 0; for w in $TESTS; do [ "$w" = "$1" ] && return 0; done; return 1; }

run_one() { # name, command...
    name=$1; shift
    want "$name" || return 0
    start=$(date +%s)
    if "$@" > "$log_dir/$name.log" 2>&1; then
        passed=$((passed + 1)); echo "PASS $name ($(( $(date +%s) - start )) s)"
    else
        failed=$((failed + 1)); failures="$failures $name"
        echo "FAIL $name ($(( $(date +%s) - start )) s), last lines of $log_dir/$name.log:"
        tail -n 25 "$log_dir/$name.log" | sed 's/^/    /'
    fi
}

for t in "$BUILD"/tests/test_*; do
    [ -x "$t" ] && [ -f "$t" ] || continue
    case "$t" in *.o|*.d) continue;; esac
    run_one "$(basename "$t")" "$t"
done
if [ "$ONLY" != c ]; then
    for t in tests/*/test_*.py; do [ -f "$t" ] && run_one "$(basename "$t")" "$PYTHON" "$t"; done
    for t in tests/*/test_*.sh; do [ -f "$t" ] && run_one "$(basename "$t")" bash "$t"; done
fi
[ -n "$failures" ] && echo "failed:$failures"
echo "check: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
