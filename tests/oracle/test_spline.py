#!/usr/bin/python3
"""Oracle tests of the engine's curves against scipy (independent references).

Run with Debian's /usr/bin/python3 (scipy, numpy); loads $BUILD/libtrajd_test.so (libtrajd and
the ctypes shims of tests/helpers/ctypes_shims.c).

* hoang_curve (global exact B-spline, the paper's ends) against a banded solve
  (scipy.linalg.solve_banded) fed to scipy.interpolate.BSpline on uniform knots;
* cubic_curve / engine curves with knots at the timestamps against
  scipy.interpolate.CubicSpline (natural, clamped) and, for method BSPLINE with
  param TIME, against make_interp_spline (a non-uniform B-spline interpolant
  solved in B-spline coefficients): the equivalence claimed in cubic.h;
* the streaming curve (fragments) against one global solve, within the
  documented bound 2 * rho^(O/2) * max|c2|/3 (rho = 2 - sqrt(3));
* real tracks (tests/data, projected to local metres with numpy): every
  waypoint hit, no NaN, velocity continuous at joins for knots at the
  timestamps, and the measured velocity jumps of (a) versus (b).
"""
import ctypes
import math
import os
import sys

import numpy as np
from scipy.interpolate import BSpline, CubicSpline, make_interp_spline
from scipy.linalg import solve_banded

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from oracle_util import check, failures, evaluate  # noqa: E402

BUILD = os.environ.get("BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
HERE = os.path.dirname(os.path.abspath(__file__))
lib = ctypes.CDLL(os.path.join(BUILD, "libtrajd_test.so"))
D = ctypes.POINTER(ctypes.c_double)
SZ = ctypes.c_size_t

# engine.h enums
BSPLINE, CUBIC = 0, 1
UNIFORM, TIME = 0, 1
HELD, MULTIPLE, NATURAL, CLAMPED, REST = 0, 1, 2, 3, 4

lib.engine_pick_flat.restype = ctypes.c_uint
lib.engine_pick_flat.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_double, ctypes.c_uint,
                                 ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_uint)]
lib.engine_curve_flat.restype = ctypes.c_long
lib.engine_curve_flat.argtypes = [ctypes.c_int] * 3 + [ctypes.c_uint] * 2 + [SZ, D, D, D, SZ]
lib.hoang_curve.restype = ctypes.c_int
lib.hoang_curve.argtypes = [SZ, D, D, ctypes.c_int, D, D, D, SZ, ctypes.POINTER(SZ)]
lib.cubic_curve.restype = ctypes.c_int
lib.cubic_curve.argtypes = [SZ, D, D, ctypes.c_int, ctypes.c_int, D, D, D, SZ, ctypes.POINTER(SZ)]

RHO = 2.0 - math.sqrt(3.0)
# Global solves in double precision against scipy's: both backward stable on
# diagonally dominant systems; 1e-12 of the track's extent leaves room for the
# different operation orders (measured ~1e-15 relative).
TOL_ORACLE_REL = 1e-12
# Documented fragment bound: |streamed - global| <= FRAG_K * rho^(O/2) * max|c2|/3
# (c2/3 = k''/6 scale of the error injected at an artificial fragment end);
# measured K <= 1.4 over random walks and several (F, O), see lib/engine/DESIGN.md.
FRAG_K = 2.0
# On the real tracks, whose intervals jump (cerknicko switches between 7 s
# and 2 s steps, visnjan has 1-41 s), an artificial end's error decays more
# slowly than rho per row near the jumps: measured factor up to 4.8
# (cerknicko, F=28/O=24, position) instead of 1.3, so the real-track checks
# allow FRAG_K_REAL.
FRAG_K_REAL = 6.0


def ptr(a):
    return a.ctypes.data_as(D)


