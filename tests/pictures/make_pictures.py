#!/usr/bin/python3
"""Draw the README pictures of the spline toolkit as SVG (no plotting library).

    make && BUILD=$PWD/build /usr/bin/python3 tests/pictures/make_pictures.py

Every curve is computed by build/libtrajd.so (ctypes) or build/bin/trajsurf;
this script only projects and draws.  It also prints the numbers quoted in
lib/spline/TOOLKIT.md (the least-squares jitter experiment).
"""
import ctypes as C
import math
import os
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "helpers"))
from toolkit_ctypes import (BUILD, Bspline, Cspline, Nurbs, PathElem, Waypoint,  # noqa: E402,F401
                            dp, lib, ptr)

COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf"]


class Svg:
    """Curves in data coordinates, fitted into a W x H box, y up, with a legend."""

    def __init__(self, title, w=720, h=480):
        self.title, self.w, self.h, self.items = title, w, h, []

    def line(self, pts, colour, width=1.6, label=None, dash=None):
        self.items.append(("line", np.asarray(pts, float), colour, width, label, dash))

    def dots(self, pts, colour, r=3.0, label=None, hollow=False):
        self.items.append(("dots", np.asarray(pts, float), colour, r, label, hollow))

    def save(self, name):
        allp = np.vstack([it[1] for it in self.items])
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        m, top = 24, 44
        legend_h = 18 * sum(1 for it in self.items if it[4])
        sc = min((self.w - 2 * m) / max(hi[0] - lo[0], 1e-9),
                 (self.h - top - m - legend_h) / max(hi[1] - lo[1], 1e-9))
        ox = (self.w - (hi[0] - lo[0]) * sc) / 2

        def X(p):
            return ox + (p[0] - lo[0]) * sc

        def Y(p):
            return top + (hi[1] - p[1]) * sc

        out = ['<?xml version="1.0" encoding="UTF-8"?>',
               f'<svg xmlns="http://www.w3.org/2000/svg" width="{self.w}" height="{self.h}" '
               f'viewBox="0 0 {self.w} {self.h}">',
               '<rect width="100%" height="100%" fill="white"/>',
               f'<text x="12" y="24" font-family="sans-serif" font-size="15">{self.title}</text>']
        ly = self.h - legend_h - 4
        for kind, pts, colour, size, label, extra in self.items:
            if kind == "line":
                d = " ".join(f"{X(p):.1f},{Y(p):.1f}" for p in pts)
                dash = f' stroke-dasharray="{extra}"' if extra else ""
                out.append(f'<polyline fill="none" stroke="{colour}" stroke-width="{size}"{dash} points="{d}"/>')
            else:
                fill = "white" if extra else colour
                for p in pts:
                    out.append(f'<circle cx="{X(p):.1f}" cy="{Y(p):.1f}" r="{size}" fill="{fill}" stroke="{colour}"/>')
            if label:
                ly += 18
                if kind == "line":
                    dash = f' stroke-dasharray="{extra}"' if extra else ""
                    out.append(f'<line x1="14" y1="{ly - 5}" x2="40" y2="{ly - 5}" stroke="{colour}" stroke-width="2"{dash}/>')
                else:
                    out.append(f'<circle cx="27" cy="{ly - 5}" r="4" fill="{"white" if extra else colour}" stroke="{colour}"/>')
                out.append(f'<text x="48" y="{ly}" font-family="sans-serif" font-size="13">{label}</text>')
        out.append("</svg>")
        with open(os.path.join(HERE, name), "w") as f:
            f.write("\n".join(out) + "\n")
        print("wrote", name)


def bspline_curve(knots, ctrl, order, n=400):
    knots = np.ascontiguousarray(knots, float)
    ctrl = np.ascontiguousarray(ctrl, float)
    b = Bspline(order, len(ctrl), 2, ptr(knots), ptr(ctrl))
    lo, hi = knots[order - 1], knots[len(ctrl)]
    out, res = np.zeros(2), []
    for t in np.linspace(lo, hi, n):
        assert lib.bspline_eval(C.byref(b), t, ptr(out)) == 0
        res.append(out.copy())
    return np.array(res)


def open_knots(nc, order):
    k = np.zeros(nc + order)
    lib.bspline_knots_open_uniform(C.c_size_t(nc), C.c_uint(order), ptr(k))
    return k


