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
. tests/uml/host.sh
run=$BUILD/uml-run
rm -rf "$run"; mkdir -p "$run"
SPEED=10     # the guest's trajd runs at speed 10 (tests/uml/daemon.sh)
echo "BUILD=$BUILD" > "$run/env"
# The track: 100 waypoints (20 s) of the figure eight, sent in 2 s of wall time.
$PY tests/helpers/cantools_trajd.py xyz tests/data/n2k_furuno_figure8_src52.csv "$run/track.csv" 100 || exit 1
$PY tests/helpers/cantools_trajd.py wplog "$run/track.csv" "$run/wp.log" --time-scale $SPEED --also-fd-obj 1 > /dev/null || exit 1
"$BUILD/bin/trajreplay" --rate 1000 -q -o "$run/ref1k.csv" "$run/track.csv" || exit 1
# The example sender's track (tests/uml/canerr.sh).
uml_line_track "$run/dtrack.csv"
# Booted with the ptrace wrapper's full-size path forced (tests/uml/xstate_preload.c),
# so a real kernel runs through it on every host, not only where it is needed.
TRAJD_XSTATE_FORCE=1 uml_boot "$run" tests/uml/all.sh 230 "$run/*.out" "$run/trajd.err" || exit 1
grep -q '(forced): ok$' "$run/xstate.log" 2>/dev/null ||
    { echo "FAIL: the guest did not go through the wrapper's full-size path: $(cat "$run/xstate.log" 2>&1)"; exit 1; }
$PY tests/helpers/cantools_trajd.py uml-check "$run" "$run/track.csv" "$run/ref1k.csv" || exit 1
tail -2 "$run/fast.err"