def engine_curve(method, param, ends, f, o, t, xyz):
    t = np.ascontiguousarray(t, dtype=float)
    xyz = np.ascontiguousarray(xyz, dtype=float)
    out = np.zeros((len(t) + 8, 14))
    n = lib.engine_curve_flat(method, param, ends, f, o, len(t), ptr(t), ptr(xyz), ptr(out), len(out))
    assert n >= 0, "engine_curve_flat failed: %d" % n
    return out[:n]


def pick(accuracy=0.0, max_lookahead=0, method=CUBIC, param=TIME):
    """(F, O, lookahead) the engine picks (0: the default accuracy/max_lookahead)."""
    f, o = ctypes.c_uint(0), ctypes.c_uint(0)
    la = lib.engine_pick_flat(method, param, accuracy, max_lookahead, ctypes.byref(f), ctypes.byref(o))
    return f.value, o.value, la


def hoang_curve(t, xyz, ends, v0=None, v1=None):
    t = np.ascontiguousarray(t, dtype=float)
    xyz = np.ascontiguousarray(xyz, dtype=float)
    out = np.zeros((len(t) + 8, 14))
    n = SZ(0)
    v0p = ptr(np.ascontiguousarray(v0, dtype=float)) if v0 is not None else None
    v1p = ptr(np.ascontiguousarray(v1, dtype=float)) if v1 is not None else None
    rc = lib.hoang_curve(len(t), ptr(t), ptr(xyz), ends, v0p, v1p, ptr(out), len(out), ctypes.byref(n))
    assert rc == 0, rc
    return out[:n.value]


def cubic_curve(t, xyz, param, ends, v0=None, v1=None):
    t = np.ascontiguousarray(t, dtype=float)
    xyz = np.ascontiguousarray(xyz, dtype=float)
    out = np.zeros((len(t) + 8, 14))
    n = SZ(0)
    v0a = np.ascontiguousarray(v0, dtype=float) if v0 is not None else None
    v1a = np.ascontiguousarray(v1, dtype=float) if v1 is not None else None
    rc = lib.cubic_curve(len(t), ptr(t), ptr(xyz), param, ends,
                         ptr(v0a) if v0a is not None else None,
                         ptr(v1a) if v1a is not None else None,
                         ptr(out), len(out), ctypes.byref(n))
    assert rc == 0, rc
    return out[:n.value]


def seg_end(segs):
    c = segs[:, 2:].reshape(-1, 3, 4)
    return c.sum(axis=2)


def seg_start(segs):
    return segs[:, 2:].reshape(-1, 3, 4)[:, :, 0]


def random_track(seed, n, dt=(0.5, 2.0)):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(dt[0], dt[1], n))
    t -= t[0]
    xyz = np.cumsum(rng.normal(0, 10, (n, 3)), axis=0)
    return t, xyz


def samples(t0, t1, t, m=2000):
    tq = np.sort(np.concatenate([np.linspace(t0, t1, m), t]))
    return tq[(tq >= t0) & (tq <= t1)]


# ---------------------------------------------------------------------------
def held_control_points(r):
    """The paper's control points with held ends, by scipy's banded solver:
    P(0) = R(0), P(N-1) = R(N-1), P(i-1) + 4 P(i) + P(i+1) = 6 R(i) inside."""
    n = len(r)
    ab = np.zeros((3, n))
    ab[0, 1:] = 1.0
    ab[1, :] = 4.0
    ab[2, :-1] = 1.0
    ab[1, 0] = ab[1, -1] = 1.0
    ab[0, 1] = 0.0
    ab[2, -2] = 0.0
    rhs = 6.0 * r
    rhs[0], rhs[-1] = r[0], r[-1]
    return solve_banded((1, 1), ab, rhs)


