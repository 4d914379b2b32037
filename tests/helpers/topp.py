"""topp.py - the time-optimal traversal of a path under per-axis velocity and acceleration
limits (phase plane: forward and backward passes of the path velocity on a fine grid of its
parameter), the offline reference for trajd's per-axis limits (issue 32), and the paths both
tests/bench/bench_axis.py and tests/oracle/test_axis_limits.py measure it on."""
import numpy as np
from scipy.interpolate import CubicSpline


def topp(qd, qdd, vlim, alim, ds):
    """Least time along a path sampled every ds of its parameter (qd, qdd: first and second
    derivatives per axis), |v_k| <= vlim[k], |a_k| <= alim[k], from rest to rest."""
    sd = topp_rate(qd, qdd, vlim, alim, ds)
    return float(np.sum(2 * ds / (sd[1:] + sd[:-1] + 1e-300)))


def topp_rate(qd, qdd, vlim, alim, ds):
    """topp's profile: the path's parameter rate at each sample."""
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
    return np.sqrt(u)


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


def figure8():
    """x = 20 sin 0.2t, y = 10 sin 0.4t at 10 Hz for 60 s (the issue's)."""
    t = np.arange(0, 60.0001, 0.1)
    return t, 20 * np.sin(0.2 * t), 10 * np.sin(0.4 * t)


def optimal_s(t, x, y, vlim, alim):
    """The least time along the curve trajd streams through these waypoints (scipy's
    CubicSpline with rest ends, knots at the timestamps: the curve to 1e-9 of the track's
    extent, lib/engine/DESIGN.md), parametrised by track time on a 1 ms grid, rest to rest."""
    grid, sd, _ = optimal_profile(t, x, y, vlim, alim)
    return float(np.sum(2 * (grid[1] - grid[0]) / (sd[1:] + sd[:-1] + 1e-300)))


def optimal_profile(t, x, y, vlim, alim):
    """optimal_s's grid of track time, its rate there, and whether that rate is held below
    the speed limits (by the acceleration limits: corners, the start and the end)."""
    cs = CubicSpline(t, np.c_[x, y], bc_type=((1, [0, 0]), (1, [0, 0])))
    grid = np.linspace(t[0], t[-1], int(round((t[-1] - t[0]) / 0.001)) + 1)
    qd = cs(grid, 1)
    sd = topp_rate(qd, cs(grid, 2), vlim, alim, grid[1] - grid[0])
    vcap = np.min([vlim[k] / np.maximum(np.abs(qd[:, k]), 1e-12) for k in range(len(vlim))],
                  axis=0)
    return grid, sd, sd < 0.999 * vcap
