#!/bin/sh
# Scenario: the bus state from real kernel error frames.  cansend writes
# frames with CAN_ERR_FLAG (the 8-digit id 2000xxxx) to vcan0; the kernel
# delivers them only to sockets whose CAN_RAW_ERR_FILTER has that class, as
# it does for a controller's reports.  trajd (error filter set) must publish
# each state on Modbus (can_state, daemon register 18, read by mbpoll) and
# count them (registers 64..79).  Then the example CAN sender streams a
# track into trajd, paced by STATUS.  Classes (linux/can/error.h): 004 CRTL with
# data[1] 04 RX warning / 20 TX passive, 040 BUSOFF, 100 RESTARTED, 200 CNT
# (data[6] TX, data[7] RX error counter).
out=$1
. tests/uml/wait.sh
. "$out/env"   # BUILD
set -u
fail() { echo "FAIL: $*"; [ -n "${tp:-}" ] && kill "$tp" 2>/dev/null; exit 1; }
cat > "$out/canerr.conf" <<CONF
[daemon]
rate_hz = 100
status_interval_s = 0
stop_timeout_s = 1
[modbus]
port = 0
systemd_socket = no
[can]
interface = vcan0
[object.boat]
input = can
output = can
CONF
"$BUILD/bin/trajd" -f -c "$out/canerr.conf" 2> "$out/canerr.err" & tp=$!
wait_grep "$out/canerr.err" "modbus: TCP on" || fail "no Modbus port"
port=$(sed -n 's/.*modbus: TCP on .* port \([0-9]*\).*/\1/p' "$out/canerr.err" | head -1)
grep -q "can: 1 object(s) on vcan0" "$out/canerr.err" || fail "trajd has no CAN socket"
reg() { # reg ADDR [TYPE]: one value of the daemon block
    mbpoll -m tcp -p "$port" -a 1 -0 -1 -t "${2:-3}" -B -r "$1" 127.0.0.1 2>/dev/null |
        sed -n 's/^\[[0-9]*\]: *\t*//p' | tr -d ' \t'
}
expect_state() { # STATE: can_state reaches it (bounded)
    i=0
    while [ $i -lt 100 ]; do
        [ "$(reg 18)" = "$1" ] && return 0
        i=$((i + 1)); sleep 0.05
    done
    fail "can_state $(reg 18), wanted $1 after $2"
}
[ "$(reg 18)" = 1 ] || fail "can_state $(reg 18) before any error frame, wanted 1 (active)"
cansend vcan0 20000004#0004000000000000; expect_state 2 "RX warning"
cansend vcan0 20000204#0020000000008005; expect_state 3 "TX passive"
cansend vcan0 20000040#0000000000000000; expect_state 4 "bus-off"
cansend vcan0 20000100#0000000000000000; expect_state 1 "restarted"
[ "$(reg 64 3:int)" = 4 ] || fail "can_err_frames $(reg 64 3:int), wanted 4"
[ "$(reg 70 3:int)" = 1 ] || fail "can_bus_offs $(reg 70 3:int), wanted 1"
[ "$(reg 78)" = 128 ] && [ "$(reg 79)" = 5 ] || fail "error counters $(reg 78)/$(reg 79), wanted 128/5"
# The shipped example sender (daemon/doc/examples/trajd_can_sender.py) paces a
# track on trajd's STATUS: every waypoint accepted, finished (its exit status).
/usr/bin/python3 daemon/doc/examples/trajd_can_sender.py "$out/dtrack.csv" --channel vcan0 \
    --timeout 60 > "$out/sender.txt" 2>&1 || { cat "$out/sender.txt"; fail "example sender"; }
kill -0 $tp || fail "trajd died"
kill -TERM $tp; wait $tp; rc=$?
tp=
exit_agrees $rc "$out/canerr.err" || fail "trajd exit code $rc"
grep -q "controller bus-off" "$out/canerr.err" || fail "bus-off not logged"
echo "canerr: ok"
