#!/bin/bash
# No C file in lib/ or daemon/ over 1 000 lines (issue 25).  The files over it
# today are listed in tests/file_size_allow.txt with their line counts; the list
# only shrinks: a listed file may not grow past its count, a file that is back
# under the limit must leave the list, and no new file may join it.
set -u
cd "$(dirname "$0")/../.." || exit 1
LIMIT=1000
allow=tests/file_size_allow.txt
fail=0
declare -A allowed
listed=0 # (an empty associative array is "unbound" to set -u in bash 5.2)
while read -r n f; do
    case "$n" in ''|\#*) continue;; esac
    allowed[$f]=$n
    listed=$((listed + 1))
done < "$allow"
for f in $(git ls-files 'lib/*.c' 'daemon/*.c' 2>/dev/null || find lib daemon -name '*.c'); do
    [ -f "$f" ] || continue
    n=$(wc -l < "$f")
    a=${allowed[$f]:-}
    if [ -z "$a" ]; then
        [ "$n" -gt $LIMIT ] && { echo "FAIL: $f has $n lines (> $LIMIT): split it by stage or concern"; fail=1; }
    elif [ "$n" -gt "$a" ]; then
        echo "FAIL: $f has $n lines, more than the $a it is allowed in $allow (the list only shrinks)"; fail=1
    elif [ "$n" -le $LIMIT ]; then
        echo "FAIL: $f has $n lines, within $LIMIT: remove it from $allow"; fail=1
    elif [ "$n" -lt "$a" ]; then
        echo "note: $f has $n lines, fewer than its $a in $allow: lower it there"
    fi
done
[ "$listed" -gt 0 ] && for f in "${!allowed[@]}"; do
    [ -f "$f" ] || { echo "FAIL: $f is listed in $allow but does not exist: remove it"; fail=1; }
done
[ $fail = 0 ] && echo "file sizes: every C file in lib/ and daemon/ within $LIMIT lines or within its allowance ($listed listed)"
exit $fail
