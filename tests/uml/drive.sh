#!/bin/sh
# Guest scenario: trajd brings up two simulated CiA 402 drives (tests/uml/drive_sim.py,
# python-canopen's LocalNode) and drives them: node 1 on x starts 2 m away from the
# track, node 2 on y is inverted; every cycle counts as late (max_late_ms tiny), so
# only SYNC and the RPDOs go out; then a drive fault, and the clear command.  The
# captures and the simulator's log are checked on the host (cantools_trajd.py drive-check).
# 20 Hz: the guest on a loaded host misses 10 ms deadlines, and a drive faults on two
# missed SYNCs (as real ones do); 50 ms leaves room.
#
# NOT YET IN tests/uml/all.sh.  Seen in the guest (host load ~12): power-on to
# Operation Enabled for both drives (NMT, the three SDOs, Shutdown, Switch on, Enable
# operation), the 2 m start and the track to its end, the injected fault detected
# and reported by trajd.  Not passing yet: after the fault the simulator stopped
# answering SDO requests (cause not found), so clear -> fault reset -> enable was
# not seen; and the STATUS wait for error 0x47 races with 0x43 (every cycle late
# here overwrites the last error).  Run it alone by putting it in all.sh.
out=$1
. tests/uml/wait.sh
. "$out/env"   # BUILD, TRAJD_PEERS
set -u
if [ ! -d "${TRAJD_PEERS:-/nonexistent}/python-canopen/canopen" ]; then
    echo "SKIP uml/drive: python-canopen not found (../shared/peers or TRAJD_PEERS)"
    touch "$out/drive.skipped"; exit 0
fi
export TRAJD_PEERS
fail() { echo "FAIL: $*"; [ -n "${tp:-}" ] && kill "$tp" 2>/dev/null; [ -n "${sp:-}" ] && kill "$sp" 2>/dev/null; exit 1; }
cat > "$out/drive.conf" <<CONF
[daemon]
rate_hz = 20
speed = 1
status_interval_s = 0
stop_timeout_s = 1
[can]
interface = vcan0
sync = yes
sync_overflow = 240
status_period_ms = 100
max_late_ms = 0.001
[object.arm]
input = can
output = can
fragment = 8
overlap = 4
start_slack = 0
can.cia402 = yes
can.cia402_enable = yes
can.cia402_cob_x = 0x201
can.cia402_cob_y = 0x202
can.cia402_cob_z = 0
can.cia402_invert_y = yes
can.cia402_sdo = 0x6060:0=8/1, 0x60C2:1=10/1, 0x60C2:2=-3/1
CONF
timeout 60 candump -r 8000000 -D -L vcan0 > "$out/dcap.log" & cp=$!
wait_rx vcan0 || fail "candump not ready"
/usr/bin/python3 tests/uml/drive_sim.py "$out" 1:20000 2:0 2> "$out/sim.err" & sp=$!
wait_grep "$out/drive_sim.ready" ready || fail "simulator not ready"
"$BUILD/bin/trajd" -f -c "$out/drive.conf" 2> "$out/drive.err" & tp=$!
# power-on to Operation Enabled: NMT start, SDOs, Shutdown, Switch on, Enable operation
wait_grep "$out/drive.err" "drives in Operation Enabled" 500 || fail "drives never enabled"
canplayer -I "$out/dwp.log" vcan0=can0 || fail "canplayer"
wait_grep "$out/dcap.log" " 6C0#03" 750 || fail "track never finished"
touch "$out/inject_fault_1"
wait_grep "$out/drive.err" "left Operation Enabled" || fail "drive fault not reported"
cansend vcan0 680#0400030000000000   # command clear: fault reset, enable again
i=0; while [ $i -lt 500 ] && [ "$(grep -c 'drives in Operation Enabled' "$out/drive.err")" -lt 2 ]; do
    i=$((i + 1)); sleep 0.02; done
[ "$(grep -c 'drives in Operation Enabled' "$out/drive.err")" -ge 2 ] || fail "not enabled again after clear"
kill -0 $tp || fail "trajd died"
kill -TERM $tp; wait $tp; rc=$?; tp=
[ $rc -eq 0 ] || fail "trajd exit code $rc"
kill -TERM $sp; wait $sp; sp=
kill $cp; wait $cp 2>/dev/null
[ -f "$out/drive_sim.json" ] || fail "simulator wrote no log"
touch "$out/ok.drive"
echo "drive scenario passed in the guest"
