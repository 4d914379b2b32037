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