def pic_bspline():
    P = np.array([[0, 0], [1, 3], [3, 3.5], [4, 0.5], [6, 0], [7, 3], [9, 3.2], [10, 0.5]], float)
    s = Svg("B-splines of orders 2, 3, 4, 6 on one control polygon (open uniform knots)")
    s.line(P, "#999", 1.0, "control polygon", "4,3")
    s.dots(P, "#999", 3.5)
    for c, q in zip(COLOURS, (2, 3, 4, 6)):
        s.line(bspline_curve(open_knots(len(P), q), P, q), c, 1.8, f"order {q} (degree {q - 1})")
    # a triple interior knot: the cubic passes through a control point with a corner
    k = np.array([0, 0, 0, 0, 1, 2, 2, 2, 3, 4, 4, 4, 4], float)
    s.line(bspline_curve(k, P + [0, -5], 4), COLOURS[4], 1.8,
           "cubic, knot 2 repeated 3 times: C0 corner at a control point (shifted down)")
    s.line(P + [0, -5], "#999", 1.0, None, "4,3")
    s.save("bspline.svg")


def nurbs_curve(c, n=400):
    out, res = np.zeros(c.dim), []
    for t in np.linspace(0, 1, n):
        assert lib.nurbs_eval(C.byref(c), t, ptr(out)) == 0
        res.append(out.copy())
    return np.array(res)


def pic_nurbs():
    s = Svg("NURBS: the seed's 9-pole unit circle and three conics (weights 0.5, 1, 2)")
    kn, cp, w = np.zeros(12), np.zeros(18), np.zeros(9)
    c = Nurbs()
    lib.nurbs_unit_circle(ptr(kn), ptr(cp), ptr(w), C.byref(c))
    pts = nurbs_curve(c, 2000)
    r = np.hypot(pts[:, 0], pts[:, 1])
    s.line(cp.reshape(9, 2), "#999", 1.0, "9 poles, weights 1 and sqrt(2)/2", "4,3")
    s.dots(cp.reshape(9, 2), "#999", 3.5)
    s.line(pts, COLOURS[0], 2.0, f"unit circle: max |r - 1| = {abs(r - 1).max():.1e} at 2000 points")
    P = np.array([[2.5, -1], [3.5, 1.5], [4.5, -1]], float)
    s.line(P, "#999", 1.0, None, "4,3")
    s.dots(P, "#999", 3.5)
    for col, wt, name in ((COLOURS[1], 0.5, "ellipse arc (w = 0.5)"), (COLOURS[2], 1.0, "parabola (w = 1)"),
                          (COLOURS[3], 2.0, "hyperbola arc (w = 2)")):
        kk, cc, ww = np.zeros(6), np.zeros(6), np.zeros(3)
        cn = Nurbs()
        Pc = np.ascontiguousarray(P)
        assert lib.nurbs_conic(ptr(Pc), 2, wt, ptr(kk), ptr(cc), ptr(ww), C.byref(cn)) == 0
        s.line(nurbs_curve(cn), col, 1.8, name)
    s.save("nurbs.svg")


def cspline_curve(t, p, end, d0=None, dn=None, n=600, closed=False):
    t = np.ascontiguousarray(t, float)
    p = np.ascontiguousarray(p, float)
    npts, dim = p.shape
    sv = np.zeros_like(p)
    scr = np.zeros(lib.cspline_scratch_len(C.c_size_t(npts), C.c_size_t(dim)))
    d0 = np.ascontiguousarray(d0 if d0 is not None else np.zeros(dim), float)
    dn = np.ascontiguousarray(dn if dn is not None else np.zeros(dim), float)
    cs = Cspline()
    rc = lib.cspline_solve(npts, dim, ptr(t), ptr(p), end, ptr(d0), ptr(dn), ptr(sv), ptr(scr), C.byref(cs))
    assert rc == 0, rc
    out, res = np.zeros(dim), []
    for x in np.linspace(t[0], t[-1], n):
        assert lib.cspline_eval(C.byref(cs), x, 0, ptr(out)) == 0
        res.append(out.copy())
    return np.array(res)


def params(p, kind):
    t = np.zeros(len(p))
    pc = np.ascontiguousarray(p, float)
    assert lib.cspline_params(len(p), p.shape[1], ptr(pc), kind, ptr(t)) == 0
    return t


