# Helpers sourced by guest scenarios (POSIX sh).  Nothing here sleeps "to be
# safe": every wait polls for its event with a bound.

# wait_rx IFACE: wait until a raw CAN socket is bound on IFACE (a receiver is ready).
wait_rx() {
    i=0
    while [ $i -lt 500 ]; do
        # an entry line "   vcan0     000    00000000 ..." (not "(vcan0: no entry)")
        grep -Eq "^ +$1 +[0-9a-f]+ " /proc/net/can/rcvlist_all 2>/dev/null && return 0
        i=$((i + 1)); sleep 0.02
    done
    echo "wait_rx: no receiver on $1" >&2; return 1
}

# wait_lines FILE N [TRIES]: wait until FILE has at least N lines (20 ms polls).
wait_lines() {
    i=0; n=${3:-500}
    while [ $i -lt "$n" ]; do
        [ -f "$1" ] && [ "$(wc -l < "$1")" -ge "$2" ] && return 0
        i=$((i + 1)); sleep 0.02
    done
    echo "wait_lines: $1 has $(wc -l < "$1" 2>/dev/null) lines, wanted $2" >&2; return 1
}

# wait_grep FILE PATTERN [TRIES]
wait_grep() {
    i=0; n=${3:-500}
    while [ $i -lt "$n" ]; do
        grep -q "$2" "$1" 2>/dev/null && return 0
        i=$((i + 1)); sleep 0.02
    done
    echo "wait_grep: '$2' not in $1" >&2; return 1
}

# mark WHAT: a line on the scenario's output (the guest's log) with the
# seconds since t0 (set t0=$(uptime_s) at the start): a failure's log says how
# long each step took.
uptime_s() { cut -d' ' -f1 /proc/uptime; }
mark() { echo "$(awk -v t0="${t0:-0}" '{printf "%.2f", $1 - t0}' /proc/uptime) s: $*"; }

# wait_gone PID NAME [TRIES]: until process PID has ended (a zombie not yet
# reaped counts as ended; 20 ms polls, 500 by default), then reaps it (its exit
# status is wait_gone's); if it has not ended, says where each of its threads
# sleeps in the kernel and returns 1.
wait_gone() {
    i=0; n=${3:-500}
    while [ $i -lt "$n" ]; do
        st=$(cut -d' ' -f3 "/proc/$1/stat" 2>/dev/null) || st=Z
        [ "$st" = Z ] && { wait "$1"; return $?; }
        i=$((i + 1)); sleep 0.02
    done
    echo "wait_gone: $2 (pid $1) has not ended:" >&2
    for t in /proc/"$1"/task/*; do
        echo "  thread $(cat "$t/comm" 2>/dev/null): state $(cut -d' ' -f3 "$t/stat" 2>/dev/null)," \
             "in $(cat "$t/wchan" 2>/dev/null)" >&2
    done
    return 1
}

# exit_agrees RC ERRFILE: trajd's exit status agrees with its exit summary in
# ERRFILE: 74 (EX_IOERR) when a "can: <object>: setpoints sent ..." line counts
# a setpoint cycle with a position not sent (late, queue full, down, write
# error: motion the drives missed), else 0 (trajd(8) EXIT STATUS).  A loaded
# guest may run a cycle late; the status must say so when it did.
exit_agrees() {
    lost=$(sed -n 's/.*can: .*: setpoints sent .*(\([0-9]*\) with a position).*/\1/p' "$2" |
           awk '{s += $1} END {print s + 0}')
    want=0; [ "$lost" -gt 0 ] && want=74
    [ "$1" -eq "$want" ] && return 0
    echo "exit_agrees: trajd exit $1 with $lost setpoint cycles with a position not sent" \
         "(wanted $want)" >&2
    return 1
}
