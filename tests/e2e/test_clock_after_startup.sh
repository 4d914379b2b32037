#!/bin/bash
# test_clock_after_startup.sh - trajd's output clock starts once the start-up
# work is done, not before it: nothing that grows with the objects runs
# between arming the clock and serving its first deadline.
#   Given 200 objects (each logs its start-up lines: "holds (state waiting)
#   ... until ...", and "started:" once), when trajd starts under strace
#   (its main thread, which runs the clock), then between the
#   timerfd_settime that arms the output clock (TFD_TIMER_ABSTIME) and the
#   first read of that timer there are at most 20 system calls: a count, not
#   a time.  Each start-up line queued for the log thread is two (the
#   terminal check and the log's eventfd), so the 200 lines logged after the
#   clock had started were 400 and more: the first tick then found the
#   deadlines of that start-up gone by (at 1 024 objects and 100 Hz, 3 to 6
#   of them, counted missed, and 35-55 ms of lateness on its exit line).
set -eu
cd "$(dirname "$0")/../.."
: "${BUILD:?BUILD must be set}"
command -v strace > /dev/null || { echo "strace missing (DEPS_TEST)"; exit 1; }
tmp=$(mktemp -d)
pid=""
tpid=""
trap '[ -n "$tpid" ] && kill "$tpid" 2> /dev/null; rm -rf "$tmp"' EXIT
track="$PWD/tests/data/n2k_furuno_figure8_src52.csv"
{
    printf '[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 0\n'
    for i in $(seq 1 200); do
        printf '[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\noutput = stdout\n' \
            "$i" "$((i - 1))" "$track"
    done
} > "$tmp/t.conf"
strace -o "$tmp/trace" -e trace=timerfd_settime,read,write,ioctl,epoll_wait,epoll_ctl,openat,close \
    "$BUILD/bin/trajd" -f -c "$tmp/t.conf" > /dev/null 2> "$tmp/err" &
pid=$!
for _ in $(seq 1 300); do
    grep -q 'started:' "$tmp/err" 2> /dev/null && break
    sleep 0.1
done
sleep 1
# trajd itself (strace, running it, holds fatal signals back)
tpid=$(pgrep -P "$pid" | head -n 1 || true)
[ -n "$tpid" ] && kill -TERM "$tpid"
wait "$pid" 2> /dev/null || true
tpid=""
grep -q 'started: 200 object' "$tmp/err" || { tail -n 5 "$tmp/err"; echo "FAIL: trajd did not start"; exit 1; }
# the output clock: the timer armed at an absolute time (the 1 s timers are relative)
fd=$(sed -n 's/^timerfd_settime(\([0-9]*\), TFD_TIMER_ABSTIME.*/\1/p' "$tmp/trace" | head -n 1)
[ -n "$fd" ] || { echo "FAIL: no output clock armed in the trace"; exit 1; }
n=$(awk -v fd="$fd" '
    !armed && index($0, "timerfd_settime(" fd ", TFD_TIMER_ABSTIME") == 1 { armed = 1; next }
    armed && index($0, "read(" fd ",") == 1 { print n; found = 1; exit }
    armed { n++ }
    END { if (!found) print "-" }' "$tmp/trace")
[ "$n" != - ] || { echo "FAIL: the output clock (fd $fd) was never read"; exit 1; }
echo "$n system calls between arming the output clock and its first read"
[ "$n" -le 20 ] || { echo "FAIL: $n system calls (more than 20) ran after the clock had started, before its first tick"; exit 1; }
echo ok