def test_hoang_held_vs_banded_bspline():
    """Given a random track, when solved with the paper's held ends (hoang_curve
    and the engine with one fragment), then the curve equals scipy's BSpline on
    the control points from solve_banded, over R(1)..R(N-2)."""
    t, xyz = random_track(1, 40)
    n = len(t)
    p = held_control_points(xyz)
    ref = BSpline(np.arange(n + 4) - 2.0, p, 3)   # segment s driven by P(s-1..s+2)
    ext = np.ptp(xyz, axis=0).max()
    tq = samples(t[1], t[-2], t)
    s_param = np.interp(tq, t, np.arange(n))      # segment j mapped onto [t_j, t_j+1]
    for name, segs in (("hoang_curve", hoang_curve(t, xyz, HELD)),
                       ("engine F=1024", engine_curve(BSPLINE, UNIFORM, HELD, 1024, 16, t, xyz))):
        check(len(segs) == n - 3, "%s held: N-3 segments (%d)" % (name, len(segs)))
        err = np.abs(evaluate(segs, tq) - ref(s_param)).max() / ext
        check(err < TOL_ORACLE_REL, "%s held vs solve_banded+BSpline: %.1e of extent" % (name, err))
        # velocity: d/dt = d/ds / T_j
        tj = np.clip(np.searchsorted(t, tq, side="right") - 1, 0, n - 2)
        vref = ref.derivative()(s_param) / (t[tj + 1] - t[tj])[:, None]
        inner = (tq > t[1]) & (tq < t[-2]) & ~np.isin(tq, t)
        errv = np.abs(evaluate(segs, tq[inner], 1) - vref[inner]).max() / ext
        check(errv < TOL_ORACLE_REL, "%s held velocity vs BSpline: %.1e" % (name, errv))


def test_hoang_multiple_vs_banded_bspline():
    """Given the paper's end-point multiplicity (N+4 points), when solved, then
    the emitted curve equals the BSpline of the extended system between R(0)
    and R(N-1), and no loop segment (between copies) is emitted."""
    t, xyz = random_track(2, 30)
    n = len(t)
    ext_idx = [0, 0, 0] + list(range(1, n - 1)) + [n - 1] * 3
    r = xyz[ext_idx]
    m = len(r)
    p = held_control_points(r)
    ref = BSpline(np.arange(m + 4) - 2.0, p, 3)
    ext = np.ptp(xyz, axis=0).max()
    tq = samples(t[0], t[-1], t)
    # real segment j (R(j)->R(j+1)) is extended segment j+2
    s_param = np.interp(tq, t, np.arange(n)) + 2.0
    for name, segs in (("hoang_curve", hoang_curve(t, xyz, MULTIPLE)),
                       ("engine F=1024", engine_curve(BSPLINE, UNIFORM, MULTIPLE, 1024, 16, t, xyz))):
        check(len(segs) == n - 1, "%s multiple: N-1 segments, loops dropped (%d)" % (name, len(segs)))
        check(bool(np.all(segs[:, 1] > 0)), "%s multiple: every emitted segment has a duration" % name)
        err = np.abs(evaluate(segs, tq) - ref(s_param)).max() / ext
        check(err < TOL_ORACLE_REL, "%s multiple vs BSpline: %.1e" % (name, err))
        check(np.abs(seg_start(segs)[0] - xyz[0]).max() < TOL_ORACLE_REL * ext and
              np.abs(seg_end(segs)[-1] - xyz[-1]).max() < TOL_ORACLE_REL * ext,
              "%s multiple: runs from R(0) to R(N-1)" % name)


