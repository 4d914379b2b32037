#!/usr/bin/python3
"""bench_axis.py - per-axis limits (issue 32 item 1): how long trajd takes along a path under
per-axis speed and acceleration limits, against the time-optimal traversal of the same path
(phase plane: forward and backward passes of the path velocity on a fine grid of its
parameter, the velocity and acceleration limits of every axis, rest to rest:
tests/helpers/topp.py), and the peak per-axis values against the limits.

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

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from topp import figure8, optimal_profile, rectangle  # noqa: E402

GOAL = 1.25


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


def main():
    exe = sys.argv[1]
    cases = [("figure-8", figure8(), (3.0, 3.0), (0.6, 1.2)),
             ("rectangle", rectangle(), (3.0, 3.0), (1.0, 1.0))]
    print("| path | limits v / a | trajd s | time-optimal s | ratio (goal <= %.2f) | peak |v| "
          "x, y | peak |a| x, y |" % GOAL)
    print("|---|---|---|---|---|---|---|")
    where = []
    with tempfile.TemporaryDirectory() as d:
        for name, (t, x, y), vl, al in cases:
            src = os.path.join(d, name + ".csv")
            write(src, t, x, y)
            lim = os.path.join(d, "lim.csv")
            base = [exe, "-q", "--profile", "machine"]
            subprocess.run(base + ["--rate", "100", "--axis-max-speed", "%g,%g,0" % vl,
                                   "--axis-max-accel", "%g,%g,0" % al, "-o", lim, src],
                           check=True, timeout=600)
            now, ts, p = rows(lim)
            grid, sd, held = optimal_profile(t, x, y, vl, al)
            topt = np.concatenate([[0.0], np.cumsum(2 * (grid[1] - grid[0]) /
                                                    (sd[1:] + sd[:-1] + 1e-300))])
            ref = topt[-1]
            where.append((name, where_time(now, ts, grid, topt, held)))
            dur = now[-1] - now[0]
            dt = np.diff(now)
            v = np.abs(np.diff(p, axis=0) / dt[:, None]).max(axis=0)
            a = np.abs(np.diff(np.diff(p, axis=0) / dt[:, None], axis=0) /
                       (0.5 * (dt[1:] + dt[:-1]))[:, None]).max(axis=0)
            print("| %s | %g,%g / %g,%g | %.1f | %.1f | %.2f | %.3f, %.3f | %.3f, %.3f |" % (
                name, vl[0], vl[1], al[0], al[1], dur, ref, dur / ref, v[0], v[1], a[0], a[1]))
    print("\nWhere the time goes, trajd s / time-optimal s: the first and last 2 s of track (the "
          "start from rest, the end at rest); the rest where the time-optimal rate is held below "
          "the speed limits (corners, turns); where it is at them")
    for name, w in where:
        print("  %s: start and end %.1f / %.1f, corners %.1f / %.1f, at the speed limit "
              "%.1f / %.1f" % ((name,) + w))


def where_time(now, ts, grid, topt, held):
    """trajd's time and the optimum's (topt: its time at each grid point of track time) over
    the first and last 2 s of track, the rest of where the optimum is held below the speed
    limits, and where it is at them."""
    def trajd(a, b):
        return np.interp(b, ts, now) - np.interp(a, ts, now)

    def opt(a, b):
        return np.interp(b, grid, topt) - np.interp(a, grid, topt)

    t0, t1 = grid[0], grid[-1]
    ends = (trajd(t0, t0 + 2) + trajd(t1 - 2, t1), opt(t0, t0 + 2) + opt(t1 - 2, t1))
    out = {True: [0.0, 0.0], False: [0.0, 0.0]}
    cut = np.flatnonzero(np.diff(held.astype(int))) + 1
    for a, b in zip(np.r_[0, cut], np.r_[cut, len(grid) - 1]):
        lo, hi = max(grid[a], t0 + 2), min(grid[b], t1 - 2)
        if hi > lo:
            out[bool(held[a])][0] += trajd(lo, hi)
            out[bool(held[a])][1] += opt(lo, hi)
    return ends + tuple(out[True]) + tuple(out[False])


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
