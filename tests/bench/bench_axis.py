#!/usr/bin/python3
"""bench_axis.py - per-axis limits (issue 32 item 1): how long trajd takes along a path under
per-axis speed and acceleration limits, against the time-optimal traversal of the same path
(phase plane: forward and backward passes of the path velocity on a fine grid of its
parameter, the velocity and acceleration limits of every axis, rest to rest), and the peak
per-axis values against the limits.

Two paths, 10 Hz waypoints: the figure-8 x = 20 sin 0.2t, y = 10 sin 0.4t (60 s) with
axis_max_speed_m_s = 3,3,3 and axis_max_accel_m_s2 = 0.6,1.2,1; and a corner-rich one, a
rectangle 40 m x 20 m with corners of 2 m radius at 4 m/s, with limits 3,3 and 1,1. The
reference path is scipy's CubicSpline through the same waypoints with rest ends (knots at the
timestamps: the curve trajd streams, to 1e-9 of the track's extent, lib/engine/DESIGN.md),
parametrised by track time on a 1 ms grid. Prints a markdown table; asserts nothing.
  usage: bench_axis.py TRAJREPLAY
"""
import csv
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.interpolate import CubicSpline

GOAL = 1.25


def topp(qd, qdd, vlim, alim, ds):
    """Least time along a path sampled every ds of its parameter (qd, qdd: first and second
    derivatives per axis), |v_k| <= vlim[k], |a_k| <= alim[k], from rest to rest."""
    n, m = qd.shape

    def acc_range(i, u):
        lo, hi = -np.inf, np.inf
        for k in range(m):
            d1, d2, a = qd[i, k], qdd[i, k], alim[k]
            if abs(d1) < 1e-12:
                if abs(d2) * u > a:
                    return 1.0, -1.0
                continue
            lk, hk = (-a - d2 * u) / d1, (a - d2 * u) / d1
            if d1 < 0:
                lk, hk = hk, lk
            lo, hi = max(lo, lk), min(hi, hk)
        return lo, hi

    mvc = np.empty(n)
    for i in range(n):
        u = min([(vlim[k] / abs(qd[i, k])) ** 2 for k in range(m) if abs(qd[i, k]) > 1e-12]
                + [1e6])
        lo, hi = 0.0, u
        if acc_range(i, hi)[0] <= acc_range(i, hi)[1]:
            mvc[i] = hi
            continue
        for _ in range(50):
            mid = 0.5 * (lo + hi)
            a, b = acc_range(i, mid)
            lo, hi = (mid, hi) if a <= b else (lo, mid)
        mvc[i] = lo
    u = np.zeros(n)
    for i in range(n - 1):
        u[i + 1] = min(mvc[i + 1], max(u[i] + 2 * ds * acc_range(i, u[i])[1], 0.0))
    u[-1] = 0.0
    for i in range(n - 1, 0, -1):
        u[i - 1] = min(u[i - 1], max(u[i] - 2 * ds * acc_range(i, u[i])[0], 0.0))
    sd = np.sqrt(u)
    return float(np.sum(2 * ds / (sd[1:] + sd[:-1] + 1e-300)))


def rows(path):
    with open(path) as f:
        r = [x for x in csv.DictReader(f) if x["state"] in ("streaming", "finished")
             and not int(x["flags"]) & 0x08]
    return (np.array([int(x["now_ns"]) * 1e-9 for x in r]), np.array([float(x["t_s"]) for x in r]),
            np.array([[float(x["x_m"]), float(x["y_m"])] for x in r]))


def write(path, t, x, y):
    with open(path, "w") as f:
        f.write("t,x,y,z\n")
        for a, b, c in zip(t, x, y):
            f.write("%r,%r,%r,0\n" % (a, b, c))