def test_uniform_natural_clamped():
    """Given uniform parameterisation, when natural / clamped, then Hoang and the
    M-form cubic both equal scipy's interpolating spline on the node index."""
    t, xyz = random_track(3, 35)
    n = len(t)
    ext = np.ptp(xyz, axis=0).max()
    tq = samples(t[0], t[-1], t)
    s_param = np.interp(tq, t, np.arange(n))
    nat = make_interp_spline(np.arange(n), xyz, k=3, bc_type="natural")(s_param)
    for name, segs in (("hoang natural", hoang_curve(t, xyz, NATURAL)),
                       ("cubic uniform natural", cubic_curve(t, xyz, UNIFORM, NATURAL)),
                       ("engine bspline/uniform/natural", engine_curve(BSPLINE, UNIFORM, NATURAL, 1024, 16, t, xyz)),
                       ("engine cubic/uniform/natural", engine_curve(CUBIC, UNIFORM, NATURAL, 1024, 16, t, xyz))):
        err = np.abs(evaluate(segs, tq) - nat).max() / ext
        check(err < TOL_ORACLE_REL, "%s vs make_interp_spline(index, natural): %.1e" % (name, err))
    v0 = np.array([1.0, -2.0, 0.5])
    v1 = np.array([-3.0, 0.0, 2.0])
    # clamped in m/s: dk/ds = v * T at the end intervals
    bc = ((1, v0 * (t[1] - t[0])), (1, v1 * (t[-1] - t[-2])))
    cl = CubicSpline(np.arange(n), xyz, bc_type=bc)(s_param)
    for name, segs in (("hoang clamped", hoang_curve(t, xyz, CLAMPED, v0, v1)),
                       ("cubic uniform clamped", cubic_curve(t, xyz, UNIFORM, CLAMPED, v0, v1))):
        err = np.abs(evaluate(segs, tq) - cl).max() / ext
        check(err < TOL_ORACLE_REL, "%s vs CubicSpline(index, clamped): %.1e" % (name, err))
        vs = evaluate(segs, np.array([t[0] + 1e-12, t[-1] - 1e-12]), 1)
        check(np.abs(vs[0] - v0).max() < 1e-6 and np.abs(vs[1] - v1).max() < 1e-6,
              "%s: end velocities are the given m/s" % name)


def test_time_knots():
    """Given knots at the timestamps, when natural / clamped / rest, then the
    curve equals CubicSpline(t), and method BSPLINE equals the non-uniform
    B-spline interpolant make_interp_spline(t) (same curve, cubic.h)."""
    t, xyz = random_track(4, 50, dt=(0.2, 3.0))
    ext = np.ptp(xyz, axis=0).max()
    tq = samples(t[0], t[-1], t)
    nat = CubicSpline(t, xyz, bc_type="natural")
    rest = CubicSpline(t, xyz, bc_type="clamped")
    bsp = make_interp_spline(t, xyz, k=3, bc_type="natural")
    cases = (("cubic_curve natural", cubic_curve(t, xyz, TIME, NATURAL), nat),
             ("engine cubic/time/natural", engine_curve(CUBIC, TIME, NATURAL, 1024, 16, t, xyz), nat),
             ("engine cubic/time/rest", engine_curve(CUBIC, TIME, REST, 1024, 16, t, xyz), rest),
             ("engine bspline/time/natural", engine_curve(BSPLINE, TIME, NATURAL, 1024, 16, t, xyz), bsp))
    v0 = np.array([2.0, -1.0, 0.25])
    v1 = np.array([0.0, 3.0, -1.5])
    clamped = CubicSpline(t, xyz, bc_type=((1, v0), (1, v1)))
    bclamped = make_interp_spline(t, xyz, k=3, bc_type=([(1, v0)], [(1, v1)]))
    cases += (("cubic_curve time clamped", cubic_curve(t, xyz, TIME, CLAMPED, v0, v1), clamped),
              ("cubic_curve time clamped vs make_interp_spline", cubic_curve(t, xyz, TIME, CLAMPED, v0, v1),
               bclamped))
    for name, segs, ref in cases:
        for der in (0, 1, 2):
            err = np.abs(evaluate(segs, tq, der) - ref(tq, der)).max() / ext
            # derivatives scale with 1/dt^der (dt >= 0.2 s here): 25x room for acceleration
            check(err < TOL_ORACLE_REL * 25, "%s vs scipy, derivative %d: %.1e" % (name, der, err))


