#!/bin/sh
# Guest scenarios with trajd on vcan0 (see tests/e2e/test_can_uml.sh, which
# prepares $out/wp.log and checks the captures afterwards).  Each phase writes
# a marker "$out/ok.<phase>" when its in-guest check passed.
out=$1
. tests/uml/wait.sh
. "$out/env"   # BUILD
set -u
fail() { echo "FAIL: $*"; [ -n "${tp:-}" ] && kill "$tp" 2>/dev/null; exit 1; }
status_re() { # STATUS frame with byte0 matching $1 (two hex digits, regex)
    echo " 6C0#$1"
}

cat > "$out/trajd.conf" <<CONF
[daemon]
rate_hz = 100
speed = 10
status_interval_s = 0
stop_timeout_s = 1
[can]
interface = vcan0
fd = yes
sync = yes
status_period_ms = 100
bitrate = 1000000
[object.boat]
id = 0
input = can
output = can
can.cia402 = yes
can.cia402_feedback = no
initial_position = 0,0,0
can.cia402_counts_per_m = 10000
can.cia402_cob_x = 0x201
can.cia402_cob_y = 0x202
can.cia402_cob_z = 0x203
[object.fdboat]
id = 1
input = can
output = can
can.fd = yes
can.brs = yes
CONF

# ---- B: stream a track from canplayer, capture with candump --------------
timeout 60 candump -r 8000000 -D -L vcan0 > "$out/cap.log" & cp=$!
wait_rx vcan0 || fail "candump not ready"
"$BUILD/bin/trajd" -f -c "$out/trajd.conf" 2> "$out/trajd.err" & tp=$!
wait_grep "$out/cap.log" " 6C0#" || fail "no STATUS from trajd"
cat /proc/net/can/rcvlist_sff > "$out/rcvlist_sff.txt"
cat /proc/net/can/rcvlist_all > "$out/rcvlist_all.txt"
canplayer -I "$out/wp.log" vcan0=can0 || fail "canplayer"
# FINISH was the last frame: wait for STATUS state finished (3), no flags
wait_grep "$out/cap.log" "$(status_re 03)" 500 || fail "never finished"
wait_grep "$out/cap.log" " 6C1#03" 500 || fail "FD object never finished"
kill -0 $tp || fail "trajd died"
touch "$out/ok.stream"

# ---- C1: interface down and up --------------------------------------------
n1=$(grep -c ' 6A0#' "$out/cap.log")
echo "down at $(cat /proc/uptime)" > "$out/down.txt"
ip link set vcan0 down
sleep 0.3   # the outage itself (not a wait for an event)
ip link set vcan0 up
echo "up at $(cat /proc/uptime)" >> "$out/down.txt"
i=0; while [ $i -lt 250 ] && [ "$(grep -c ' 6A0#' "$out/cap.log")" -lt $((n1 + 60)) ]; do i=$((i+1)); sleep 0.02; done
[ "$(grep -c ' 6A0#' "$out/cap.log")" -ge $((n1 + 60)) ] || fail "no setpoints after up"
kill -0 $tp || fail "trajd died after down/up"
# STATUS reports the outage: bus-down flag (0x10) with tx-drop (0x20), finished
wait_grep "$out/cap.log" "$(status_re 33)" || fail "no STATUS with bus-down flag"
kill $cp; wait $cp 2>/dev/null
touch "$out/ok.downup"

# ---- C2: interface removed and re-created (new ifindex) --------------------
# candump on "any" survives the removal and sees the new vcan0 at once
timeout 30 candump -r 8000000 -D -L any > "$out/cap2.log" & cp=$!
wait_rx any || fail "candump 2 not ready"
ip link del vcan0
sleep 0.3   # the outage itself
ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 up
wait_grep "$out/cap2.log" " 6A0#" || fail "trajd did not reopen the new vcan0"
wait_grep "$out/cap2.log" "$(status_re 33)" || fail "no STATUS with bus-down after removal"
kill -0 $tp || fail "trajd died after removal"
kill $cp; wait $cp 2>/dev/null
touch "$out/ok.removed"

# ---- D: TX queue full: a slow qdisc makes write() fail with ENOBUFS --------
busybox insmod /usr/lib/uml/modules/$(uname -r)/kernel/net/sched/sch_tbf.ko 2>/dev/null
tc qdisc add dev vcan0 root tbf rate 8kbit burst 256 limit 128 || fail "tc tbf"
timeout 30 candump -r 8000000 -D -L vcan0 > "$out/cap3.log" & cp=$!
wait_rx vcan0 || fail "candump 3 not ready"
# a STATUS with the tx-drop flag (0x2x) gets through the slow queue
wait_grep "$out/cap3.log" "$(status_re 2.)" 500 || fail "no STATUS reporting dropped setpoints"
# ... and logged as they come, not only at exit
wait_grep "$out/trajd.err" "setpoint cycle(s) not sent" 500 || fail "dropped setpoints not logged"
tc qdisc del dev vcan0 root
kill -0 $tp || fail "trajd died under ENOBUFS"
kill $cp; wait $cp 2>/dev/null
touch "$out/ok.enobufs"