def rectangle():
    """A 40 x 20 m rectangle with 2 m corner radii at 4 m/s, sampled every 0.1 s."""
    w, h, r, v = 40.0, 20.0, 2.0, 4.0
    pieces, per = [], (w - 2 * r, h - 2 * r)
    length = 2 * sum(per) + 2 * np.pi * r
    s = np.arange(0, length, v * 0.1)
    out = []
    for d in s:
        # walk the perimeter: straight, quarter circle, ...
        x, y, left, ang = r, 0.0, d, 0.0
        for side in range(4):
            run = per[side % 2]
            if left <= run:
                x, y = x + left * np.cos(ang), y + left * np.sin(ang)
                break
            x, y, left = x + run * np.cos(ang), y + run * np.sin(ang), left - run
            arc = 0.5 * np.pi * r
            cx, cy = x - r * np.sin(ang), y + r * np.cos(ang)
            if left <= arc:
                a = ang + left / r
                x, y = cx + r * np.sin(a), cy - r * np.cos(a)
                break
            ang += 0.5 * np.pi
            x, y, left = cx + r * np.sin(ang), cy - r * np.cos(ang), left - arc
        out.append((x, y))
    del pieces
    p = np.array(out)
    return 0.1 * np.arange(len(p)), p[:, 0], p[:, 1]


def main():
    exe = sys.argv[1]
    t8 = np.arange(0, 60.0001, 0.1)
    cases = [("figure-8", (t8, 20 * np.sin(0.2 * t8), 10 * np.sin(0.4 * t8)),
              (3.0, 3.0), (0.6, 1.2)),
             ("rectangle", rectangle(), (3.0, 3.0), (1.0, 1.0))]
    print("| path | limits v / a | trajd s | time-optimal s | ratio (goal <= %.2f) | peak |v| "
          "x, y | peak |a| x, y |" % GOAL)
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for name, (t, x, y), vl, al in cases:
            src = os.path.join(d, name + ".csv")
            write(src, t, x, y)
            lim = os.path.join(d, "lim.csv")
            base = [exe, "-q", "--profile", "machine"]
            subprocess.run(base + ["--rate", "100", "--axis-max-speed", "%g,%g,0" % vl,
                                   "--axis-max-accel", "%g,%g,0" % al, "-o", lim, src],
                           check=True, timeout=600)
            now, _, p = rows(lim)
            cs = CubicSpline(t, np.c_[x, y], bc_type=((1, [0, 0]), (1, [0, 0])))
            grid = np.linspace(t[0], t[-1], int(round((t[-1] - t[0]) / 0.001)) + 1)
            ref = topp(cs(grid, 1), cs(grid, 2), vl, al, grid[1] - grid[0])
            dur = now[-1] - now[0]
            dt = np.diff(now)
            v = np.abs(np.diff(p, axis=0) / dt[:, None]).max(axis=0)
            a = np.abs(np.diff(np.diff(p, axis=0) / dt[:, None], axis=0) /
                       (0.5 * (dt[1:] + dt[:-1]))[:, None]).max(axis=0)
            print("| %s | %g,%g / %g,%g | %.1f | %.1f | %.2f | %.3f, %.3f | %.3f, %.3f |" % (
                name, vl[0], vl[1], al[0], al[1], dur, ref, dur / ref, v[0], v[1], a[0], a[1]))


def cost(exe):
    """trajreplay's CPU time on an hour of the figure-8 (36 000 waypoints, 10 Hz) with the
    per-axis limits, which cap every segment, against the same run without them: the speed
    cap's look ahead stops at the nearest segment that binds (engine_scale.c
    scale_ceil_room), instead of every capped segment queued at every tick."""
    t = np.arange(0, 3600.0001, 0.1)
    out = []
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "f8.csv")
        write(src, t, 20 * np.sin(0.2 * t), 10 * np.sin(0.4 * t))
        for extra in ([], ["--axis-max-speed", "3,3,0", "--axis-max-accel", "0.6,1.2,0"]):
            best = float("inf")
            for _ in range(3):
                r0 = os.times()
                subprocess.run([exe, "-q", "--binary", "--profile", "machine", "--rate", "100",
                                "-o", os.path.join(d, "o.bin")] + extra + [src], check=True,
                               timeout=600, stderr=subprocess.DEVNULL)
                r1 = os.times()
                best = min(best, (r1.children_user - r0.children_user) +
                           (r1.children_system - r0.children_system))
            out.append(best)
    print("\nCPU of an hour of the figure-8 at 100 Hz (best of 3): %.2f s without the limits, "
          "%.2f s with them (%.2fx)" % (out[0], out[1], out[1] / out[0]))


if __name__ == "__main__":
    main()
    cost(sys.argv[1])
