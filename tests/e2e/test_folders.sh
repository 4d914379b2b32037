#!/bin/bash
# Every code folder of lib/ and daemon/ has a README.md of at most 40 lines
# saying what lives there, what it may include ("May include:") and where its
# tests are ("Tests:"); and every #include "x.h" of the folder's sources names
# a header of the folder itself or of a folder its README allows (issue 25).
# The long READMEs not yet split are listed in tests/folder_readme_allow.txt,
# a list that only shrinks.
set -u
cd "$(dirname "$0")/../.." || exit 1
fail=0
bad() { echo "FAIL: $*"; fail=1; }
allow=$(grep -v '^#' tests/folder_readme_allow.txt 2>/dev/null)
n=0
for d in $(find lib daemon -name '*.[ch]' -o -name '*.cc' | xargs -n1 dirname | sort -u); do
    n=$((n + 1))
    r=$d/README.md
    [ -f "$r" ] || { bad "$d has no README.md"; continue; }
    lines=$(wc -l < "$r")
    if [ "$lines" -gt 40 ]; then
        echo "$allow" | grep -qx "$d" || bad "$r has $lines lines (at most 40)"
    elif echo "$allow" | grep -qx "$d"; then
        bad "$r is within 40 lines: remove $d from tests/folder_readme_allow.txt"
    fi
    grep -q '^Tests: ' "$r" || bad "$r has no 'Tests:' line"
    may=$(sed -n '/^May include:/,/^Tests:/p' "$r" | sed '$d' | sed 's/^May include://' | tr ',' ' ')
    [ -n "$(sed -n '/^May include:/p' "$r")" ] || { bad "$r has no 'May include:' line"; continue; }
    dirs="$d/"
    for w in $may; do case "$w" in lib/*|daemon/*) dirs="$dirs ${w%/}/";; esac; done
    for f in "$d"/*.c "$d"/*.h "$d"/*.cc; do
        [ -f "$f" ] || continue
        for h in $(sed -n 's/^#include "\([^"]*\)".*/\1/p' "$f"); do
            where=$(ls lib/"$h" lib/*/"$h" daemon/*/"$h" 2>/dev/null | head -1)
            [ -n "$where" ] || continue
            hd="$(dirname "$where")/"
            ok=0
            for a in $dirs; do [ "$hd" = "$a" ] && ok=1; done
            [ $ok = 1 ] || bad "$f includes $h ($hd), which $r does not allow (May include:$may)"
        done
    done
done
[ $fail = 0 ] && echo "folders: $n code folders, each with its README (what, may include, tests), includes within it"
exit $fail