# ---- E: malformed frames are counted in STATUS ------------------------------
timeout 30 candump -r 8000000 -D -L vcan0 > "$out/cap4.log" & cp=$!
wait_rx vcan0 || fail "candump 4 not ready"
cansend vcan0 680#0011
cansend vcan0 680#0911000000000000
# STATUS byte 5 = malformed frames = 2 (bytes 0..4 = 10 hex digits before it)
wait_grep "$out/cap4.log" " 6C0#[0-9A-F]\{10\}02" || fail "malformed frames not reported"
wait_grep "$out/trajd.err" "malformed frame(s) on id 0x680" 500 || fail "malformed frames not logged"
kill $cp; wait $cp 2>/dev/null
touch "$out/ok.malformed"

# ---- E2: trajd stalled while a peer floods it: the frames the kernel drops
# from its full receive queue are counted (SO_RXQ_OVFL) and logged
kill -STOP $tp
cangen vcan0 -I 680 -L 1 -D 00 -g 0 -n 200000 -i 2>/dev/null
kill -CONT $tp
wait_grep "$out/trajd.err" "dropped by the kernel, trajd's receive queue full" 500 ||
    fail "the kernel's receive-queue drops not logged"
kill -0 $tp || fail "trajd died after the flood"
touch "$out/ok.rxdrop"

# ---- stop: SIGTERM.  The cycles not sent above (down, removed, ENOBUFS) are
# setpoints the drives never got: trajd exits 74 (EX_IOERR) and says how many
# (trajd(8) EXIT STATUS), as for a lost output line
kill -TERM $tp
wait $tp; rc=$?
[ $rc -eq 74 ] || fail "trajd exit code $rc, not 74 after setpoint cycles not sent"
grep -q "setpoint cycles with a position were not sent on the CAN bus.*exit status 74" "$out/trajd.err" ||
    fail "the exit status not explained"
tp=
touch "$out/ok.stop"

# ---- G: flow control: a sender paced by STATUS fills a small buffer -------
cat > "$out/pace.conf" <<CONF
[daemon]
rate_hz = 100
speed = 10
status_interval_s = 0
stop_timeout_s = 1
[can]
interface = vcan0
status_period_ms = 100
[object.boat]
input = can
output = can
capacity = 40
fragment = 8
overlap = 4
CONF
"$BUILD/bin/trajd" -f -c "$out/pace.conf" 2> "$out/pace.err" & tp=$!
/usr/bin/python3 tests/uml/pacer.py "$out/track.csv" "$out" || fail "paced sender (see pacer.txt)"
kill -TERM $tp; wait $tp; rc=$?
exit_agrees $rc "$out/pace.err" || fail "trajd (pace) exit code $rc"
tp=
touch "$out/ok.flow"

# ---- H: started before its interface exists: runs DOWN, streams once it appears
sed 's/^interface = vcan0$/interface = vcan1/' "$out/pace.conf" > "$out/late.conf"
timeout 30 candump -r 8000000 -D -L any > "$out/cap6.log" & cp=$!
wait_rx any || fail "candump 6 not ready"
"$BUILD/bin/trajd" -f -c "$out/late.conf" 2> "$out/late.err" & tp=$!
wait_grep "$out/late.err" "vcan1: No such device" || fail "trajd did not report the missing interface"
kill -0 $tp || fail "trajd exited without its interface"
ip link add dev vcan1 type vcan && ip link set vcan1 up
wait_grep "$out/cap6.log" " vcan1 6A0#" || fail "no setpoints once vcan1 appeared"
kill -TERM $tp; wait $tp; rc=$?
exit_agrees $rc "$out/late.err" || fail "trajd (late interface) exit code $rc"
tp=
kill $cp; wait $cp 2>/dev/null
touch "$out/ok.late_iface"

# ---- F: frames per second trajd emits on vcan0 (measured, not asserted) -----
{
    printf '[daemon]\nrate_hz = 10000\nspeed = 1\nstatus_interval_s = 0\nstop_timeout_s = 1\n'
    printf '[can]\ninterface = vcan0\nmax_load_percent = 0\nsync = yes\n'
    for i in 0 1 2 3 4 5 6 7; do printf '[object.o%d]\nid = %d\ninput = can\noutput = can\n' $i $i; done
} > "$out/fast.conf"
timeout 30 candump -r 8000000 -D -L vcan0 > "$out/cap5.log" & cp=$!
wait_rx vcan0 || fail "candump 5 not ready"
tx0=$(cat /sys/class/net/vcan0/statistics/tx_packets); t0=$(cut -d' ' -f1 /proc/uptime)
timeout -s TERM 3 "$BUILD/bin/trajd" -f -c "$out/fast.conf" 2> "$out/fast.err"
tx1=$(cat /sys/class/net/vcan0/statistics/tx_packets); t1=$(cut -d' ' -f1 /proc/uptime)
kill $cp; wait $cp 2>/dev/null
# the kernel's count of frames sent on vcan0 (only trajd sends now), over the run
echo "$tx0 $tx1 $t0 $t1" > "$out/fast.txt"
echo "all guest phases passed"
