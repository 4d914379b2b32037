#!/usr/bin/python3
"""test_safety_accel_cap.py - a configured safety_max_accel_m_s2 is kept by the engine, not
only judged by the monitor (engine.h cap_accel_m_s2, daemon/core/cfg.h CFG_SAFETY_SPEED_SHARE).

trajd replays a circle of 20 m radius at 4 m/s (10 Hz, 40 s; 0.8 m/s^2 towards the centre),
reached by a transfer of 8 m from its initial position, for an object whose
safety_max_accel_m_s2 is 1.5: below the time scaling's own 5 m/s^2 and the acceleration
the rest ends of the curve ask.  The engine keeps the bound along the path (the start and
the end ramp, the curve's own acceleration, the transfer), so the monitor never holds it.
Wanted:
  - exit 0, no setpoint held by the monitor (ENGINE_SP_FAULT), the run reaches the last
    waypoint at rest;
  - every row-to-row acceleration (second differences of the positions, as the monitor
    judges them) within the bound;
  - every streamed row on the curve through every waypoint: scipy's CubicSpline with zero
    end velocities (ends = rest) at the row's t_s, within 1e-4 m.
Before, the engine planned the start's ramp at 5 m/s^2 and the monitor held the object on
its first row above 1.5 m/s^2 (a step to rest), until clear: exit 75.
Run with Debian's /usr/bin/python3; BUILD is the build directory.
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.interpolate import CubicSpline

BUILD = os.environ.get("BUILD", "build")
TRAJD = os.path.join(BUILD, "bin", "trajd")
BOUND = 1.5
FAILED = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILED.append(what)


def main():
    t = np.arange(401) * 0.1
    x, y = 20 * np.cos(0.2 * t), 20 * np.sin(0.2 * t)
    with tempfile.TemporaryDirectory() as tmp:
        track = os.path.join(tmp, "circle.csv")
        with open(track, "w") as f:
            f.write("t,x,y,z\n")
            for k in range(len(t)):
                f.write("%r,%r,%r,0\n" % (t[k], x[k], y[k]))
        out = os.path.join(tmp, "a.csv")
        conf = os.path.join(tmp, "trajd.conf")
        with open(conf, "w") as f:
            f.write("[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                    "status_interval_s = 0\n[object.a]\ninput = replay\nreplay.track = %s\n"
                    "output = csv\ncsv.path = %s\nsafety_max_accel_m_s2 = %g\n"
                    "initial_position = 28,0,0\n" % (track, out, BOUND))
        p = subprocess.run([TRAJD, "-f", "-c", conf], capture_output=True, text=True,
                           timeout=300)
        with open(out) as f:
            rows = [r for r in csv.DictReader(f) if not r["object"].startswith("#")]
    flags = np.array([int(r["flags"]) for r in rows])
    check(p.returncode == 0 and not (flags & 0x20).any(),
          "trajd: exit %d, %d setpoints held by the safety monitor"
          % (p.returncode, int((flags & 0x20).astype(bool).sum())))
    check(rows[-1]["state"] == "finished"
          and math.hypot(float(rows[-1]["x_m"]) - x[-1], float(rows[-1]["y_m"]) - y[-1]) < 1e-6,
          "ends at rest on the last waypoint (%s at %s, %s)"
          % (rows[-1]["state"], rows[-1]["x_m"], rows[-1]["y_m"]))
    check(((flags & 0x08) != 0).any(), "the track is reached by a transfer")
    now = np.array([int(r["now_ns"]) * 1e-9 for r in rows])
    pos = np.array([[float(r["x_m"]), float(r["y_m"])] for r in rows])
    ok = np.isfinite(pos).all(axis=1)
    regular = ok[2:] & ok[1:-1] & ok[:-2] & (np.abs(np.diff(now)[1:] - 0.01) < 1e-9) \
        & (np.abs(np.diff(now)[:-1] - 0.01) < 1e-9)
    acc = np.hypot(*(pos[2:] - 2 * pos[1:-1] + pos[:-2]).T) / 0.01 ** 2
    acc = acc[regular]
    check(acc.max() <= BOUND, "row-to-row acceleration at most %.4f m/s^2, bound %g"
          % (acc.max(), BOUND))
    ref = CubicSpline(t, np.c_[x, y], bc_type="clamped")
    st = np.array([r["state"] == "streaming" and not int(r["flags"]) & 8 for r in rows])
    ts = np.array([float(r["t_s"]) for r in rows])
    dev = np.hypot(*(pos[st] - ref(ts[st])).T)
    check(st.sum() > 1000 and dev.max() < 1e-4,
          "%d streamed rows on scipy's spline through every waypoint, worst %.2e m"
          % (st.sum(), dev.max()))


if __name__ == "__main__":
    main()
    sys.exit(1 if FAILED else 0)
