#!/bin/bash
# The manual pages (build/man, made by `make all` from daemon/doc/ and, for
# trajd.conf(5), from config/trajd.conf's comments):
#   - trajd(8), trajd.conf(5) and one page per program in $BUILD/bin exist;
#   - each renders with no warning from groff (-ww: all warnings) nor man-db
#     (man --warnings -l), at 80 and 60 columns;
#   - no drift: every long option a program's --help lists (up to "Engine
#     settings": trajreplay's generated engine options are referred to as a
#     whole) is in its page, and every key of config/trajd.conf is in
#     trajd.conf(5).
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
command -v groff > /dev/null && command -v man > /dev/null ||
    { echo "FAIL: groff-base and man-db not installed (make deps installs them)"; exit 1; }
man_dir="$BUILD/man"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
bad() { echo "FAIL $*"; fail=1; }
pages="trajd.8 trajd.conf.5"
for bin in "$BUILD"/bin/*; do
    p=$(basename "$bin")
    [ "$p" = trajd ] || pages="$pages $p.1"
done
for page in $pages; do
    f="$man_dir/$page"
    [ -s "$f" ] || { bad "$page: no $f"; continue; }
    groff -man -ww -z "$f" 2> "$tmp/w"; [ -s "$tmp/w" ] && bad "$page: groff: $(head -3 "$tmp/w")"
    for w in 80 60; do
        MANWIDTH=$w man --warnings -l "$f" > "$tmp/$page.txt" 2> "$tmp/w"
        [ -s "$tmp/w" ] && bad "$page at $w columns: $(head -3 "$tmp/w")"
    done
    grep -q "^NAME" "$tmp/$page.txt" || bad "$page: no NAME section"
done
# options in --help against the page text
for bin in "$BUILD"/bin/*; do
    p=$(basename "$bin"); page=$p.1; [ "$p" = trajd ] && page=trajd.8
    [ -s "$tmp/$page.txt" ] || continue
    "$bin" --help | awk '/^Engine settings/ { exit } { print }' |
        grep -o -- '--[a-z][a-z-]*' | sort -u > "$tmp/opts"
    [ -s "$tmp/opts" ] || bad "$p: no long option found in --help"
    # man renders a hyphen as U+2010 or '-', and may hyphenate: compare without them
    tr -d '\n' < "$tmp/$page.txt" | sed 's/‐/-/g; s/ //g' > "$tmp/flat"
    while read -r o; do
        grep -q -- "$o" "$tmp/flat" || bad "$page does not document $o (listed by $p --help)"
    done < "$tmp/opts"
done
# every key of the example config in trajd.conf(5)
sed -n 's/^#\{0,1\}\([a-z][a-z0-9_.]*\) =.*/\1/p' config/trajd.conf | sort -u > "$tmp/keys"
[ "$(wc -l < "$tmp/keys")" -ge 20 ] || bad "only $(wc -l < "$tmp/keys") keys read from config/trajd.conf"
while read -r k; do
    grep -q "^\\\\fB$(printf %s "$k" | sed 's/\./\\./g')\\\\fR" "$man_dir/trajd.conf.5" ||
        bad "trajd.conf(5) has no entry for key $k"
done < "$tmp/keys"
# trajd.conf(5) is the installed file's page (make install writes exit_when_done = no:
# the page said "yes (as the shipped example sets it)")
MANWIDTH=200 man -l "$man_dir/trajd.conf.5" 2> /dev/null | tr -s ' ' > "$tmp/conf5"
grep -q "As installed (a service): off" "$tmp/conf5" ||
    bad "trajd.conf(5) does not describe exit_when_done as installed (off)"
grep -q "so it is on here" "$tmp/conf5" && bad "trajd.conf(5) describes the repository's example"
[ "$fail" -eq 0 ] && echo "ok: $(echo $pages | wc -w) pages render cleanly, document every --help option and $(wc -l < "$tmp/keys") config keys"
exit "$fail"
