#!/bin/sh
# Modbus load benchmark: see tests/bench_mbsrv_load.py (prints a table).
exec "${PYTHON:-/usr/bin/python3}" "$(dirname "$0")/bench_mbsrv_load.py"
