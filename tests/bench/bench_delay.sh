#!/bin/sh
# bench_delay.sh - the play-out delay D stated and measured in one run: D per
# configuration on three synthetic regular tracks (10 Hz, 1 Hz, 200 Hz), and
# the lag over a track of six pieces separated by silences and transfers, and
# the accuracy/latency frontier on a bundled track (tests/bench/bench_delay.py
# says what is measured and how).  Tracks are
# built in a temporary directory; trajreplay's virtual clock makes the
# tables deterministic.  lib/engine/DESIGN.md "The delay measured" shows them
# (tests/e2e/test_doc_counts.py recomputes its table).  Asserts nothing.
#   BUILD  absolute build directory (set by make bench)
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
exec /usr/bin/python3 tests/bench/bench_delay.py "$BUILD/bin/trajreplay"