def test_fragments_vs_global():
    """Given a 400-point random walk, when streamed with several (F, O), then
    every position is within FRAG_K * rho^(O/2) * max|c2|/3 of one global solve."""
    worst_k = 0.0
    for seed in (5, 6):
        t, xyz = random_track(seed, 400, dt=(0.2, 3.0))
        ext = np.ptp(xyz, axis=0).max()
        for method, param, ends in ((CUBIC, TIME, REST), (BSPLINE, UNIFORM, NATURAL), (BSPLINE, UNIFORM, HELD)):
            g = engine_curve(method, param, ends, 1024, 16, t, xyz)  # one fragment: global
            scale = np.abs(g[:, [4, 8, 12]]).max() / 3.0
            tq = samples(g[0, 0], g[-1, 0] + g[-1, 1], t, 4000)
            ref = evaluate(g, tq)
            for f, o in ((8, 4), (16, 8), (32, 8), (32, 16), (48, 24), (64, 32), (32, 30)):
                s = engine_curve(method, param, ends, f, o, t, xyz)
                err = np.abs(evaluate(s, tq) - ref).max()
                bound = FRAG_K * RHO ** (o / 2) * scale
                check(len(s) == len(g) and err <= bound,
                      "seed %d m%d p%d e%d F=%d O=%d: %.1e of extent (bound %.1e)"
                      % (seed, method, param, ends, f, o, err / ext, bound / ext))
                worst_k = max(worst_k, err / (RHO ** (o / 2) * scale))
    # lib/engine/DESIGN.md: "the measured factor is <= 1.3 instead of 2, tested for 7 (F,O) pairs"
    import re
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "engine",
                           "DESIGN.md"), encoding="utf-8") as f:
        k, pairs = re.search(r"the measured factor is ≤ (\S+) instead of 2, tested for (\d+) \(F,O\) pairs",
                             " ".join(f.read().split())).groups()
    check(float(k) == float("%.1f" % worst_k) and int(pairs) == 7,
          "lib/engine/DESIGN.md: factor <= %s over %s (F,O) pairs, the run %.2f over 7" % (k, pairs, worst_k))


def test_default_accuracy_vs_scipy():
    """Given regular random walks (waypoints every 0.2 s), when streamed with
    the default settings, then the curve is within 1e-8 of the extent of
    scipy's CubicSpline through every waypoint (one global solve, clamped at
    rest as ends = rest) with a lookahead of at most 18 waypoints; and for
    other accuracy / max_lookahead pairs, within accuracy of the curvature
    scale (the documented bound, engine.h) and within max_lookahead."""
    fd, od, la = pick()
    check(la <= 18, "defaults: F=%d O=%d, lookahead %d <= 18 waypoints" % (fd, od, la))
    errs, picks = [], {}
    for seed in (11, 12, 13):
        rng = np.random.default_rng(seed)
        n = 1000
        t = np.arange(n) * 0.2
        xyz = np.cumsum(rng.uniform(-1, 1, (n, 3)), axis=0)
        ext = np.ptp(xyz, axis=0).max()
        ref = CubicSpline(t, xyz, bc_type="clamped")
        tq = samples(t[0], t[-1], t, 20000)
        s = engine_curve(CUBIC, TIME, REST, 0, 0, t, xyz)
        err = np.abs(evaluate(s, tq) - ref(tq)).max() / ext
        check(len(s) == n - 1 and err <= 1e-8,
              "seed %d defaults F=%d O=%d vs scipy global: %.1e of extent <= 1e-8" % (seed, fd, od, err))
        errs.append(err)
        scale = np.abs(ref.c[1]).max() / 3.0 * 0.2 ** 2  # max |c2|/3 in the u form (h = 0.2 s)
        for acc, mla in ((1e-3, 12), (1e-5, 16), (1e-9, 24), (1e-11, 30)):
            f, o, la2 = pick(acc, mla)
            picks[(acc, mla)] = (f, o)
            check(la2 > 0 and la2 <= mla and 2 * RHO ** (o / 2) <= acc,
                  "accuracy %.0e max_lookahead %d: F=%d O=%d lookahead %d" % (acc, mla, f, o, la2))
            s = engine_curve(CUBIC, TIME, REST, f, o, t, xyz)
            err = np.abs(evaluate(s, tq) - ref(tq)).max()
            check(err <= acc * scale, "seed %d accuracy %.0e: %.1e of the curvature scale"
                  % (seed, acc, err / scale))
    f, o, la2 = pick(1e-12, 12)
    check(la2 == 0, "accuracy 1e-12 within 12 waypoints: refused (no fragment fits)")


