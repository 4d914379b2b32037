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
# each LOG (globs allowed) and returns 1.
uml_boot() {
    local run=$1 script=$2 tmo=$3 umldir start_ms rc f
    shift 3
    command -v linux.uml > /dev/null || { echo "linux.uml missing (apt-get install user-mode-linux)"; return 1; }
    # UML keeps its pid file and mconsole socket in uml_dir, by default ~/.uml:
    # without HOME (env -i, some service managers) it panics at boot.  A short
    # temporary path (the socket's name must fit in 108 bytes), removed after.
    umldir=$(mktemp -d) || return 1
    start_ms=$(( $(date +%s%N) / 1000000 ))
    # Host timeout > guest timeout, so a hung scenario still leaves a verdict file.
    timeout -k 5 $((tmo + 20)) linux.uml uml_dir="$umldir" mem=256M rootfstype=hostfs rootflags=/ ro \
        quiet loglevel=1 init="$PWD/tests/uml/init.sh" trajd_dir="$run" trajd_script="$script" \
        trajd_src="$PWD" trajd_timeout="$tmo" con=null con0=null,fd:1 < /dev/null > "$run/console.log" 2>&1
    rm -rf "$umldir"
    # (shell arithmetic: bc is not on a minimal Debian)
    echo "uml: boot and $script took $(( $(date +%s%N) / 1000000 - start_ms )) ms"
    cat "$run/guest.log" 2>/dev/null
    [ -f "$run/rc" ] || { echo "no verdict file: the guest did not finish"; cat "$run/console.log"; return 1; }
    rc=$(cat "$run/rc")
    echo "uml: guest exit code $rc"
    [ "$rc" = 0 ] && return 0
    for f in "$@"; do echo "== $f"; tail -30 "$f"; done
    return 1
}
