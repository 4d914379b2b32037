#!/bin/sh
# cppcheck finds nothing in lib/, daemon/ and the C tests: `make lint` (the
# Makefile says which checks and why; a false positive is suppressed on its
# line with the reason).  Here so that tests/run.sh, and so make check, run it.
set -eu
cd "$(dirname "$0")/../.."
if ! command -v cppcheck > /dev/null; then
    echo "FAIL: cppcheck is not installed (make check installs it with DEPS_TEST)"
    exit 1
fi
exec make -s --no-print-directory lint BUILD="${BUILD:-build}"
