#!/bin/sh
# Guest scenario of tests/e2e/test_drive_uml.sh: trajd brings up simulated CiA 402
# drives (tests/uml/drive_sim.py on python-canopen's LocalNode) from power-on and
# drives them.  Object 'arm': node 1 on x starts 2 m away from the track, node 2
# on y is inverted, the RPDO carries the controlword; every cycle counts as late
# (max_late_ms tiny), so only SYNC and the RPDOs go out.  Object 'spare': node 3,
# whose configuration list has an object the drive lacks (SDO abort).  Then a
# drive fault (that drive alone disabled) and a quick stop, each followed by the clear command; then node 2's
# heartbeat stops: the object is held, a Modbus override refused until clear.  Every wait
# is for an event with a generous bound (a loaded host slows the guest a lot);
# the captures and the simulator's log are checked on the host
# (tests/helpers/cantools_trajd.py drive-check).
# 20 Hz: the guest on a loaded host misses 10 ms deadlines, and a drive faults
# on two missed SYNCs (as real ones do); 50 ms leaves room.
out=$1
. tests/uml/wait.sh
. "$out/env"   # BUILD, TRAJD_PEERS
set -u
if [ ! -d "${TRAJD_PEERS:-/nonexistent}/python-canopen/canopen" ]; then
    # the host found it (test_drive_uml.sh skips before booting otherwise): not seeing it here fails
    echo "FAIL uml/drive: python-canopen not visible in the guest at ${TRAJD_PEERS:-?}"
    exit 1
fi
export TRAJD_PEERS
t0=$(uptime_s)
fail() {
    mark "FAIL: $*" >&2
    [ -n "${tp:-}" ] && kill "$tp" 2>/dev/null
    [ -n "${sp:-}" ] && { kill "$sp" 2>/dev/null; wait_gone "$sp" simulator 1000; }
    exit 1
}
# count_ev NODE STATE: how many times the simulated drive NODE entered STATE
count_ev() { grep -c "^[0-9.]* $1 $2 " "$out/sim_events.txt" 2>/dev/null; }
# wait_ev NODE STATE N: until NODE entered STATE at least N times (up to 40 s)
wait_ev() {
    i=0
    while [ $i -lt 2000 ]; do
        [ "$(count_ev "$1" "$2")" -ge "$3" ] && return 0
        i=$((i + 1)); sleep 0.02
    done
    echo "wait_ev: node $1 entered $2 $(count_ev "$1" "$2") times, wanted $3" >&2; return 1
}
# The configuration is README.md's "Wiring a CiA 402 drive" example (the host
# test extracts it into drive.conf), with the test's own settings around it.
[ -f "$out/drive.conf" ] || fail "no drive.conf"
mark "start"
timeout 100 candump -r 8000000 -D -L vcan0 > "$out/dcap.log" & cp=$!
wait_rx vcan0 || fail "candump not ready"
/usr/bin/python3 tests/uml/drive_sim.py "$out" 1:20000 2:0 3:0 2> "$out/sim.err" & sp=$!
wait_grep "$out/drive_sim.ready" ready 2000 || fail "simulator not ready"
mark "simulator ready"
"$BUILD/bin/trajd" -f -c "$out/drive.conf" 2> "$out/drive.err" & tp=$!
# ---- power-on to Operation Enabled: NMT start, SDOs, Shutdown, Switch on, Enable operation
wait_ev 1 OPERATION_ENABLED 1 || fail "node 1 never enabled"
wait_ev 2 OPERATION_ENABLED 1 || fail "node 2 never enabled"
wait_grep "$out/drive.err" "drives in Operation Enabled" 2000 || fail "trajd did not report the drives enabled"
# node 3 refused its configuration: reported, never enabled
wait_grep "$out/drive.err" "refused SDO write of 0x6071" 2000 || fail "SDO abort not reported"
touch "$out/ok.bringup"; mark "drives enabled"
# ---- the track: from 2 m away, smoothly; every cycle late
canplayer -I "$out/dwp.log" vcan0=can0 || fail "canplayer"
# STATUS byte 0: engine state in bits 0..2 (3 = finished), flags above (tx-drop: late)
wait_grep "$out/dcap.log" " 6C0#[0-9A-F]3" 2000 || fail "track never finished"
touch "$out/ok.track"; mark "track played"
# ---- drive fault: trajd holds and reports; clear -> fault reset -> enabled again
kill -USR1 "$sp"
wait_ev 1 FAULT 1 || fail "simulator did not fault"
wait_grep "$out/drive.err" "left Operation Enabled" 2000 || fail "drive fault not reported"
# ... and on Modbus: object 0's drive registers (76..79) and the daemon's (36..41)
mbpoll -m tcp -p 1502 -a 1 -0 -r 176 -c 4 -t 3:hex -1 127.0.0.1 > "$out/mb_obj.txt" 2>&1 || fail "mbpoll object"
mbpoll -m tcp -p 1502 -a 1 -0 -r 36 -c 6 -t 3:hex -1 127.0.0.1 > "$out/mb_daemon.txt" 2>&1 || fail "mbpoll daemon"
# the faulted drive alone is disabled (Disable voltage, then its fault reset
# after clear); node 2 stays enabled where it stands
sleep 1
[ "$(count_ev 2 SWITCH_ON_DISABLED)" = 1 ] || fail "trajd disabled the object's healthy drive"
cansend vcan0 680#0400030000000000   # command clear: fault reset, enable again
wait_ev 1 OPERATION_ENABLED 2 || fail "node 1 not enabled again after clear"
# the first target after the enable (drive_sim.py FIRST_TARGET: the host
# checks it was where the drive stood)
wait_ev 1 FIRST_TARGET 2 || fail "node 1 got no target after the clear"
[ "$(count_ev 2 OPERATION_ENABLED)" = 1 ] || fail "node 2 enabled again: it never left"
touch "$out/ok.fault"; mark "fault and clear"
# ---- the drives' own quick stop: trajd disables them (no re-enable without clear)
kill -USR2 "$sp"
wait_ev 2 QUICK_STOP_ACTIVE 1 || fail "simulator did not quick-stop"
wait_ev 1 SWITCH_ON_DISABLED 3 || fail "trajd did not disable quick-stopped node 1"
wait_ev 2 SWITCH_ON_DISABLED 2 || fail "trajd did not disable quick-stopped node 2"
cansend vcan0 680#0400030000000000
wait_ev 1 OPERATION_ENABLED 3 || fail "node 1 not enabled again after the quick stop"
wait_ev 2 OPERATION_ENABLED 2 || fail "node 2 not enabled again after the quick stop"
wait_ev 1 FIRST_TARGET 3 || fail "node 1 got no target after the quick stop"
wait_ev 2 FIRST_TARGET 2 || fail "node 2 got no target after the quick stop"
touch "$out/ok.quickstop"; mark "quick stop and clear"
# ---- a drive goes silent (node 2's heartbeat stops, its PDOs go on): trajd reports it
# and holds the object (override 0); an override written by Modbus is refused
# (exception 03) until the clear command releases the hold
kill -HUP "$sp"
wait_ev 2 HEARTBEAT_OFF 1 || fail "simulator did not stop its heartbeat"
wait_grep "$out/drive.err" "heartbeat was not heard in time" 2000 || fail "heartbeat loss not reported"
# object 0's override in force (172) and drive states (176); the daemon's heartbeat count (41)
mbpoll -m tcp -p 1502 -a 1 -0 -r 172 -c 5 -t 3:hex -1 127.0.0.1 > "$out/mb_hb.txt" 2>&1 || fail "mbpoll hb"
mbpoll -m tcp -p 1502 -a 1 -0 -r 41 -t 3:hex -1 127.0.0.1 > "$out/mb_hb_daemon.txt" 2>&1 || fail "mbpoll hb count"
if mbpoll -m tcp -p 1502 -a 1 -0 -r 101 -t 4 -1 127.0.0.1 50 > "$out/mb_hb_override.txt" 2>&1; then
    fail "override accepted while held: $(cat "$out/mb_hb_override.txt")"
