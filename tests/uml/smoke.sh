#!/bin/sh
# Scenario: the kernel passes a classic and an FD frame through vcan0 and
# candump -L logs both (proves the harness before anything of ours runs).
out=$1
. tests/uml/wait.sh
timeout 5 candump -L vcan0 > "$out/smoke.log" & p=$!
wait_rx vcan0 || exit 1
cansend vcan0 123#DEADBEEF
cansend vcan0 456##1112233445566778899AABBCC
wait_lines "$out/smoke.log" 2
kill $p
grep -q ' vcan0 123#DEADBEEF$' "$out/smoke.log" || exit 1
# The kernel adds a flag to an FD frame (##1 is logged as ##5): compare loosely.
grep -q ' vcan0 456##.112233445566778899AABBCC$' "$out/smoke.log" || exit 1
echo "smoke: ok"
