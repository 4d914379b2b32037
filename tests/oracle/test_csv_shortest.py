"""test_csv_shortest.py - the default number form of the setpoint CSV
(daemon/csv/csv_shortest.h) against Python's repr(), an independent
shortest round-trip formatter (David Gay's dtoa in CPython):

  1. csv_shortest() of 500 000 random bit patterns, 300 000 values in the
     ranges setpoints take, short decimals, and every power of two, through
     test_csv_shortest --print: byte for byte repr(x) (NaN as 'nan');
  2. every number field of trajreplay's default CSV on two real tracks is
     repr(float(field)) and reads back to the --binary record's double.

Run with /usr/bin/python3 (Debian numpy).
"""
import math
import os
import random
import struct
import subprocess
import sys
import tempfile

import numpy as np

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
PRINTER = os.path.join(BUILD, "tests", "test_csv_shortest")
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")
DTYPE = np.dtype([("now_ns", "<i8"), ("t_s", "<f8"), ("pos_m", "<f8", 3), ("vel_m_s", "<f8", 3),
                  ("acc_m_s2", "<f8", 3), ("state", "<u4"), ("flags", "<u4"), ("cycle", "<u4"),
                  ("track", "<u4"), ("reserved", "<u8")])
failures = 0


def check(cond, what):
    global failures
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures += 1


def bits(x):
    return struct.unpack("<Q", struct.pack("<d", x))[0]


def values():
    rnd = random.Random(13)
    v = []
    for _ in range(500000):
        x = struct.unpack("<d", struct.pack("<Q", rnd.getrandbits(64)))[0]
        v.append(x)
    for _ in range(300000):
        v.append(rnd.uniform(-0.5, 0.5) * 2.0 ** rnd.randint(-30, 30))
    for _ in range(100000):
        v.append(rnd.randint(-10**7, 10**7) / 10 ** rnd.randint(0, 9))
    v += [2.0 ** e for e in range(-1074, 1024)] + [-(2.0 ** e) for e in range(-1074, 1024)]
    v += [10.0 ** e for e in range(-323, 309)] + [0.0, -0.0, math.inf, -math.inf, math.nan]
    v += [1e15, 1e16, 9.999999999999999e15, 0.0001, 0.00009999999999999999, 1e-5]
    return v


def main():
    v = values()
    inp = "".join("%016x\n" % bits(x) for x in v)
    r = subprocess.run([PRINTER, "--print"], input=inp, capture_output=True, text=True)
    got = r.stdout.split("\n")[:-1]
    check(r.returncode == 0 and len(got) == len(v), "printer answered %d of %d" % (len(got), len(v)))
    bad = [(x, g) for x, g in zip(v, got) if g != ("nan" if math.isnan(x) else repr(x))]
    for x, g in bad[:10]:
        print("   %r: got %r" % (x, g))
    check(not bad, "%d values: csv_shortest == repr (%d differ)" % (len(v), len(bad)))

    with tempfile.TemporaryDirectory() as tmp:
        for track in ("n2k_furuno_figure8_src52.csv", "gpxgo_visnjan.csv"):
            path = os.path.join(DATA, track)
            csv, binf = os.path.join(tmp, "a.csv"), os.path.join(tmp, "a.bin")
            for args, out in (([], csv), (["--binary"], binf)):
                r = subprocess.run([TRAJREPLAY, "-q", "--rate", "10"] + args + ["-o", out, path],
                                   capture_output=True)
                check(r.returncode == 0, "%s %s exit %d" % (track, args, r.returncode))
            rows = np.fromfile(binf, dtype=DTYPE, offset=64)
            with open(csv) as f:
                lines = f.read().splitlines()[1:]
            check(len(lines) == len(rows) and len(rows) > 1000, "%s: %d rows" % (track, len(rows)))
            nbad = nfields = 0
            for line, rec in zip(lines, rows):
                fields = line.split(",")[2:12]
                want = [rec["t_s"]] + list(rec["pos_m"]) + list(rec["vel_m_s"]) + list(rec["acc_m_s2"])
                for s, w in zip(fields, want):
                    nfields += 1
                    x = float(s)
                    same = (math.isnan(x) and math.isnan(w)) or bits(x) == bits(float(w))
                    form = s == ("nan" if math.isnan(x) else repr(x))
                    if not (same and form):
                        nbad += 1
                        if nbad <= 5:
                            print("   %s: field %r, binary %r" % (track, s, float(w)))
            check(nbad == 0, "%s: %d fields are repr(float(field)) and the binary's double"
                  % (track, nfields))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