fi
grep -qi "illegal data value" "$out/mb_hb_override.txt" || fail "override: $(cat "$out/mb_hb_override.txt")"
cansend vcan0 680#0400053200000000   # the same override (command 5, 50 %) by CAN: refused
wait_grep "$out/drive.err" "command frame(s) refused, the last override on id 0x680: the object is held" 2000 ||
    fail "CAN override during the hold not reported as refused for the hold"
kill -HUP "$sp"
wait_ev 2 HEARTBEAT_ON 1 || fail "simulator did not restart its heartbeat"
cansend vcan0 680#0400030000000000   # command clear: releases the hold
i=0
until mbpoll -m tcp -p 1502 -a 1 -0 -r 101 -t 4 -1 127.0.0.1 50 > "$out/mb_hb_release.txt" 2>&1; do
    i=$((i + 1)); [ $i -lt 100 ] || fail "override still refused after clear: $(cat "$out/mb_hb_release.txt")"
    sleep 0.1
done
i=0   # the override in force follows within a tick
until mbpoll -m tcp -p 1502 -a 1 -0 -r 172 -c 5 -t 3:hex -1 127.0.0.1 > "$out/mb_hb_after.txt" 2>&1 &&
      grep -q "^\[172\]:[[:space:]]*0x0032" "$out/mb_hb_after.txt"; do
    i=$((i + 1)); [ $i -lt 100 ] || fail "override in force not 50 %: $(cat "$out/mb_hb_after.txt")"
    sleep 0.1
done
touch "$out/ok.heartbeat"; mark "heartbeat loss and clear"
kill -0 $tp || fail "trajd died"
# each end bounded: trajd brings its objects to rest in at most 5 s, the
# simulator ends within 10 s of SIGTERM (faulthandler), candump at once
kill -TERM $tp; wait_gone $tp trajd 1000; rc=$?
exit_agrees $rc "$out/drive.err" || fail "trajd exit code $rc"
tp=; mark "trajd ended"
kill -TERM $sp; wait_gone $sp simulator 1000 || fail "the simulator did not end"
sp=; mark "simulator ended"
kill $cp; wait_gone $cp candump || fail "candump did not end"
[ -f "$out/drive_sim.json" ] || fail "simulator wrote no log"
touch "$out/ok.drive"; mark "end"
echo "drive scenario passed in the guest"
