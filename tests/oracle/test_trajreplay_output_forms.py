"""test_trajreplay_output_forms.py - trajreplay --precision N and --binary
against the default CSV (the shortest round-trip form, which reads back to every double).

References: Python's own "%.*f" formatting (correctly rounded, independent of
our formatter) of the default CSV's numbers, and numpy.fromfile reading the
binary layout documented in daemon/csv/csv_format.h.
Run with /usr/bin/python3 (Debian numpy).
"""
import ast
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
TRACKS = [os.path.join(DATA, "n2k_furuno_figure8_src52.csv"), os.path.join(DATA, "gpxgo_visnjan.csv")]
STATES = {"waiting": 0, "streaming": 1, "underrun": 2, "finished": 3}
# The record layout as trajreplay(1) "BINARY FORMAT" gives it to a user: its
# np.dtype line, taken from the man page's source (and the same in
# lib/format/spfile.h's comment), so the documented reader is what is tested.
MAN = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "daemon", "doc", "trajreplay.1")
SPFILE_H = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "format", "spfile.h")


def documented_dtype(path):
    text = open(path).read()
    m = re.search(r"np\.dtype\((\[.*?\])\)", text.replace("\n *  ", " ").replace("\n *", " "), re.S)
    return np.dtype(ast.literal_eval(m.group(1))) if m else None


DTYPE = documented_dtype(MAN)

failures = 0


def check(cond, what):
    global failures
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures += 1


def replay(args, path):
    # 10 Hz: enough rows (~20 000 on visnjan) to cover every kind, in seconds
    r = subprocess.run([TRAJREPLAY, "-q", "--rate", "10"] + args + ["-o", path], capture_output=True)
    if r.returncode != 0:
        print(r.stderr.decode())
    return r.returncode


with tempfile.TemporaryDirectory() as tmp:
    for track in TRACKS:
        name = os.path.basename(track)
        base = os.path.join(tmp, "default.csv")
        check(replay([track], base) == 0, f"{name}: default CSV")
        with open(base) as f:
            header = f.readline()
            rows = [l.rstrip("\n").split(",") for l in f]
        check(len(rows) > 3000, f"{name}: {len(rows)} rows")
        # a zero is written 0.0, never -0.0 (the engine's setpoints carry +0.0: make run
        # showed -0.0 for velocities at rest)
        negzero = sum(1 for r in rows for v in r[2:12] if v == "-0.0")
        check(negzero == 0, f"{name}: no '-0.0' field ({negzero})")

        # --precision N: every number is Python's "%.Nf" of the default's double.
        for prec in (0, 3, 9, 17):
            out = os.path.join(tmp, f"p{prec}.csv")
            check(replay(["--precision", str(prec), track], out) == 0, f"{name}: --precision {prec}")
            with open(out) as f:
                h = f.readline()
                got = [l.rstrip("\n").split(",") for l in f]
            bad = sum(1 for a, b in zip(rows, got)
                      if b != a[:2] + ["%.*f" % (prec, float(v)) for v in a[2:12]] + a[12:])
            check(h == header and len(got) == len(rows) and bad == 0,
                  f"{name}: --precision {prec}: {len(got)} rows, {bad} differ from Python's %.{prec}f")

        # --binary: numpy.fromfile with the documented layout gives the same doubles.
        check(DTYPE is not None and documented_dtype(SPFILE_H) == DTYPE,
              "trajreplay(1) and spfile.h give one numpy dtype")
        out = os.path.join(tmp, "sp.bin")
        check(replay(["--binary", "--object", "boat", track], out) == 0, f"{name}: --binary")
        raw = open(out, "rb").read(64)
        check(raw[:8] == b"TRAJDSP1" and int.from_bytes(raw[8:12], "little") == 64
              and int.from_bytes(raw[12:16], "little") == 112 and raw[16:21] == b"boat\0",
              f"{name}: binary header (magic, sizes, object)")
        check((os.path.getsize(out) - 64) % DTYPE.itemsize == 0 and DTYPE.itemsize == 112,
              f"{name}: whole 112-byte records")
        rec = np.fromfile(out, dtype=DTYPE, offset=64)
        check(len(rec) == len(rows), f"{name}: {len(rec)} records, {len(rows)} CSV rows")
        want = np.array([[float(v) for v in r[2:12]] for r in rows])
        got = np.column_stack([rec["t_s"], rec["pos_m"], rec["vel_m_s"], rec["acc_m_s2"]])
        # (NaN positions, flagged NO_POSITION, before the first waypoint is confirmed)
        check(np.array_equal(want, got, equal_nan=True), f"{name}: binary doubles equal the CSV's bit for bit")
        check(np.array_equal(rec["now_ns"], [int(r[1]) for r in rows])
              and np.array_equal(rec["state"], [STATES[r[12]] for r in rows])
              and np.array_equal(rec["flags"], [int(r[13]) for r in rows])
              and np.array_equal(rec["cycle"], [int(r[14]) for r in rows])
              and np.array_equal(rec["track"], [int(r[15]) for r in rows])
              and not rec["reserved"].any(), f"{name}: binary integers equal the CSV's")

    # bad values refused
    for bad in ("18", "-1", "x"):
        r = subprocess.run([TRAJREPLAY, "-q", "--precision", bad, TRACKS[0]], capture_output=True)
        check(r.returncode == 2 and b"--precision" in r.stderr, f"--precision {bad}: exit 2")

print(f"{'FAILED' if failures else 'passed'}: {failures} failure(s)")
sys.exit(1 if failures else 0)
