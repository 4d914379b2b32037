# Sourced by the host-side UML tests (tests/e2e/test_can_uml.sh,
# tests/e2e/test_drive_uml.sh): the line track and one guest boot.

# uml_line_track FILE: a line along y at 1 m/s for 3 s, 20 waypoints/s, from
# (0, 0, 0).
uml_line_track() {
    awk 'BEGIN { print "t_s,x_m,y_m,z_m";
                 for (i = 0; i <= 60; i++) printf "%.6f,0.000000,%.6f,0.000000\n", i * 0.05, i * 0.05 }' > "$1"
}

# uml_boot RUN SCRIPT GUEST_TIMEOUT_S LOG...: boot user-mode-linux with
# tests/uml/init.sh running SCRIPT on RUN (a directory of the host, seen by
# the guest through hostfs); the verdict comes from the file RUN/rc that the
# guest writes (linux.uml always exits 0).  On failure prints the tail of
# each LOG (globs allowed, quoted: expanded once the guest is done) and
# returns 1.
uml_boot() {
    local run=$1 script=$2 tmo=$3 umldir start_ms rc f
    shift 3
    command -v linux.uml > /dev/null || { echo "linux.uml missing (apt-get install user-mode-linux)"; return 1; }
    # UML keeps its pid file and mconsole socket in uml_dir, by default ~/.uml:
    # without HOME (env -i, some service managers) it panics at boot.  A short
    # temporary path (the socket's name must fit in 108 bytes), removed after.
    umldir=$(mktemp -d) || return 1
    # UML 6.1 sets its processes' FPU state with a buffer of the older XSAVE
    # size, which hosts with AVX-512 or AMX refuse (EFAULT: the guest panics
    # with "ptrace set fp regs failed, errno = 14"): the ptrace() wrapper
    # retries with the host's full size (tests/uml/xstate_preload.c).
    local preload=${BUILD:-$PWD/build}/tests/uml/xstate_preload.so
    [ -f "$preload" ] || { echo "uml: $preload missing (make all builds it)"; rm -rf "$umldir"; return 1; }
    start_ms=$(( $(date +%s%N) / 1000000 ))
    # Host timeout > guest timeout, so a hung scenario still leaves a verdict file.
    LD_PRELOAD="$preload" TRAJD_XSTATE_LOG="$run/xstate.log" \
    timeout -k 5 $((tmo + 20)) linux.uml uml_dir="$umldir" mem=256M rootfstype=hostfs rootflags=/ ro \
        quiet loglevel=1 init="$PWD/tests/uml/init.sh" trajd_dir="$run" trajd_script="$script" \
        trajd_src="$PWD" trajd_timeout="$tmo" con=null con0=null,fd:1 < /dev/null > "$run/console.log" 2>&1
    rm -rf "$umldir"
    # (shell arithmetic: bc is not on a minimal Debian)
    echo "uml: boot and $script took $(( $(date +%s%N) / 1000000 - start_ms )) ms" \
         "(CAN path: vcan in a user-mode-linux $(linux.uml --version 2>/dev/null | head -1) guest;" \
         "$([ -s "$run/xstate.log" ] && cat "$run/xstate.log" || echo "xstate: host size accepted"))"
    if [ ! -f "$run/rc" ]; then
        cat "$run/guest.log" 2>/dev/null
        uml_no_verdict "$run/console.log"
        return 1
    fi
    rc=$(cat "$run/rc")
    if [ "$rc" != 0 ]; then
        # the logs first, the guest's own account last: a failure's last lines
        # (what tests/run.sh shows) say which step failed and how long each took
        # the globs expanded now: at the call the guest had written none of them
        local p
        for p in "$@"; do
            for f in $p; do echo "== $f"; tail -30 "$f"; done
        done
        [ -s "$run/ps.txt" ] && { echo "== $run/ps.txt (the guest's processes 10 s before its timeout)"; cat "$run/ps.txt"; }
        echo "== $run/guest.log"
    fi
    cat "$run/guest.log" 2>/dev/null
    echo "uml: guest exit code $rc"
    [ "$rc" = 0 ]
}

# uml_no_verdict CONSOLE: one line naming why the guest gave no verdict (the
# console has the whole kernel trace).
uml_no_verdict() {
    local why
    if grep -q 'ptrace set fp regs failed' "$1"; then
        why="the guest panicked at boot: ptrace set fp regs failed (the host's XSAVE area is larger than UML's and the ptrace wrapper did not widen it)"
    elif why=$(grep -m1 -o 'Kernel panic.*' "$1"); then
        why="the guest panicked: $why"
    elif [ ! -s "$1" ]; then
        why="linux.uml printed nothing (killed by the host timeout?)"
    else
        why="the guest did not finish: $(grep -v '^ *\[<' "$1" | grep . | tail -1)"
    fi
    echo "uml: $why (console: $1)"
}
