#!/bin/bash
# test_install.sh - `make install` / `make uninstall` like a Debian package
# (PREFIX=/usr, DESTDIR staging, FHS), checked by a client built against it:
#   Given `make install DESTDIR=tmp PREFIX=/usr`, then binaries, the four man
#   pages, the DBC, example configs, libtrajd.a, libtrajd.so with its soname
#   (readelf), the headers under include/trajd/ and trajd.pc are in place;
#   daemon/doc/examples/trajd_client.c, as installed, builds with
#   `pkg-config --cflags --libs trajd` (PKG_CONFIG_PATH and SYSROOT into
#   DESTDIR: nothing of the source tree on its include path), links to the
#   installed libtrajd.so.0 (readelf NEEDED) and runs to the end of its track;
#   it also builds with --static against libtrajd.a;
#   then `make uninstall` leaves no file in DESTDIR.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
command -v pkg-config > /dev/null || { echo "FAIL: pkg-config not installed (make deps installs it)"; exit 1; }
PREFIX=/usr
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
dest="$tmp/root"
fail() { echo "FAIL: $*"; exit 1; }
make --no-print-directory install BUILD="$BUILD" DESTDIR="$dest" PREFIX="$PREFIX" > "$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "make install"; }
for f in bin/trajd bin/trajctl bin/trajreplay bin/trajsurf share/man/man8/trajd.8 share/man/man5/trajd.conf.5 \
         share/man/man1/trajctl.1 share/man/man1/trajreplay.1 share/man/man1/trajsurf.1 share/trajd/trajd.dbc share/trajd/trajd.lua \
         share/doc/trajd/examples/trajd.conf share/doc/trajd/examples/trajd_client.c \
         share/doc/trajd/examples/trajd_can_sender.py share/doc/trajd/examples/trajd_modbus_hmi.py \
         lib/libtrajd.a lib/libtrajd.so lib/libtrajd.so.0 lib/pkgconfig/trajd.pc \
         include/trajd/engine.h include/trajd/motion.h; do
    [ -e "$dest$PREFIX/$f" ] || fail "missing $PREFIX/$f"