def pic_cspline():
    P = np.array([[0, 0], [0.5, 2], [1, 2.2], [4, 3], [6.5, 0.5], [7, 0], [9, 1.5]], float)
    s = Svg("Cubic interpolating spline (seed 002): parameters and end conditions")
    s.dots(P, "black", 3.5, "points")
    tu, tc = params(P, 0), params(P, 1)
    s.line(cspline_curve(tu, P, 0), COLOURS[0], 1.8, "uniform parameter t_i = i, natural ends")
    s.line(cspline_curve(tc, P, 0), COLOURS[1], 1.8, "chord-length parameter, natural ends")
    s.line(cspline_curve(tc, P, 1), COLOURS[2], 1.4, "chord length, constant end curvature (5.20)", "6,3")
    s.line(cspline_curve(tc, P, 2, [0, 3], [3, 0]), COLOURS[3], 1.4,
           "chord length, clamped: start up, end right", "2,2")
    Q = np.array([[12, 0], [15, 0.5], [16, 3], [13.5, 3.6], [12.5, 2], [12, 0]], float)
    s.dots(Q[:-1], "black", 3.5)
    s.line(cspline_curve(params(Q, 1), Q, 3), COLOURS[4], 1.8, "closed curve (periodic, Sherman-Morrison)")
    s.save("cspline.svg")


def pic_lsq():
    """A receiver standing still for 60 s (1 m jitter), then walking 1.4 m/s."""
    rng = np.random.default_rng(20261121)
    t = np.arange(0, 120.0, 1.0)
    truth = np.where(t[:, None] < 60, [[0.0, 0.0]], np.c_[1.4 * (t - 60), 0.3 * (t - 60)])
    truth = np.asarray(truth, float)
    meas = truth + rng.normal(0, 1.0, truth.shape)
    meas = np.ascontiguousarray(meas)
    exact = cspline_curve(t, meas, 0, n=1200)
    # least squares on the same timestamps: one control point per 10 s
    nc, order = 14, 4
    u = np.ascontiguousarray(t / t[-1])
    kn = np.zeros(nc + order)
    lib.lsq_knots(nc, order, 0.0, 1.0, ptr(kn))
    ctrl = np.zeros((nc, 2))
    work = np.zeros(lib.lsq_work_len(C.c_size_t(nc), C.c_uint(order), C.c_size_t(2)))
    assert lib.lsq_fit(len(t), 2, ptr(u), ptr(meas), order, nc, ptr(kn), 0, ptr(ctrl), ptr(work)) == 0
    b = Bspline(order, nc, 2, ptr(kn), ptr(ctrl))
    tt = np.linspace(0, 1, 1200)
    smooth = []
    out = np.zeros(2)
    for x in tt:
        lib.bspline_eval(C.byref(b), x, ptr(out))
        smooth.append(out.copy())
    smooth = np.array(smooth)
    ts = tt * t[-1]
    still = ts < 55

    def stats(curve):
        seg = np.linalg.norm(np.diff(curve[still], axis=0), axis=1).sum()
        dev = np.linalg.norm(curve[still] - [0, 0], axis=1).max()
        tr = np.where(ts[:, None] < 60, [[0.0, 0.0]], np.c_[1.4 * (ts - 60), 0.3 * (ts - 60)])
        rms = np.sqrt(np.mean(np.sum((curve - tr) ** 2, axis=1)))
        return seg, dev, rms
    se, de, re = stats(exact)
    ss, ds, rs = stats(smooth)
    print(f"lsq demo: standing still 0..55 s: exact interpolation travels {se:.1f} m, max {de:.2f} m off; "
          f"least squares travels {ss:.1f} m, max {ds:.2f} m off; "
          f"RMS error to the truth over 0..120 s: exact {re:.2f} m, least squares {rs:.2f} m")
    s = Svg("Jittery fixes (sigma 1 m): exact interpolation vs least-squares B-spline")
    s.line(exact, COLOURS[1], 1.0, f"exact cubic spline through every fix: {se:.0f} m travelled while standing still")
    s.line(smooth, COLOURS[0], 2.2, f"least squares, 14 control points (one per ~10 s): {ss:.1f} m")
    s.dots(meas, "black", 2.2, "fixes: 60 s standing at (0,0), then walking 1.4 m/s", hollow=True)
    s.save("lsq.svg")
    return se, de, re, ss, ds, rs


