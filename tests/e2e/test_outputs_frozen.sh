#!/bin/bash
# test_outputs_frozen.sh - trajreplay's setpoint CSV for every track in
# tests/data, every method and every parameterisation, is byte-identical to
# the checksums in tests/data/outputs.sha256.
#
# The list was generated before the source tree was restructured, so a
# structural change that alters a single bit of output fails here.  trajd's
# replay is byte-identical to trajreplay (test_daemon.py compares the two row
# by row), so this covers the daemon's output too (but for the hold rows
# trajd streams through gaps longer than max_gap_s, which trajreplay skips
# unless --keep-gaps).
#
# A change that is *meant* to alter output regenerates the list with
#     bash tests/e2e/test_outputs_frozen.sh --update
# and says why in its commit message.
set -eu
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build}
TR="$BUILD/bin/trajreplay"
LIST=tests/data/outputs.sha256
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT

for track in tests/data/*.csv tests/data/*.gpx tests/data/*.path; do
    [ -f "$track" ] || continue
    for method in bspline cubic smooth; do
        for param in uniform time; do
            name="$(basename "$track").$method.$param.csv"
            "$TR" -q --method "$method" --param "$param" --object frozen \
                -o "$tmp/$name" "$track" 2> "$tmp/$name.err" || {
                echo "trajreplay failed on $track $method $param:"; cat "$tmp/$name.err"; exit 1; }
        done
    done
done
(cd "$tmp" && sha256sum -- *.csv) > "$tmp/now.sha256"
if [ "${1:-}" = --update ]; then
    cp "$tmp/now.sha256" "$LIST"; echo "wrote $LIST ($(wc -l < "$LIST") outputs)"; exit 0
fi
if ! diff -u "$LIST" "$tmp/now.sha256"; then
    echo "FAIL: outputs differ from $LIST (lines above: - stored, + now)"; exit 1
fi
# A list that compares nothing cannot fail: make sure it covered every case.
n=$(wc -l < "$LIST")
[ "$n" -ge 30 ] || { echo "FAIL: only $n outputs in $LIST"; exit 1; }
echo "1 passed, 0 failed: $n outputs byte-identical to $LIST"