# ---------------------------------------------------------------------------
    defaults_doc_is_this_run(fd, od, la, errs, picks)


def load_track(name):
    """Test-only local projection (equirectangular about the first point), and
    the engine's own filtering: drop rows not strictly later than the last kept."""
    a = np.genfromtxt(os.path.join(HERE, "..", "data", name), delimiter=",", names=True)
    lat0, lon0 = math.radians(a["lat_deg"][0]), math.radians(a["lon_deg"][0])
    r_earth = 6371008.8
    x = (np.radians(a["lon_deg"]) - lon0) * math.cos(lat0) * r_earth
    y = (np.radians(a["lat_deg"]) - lat0) * r_earth
    z = np.nan_to_num(a["alt_m"] - (a["alt_m"][0] if np.isfinite(a["alt_m"][0]) else 0.0))
    t = a["t_s"]
    keep, last = [], -np.inf
    for i in range(len(t)):
        if t[i] > last + 1e-9:
            keep.append(i)
            last = t[i]
    keep = np.array(keep)
    return t[keep], np.column_stack([x, y, z])[keep]


def joins_velocity_jump(segs):
    """|v(end of j) - v(start of j+1)| at every join, m/s."""
    c = segs[:, 2:].reshape(-1, 3, 4)
    v_end = (c[:, :, 1] + 2 * c[:, :, 2] + 3 * c[:, :, 3]) / segs[:, 1][:, None]
    v_start = c[:, :, 1] / segs[:, 1][:, None]
    return np.linalg.norm(v_end[:-1] - v_start[1:], axis=1)


