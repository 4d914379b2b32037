#!/bin/sh
# fresh_debian.sh - the README's two commands on a fresh Debian 12: a minimal
# bookworm chroot (debootstrap --variant=minbase: no make, no git, no procps),
# the README's step 0, a clone of this repository, `make check` twice (timed:
# first with the installs), a 15 s `make run` that must stream setpoints, and
# `make install PREFIX=/usr` whose /etc/trajd/trajd.conf passes its check and
# runs as the service would (still serving Modbus 20 s later, exit 0 on SIGTERM).
# Not part of `make check` (it needs root, debootstrap and Debian's archive;
# ~4 min).  Usage, as root:  sh tests/fresh_debian.sh [BRANCH]
#   FRESH_DIR   where the chroot is made (default /var/tmp/trajd-fresh; removed first)
#   MIRROR      Debian mirror (default http://deb.debian.org/debian)
#   FRESH_STEPS all (default), or run-install: skip the two make check runs
# Outside the chroot it needs ../shared beside the repository only as CI has it.
set -eu
cd "$(dirname "$0")/.."
BRANCH=${1:-$(git rev-parse --abbrev-ref HEAD)}
STEPS=${FRESH_STEPS:-all}   # all, or run-install: make run and make install only (minutes, not an hour)
R=${FRESH_DIR:-/var/tmp/trajd-fresh}
MIRROR=${MIRROR:-http://deb.debian.org/debian}
[ "$(id -u)" -eq 0 ] || { echo "fresh_debian: run as root" >&2; exit 1; }
sh tests/deps.sh debootstrap git

umount_all() {
    for m in src dev/shm dev/pts dev sys proc; do
        mountpoint -q "$R/$m" 2>/dev/null && umount "$R/$m"
    done
    return 0
}
trap umount_all EXIT
umount_all
rm -rf --one-file-system "$R"
debootstrap --variant=minbase bookworm "$R" "$MIRROR" > /tmp/fresh_debian.debootstrap.log 2>&1 \
    || { tail /tmp/fresh_debian.debootstrap.log; exit 1; }
mount -t proc proc "$R/proc"
mount -t sysfs sys "$R/sys"
mount --bind /dev "$R/dev"
mount -t devpts -o newinstance,ptmxmode=0666 devpts "$R/dev/pts"
mount -t tmpfs -o mode=1777 tmpfs "$R/dev/shm"
cp /etc/resolv.conf "$R/etc/resolv.conf"
mkdir -p "$R/src" "$R/root/ci"
# the repository's object store (a worktree's .git is only a pointer to it)
mount --bind -o ro "$(cd "$(git rev-parse --git-common-dir)" && pwd)" "$R/src"
[ -d ../shared ] && cp -a ../shared "$R/root/ci/shared"

# Only PATH and HOME in the environment, no terminal, no standard input (as CI).
chroot "$R" /usr/bin/env -i PATH=/usr/sbin:/usr/bin:/sbin:/bin HOME=/root /bin/bash -c "
set -u
run() { # log, command...: run it, print its time and exit code
    log=\$1; shift; s=\$(date +%s); \"\$@\" > \"\$log\" 2>&1 < /dev/null; rc=\$?
    echo \"\$(( \$(date +%s) - s )) s, exit \$rc\"; return \$rc
}
echo '== step 0: apt-get update && apt-get install -y make git'
run /root/ci/step0.log sh -c 'apt-get update -q && apt-get install -y -q make git' || exit 1
cd /root/ci && git clone -q -b '$BRANCH' /src main && cd main && git log --oneline -1 || exit 1
rc1=0; rc2=0
if [ '$STEPS' = all ]; then
echo '== make check (first: installs the packages)'
run /root/ci/check1.log make check; rc1=\$?
grep -E '^FAIL|check:' /root/ci/check1.log
echo '== make check (second)'
run /root/ci/check2.log make check; rc2=\$?
grep -E '^FAIL|check:' /root/ci/check2.log
fi
if [ '$STEPS' != all ]; then
    echo '== make deps-run and the build (make check did both)'
    run /root/ci/build.log sh -c 'make deps-run && make -j2 build/bin/trajd' || exit 1
fi
echo '== timeout -s INT 15 make run'
run /root/ci/run.log timeout -s INT 15 make run
[ '$STEPS' = all ] || sh tests/deps.sh mbpoll > /dev/null
n=\$(grep -c ',streaming,' /root/ci/run.log)
echo \"setpoints streamed: \$n\"; grep '^<' /root/ci/run.log | tail -1
echo '== make install (PREFIX=/usr), then the installed config as the service runs it'
run /root/ci/install.log make install PREFIX=/usr; rci=\$?
/usr/bin/trajd --check-config /etc/trajd/trajd.conf; rcc=\$?
mkdir -p /run/trajd
/usr/bin/trajd -f -c /etc/trajd/trajd.conf > /root/ci/svc.out 2> /root/ci/svc.err &
svc=\$!; sleep 20
kill -0 \$svc 2> /dev/null; alive=\$?
mbpoll -m tcp -p 1502 -a 1 -t 3 -0 -r 0 -c 1 -1 127.0.0.1 > /root/ci/mb.out 2>&1; rcm=\$?
kill -TERM \$svc; wait \$svc; rcs=\$?
echo \"installed: install \$rci, check-config \$rcc, running after 20 s \$alive, Modbus \$rcm, SIGTERM exit \$rcs\"
[ \$rc1 -eq 0 ] && [ \$rc2 -eq 0 ] && [ \$n -gt 100 ] && [ \$rci -eq 0 ] && [ \$rcc -eq 0 ] &&
    [ \$alive -eq 0 ] && [ \$rcm -eq 0 ] && [ \$rcs -eq 0 ]
" && rc=0 || rc=$?
echo "fresh_debian: logs in $R/root/ci/; exit $rc"
exit $rc
