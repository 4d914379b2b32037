#!/bin/bash
# CAN scenarios on a real Linux kernel with vcan: user-mode-linux runs as an
# ordinary process (this host's kernel has no CAN; see SOCKETCAN.md).  One boot
# runs every scenario of tests/uml/all.sh; the verdict comes from a file the
# guest writes (linux.uml always exits 0).
set -u
cd "$(dirname "$0")/.." || exit 1
: "${BUILD:=$PWD/build}"
command -v linux.uml > /dev/null || { echo "linux.uml missing (apt-get install user-mode-linux)"; exit 1; }
run=$BUILD/uml-run
rm -rf "$run"; mkdir -p "$run"

# Host timeout > guest timeout, so a hung scenario still leaves a verdict file.
timeout -k 5 90 linux.uml mem=256M rootfstype=hostfs rootflags=/ ro quiet loglevel=1 \
    init="$PWD/tests/uml/init.sh" trajd_dir="$run" trajd_script=tests/uml/all.sh \
    trajd_src="$PWD" trajd_timeout=70 con=null con0=null,fd:1 < /dev/null > "$run/console.log" 2>&1
cat "$run/guest.log" 2>/dev/null
[ -f "$run/rc" ] || { echo "no verdict file: the guest did not finish"; cat "$run/console.log"; exit 1; }
rc=$(cat "$run/rc")
echo "uml: guest exit code $rc"
[ "$rc" = 0 ]