done
# The installed headers are the client API: those that say so, each usable alone
# with nothing but the installed ones; the engine's parts are not installed.
inc="$dest$PREFIX/include/trajd"
want=$(grep -l '^/\* trajd public API: ' lib/motion.h lib/*/*.h | xargs -n1 basename | sort)
have=$(ls "$inc" | sort)
[ "$want" = "$have" ] || fail "installed headers differ from the public ones: $(diff <(echo "$want") <(echo "$have") | tr '\n' ' ')"
for h in accept.h timescale.h tridiag.h frag.h playout.h transfer.h; do
    [ -e "$inc/$h" ] && fail "internal header $h installed"
done
for h in $have; do
    printf '#include "%s"\nint main(void) { return 0; }\n' "$h" > "$tmp/h.c"
    cc -std=c11 -Wall -Werror -fsyntax-only -I"$inc" "$tmp/h.c" 2> "$tmp/h.err" ||
        { cat "$tmp/h.err"; fail "installed $h does not compile alone against the installed headers"; }
done
soname=$(readelf -d "$dest$PREFIX/lib/libtrajd.so" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
[ "$soname" = libtrajd.so.0 ] || fail "soname '$soname', want libtrajd.so.0"
[ "$(readlink "$dest$PREFIX/lib/libtrajd.so")" = libtrajd.so.0 ] || fail "libtrajd.so does not point at libtrajd.so.0"

export PKG_CONFIG_PATH="$dest$PREFIX/lib/pkgconfig" PKG_CONFIG_SYSROOT_DIR="$dest" PKG_CONFIG_LIBDIR=
pkg-config --exists trajd || fail "pkg-config does not find trajd"
flags=$(pkg-config --cflags --libs trajd)
case "$flags" in *"$PWD"*) fail "pkg-config flags name the source tree: $flags";; esac
src="$dest$PREFIX/share/doc/trajd/examples/trajd_client.c"
cp "$src" "$tmp/client.c"    # away from the source tree: no header found by accident
# shellcheck disable=SC2086
cc -std=c11 -Wall -Wextra -Werror "$tmp/client.c" $flags -lm -o "$tmp/client" || fail "client does not build: $flags"
readelf -d "$tmp/client" | grep -q 'NEEDED.*\[libtrajd.so.0\]' || fail "client not linked to libtrajd.so.0"
LD_LIBRARY_PATH="$dest$PREFIX/lib" "$tmp/client" > "$tmp/out" || { cat "$tmp/out"; fail "client run"; }
tail -1 "$tmp/out" | grep -q '^finished at x = 3.000000 m' || fail "client output: $(tail -1 "$tmp/out")"
# shellcheck disable=SC2086
cc -std=c11 "$tmp/client.c" -static $(pkg-config --static --cflags --libs trajd) -o "$tmp/client_static" ||
    fail "static client does not build"
"$tmp/client_static" > /dev/null || fail "static client run"

for f in share/doc/trajd/PROTOCOL.md share/doc/trajd/README.md share/doc/trajd/REFERENCE.md \
         share/doc/trajd/CLOCK.md share/doc/trajd/TIMESCALE.md share/doc/trajd/examples/demo.conf \
         share/trajd/tracks/n2k_furuno_figure8_src52.csv; do
    [ -e "$dest$PREFIX/$f" ] || fail "missing $PREFIX/$f"
done

# Installed where it runs (PREFIX and SYSCONFDIR in a directory of the test's,
# no DESTDIR): every installed config passes the installed trajd's
# --check-config as it lies (its paths resolve there), and /etc/trajd/trajd.conf
# runs as a service would: past the end of its demo track it keeps serving.
live="$tmp/live"
make --no-print-directory install BUILD="$BUILD" PREFIX="$live" SYSCONFDIR="$live/etc" > "$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "make install PREFIX=$live"; }
for c in "$live/etc/trajd/trajd.conf" "$live"/share/doc/trajd/examples/*.conf; do
    # (the output file the service writes in its RuntimeDirectory, here a directory of ours)
    sed "s|^csv.path = /run/trajd/|csv.path = $tmp/|" "$c" > "$tmp/check.conf"
    cp "$tmp/check.conf" "$(dirname "$c")/check-$(basename "$c")"
    "$live/bin/trajd" --check-config "$(dirname "$c")/check-$(basename "$c")" > "$tmp/cc.log" 2>&1 ||
        { cat "$tmp/cc.log"; fail "installed $(basename "$c") does not pass --check-config"; }
    rm -f "$(dirname "$c")/check-$(basename "$c")"
done
grep -q '^exit_when_done = no$' "$live/etc/trajd/trajd.conf" || fail "the installed trajd.conf exits when its replay ends"
# At speed 200 the 360 s demo track plays in under 2 s: 4 s later trajd still runs and answers Modbus.
sed -e "s|^csv.path = /run/trajd/|csv.path = $tmp/|" -e 's|^#speed = 1.0$|speed = 200|' -e 's|^#port = 1502$|port = 0|' \
    "$live/etc/trajd/trajd.conf" > "$live/etc/trajd/fast.conf"
"$live/bin/trajd" -f -c "$live/etc/trajd/fast.conf" > "$tmp/svc.out" 2> "$tmp/svc.err" &
svc=$!
sleep 6
kill -0 "$svc" 2> /dev/null || { cat "$tmp/svc.err"; fail "the installed config's trajd exited after its demo track"; }
port=$(sed -n 's/.*modbus: TCP on [^ ]* port \([0-9][0-9]*\).*/\1/p' "$tmp/svc.err" | head -1)
# the daemon block's first register: the protocol version (config/PROTOCOL.md), read by mbpoll
mbpoll -m tcp -p "${port:-0}" -a 1 -t 3 -0 -r 0 -c 1 -1 127.0.0.1 > "$tmp/mb.out" 2>&1 ||
    { cat "$tmp/mb.out"; kill -TERM "$svc"; fail "the installed config's Modbus server does not answer"; }
kill -TERM "$svc"; wait "$svc"; rc=$?
[ "$rc" = 0 ] || { cat "$tmp/svc.err"; fail "SIGTERM: exit $rc"; }
grep -q 'boat finished' "$tmp/svc.err" || { tail -3 "$tmp/svc.err"; fail "the demo track did not play to its end"; }
echo "installed config: ran past its track's end, Modbus on port ${port:-?}, exit 0 on SIGTERM"
make --no-print-directory uninstall BUILD="$BUILD" PREFIX="$live" SYSCONFDIR="$live/etc" > "$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "make uninstall PREFIX=$live"; }

make --no-print-directory uninstall BUILD="$BUILD" DESTDIR="$dest" PREFIX="$PREFIX" > "$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "make uninstall"; }
left=$(find "$dest" ! -type d)
[ -z "$left" ] || fail "make uninstall left: $left"
echo "ok: installed into DESTDIR, client built with pkg-config (shared, soname libtrajd.so.0, and static) ran to x = 3 m, uninstall left no file"
