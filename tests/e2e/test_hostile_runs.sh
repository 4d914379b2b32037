#!/bin/bash
# test_hostile_runs.sh - issue 24 items 4 and 9: runs that must not end with
# exit 0 as if nothing happened.
#   - ends = clamped with a start or end velocity beyond the speed limit in
#     force (or, without one, beyond max_abs_m per second) is refused: by
#     trajreplay (--start-vel 1e10,0,0 streamed 38 177 m/s with exit 0;
#     1e308 gave NaN rows) and by trajd --check-config;
#   - a trajd run in which an object ended held by the safety monitor exits
#     CORE_EXIT_HELD (75), naming the object (the old code exited 0).
# Each case failed on the old code.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
TR="$BUILD/bin/trajreplay"
TD="$BUILD/bin/trajd"
case $TD in /*) ;; *) TD=$PWD/$TD ;; esac
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
pass=0; fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
TRACK=tests/data/gpxgo_visnjan.csv

for v in 1e10,0,0 1e308,0,0 0,0,-1e50; do
    "$TR" --ends clamped --start-vel "$v" --max-rows 100000 -o "$tmp/o.csv" "$TRACK" 2> "$tmp/e"; rc=$?
    [ $rc -eq 2 ] && grep -q "start_vel_m_s/end_vel_m_s: faster than" "$tmp/e" && ok ||
        { bad "--start-vel $v: exit $rc, want 2:"; cat "$tmp/e"; }
done
"$TR" --ends clamped --end-vel 0,401,0 -o "$tmp/o.csv" "$TRACK" 2> "$tmp/e"; rc=$?
[ $rc -eq 2 ] && ok || bad "--end-vel 0,401,0 (auto: 400 m/s): exit $rc, want 2"
# within the limit: still a run
"$TR" --ends clamped --start-vel 3,0,0 --end-vel 0,0,0 -o "$tmp/o.csv" "$TRACK" 2> "$tmp/e"; rc=$?
[ $rc -eq 0 ] && ok || { bad "--start-vel 3,0,0: exit $rc, want 0"; cat "$tmp/e"; }

printf '[object.boat]\ninput = replay\nreplay.track = %s\noutput = stdout\nends = clamped\nstart_vel_m_s = 1e10,0,0\n' \
    "$PWD/$TRACK" > "$tmp/sv.conf"
"$TD" --check-config "$tmp/sv.conf" > "$tmp/e" 2>&1; rc=$?
[ $rc -ne 0 ] && grep -q "sv.conf:6: .*start_vel_m_s/end_vel_m_s: faster than" "$tmp/e" && ok ||
    { bad "trajd --check-config start_vel 1e10: exit $rc"; cat "$tmp/e"; }

# an object the safety monitor holds until the end: exit 75, named
{ echo t,x,y,z; i=0; while [ $i -le 40 ]; do echo "$i,$((2 * i)),0,0"; i=$((i + 1)); done; } > "$tmp/fast.csv"
printf '[daemon]\nrate_hz = 20\nspeed = 20\nexit_when_done = yes\nstatus_interval_s = 0\n' > "$tmp/h.conf"
printf '[object.a]\ninput = replay\nreplay.track = fast.csv\noutput = csv\ncsv.path = out.csv\n' >> "$tmp/h.conf"
# (a position box it leaves at x = 20 m: a speed or an acceleration bound set is
# kept by the engine, which slows)
printf 'position_min_m = -1000,-1000,-1000\nposition_max_m = 20,1000,1000\n' >> "$tmp/h.conf"
(cd "$tmp" && timeout -k 5 120 "$TD" -f -c h.conf 2> err); rc=$?  # bounded: a hang fails
[ $rc -eq 75 ] && ok || bad "safety hold: exit $rc, want 75"
grep -q "object 'a' ended held: position outside position_min_m .. position_max_m" "$tmp/err" && ok ||
    { bad "safety hold not named:"; cat "$tmp/err"; }

# trajreplay -o on its own track by another spelling: refused, the track intact (item 5)
cp "$TRACK" "$tmp/t.csv"; mkdir -p "$tmp/sub"
"$TR" -o "$tmp/sub/../t.csv" "$tmp/t.csv" 2> "$tmp/e"; rc=$?
[ $rc -eq 2 ] && grep -q "are one file" "$tmp/e" && ok || { bad "-o on the track: exit $rc"; cat "$tmp/e"; }
cmp -s "$TRACK" "$tmp/t.csv" && ok || bad "-o on the track: the track was overwritten"

# CiA 402 at 1e7 increments/m (int32: +-214.748 m) on a track to 325 m (item 2):
# no target goes out clipped to INT32_MAX (the old code sent 0x7FFFFFFF and
# held the drive there silently, exit 0); the safety monitor holds the object
# at the edge of the derived box, names it, and the run exits 75.
{ echo t,x,y,z; i=0; while [ $i -le 325 ]; do echo "$i,$i,0,0"; i=$((i + 1)); done; } > "$tmp/road.csv"
cat > "$tmp/c.conf" <<CONF
[daemon]
rate_hz = 20
speed = 50
exit_when_done = yes
status_interval_s = 0
[can]
log_out = out.log
[object.car]
input = replay
replay.track = road.csv
output = can
profile = road
initial_position = 0,0,0
can.own = no
can.cia402 = targets
can.cia402_cob_x = 0x201
can.cia402_cob_y = 0
can.cia402_cob_z = 0
can.cia402_counts_per_m = 1e7
CONF
(cd "$tmp" && timeout -k 5 120 "$TD" -f -c c.conf 2> err); rc=$?  # bounded: a hang fails
[ $rc -eq 75 ] && ok || bad "CiA 402 beyond int32: exit $rc, want 75"
grep -q "object 'car' ended held: position outside position_min_m .. position_max_m" "$tmp/err" && ok ||
    { bad "CiA 402 beyond int32: not named"; cat "$tmp/err"; }
n=$(grep -c " 201#" "$tmp/out.log"); top=$(grep -c " 201#FFFFFF7F" "$tmp/out.log")
[ "$n" -gt 1000 ] && [ "$top" -eq 0 ] && ok || bad "RPDO targets: $top of $n at INT32_MAX"

# more than 10 % of the fixes refused (item 9): a warning line from trajreplay
# (exit 0 without --strict) and from trajd (the old code said nothing)
{ echo t,x,y,z; i=0; while [ $i -le 60 ]; do
    if [ $((i % 6)) -eq 3 ]; then echo "$i,100000,0,0"; else echo "$i,$i,0,0"; fi; i=$((i + 1)); done
} > "$tmp/spiky.csv"
"$TR" -o /dev/null "$tmp/spiky.csv" 2> "$tmp/e"; rc=$?
[ $rc -eq 0 ] && grep -q "spiky.csv: warning: 1[0-9].[0-9] % of the track's fixes were refused" "$tmp/e" &&
    ok || { bad "trajreplay >10 % refused: exit $rc, no warning"; cat "$tmp/e"; }
printf '[daemon]\nrate_hz = 20\nspeed = 50\nexit_when_done = yes\nstatus_interval_s = 0\n' > "$tmp/s.conf"
printf '[object.a]\ninput = replay\nreplay.track = spiky.csv\noutput = csv\ncsv.path = s.csv\n' >> "$tmp/s.conf"
(cd "$tmp" && timeout -k 5 120 "$TD" -f -c s.conf 2> err); rc=$?  # bounded: a hang fails
grep -q "<4>object a: replay.track .*spiky.csv: 1[0-9].[0-9] % of its 61 fixes were refused" "$tmp/err" &&
    ok || { bad "trajd >10 % refused: no warning (exit $rc)"; cat "$tmp/err"; }

# the README's drive config still passes --check-config (its box is derived)
awk '/<!-- drive-config:/{f=1;next} f&&/^$/{exit} f{sub(/^    /,"");print}' README.md > "$tmp/drive.conf"
"$TD" --check-config "$tmp/drive.conf" > "$tmp/e" 2>&1 && ok || { bad "README drive config"; cat "$tmp/e"; }

echo "test_hostile_runs: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