def test_real_tracks():
    """Given the real logged tracks, when streamed with the defaults (knots at
    the timestamps, F and O picked from accuracy and max_lookahead) and with
    the paper's uniform B-spline (F=32, O=16), then:
    every waypoint is hit (b: 1e-9 of the extent), the fragments stay within the
    bound of one global solve, nothing is NaN, the velocity is continuous at
    the joins for (b); the velocity jumps of (a) are printed (lib/engine/DESIGN.md)."""
    measured = {}
    for name in ("gpxgo_visnjan.csv", "gpxpy_cerknicko-jezero.csv", "n2k_furuno_figure8_src52.csv"):
        t, xyz = load_track(name)
        ext = np.ptp(xyz, axis=0).max()
        fd, od, _ = pick()
        b = engine_curve(CUBIC, TIME, REST, 0, 0, t, xyz)  # the defaults: F=fd, O=od
        bg = cubic_curve(t, xyz, TIME, REST)
        check(bool(np.all(np.isfinite(b))), "%s (b): no NaN" % name)
        miss = max(np.abs(seg_start(b) - xyz[:-1]).max(), np.abs(seg_end(b) - xyz[1:]).max())
        check(miss < 1e-9 * ext, "%s (b): every waypoint hit, %.1e of extent" % (name, miss / ext))
        tq = samples(t[0], t[-1], t, 20000)
        scale = np.abs(bg[:, [4, 8, 12]]).max() / 3.0
        err = np.abs(evaluate(b, tq) - evaluate(bg, tq)).max()
        check(err <= FRAG_K_REAL * RHO ** (od / 2) * scale,
              "%s (b): F=%d/O=%d vs global %.1e of extent (bound %.1e)"
              % (name, fd, od, err / ext, FRAG_K_REAL * RHO ** (od / 2) * scale / ext))
        jb = joins_velocity_jump(b)
        jbg = joins_velocity_jump(bg)
        vmax = np.abs(evaluate(bg, tq, 1)).max()
        check(jbg.max() < 1e-9 * vmax, "%s (b) global: velocity continuous at joins (max jump %.1e m/s)"
              % (name, jbg.max()))
        check(jb.max() <= FRAG_K_REAL * RHO ** (od / 2) * vmax,
              "%s (b) F=%d/O=%d: velocity jump at joins %.1e m/s <= rho^(O/2) scale (vmax %.1f m/s)"
              % (name, fd, od, jb.max(), vmax))
        a = engine_curve(BSPLINE, UNIFORM, NATURAL, 32, 16, t, xyz)
        ag = hoang_curve(t, xyz, NATURAL)
        ja = joins_velocity_jump(a)
        missa = max(np.abs(seg_start(a) - xyz[:-1]).max(), np.abs(seg_end(a) - xyz[1:]).max())
        missag = max(np.abs(seg_start(ag) - xyz[:-1]).max(), np.abs(seg_end(ag) - xyz[1:]).max())
        check(missag < 1e-9 * ext, "%s (a) global: every waypoint hit, %.1e" % (name, missag / ext))
        check(missa < 1e-4 * ext, "%s (a) F=32/O=16: waypoints missed by at most %.1e of extent (%.2e m)"
              % (name, missa / ext, missa))
        a48 = engine_curve(BSPLINE, UNIFORM, NATURAL, 48, 24, t, xyz)
        miss48 = max(np.abs(seg_start(a48) - xyz[:-1]).max(), np.abs(seg_end(a48) - xyz[1:]).max())
        check(miss48 < 1e-9 * ext, "%s (a) F=48/O=24: every waypoint hit, %.1e of extent" % (name, miss48 / ext))
        print("     measured %s: velocity jump at joins, (a) uniform: max %.3g median %.3g m/s;"
              " (b) time knots: max %.3g m/s; vmax %.3g m/s"
              % (name, ja.max(), np.median(ja), jb.max(), vmax))
        if name.startswith("gpxgo"):
            check(ja.max() > 1e3 * max(jb.max(), 1e-12), "visnjan: (a) jumps dwarf (b)'s")
        a64 = engine_curve(BSPLINE, UNIFORM, NATURAL, 64, 32, t, xyz)
        miss64 = max(np.abs(seg_start(a64) - xyz[:-1]).max(), np.abs(seg_end(a64) - xyz[1:]).max())
        measured[name.split(".")[0]] = dict(ja=ja.max(), ja_med=np.median(ja), jb=jb.max(), vmax=vmax,
                                            err_rel=err / ext, missa=missa, missa_rel=missa / ext,
                                            miss64_rel=miss64 / ext, missag_rel=missag / ext)
    doc_is_this_run(measured)


def defaults_doc_is_this_run(fd, od, la, errs, picks):
    """lib/engine/DESIGN.md's defaults and picks, and tests/bench/RESULTS.md's range of the
    defaults' error against scipy, are this run's (issue 14: no stale numbers)."""
    import re
    here = os.path.dirname(os.path.abspath(__file__))
    with open(os.path.join(here, "..", "..", "lib", "engine", "DESIGN.md"), encoding="utf-8") as f:
        doc = " ".join(f.read().split())
    got = re.search(r"max_lookahead 18, give F = (\d+), O = (\d+): (\d+) waypoints of lookahead on "
                    r"regular input, (\S+) of the extent against one global solve", doc).groups()
    check((int(got[0]), int(got[1]), int(got[2])) == (fd, od, la) and
          float(got[3]) == float("%.0e" % np.median(errs)),
          "lib/engine/DESIGN.md defaults: %s, the run F=%d O=%d lookahead %d, %.1e" % (got, fd, od, la,
                                                                                      np.median(errs)))
    fo, pairs = re.search(r"(\d+/\d+, \d+/\d+ and \d+/\d+) are what (\(\S+, \d+\), \(\S+, \d+\) and "
                          r"\(\S+, \d+\)) pick", doc).groups()
    fo = [tuple(int(x) for x in p.split("/")) for p in re.findall(r"\d+/\d+", fo)]
    pairs = [(float(a), int(b)) for a, b in re.findall(r"\((\S+), (\d+)\)", pairs)]
    check([picks.get(p) for p in pairs] == fo, "lib/engine/DESIGN.md picks %s for %s, the run %s"
          % (fo, pairs, [picks.get(p) for p in pairs]))
    with open(os.path.join(here, "..", "bench", "RESULTS.md"), encoding="utf-8") as f:
        res = " ".join(f.read().split())
    lo, hi = re.search(r"\(test_default_accuracy_vs_scipy\) prints (\S+) \.\. (\S+) of the extent", res).groups()
    check((float(lo), float(hi)) == (float("%.1e" % min(errs)), float("%.1e" % max(errs))),
          "tests/bench/RESULTS.md: %s .. %s, the run %.1e .. %.1e" % (lo, hi, min(errs), max(errs)))


