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

make --no-print-directory uninstall BUILD="$BUILD" DESTDIR="$dest" PREFIX="$PREFIX" > "$tmp/log" 2>&1 ||
    { cat "$tmp/log"; fail "make uninstall"; }
left=$(find "$dest" ! -type d)
[ -z "$left" ] || fail "make uninstall left: $left"
echo "ok: installed into DESTDIR, client built with pkg-config (shared, soname libtrajd.so.0, and static) ran to x = 3 m, uninstall left no file"
