#!/bin/sh
# test_closed_fds.sh - issue 24 item 3: trajd, trajreplay and trajsurf started
# with fds 0-2 closed open /dev/null on them first, so their output file never
# becomes fd 2 and no log line lands among its rows.  Each case failed on the
# old code (the CSV file was fd 2: "rejected" lines among the setpoints).
set -u
cd "$(dirname "$0")/../.." || exit 1
BUILD=${BUILD:-build}
TR="$BUILD/bin/trajreplay"
TD="$(cd "$(dirname "$BUILD/bin/trajd")" && pwd)/trajd"  # absolute: run from other directories
TS="$BUILD/bin/trajsurf"
case $TD in /*) ;; *) TD=$PWD/$TD ;; esac
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
# no message text among the rows (what each program writes to stderr)
rows_only() { # file, what
    if grep -n 'rejected\|trajreplay\|trajd\|trajsurf\|warning' "$1" > "$tmp/stray"; then
        bad "$2: messages among the rows:"; head -3 "$tmp/stray" | sed 's/^/    /'
    else ok; fi
}

# a straight walk at 1 m/s with one fix 100 km off (refused, and logged)
{ echo t,x,y,z; i=0; while [ $i -le 60 ]; do
    if [ $i -eq 30 ]; then echo "$i,100000,0,0"; else echo "$i,$i,0,0"; fi; i=$((i + 1)); done
} > "$tmp/walk.csv"

# trajreplay, fd 2 closed: the rejection goes nowhere, not into out.csv
"$TR" -o "$tmp/out.csv" "$tmp/walk.csv" 2> "$tmp/e0" && grep -q "walk.csv:32: rejected" "$tmp/e0" &&
    ok || bad "trajreplay did not report the refused fix"
"$TR" -o "$tmp/out.csv" "$tmp/walk.csv" 2>&-; rc=$?
[ $rc -eq 0 ] && ok || bad "trajreplay exit $rc, want 0"
[ -s "$tmp/out.csv" ] && ok || bad "trajreplay: no rows"
rows_only "$tmp/out.csv" "trajreplay 2>&-"

# all three closed
"$TR" -o "$tmp/out3.csv" "$tmp/walk.csv" 0<&- 1>&- 2>&-; rc=$?
[ $rc -eq 0 ] && ok || bad "trajreplay (0-2 closed) exit $rc, want 0"
rows_only "$tmp/out3.csv" "trajreplay 0<&- 1>&- 2>&-"

# trajd with a CSV output, fds 0-2 closed: the log (stderr) is not in the CSV
cat > "$tmp/d.conf" <<CONF
[daemon]
rate_hz = 20
speed = 50
exit_when_done = yes
status_interval_s = 0
[object.a]
input = replay
replay.track = walk.csv
output = csv
csv.path = d.csv
CONF
(cd "$tmp" && timeout -k 5 120 "$TD" -f -c d.conf 0<&- 1>&- 2>&-); rc=$?  # bounded: a hang fails
[ $rc -eq 0 ] && ok || bad "trajd exit $rc, want 0"
[ -s "$tmp/d.csv" ] && ok || bad "trajd: no rows"
rows_only "$tmp/d.csv" "trajd 0<&- 1>&- 2>&-"

# trajsurf, fds 0-2 closed: the samples file is whole and only samples
printf '0,1,2\n1,2,3\n2,3,4\n' > "$tmp/g.csv"
"$TS" -n 2 -o "$tmp/s.csv" "$tmp/g.csv" 0<&- 1>&- 2>&-; rc=$?
[ $rc -eq 0 ] && ok || bad "trajsurf exit $rc, want 0"
rows_only "$tmp/s.csv" "trajsurf"

echo "test_closed_fds: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