def pic_path():
    prog = ["start 0 0 0", "speed 2", "step 1", "line 20 0 0", "arc 20 10 10 -90 90",
            "line 5 20 0", "circle 5 10 10 90 ccw", "arc 0 20 5 0 180"]
    el = (PathElem * len(prog))()
    for i, line in enumerate(prog):
        assert lib.path_parse_line(line.encode(), C.byref(el[i])) == 0
    n = C.c_size_t()
    wp = (Waypoint * 4096)()
    assert lib.path_expand(el, len(prog), wp, 4096, C.byref(n)) == 0
    pts = np.array([[wp[i].pos_m[0], wp[i].pos_m[1]] for i in range(n.value)])
    t = np.array([wp[i].t_s for i in range(n.value)])
    s = Svg("Path of lines and exact NURBS arcs, sampled at 2 m/s every second, then interpolated")
    s.line(cspline_curve(t, pts, 0, n=3000), COLOURS[0], 1.5, "cubic spline on the timestamps")
    s.dots(pts, COLOURS[1], 2.4, f"{n.value} waypoints: " + "; ".join(prog[3:]))
    s.save("path.svg")


def pic_engine_smooth():
    """trajreplay on a real phone track (tests/data/gpxgo_visnjan.csv): cubic vs smooth."""
    data = os.path.join(HERE, "..", "data", "gpxgo_visnjan.csv")
    runs = {}
    for m in ("cubic", "smooth"):
        out = os.path.join(BUILD, "picture_visnjan_%s.csv" % m)
        subprocess.run([os.path.join(BUILD, "bin", "trajreplay"), "-q", "--rate", "10", "--method", m,
                        "-o", out, data], check=True)
        d = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding=None)
        runs[m] = d
        v = np.hypot(d["vx_m_s"], d["vy_m_s"])
        a = np.hypot(d["ax_m_s2"], d["ay_m_s2"])
        # (rows before the first position exist have NaN positions: left out)
        print("visnjan %s: path %.0f m, p99 speed %.2f m/s, p99 acceleration %.2f m/s^2, max %.2f" % (
            m, np.nansum(np.hypot(np.diff(d["x_m"]), np.diff(d["y_m"]))), np.nanpercentile(v, 99),
            np.nanpercentile(a, 99), np.nanmax(a)))
    # the fixes, converted like trajreplay does: take them from the cubic run's
    # waypoint times (the curve passes through them), first 400 s
    t0, t1 = 0.0, 400.0
    s = Svg("Real phone track (Visnjan walk, first 400 s): trajreplay --method cubic vs smooth")
    for m, col, w in (("cubic", COLOURS[1], 1.0), ("smooth", COLOURS[0], 2.0)):
        d = runs[m]
        sel = (d["t_s"] >= t0) & (d["t_s"] <= t1)
        s.line(np.c_[d["x_m"][sel], d["y_m"][sel]], col, w,
               "method %s%s" % (m, " (exact through every fix)" if m == "cubic" else
                                " (window 24, 6 control points)"))
    fx = np.genfromtxt(data, delimiter=",", names=True)
    d = runs["cubic"]
    ts = fx["t_s"][(fx["t_s"] >= t0) & (fx["t_s"] <= t1)]
    pts = np.c_[np.interp(ts, d["t_s"], d["x_m"]), np.interp(ts, d["t_s"], d["y_m"])]
    s.dots(pts, "black", 2.2, "fixes (phone GPS, 1-41 s apart)", hollow=True)
    s.save("engine_smooth.svg")


def pic_surface():
    rows = []
    for r in range(9):
        rows.append(",".join("%.4f" % (2.5 * math.sin(0.6 * c) * math.cos(0.5 * r) + 0.08 * r * c)
                             for c in range(12)))
    src = os.path.join(BUILD, "picture_grid.csv")
    with open(src, "w") as f:
        f.write("\n".join(rows) + "\n")
    subprocess.run([os.path.join(BUILD, "bin", "trajsurf"), "-n", "4", "-z", "1.2", "-o",
                    os.path.join(BUILD, "picture_surface.csv"), "-s", os.path.join(HERE, "surface.svg"), src],
                   check=True)
    print("wrote surface.svg")


if __name__ == "__main__":
    pic_bspline()
    pic_nurbs()
    pic_cspline()
    pic_lsq()
    pic_path()
    pic_engine_smooth()
    pic_surface()
