#!/bin/sh
# test_bad_lines.sh - issue 11: no parser guesses or drops a line silently.
# trajreplay and trajd (replay input) on tracks with a missing or extra
# field, with and without skipping; a path with "wait 1e300".  Each case
# failed on the old code (a missing z was read as 0, an extra field ignored,
# the rest of the path after the wait dropped with exit 0).
set -u
cd "$(dirname "$0")/../.." || exit 1
BUILD=${BUILD:-build}
TR="$BUILD/bin/trajreplay"
TD="$BUILD/bin/trajd"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
has() { grep -qF -- "$2" "$1" || { bad "$3: '$2' not in:"; sed 's/^/    /' "$1"; return 1; }; }

# a track whose row 3 lacks z and row 5 has an extra field
printf 't,x,y,z\n0,0,0,0\n1,1,1\n2,2,2,2\n3,3,3,3,3\n4,4,4,4\n5,5,5,5\n' > "$tmp/rows.csv"

# Given the rows, when replayed without --skip-bad, then exit 1 naming line 3.
"$TR" -q -o /dev/null "$tmp/rows.csv" 2> "$tmp/e1"; rc=$?
[ $rc -eq 1 ] && ok || bad "missing z: exit $rc, want 1"
has "$tmp/e1" "rows.csv:3: 3 fields, the header has 4 (field missing)" "missing z" && ok

# With --skip-bad, exit 0, both lines reported with file:line, 4 rows kept.
"$TR" -q --skip-bad --summary -o /dev/null "$tmp/rows.csv" 2> "$tmp/e2"; rc=$?
[ $rc -eq 0 ] && ok || bad "skip-bad: exit $rc, want 0"
has "$tmp/e2" "skipped $tmp/rows.csv:3: 3 fields" "skip-bad line 3" && ok
has "$tmp/e2" "skipped $tmp/rows.csv:5: 5 fields, the header has 4 (extra field)" "skip-bad line 5" && ok
has "$tmp/e2" "summary: waypoints 4" "skip-bad kept rows" && ok
has "$tmp/e2" "summary: skipped_lines 2" "skip-bad count" && ok

# trajd: the config is rejected at the track's line, or with replay.skip_bad
# accepted with each skipped line logged.
cat > "$tmp/d.conf" <<CONF
[object.a]
input = replay
replay.track = rows.csv
output = stdout
CONF
"$TD" --check-config "$tmp/d.conf" > "$tmp/o3" 2> "$tmp/e3"; rc=$?
[ $rc -ne 0 ] && ok || bad "trajd: missing z accepted"
has "$tmp/e3" "rows.csv:3: 3 fields" "trajd missing z" && ok
printf 'replay.skip_bad = yes\n' >> "$tmp/d.conf"
"$TD" --check-config "$tmp/d.conf" > "$tmp/o4" 2> "$tmp/e4"; rc=$?
[ $rc -eq 0 ] && ok || { bad "trajd skip_bad: exit $rc"; cat "$tmp/e4"; }
has "$tmp/e4" "rows.csv:3: 3 fields" "trajd skip_bad line 3" && ok
has "$tmp/e4" "rows.csv:5: 5 fields" "trajd skip_bad line 5" && ok
# ... and run: the skipped lines are on the exit line too, not only in the start's log
printf '[daemon]\nspeed = 20\nexit_when_done = yes\nstatus_interval_s = 0\n' > "$tmp/r.conf"
cat "$tmp/d.conf" >> "$tmp/r.conf"
"$TD" -f -c "$tmp/r.conf" > /dev/null 2> "$tmp/e7"; rc=$?
[ $rc -eq 0 ] && ok || { bad "trajd skip_bad run: exit $rc"; cat "$tmp/e7"; }
has "$tmp/e7" "track lines skipped 2" "trajd skip_bad on the exit line" && ok

# A path with "wait 1e300": refused at its line, not replayed short.
printf 'start 0 0 0\nline 1 0 0\nwait 1e300\nline 5 0 0\n' > "$tmp/w.path"
"$TR" -q -o /dev/null "$tmp/w.path" 2> "$tmp/e5"; rc=$?
[ $rc -eq 1 ] && ok || bad "wait 1e300: exit $rc, want 1"
has "$tmp/e5" "w.path:3: path: time beyond" "wait 1e300" && ok

# A speed too low for the line that follows: the line's number is given.
printf 'start 0 0 0\nspeed 1e-9\nline 100 0 0\n' > "$tmp/s.path"
"$TR" -q -o /dev/null "$tmp/s.path" 2> "$tmp/e6"; rc=$?
[ $rc -eq 1 ] && ok || bad "slow path: exit $rc, want 1"
has "$tmp/e6" "s.path:3: path: value out of range" "slow path" && ok

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
