#!/bin/sh
# Run every test program; each ends PASS, FAIL or SKIP.  The closing line is
#   check: N passed, M failed, K skipped
# with the skipped tests and their reasons listed just above it.
#   BUILD   absolute path of the build directory (binaries in $BUILD/bin, tests in $BUILD/tests)
#   PYTHON  interpreter that sees Debian's scipy (default /usr/bin/python3)
#   ONLY    "c" to run only the cmocka binaries (the sanitizer pass)
#   TESTS   space-separated names to run only those (e.g. TESTS="test_tridiag test_replay.py")
#   JOBS    how many test programs run at once (default: twice the number of CPUs, and
#           one more, as most of them wait on a daemon or a guest kernel: on 2 CPUs the
#           plain pass ran 4 at a time, 1 040 s of programs in 262 s, the CPUs not full).  The
#           programs named in tests/serial.txt run afterwards, one at a time.
#   TEST_TIMEOUT_S  the most one test program may take (default 900 s; then it fails)
#   COUNTS  a file to which the three counts are appended ("passed failed skipped"), so
#           that `make check` can add up the plain and the sanitizer pass
# A test skips by exiting 77 (as in automake), or by exiting 0 with a first line
# "SKIP: reason".  Only what the project cannot install may make a test skip (the
# peers of ../shared, a kernel with CAN of its own); a test whose dependency is
# one `make check` installs fails instead.  A Python test some of whose cases
# were skipped (unittest's "OK (skipped=N)") passes, and is listed with them.
# Each test program is one unit here; cmocka prints its own per-case lines.
# Each program's outcome lands in $BUILD/test-logs/NAME.res ("PASS|FAIL|SKIP secs
# note"); its output in NAME.log.  The time each took is kept in
# $BUILD/test-times, and the next run starts the longest first.
set -u
cd "$(dirname "$0")/.." || exit 1
: "${BUILD:?BUILD must be set}"
PYTHON=${PYTHON:-/usr/bin/python3}
ONLY=${ONLY:-}
export BUILD PYTHON
log_dir="$BUILD/test-logs"; mkdir -p "$log_dir"
times="$BUILD/test-times"
nl='
'

# skip_reason LOG: the text after the first "SKIP:" line, or the log's last line.
skip_reason() {
    r=$(sed -n 's/^SKIP:* *//p' "$1" | head -n 1)
    [ -n "$r" ] || r=$(grep . "$1" | tail -n 1)
    echo "$r"
}

# --one NAME: run one program, write NAME.res, print its outcome (whole, under a lock).
if [ "${1:-}" = --one ]; then
    name=$2
    case "$name" in
        *.py) set -- "$PYTHON" "$(ls tests/*/"$name" | head -n 1)";;
        *.sh) set -- bash "$(ls tests/*/"$name" | head -n 1)";;
        *) set -- "$BUILD/tests/$name";;
    esac
    start=$(date +%s)
    log="$log_dir/$name.log"; out="$log_dir/$name.out"
    # bounded: a test that hangs fails (124) instead of holding up the run
    timeout -k 10 "${TEST_TIMEOUT_S:-900}" "$@" > "$log" 2>&1 < /dev/null
    rc=$?
    secs=$(( $(date +%s) - start ))
    if [ $rc = 77 ] || { [ $rc = 0 ] && head -n 1 "$log" | grep -q '^SKIP'; }; then
        echo "SKIP $secs $(skip_reason "$log")" > "$log_dir/$name.res"
        echo "SKIP $name ($secs s): $(skip_reason "$log")" > "$out"
    elif [ $rc = 0 ]; then
        cases=$(sed -n 's/^OK (.*skipped=\([0-9]*\).*/\1/p' "$log" | tail -n 1)
        note=""
        if [ -n "$cases" ]; then
            ran=$(sed -n 's/^Ran \([0-9]*\) tests* in.*/\1/p' "$log" | tail -n 1)
            note="$cases of ${ran:-?} cases skipped (passed; reasons: $PYTHON <test> -v)"
        fi
        echo "PASS $secs $note" > "$log_dir/$name.res"
        echo "PASS $name ($secs s)" > "$out"
    else
        echo "FAIL $secs" > "$log_dir/$name.res"
        { echo "FAIL $name ($secs s, exit $rc), last lines of $log:"
          tail -n 25 "$log" | sed 's/^/    /'; } > "$out"
    fi
    flock "$log_dir/.print" cat "$out"
    exit 0
