#!/bin/sh
# bench_axis.sh - per-axis limits against the time-optimal traversal of the same path
# (tests/bench/bench_axis.py says how); asserts nothing.
#   BUILD  absolute build directory (set by make bench)
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
exec /usr/bin/python3 tests/bench/bench_axis.py "$BUILD/bin/trajreplay"
