#!/bin/sh
# Modbus load benchmark: see tests/bench/bench_modbus_server_load.py (prints a table).
exec "${PYTHON:-/usr/bin/python3}" "$(dirname "$0")/bench_modbus_server_load.py"