fi

want() { [ -z "${TESTS:-}" ] && return 0; for w in $TESTS; do [ "$w" = "$1" ] && return 0; done; return 1; }

# Every program to run, one name a line, in the order they were always listed.
list_all() {
    for t in "$BUILD"/tests/test_*; do
        [ -x "$t" ] && [ -f "$t" ] || continue
        case "$t" in *.o|*.d) continue;; esac
        n=$(basename "$t"); want "$n" && echo "$n"
    done
    if [ "$ONLY" != c ]; then
        for t in tests/*/test_*.py tests/*/test_*.sh; do
            [ -f "$t" ] || continue
            n=$(basename "$t"); want "$n" && echo "$n"
        done
    fi
}
serial() { grep -qx "$1" tests/serial.txt 2>/dev/null; }
# Longest first (the times of the last run; a program never timed goes first:
# the kernel tests, then the scripts, then the C programs).
by_time() {
    while read -r n; do
        case "$n" in *uml*) u=100000;; *.py|*.sh) u=50000;; *) u=10000;; esac
        s=$(awk -v n="$n" -v u="$u" '$2 == n { s = $1 } END { print (s == "" ? u : s) }' "$seed" 2>/dev/null)
        echo "${s:-$u} $n"
    done | sort -s -k1,1nr | cut -d' ' -f2
}

all=$(list_all)
for n in $all; do rm -f "$log_dir/$n.res"; done
# the order of a clone's first run: the times in tests/test-times.txt
seed=$times; [ -f "$seed" ] || seed=tests/test-times.txt
par=""; ser=""
for n in $all; do if serial "$n"; then ser="$ser$n$nl"; else par="$par$n$nl"; fi; done
jobs=${JOBS:-$(( $(nproc 2>/dev/null || echo 1) * 2 + 1 ))}
printf '%s' "$par" | by_time | xargs -r -n 1 -P "$jobs" sh tests/run.sh --one
printf '%s' "$ser" | xargs -r -n 1 -P 1 sh tests/run.sh --one

passed=0; failed=0; skipped=0; failures=""; skip_lines=""
new_times=""
for n in $all; do
    res="$log_dir/$n.res"
    if [ ! -f "$res" ]; then failed=$((failed + 1)); failures="$failures $n(no result)"; continue; fi
    read -r outcome secs note < "$res"
    new_times="$new_times$secs $n$nl"
    case "$outcome" in
        PASS) passed=$((passed + 1))
              [ -n "$note" ] && skip_lines="$skip_lines  $n: $note$nl";;
        SKIP) skipped=$((skipped + 1)); skip_lines="$skip_lines  $n: $note$nl";;
        *) failed=$((failed + 1)); failures="$failures $n";;
    esac
done
# keep the times of programs this run did not run (TESTS=...)
{ [ -f "$times" ] && awk 'NR == FNR { seen[$2] = 1; next } !($2 in seen)' - "$times" <<EOT
$new_times
EOT
  printf '%s' "$new_times"; } > "$times.new" 2>/dev/null && mv "$times.new" "$times"
[ -n "${COUNTS:-}" ] && echo "$passed $failed $skipped" >> "$COUNTS"
[ -n "$failures" ] && echo "failed:$failures"
[ -n "$skip_lines" ] && printf 'skipped:\n%s' "$skip_lines"
echo "check: $passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
