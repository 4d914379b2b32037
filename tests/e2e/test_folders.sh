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
# every header a source may name, in sorted order (daemon/ before lib/)
hdrs=$(ls lib/*.h lib/*/*.h daemon/*/*.h 2>/dev/null | LC_ALL=C sort | tr '\n' ' ')
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
    # the folder of each "x.h" included: that of the first of lib/x.h, lib/*/x.h
    # and daemon/*/x.h in sorted order (one awk over the folder's sources: a
    # process for each include took 15 s)
    srcs=$(ls "$d"/*.c "$d"/*.h "$d"/*.cc 2>/dev/null)
    [ -n "$srcs" ] || continue
    out=$(awk -v dirs="$dirs" -v r="$r" -v may="$may" -v hdrs="$hdrs" '
        BEGIN {
            n = split(hdrs, hl, " ")
            for (i = 1; i <= n; i++) {
                b = hl[i]; sub(/.*\//, "", b)
                dd = hl[i]; sub(/[^\/]*$/, "", dd)
                if (!(b in where)) where[b] = dd
            }
            m = split(dirs, al, " ")
            for (i = 1; i <= m; i++) ok[al[i]] = 1
        }
        /^#include "[^"]*"/ {
            h = $0; sub(/^#include "/, "", h); sub(/".*/, "", h)
            if ((h in where) && !(where[h] in ok))
                printf "%s includes %s (%s), which %s does not allow (May include:%s)\n",
                    FILENAME, h, where[h], r, may
        }' $srcs)
    if [ -n "$out" ]; then
        while IFS= read -r l; do bad "$l"; done <<EOT
$out
EOT
    fi
done
[ $fail = 0 ] && echo "folders: $n code folders, each with its README (what, may include, tests), includes within it"
exit $fail
