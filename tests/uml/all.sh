#!/bin/sh
# Runs every guest scenario in one boot; each prints its own PASS/FAIL line.
# Exit code = number of failed scenarios (0 = all passed).
out=$1
failed=0
for s in smoke daemon canerr; do
    if sh "tests/uml/$s.sh" "$out" > "$out/$s.out" 2>&1; then
        echo "PASS uml/$s"
    else
        echo "FAIL uml/$s (exit $?):"; sed 's/^/    /' "$out/$s.out"; failed=$((failed + 1))
    fi
done
exit $failed
