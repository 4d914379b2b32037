#!/bin/sh
# Run every test program; each ends PASS, FAIL or SKIP.  The closing line is
#   check: N passed, M failed, K skipped
# with the skipped tests and their reasons listed just above it.
#   BUILD   absolute path of the build directory (binaries in $BUILD/bin, tests in $BUILD/tests)
#   PYTHON  interpreter that sees Debian's scipy (default /usr/bin/python3)
#   ONLY    "c" to run only the cmocka binaries (the sanitizer pass)
#   TESTS   space-separated names to run only those (e.g. TESTS="test_tridiag test_replay.py")
#   TEST_TIMEOUT_S  the most one test program may take (default 900 s; then it fails)
#   COUNTS  a file to which the three counts are appended ("passed failed skipped"), so
#           that `make check` can add up the plain and the sanitizer pass
# A test skips by exiting 77 (as in automake), or by exiting 0 with a first line
# "SKIP: reason".  Only what the project cannot install may make a test skip (the
# peers of ../shared, a kernel with CAN of its own); a test whose dependency is
# one `make check` installs fails instead.  A Python test some of whose cases
# were skipped (unittest's "OK (skipped=N)") passes, and is listed with them.
# Each test program is one unit here; cmocka prints its own per-case lines.
set -u
cd "$(dirname "$0")/.." || exit 1
: "${BUILD:?BUILD must be set}"
PYTHON=${PYTHON:-/usr/bin/python3}
ONLY=${ONLY:-}
export BUILD PYTHON
passed=0; failed=0; skipped=0; failures=""; skip_lines=""
log_dir="$BUILD/test-logs"; mkdir -p "$log_dir"
nl='
'

want() { [ -z "${TESTS:-}" ] && return 0; for w in $TESTS; do [ "$w" = "$1" ] && return 0; done; return 1; }

# skip_reason LOG: the text after the first "SKIP:" line, or the log's last line.
skip_reason() {
    r=$(sed -n 's/^SKIP:* *//p' "$1" | head -n 1)
    [ -n "$r" ] || r=$(grep . "$1" | tail -n 1)
    echo "$r"
}

run_one() { # name, command...
    name=$1; shift
    want "$name" || return 0
    start=$(date +%s)
    log="$log_dir/$name.log"
    # bounded: a test that hangs fails (124) instead of holding up the run
    timeout -k 10 "${TEST_TIMEOUT_S:-900}" "$@" > "$log" 2>&1
    rc=$?
    secs=$(( $(date +%s) - start ))
    if [ $rc = 77 ] || { [ $rc = 0 ] && head -n 1 "$log" | grep -q '^SKIP'; }; then
        skipped=$((skipped + 1))
        skip_lines="$skip_lines  $name: $(skip_reason "$log")$nl"
        echo "SKIP $name ($secs s): $(skip_reason "$log")"
    elif [ $rc = 0 ]; then
        passed=$((passed + 1)); echo "PASS $name ($secs s)"
        cases=$(sed -n 's/^OK (.*skipped=\([0-9]*\).*/\1/p' "$log" | tail -n 1)
        if [ -n "$cases" ]; then
            ran=$(sed -n 's/^Ran \([0-9]*\) tests* in.*/\1/p' "$log" | tail -n 1)
            skip_lines="$skip_lines  $name: $cases of ${ran:-?} cases skipped (passed; reasons: $PYTHON <test> -v)$nl"
        fi
    else
        failed=$((failed + 1)); failures="$failures $name"
        echo "FAIL $name ($secs s), last lines of $log:"
        tail -n 25 "$log" | sed 's/^/    /'
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
[ -n "${COUNTS:-}" ] && echo "$passed $failed $skipped" >> "$COUNTS"
[ -n "$failures" ] && echo "failed:$failures"
[ -n "$skip_lines" ] && printf 'skipped:\n%s' "$skip_lines"
echo "check: $passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
