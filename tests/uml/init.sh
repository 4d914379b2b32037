#!/bin/sh
# PID 1 of the user-mode-linux guest used by tests/e2e/test_can_uml.sh.
# Kernel command line words (no spaces in values):
#   trajd_dir=<dir>     writable hostfs directory (results, logs)
#   trajd_script=<sh>   scenario script to run (with sh), cwd = the source tree
#   trajd_src=<dir>     the source tree (read-only through hostfs)
#   trajd_timeout=<s>   guest-side timeout for the script (shorter than the host's)
# Writes <dir>/rc with the script's exit code, then powers off.  linux.uml itself
# always exits 0, so the host reads the verdict from that file.
PATH=/usr/sbin:/usr/bin:/sbin:/bin
export PATH
mount -t proc proc /proc 2>/dev/null
dir=; script=; src=; tmo=40
for w in $(cat /proc/cmdline); do
    case "$w" in
        trajd_dir=*) dir=${w#trajd_dir=} ;;
        trajd_script=*) script=${w#trajd_script=} ;;
        trajd_src=*) src=${w#trajd_src=} ;;
        trajd_timeout=*) tmo=${w#trajd_timeout=} ;;
    esac
done
# guest_ps: one line per user process: pid, name, state, where it sleeps in
# the kernel (shell builtins only: a fork per line is slow in the guest)
guest_ps() {
    for p in /proc/[0-9]*; do
        read -r st 2>/dev/null < "$p/stat" || continue
        set -- $st
        [ "$1" = 2 ] || [ "$4" = 2 ] && continue   # kthreadd and the kernel's threads
        w=; read -r w 2>/dev/null < "$p/wchan"
        echo "$1 $2 $3 ${w:--}"
    done
}
mount -t sysfs sys /sys 2>/dev/null
grep -q ' /dev ' /proc/mounts || mount -t devtmpfs dev /dev 2>/dev/null
mkdir -p /dev/pts /dev/shm
mount -t devpts devpts /dev/pts 2>/dev/null
for m in /tmp /run /dev/shm; do mount -t tmpfs tmpfs $m 2>/dev/null; done
# A tree under /tmp or /run (where a CI clone may well be) is hidden by those
# tmpfs mounts: bring it back through hostfs at the same path.
if [ ! -d "$src/tests/uml" ]; then
    mkdir -p "$src" && mount -t hostfs -o "$src" none "$src"
fi
mkdir -p "$dir"
mount -t hostfs -o "$dir" none "$dir"
# Host directories a scenario names in $dir/env (the build, the CANopen peers)
# may lie under /tmp too (a clone under mktemp -d with shared/ beside it).
if [ -f "$dir/env" ]; then
    for p in $(sed -n 's/^\(BUILD\|TRAJD_PEERS\)=//p' "$dir/env"); do
        [ -d "$p" ] || { mkdir -p "$p" && mount -t hostfs -o "$p" none "$p"; }
    done
fi
{
    echo "guest: $(uname -r)"
    k=/usr/lib/uml/modules/$(uname -r)/kernel
    # can-bcm: python-can sends periodic frames (a simulated node's heartbeat) through it
    for mod in net/can/can.ko net/can/can-raw.ko net/can/can-bcm.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
        busybox insmod "$k/$mod" || echo "guest: insmod $mod failed"
    done
    ip link set lo up
    ip link add dev vcan0 type vcan && ip link set vcan0 mtu 72 up
    cd "$src" || exit 1
    rc=0
    # 10 s before the timeout, what every process is doing (its state, where
    # it sleeps in the kernel) goes to $dir/ps.txt: a scenario that hangs says
    # where, not only that it timed out
    (sleep $((tmo > 20 ? tmo - 10 : tmo / 2)); guest_ps > "$dir/ps.txt") & wd=$!
    timeout -k 2 "$tmo" sh "$script" "$dir" || rc=$?
    kill "$wd" 2>/dev/null
    echo "guest: script exit $rc$([ "$rc" = 124 ] || [ "$rc" = 137 ] && echo " (timed out after $tmo s; its processes 10 s before: ps.txt)")"
    echo $rc > "$dir/rc"
} > "$dir/guest.log" 2>&1
sync
busybox poweroff -f
