"""cap_circle.py - what tests/oracle/test_safety_speed_cap.py and
test_safety_accel_cap.py share: a circle of 20 m radius at 4 m/s (10 Hz, 40 s)
replayed by the real trajd for an object with a safety bound (the keys given),
its CSV rows read back, and the checks printed as "ok" or "FAIL" lines."""
import csv
import math
import os
import subprocess
import tempfile

import numpy as np
from scipy.interpolate import CubicSpline

BUILD = os.environ.get("BUILD", "build")
TRAJD = os.path.join(BUILD, "bin", "trajd")
FAILED = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILED.append(what)


def circle():
    """(t, x, y) of the track."""
    t = np.arange(401) * 0.1
    return t, 20 * np.cos(0.2 * t), 20 * np.sin(0.2 * t)


def run(keys):
    """trajd on the circle with the object keys given: (completed process, rows)."""
    t, x, y = circle()
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
                    "output = csv\ncsv.path = %s\n%s" % (track, out, keys))
        p = subprocess.run([TRAJD, "-f", "-c", conf], capture_output=True, text=True,
                           timeout=300)
        with open(out) as f:
            rows = [r for r in csv.DictReader(f) if not r["object"].startswith("#")]
    return p, rows


def check_common(p, rows):
    """Exit 0, nothing held, at rest on the last waypoint at the end, and every
    streamed row on scipy's CubicSpline (ends = rest) through every waypoint at
    its t_s within 1e-4 m.  Returns (now, pos, streamed mask)."""
    t, x, y = circle()
    flags = np.array([int(r["flags"]) for r in rows])
    check(p.returncode == 0 and not (flags & 0x20).any(),
          "trajd: exit %d, %d setpoints held by the safety monitor"
          % (p.returncode, int((flags & 0x20).astype(bool).sum())))
    check(rows[-1]["state"] == "finished"
          and math.hypot(float(rows[-1]["x_m"]) - x[-1], float(rows[-1]["y_m"]) - y[-1]) < 1e-6,
          "ends at rest on the last waypoint (%s at %s, %s)"
          % (rows[-1]["state"], rows[-1]["x_m"], rows[-1]["y_m"]))
    now = np.array([int(r["now_ns"]) * 1e-9 for r in rows])
    pos = np.array([[float(r["x_m"]), float(r["y_m"])] for r in rows])
    ref = CubicSpline(t, np.c_[x, y], bc_type="clamped")
    st = np.array([r["state"] == "streaming" and not int(r["flags"]) & 8 for r in rows])
    ts = np.array([float(r["t_s"]) for r in rows])
    dev = np.hypot(*(pos[st] - ref(ts[st])).T)
    check(st.sum() > 1000 and dev.max() < 1e-4,
          "%d streamed rows on scipy's spline through every waypoint, worst %.2e m"
          % (st.sum(), dev.max()))
    return now, pos, st