def doc_is_this_run(m):
    """lib/engine/DESIGN.md's figures of the real tracks are this run's, as the
    doc rounds them (issue 14: no stale numbers)."""
    import re
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib", "engine",
                           "DESIGN.md"), encoding="utf-8") as f:
        doc = " ".join(f.read().split())

    def same(shown, value, what):
        num = re.match(r"[\d.]+(e-?\d+)?", shown).group(0)
        mant = num.split("e")[0]
        d = len(mant.split(".")[1]) if "." in mant else 0
        got = ("%.*e" % (d, value)) if "e" in num else ("%.*f" % (d, value))
        check(float(got) == float(num), "lib/engine/DESIGN.md %s: %s, the run gives %.3g" % (what, shown, value))

    rows = {"gpxgo_visnjan": "| gpxgo_visnjan (", "gpxpy_cerknicko-jezero": "| gpxpy_cerknicko-jezero (",
            "n2k_furuno_figure8_src52": "| n2k figure-8 ("}
    for name, start in rows.items():
        row = doc[doc.index(start):].split(" | ", 1)[1].split(" |")[:3]
        ja, med = row[0].split(" / ")
        for shown, key in ((ja, "ja"), (med, "ja_med"), (row[1], "jb"), (row[2], "vmax")):
            same(shown.strip(), m[name][key], "velocity-jump table %s %s" % (name, key))
    cer, vis, f8 = re.search(r"error decays more slowly near the jumps: (\S+) of the extent on cerknicko, "
                             r"(\S+) on visnjan, (\S+) on the figure-8", doc).groups()
    for shown, name in ((cer, "gpxpy_cerknicko-jezero"), (vis, "gpxgo_visnjan"), (f8, "n2k_furuno_figure8_src52")):
        same(shown, m[name]["err_rel"], "real-track error " + name)
    up, cer, vis, f8, g64, gg = re.search(
        r"misses waypoints near junctions by up to (\S+) of the extent at F=32/O=16 \((\S+ \S+) on "
        r"cerknicko, (\S+ \S+) on visnjan, (\S+ \S+) on the figure-8\), within 1e-9 of the extent from "
        r"F=48/O=24 on \(tested on all three tracks; (\S+) at 64/32\); the global \(a\) hits them to "
        r"(\S+)\.", doc).groups()
    same(up, max(v["missa_rel"] for v in m.values()), "(a) misses, of the extent")
    scale = {"cm": 1e-2, "mm": 1e-3, "µm": 1e-6}
    for shown, name in ((cer, "gpxpy_cerknicko-jezero"), (vis, "gpxgo_visnjan"), (f8, "n2k_furuno_figure8_src52")):
        same(shown, m[name]["missa"] / scale[shown.split()[1]], "(a) misses " + name)
    same(g64, max(v["miss64_rel"] for v in m.values()), "(a) misses at 64/32")
    same(gg, max(v["missag_rel"] for v in m.values()), "(a) global misses")


if __name__ == "__main__":
    test_hoang_held_vs_banded_bspline()
    test_hoang_multiple_vs_banded_bspline()
    test_uniform_natural_clamped()
    test_time_knots()
    test_fragments_vs_global()
    test_default_accuracy_vs_scipy()
    test_real_tracks()
    print("%d failure(s)" % len(failures))
    sys.exit(1 if failures else 0)
