#!/bin/bash
# test_mbmap_readme.sh - the register tables in config/PROTOCOL.md ("## Modbus",
# between the mbmap markers) are exactly what lib/proto/mbmap.c's field table
# generates (test_mbmap --markdown), so the documentation cannot drift from
# the single source.  To regenerate after changing the map:
#     build/tests/test_mbmap --markdown   (paste between the markers)
set -u
BUILD=${BUILD:?}
cd "$(dirname "$0")/../.." || exit 1
want=$("$BUILD/tests/test_mbmap" --markdown) || { echo "test_mbmap --markdown failed"; exit 1; }
have=$(sed -n '/^<!-- mbmap:begin/,/^<!-- mbmap:end/p' config/PROTOCOL.md | sed '1d;$d')
[ -n "$have" ] || { echo "config/PROTOCOL.md has no <!-- mbmap:begin --> ... <!-- mbmap:end --> block"; exit 1; }
if [ "$want" != "$have" ]; then
    echo "config/PROTOCOL.md register tables differ from lib/proto/mbmap.c (- PROTOCOL.md, + generated):"
    diff <(printf '%s\n' "$have") <(printf '%s\n' "$want")
    exit 1
fi
echo "PROTOCOL.md register tables match lib/proto/mbmap.c ($(printf '%s\n' "$want" | grep -c '^| [0-9]') fields)"
