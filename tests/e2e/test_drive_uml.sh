#!/bin/bash
# CiA 402 drives simulated on vcan inside user-mode-linux (tests/uml/drive.sh,
# tests/uml/drive_sim.py on python-canopen's LocalNode): trajd brings them up
# from power-on to Operation Enabled and drives them; the verdict comes from
# the guest's files, checked here (tests/helpers/cantools_trajd.py drive-check).
# Skips when python-canopen (../shared/peers, or TRAJD_PEERS) is absent.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:=$PWD/build}"
PY=${PYTHON:-/usr/bin/python3}
peers=${TRAJD_PEERS:-$PWD/../shared/peers}
if [ ! -d "$peers/python-canopen/canopen" ]; then
    echo "SKIP: python-canopen not found at $peers/python-canopen (the drive simulator runs on it; set TRAJD_PEERS)"
    exit 0
fi
command -v linux.uml > /dev/null || { echo "linux.uml missing (apt-get install user-mode-linux)"; exit 1; }
run=$BUILD/uml-drive
rm -rf "$run"; mkdir -p "$run"
{ echo "BUILD=$BUILD"; echo "TRAJD_PEERS=$(cd "$peers" && pwd)"; } > "$run/env"
# The track: a line along y at 1 m/s for 3 s, 20 waypoints/s, from (0, 0, 0)
$PY - "$run/dtrack.csv" <<'PYEOF' || exit 1
import sys
with open(sys.argv[1], "w") as f:
    f.write("t_s,x_m,y_m,z_m\n")
    for i in range(61):
        f.write("%.6f,0.000000,%.6f,0.000000\n" % (i * 0.05, i * 0.05))
PYEOF
$PY tests/helpers/cantools_trajd.py wplog "$run/dtrack.csv" "$run/dwp.log" > /dev/null || exit 1
# The config: README.md's drive example exactly (so it cannot rot), on vcan0; the test
# adds only what it needs: every cycle counts as late (max_late_ms tiny: SYNC and the
# RPDOs must still go out), and object 'spare' (node 3), whose list has an object the
# drive lacks (0x6071: SDO abort, reported, that drive never enabled), and a Modbus
# server the guest reads with mbpoll.
$PY - README.md "$run/drive.conf" <<'PYEOF' || exit 1
import sys
lines = open(sys.argv[1]).read().splitlines()
i = next(k for k, l in enumerate(lines) if l.startswith("<!-- drive-config:"))
block = []
for l in lines[i + 1:]:
    if not l.startswith("    "):
        break
    block.append(l[4:])
conf = "\n".join(block) + "\n"
assert "interface = can0\n" in conf and "[can]\n" in conf, conf
conf = conf.replace("interface = can0\n", "interface = vcan0\n")
conf = conf.replace("[can]\n", "[can]\nmax_late_ms = 0.001\n")
conf += ("[object.spare]\nid = 1\ninput = can\noutput = can\ncan.own = no\ncan.cia402 = yes\n"
         "can.cia402_enable = yes\ncan.cia402_cob_x = 0x203\ncan.cia402_cob_y = 0\n"
         "can.cia402_cob_z = 0\ncan.cia402_sdo = 0x6060:0=8/1, 0x6071:0=0/2\n"
         "[modbus]\naddress = 127.0.0.1\nport = 1502\n")
open(sys.argv[2], "w").write(conf)
PYEOF
"$BUILD/bin/trajd" --check-config "$run/drive.conf" || exit 1
umldir=$(mktemp -d) || exit 1
trap 'rm -rf "$umldir"' EXIT
start_ms=$(( $(date +%s%N) / 1000000 ))
timeout -k 5 190 linux.uml uml_dir="$umldir" mem=256M rootfstype=hostfs rootflags=/ ro quiet loglevel=1 \
    init="$PWD/tests/uml/init.sh" trajd_dir="$run" trajd_script=tests/uml/drive.sh \
    trajd_src="$PWD" trajd_timeout=170 con=null con0=null,fd:1 < /dev/null > "$run/console.log" 2>&1
echo "uml: boot and drive scenario took $(( $(date +%s%N) / 1000000 - start_ms )) ms"
cat "$run/guest.log" 2>/dev/null
[ -f "$run/rc" ] || { echo "no verdict file: the guest did not finish"; cat "$run/console.log"; exit 1; }
rc=$(cat "$run/rc")
echo "uml: guest exit code $rc"
[ "$rc" = 0 ] || { for f in "$run"/drive.err "$run"/sim.err; do echo "== $f"; tail -30 "$f"; done; exit 1; }
TRAJD_PEERS=$(cd "$peers" && pwd) $PY tests/helpers/cantools_trajd.py drive-check "$run" || exit 1
