#!/usr/bin/python3
"""moving.py - wait until the object's drives move at a given speed, judged
from the bus: the targets of the RPDOs 0x201..0x203 (controlword u16, target
i32) in the last SYNC intervals of a growing candump -L log.  A scenario of
tests/uml/drive_events.sh uses it to fire each event mid-motion.

Usage: moving.py LOG COUNTS_PER_M PERIOD_S VMIN_M_S TIMEOUT_S
Exits 0 once the speed over the last 4 cycles is >= VMIN, 1 at the timeout.
"""
import os
import sys
import time


def speed(path, cpm, period):
    with open(path, "rb") as f:
        f.seek(max(0, os.path.getsize(path) - 16000))
        lines = f.read().decode(errors="replace").splitlines()[1:]
    tgt = {}      # node -> targets, one per SYNC
    for line in lines:
        w = line.split()
        if len(w) != 3 or "#" not in w[2]:
            continue
        cid, data = w[2].split("#")
        cid = int(cid, 16)
        if cid == 0x080:
            for v in tgt.values():
                v.append(v[-1] if v else None)
        elif 0x201 <= cid <= 0x203 and len(data) == 12:
            b = bytes.fromhex(data)
            v = tgt.setdefault(cid, [None])
            v[-1] = int.from_bytes(b[2:6], "little", signed=True)
    if len(tgt) < 3:
        return 0.0
    d2 = 0.0
    for v in tgt.values():
        v = [x for x in v if x is not None][-6:-1]   # complete cycles only
        if len(v) < 5:
            return 0.0
        d2 += ((v[-1] - v[0]) / cpm) ** 2
    return d2 ** 0.5 / (4 * period)


def main():
    path, cpm, period, vmin, tmo = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), \
        float(sys.argv[4]), float(sys.argv[5])
    end = time.monotonic() + tmo
    v = 0.0
    while time.monotonic() < end:
        v = speed(path, cpm, period)
        if v >= vmin:
            print("moving at %.3f m/s" % v)
            return 0
        time.sleep(0.05)
    print("not moving at %g m/s within %g s (last %.3f)" % (vmin, tmo, v), file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
