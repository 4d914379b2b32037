#!/bin/bash
# Every program in $BUILD/bin answers --help and --version (and -h, -V) the GNU way:
#   --help     exit 0, a "usage: PROGRAM" line on stdout, nothing on stderr;
#   --version  exit 0, exactly one line "PROGRAM VERSION" on stdout, with the
#              version of daemon/core/version.h (the same for every program);
#   an unknown option: exit 2 (or EX_USAGE 64, sysexits.h, which the daemon
#   uses), nothing on stdout, a message on stderr.
# The list of programs is the build's, so a program added later is covered.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
version=$(sed -n 's/^#define TRAJD_VERSION "\(.*\)"$/\1/p' daemon/core/version.h)
[ -n "$version" ] || { echo "no TRAJD_VERSION in daemon/core/version.h"; exit 1; }
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0; n=0
bad() { echo "FAIL $*"; fail=1; }
for bin in "$BUILD"/bin/*; do
    [ -x "$bin" ] && [ -f "$bin" ] || continue
    p=$(basename "$bin"); n=$((n + 1))
    for h in --help -h; do
        "$bin" "$h" > "$tmp/out" 2> "$tmp/err"; rc=$?
        [ "$rc" -eq 0 ] || bad "$p $h: exit $rc, want 0"
        grep -q "^usage: $p\b" "$tmp/out" || bad "$p $h: no 'usage: $p' line on stdout"
        [ -s "$tmp/err" ] && bad "$p $h: wrote on stderr: $(head -c 200 "$tmp/err")"
    done
    for v in --version -V; do
        "$bin" "$v" > "$tmp/out" 2> "$tmp/err"; rc=$?
        [ "$rc" -eq 0 ] || bad "$p $v: exit $rc, want 0"
        [ "$(cat "$tmp/out")" = "$p $version" ] || bad "$p $v: printed '$(head -c 200 "$tmp/out")', want '$p $version'"
        [ -s "$tmp/err" ] && bad "$p $v: wrote on stderr"
    done
    "$bin" --no-such-option > "$tmp/out" 2> "$tmp/err"; rc=$?
    [ "$rc" -eq 2 ] || [ "$rc" -eq 64 ] || bad "$p --no-such-option: exit $rc, want 2 or 64"
    [ -s "$tmp/out" ] && bad "$p --no-such-option: wrote on stdout"
    [ -s "$tmp/err" ] || bad "$p --no-such-option: no message on stderr"
done
[ "$n" -ge 3 ] || bad "only $n programs in $BUILD/bin"
# The Python helpers the docs advertise answer --help too (exit 0, text on stdout).
PY=${PYTHON:-/usr/bin/python3}
for h in $(grep -ohE '(tests/helpers|daemon/doc/examples)/[a-z_]+\.py' README.md daemon/REFERENCE.md \
           config/PROTOCOL.md daemon/doc/*.md | sort -u); do
    [ -f "$h" ] || { bad "$h is advertised by the docs but does not exist"; continue; }
    n=$((n + 1))
    "$PY" "$h" --help > "$tmp/out" 2> "$tmp/err"; rc=$?
    [ "$rc" -eq 0 ] || bad "$h --help: exit $rc, want 0: $(tail -c 200 "$tmp/err")"
    [ -s "$tmp/out" ] || bad "$h --help: nothing on stdout"
done
[ "$fail" -eq 0 ] && echo "ok: $n programs and helpers answer --help, -h, --version, -V (version $version) and refuse an unknown option"
exit "$fail"
