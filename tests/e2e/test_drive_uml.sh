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
    exit 77  # skipped (tests/run.sh): ../shared is not part of a user's checkout
fi
. tests/uml/host.sh
run=$BUILD/uml-drive
rm -rf "$run"; mkdir -p "$run"
{ echo "BUILD=$BUILD"; echo "TRAJD_PEERS=$(cd "$peers" && pwd)"; } > "$run/env"
uml_line_track "$run/dtrack.csv"
$PY tests/helpers/cantools_trajd.py wplog "$run/dtrack.csv" "$run/dwp.log" > /dev/null || exit 1
# The config: README.md's drive example exactly (so it cannot rot), on vcan0; the test
# adds only what it needs: every cycle counts as late (max_late_ms tiny: SYNC and the
# RPDOs must still go out), and object 'spare' (node 3), whose list has an object the
# drive lacks (0x6071: SDO abort, reported, that drive never enabled), and a Modbus
# server the guest reads with mbpoll and writes arm's feed override to.
$PY - README.md "$run/drive.conf" <<'PYEOF' || exit 1
import sys
sys.path.insert(0, "tests/helpers")
from readme_conf import drive_config
conf = drive_config(sys.argv[1])
assert "interface = can0\n" in conf and "[can]\n" in conf, conf
conf = conf.replace("interface = can0\n", "interface = vcan0\n")
conf = conf.replace("[can]\n", "[can]\nmax_late_ms = 0.001\n")
conf = conf.replace("[object.arm]\n", "[object.arm]\nwritable = yes\n")  # its override by Modbus
conf += ("[object.spare]\nid = 1\ninput = can\noutput = can\ncan.own = no\ncan.cia402 = yes\n"
         "can.cia402_enable = yes\ncan.cia402_cob_x = 0x203\ncan.cia402_cob_y = 0\n"
         "can.cia402_cob_z = 0\ncan.cia402_sdo = 0x6060:0=8/1, 0x6071:0=0/2\n"
         "[modbus]\naddress = 127.0.0.1\nport = 1502\nwrites = yes\n")
open(sys.argv[2], "w").write(conf)
PYEOF
"$BUILD/bin/trajd" --check-config "$run/drive.conf" || exit 1
uml_boot "$run" tests/uml/drive.sh 170 "$run/drive.err" "$run/sim.err" || exit 1
TRAJD_PEERS=$(cd "$peers" && pwd) $PY tests/helpers/cantools_trajd.py drive-check "$run" || exit 1
