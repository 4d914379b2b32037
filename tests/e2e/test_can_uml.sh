#!/bin/bash
# CAN scenarios on a real Linux kernel with vcan: user-mode-linux runs as an
# ordinary process (for hosts whose kernel has no CAN modules).  One boot
# runs every scenario of tests/uml/all.sh (smoke: cansend/candump; canerr: error
# frames injected with cansend, the bus state on Modbus; daemon:
# trajd streaming a track sent by canplayer, down/up, removal, ENOBUFS,
# malformed frames, SIGTERM, throughput); the verdict comes from a file the
# guest writes (linux.uml always exits 0).  The captures are then checked
# here against trajreplay (tests/helpers/cantools_trajd.py uml-check).
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:=$PWD/build}"
PY=${PYTHON:-/usr/bin/python3}
command -v linux.uml > /dev/null || { echo "linux.uml missing (apt-get install user-mode-linux)"; exit 1; }
run=$BUILD/uml-run
rm -rf "$run"; mkdir -p "$run"
SPEED=10     # the guest's trajd runs at speed 10 (tests/uml/daemon.sh)
echo "BUILD=$BUILD" > "$run/env"
# The track: 100 waypoints (20 s) of the figure eight, sent in 2 s of wall time.
$PY tests/helpers/cantools_trajd.py xyz tests/data/n2k_furuno_figure8_src52.csv "$run/track.csv" 100 || exit 1
$PY tests/helpers/cantools_trajd.py wplog "$run/track.csv" "$run/wp.log" --time-scale $SPEED --also-fd-obj 1 > /dev/null || exit 1
"$BUILD/bin/trajreplay" --rate 1000 -q -o "$run/ref1k.csv" "$run/track.csv" || exit 1
# The example sender's track (tests/uml/canerr.sh): a line at 1 m/s for 3 s.
$PY - "$run/dtrack.csv" <<'PYEOF' || exit 1
import sys
with open(sys.argv[1], "w") as f:
    f.write("t_s,x_m,y_m,z_m\n")
    for i in range(61):
        f.write("%.6f,0.000000,%.6f,0.000000\n" % (i * 0.05, i * 0.05))
PYEOF

# UML keeps its pid file and mconsole socket in uml_dir, by default ~/.uml: without
# HOME (env -i, some service managers) it panics at boot.  A short temporary path
# (the socket's name must fit in 108 bytes), removed afterwards.
umldir=$(mktemp -d) || exit 1
trap 'rm -rf "$umldir"' EXIT
start_ms=$(( $(date +%s%N) / 1000000 ))
# Host timeout > guest timeout, so a hung scenario still leaves a verdict file.
timeout -k 5 250 linux.uml uml_dir="$umldir" mem=256M rootfstype=hostfs rootflags=/ ro quiet loglevel=1 \
    init="$PWD/tests/uml/init.sh" trajd_dir="$run" trajd_script=tests/uml/all.sh \
    trajd_src="$PWD" trajd_timeout=230 con=null con0=null,fd:1 < /dev/null > "$run/console.log" 2>&1
# (shell arithmetic: bc is not on a minimal Debian)
echo "uml: boot and scenarios took $(( $(date +%s%N) / 1000000 - start_ms )) ms"
cat "$run/guest.log" 2>/dev/null
[ -f "$run/rc" ] || { echo "no verdict file: the guest did not finish"; cat "$run/console.log"; exit 1; }
rc=$(cat "$run/rc")
echo "uml: guest exit code $rc"
[ "$rc" = 0 ] || { for f in "$run"/*.out "$run"/trajd.err; do echo "== $f"; tail -20 "$f"; done; exit 1; }
$PY tests/helpers/cantools_trajd.py uml-check "$run" "$run/track.csv" "$run/ref1k.csv" || exit 1
tail -2 "$run/fast.err"
