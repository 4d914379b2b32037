#!/bin/sh
# Install the Debian packages named as arguments that are missing.
# As root it runs apt-get itself; otherwise it says what to run.
# Another apt (unattended-upgrades on a freshly booted machine, a second
# install) may hold the locks: apt-get install waits for them (DPkg::Lock::Timeout);
# apt-get update does not (apt 2.6), so it is retried while the lock is the reason.
LOCK_WAIT_S=600   # bound on waiting for another apt to finish
missing=""
for p in "$@"; do
    dpkg-query -W -f='${Status}\n' "$p" 2>/dev/null | grep -q 'ok installed' || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "deps: missing Debian packages:$missing" >&2
if [ "$(id -u)" -ne 0 ]; then
    echo "deps: run as root, or: sudo apt-get install --no-install-recommends$missing" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive
err=$(mktemp) || exit 1
trap 'rm -f "$err"' EXIT
waited=0
until apt-get update -q 2> "$err" >&2; do
    cat "$err" >&2
    grep -q 'Could not get lock' "$err" && [ "$waited" -lt "$LOCK_WAIT_S" ] || exit 1
    echo "deps: another apt holds the package lists; retrying in 5 s" >&2
    sleep 5; waited=$((waited + 5))
done
cat "$err" >&2
# shellcheck disable=SC2086
apt-get install -y -q --no-install-recommends -o DPkg::Lock::Timeout=$LOCK_WAIT_S $missing >&2 || exit 1
