#!/bin/bash
# The ptrace() wrapper that lets user-mode-linux boot on hosts with a large
# XSAVE area (tests/uml/xstate_preload.c), checked on every host:
#   1. xstate_check sets a traced child's FPU state with a buffer smaller than
#      the host's XSAVE area (832 bytes): plain, the host may refuse it (EFAULT
#      where the CPU has AVX-512 or AMX); through the wrapper it must succeed
#      and the child must see xmm1 as set and its AVX-512 state kept;
#   2. the same with TRAJD_XSTATE_FORCE=1, the full-size path taken on every
#      call, so the path is exercised where the host would not need it;
# and test_can_uml.sh boots its guest forced, so a real kernel runs through it.
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:=$PWD/build}"
check=$BUILD/tests/uml/xstate_check
so=$BUILD/tests/uml/xstate_preload.so
[ -x "$check" ] && [ -f "$so" ] || { echo "FAIL: $check or $so not built (make all)"; exit 1; }
log=$(mktemp); trap 'rm -f "$log"' EXIT
fail=0

"$check"; plain=$?
case $plain in
    0) echo "host: accepts UML's smaller XSTATE buffer (the wrapper only needed where it refuses)";;
    3) echo "host: refuses UML's smaller XSTATE buffer with EFAULT (the wrapper is needed here)";;
    *) echo "FAIL: xstate_check itself failed ($plain)"; exit 1;;
esac

LD_PRELOAD=$so TRAJD_XSTATE_LOG=$log "$check" || { echo "FAIL: through the wrapper"; fail=1; }
if [ $plain = 3 ]; then
    grep -q '^xstate: full-size SETREGSET 832 of [0-9]* bytes: ok$' "$log" ||
        { echo "FAIL: the wrapper did not retry with the full size: $(cat "$log")"; fail=1; }
fi
: > "$log"
LD_PRELOAD=$so TRAJD_XSTATE_FORCE=1 TRAJD_XSTATE_LOG=$log "$check" || { echo "FAIL: forced"; fail=1; }
grep -q '^xstate: full-size SETREGSET 832 of [0-9]* bytes (forced): ok$' "$log" ||
    { echo "FAIL: forced, the full-size path was not taken: $(cat "$log")"; fail=1; }
cat "$log"
[ $fail = 0 ] && echo "test_uml_xstate: ok"
exit $fail
