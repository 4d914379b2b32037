#!/usr/bin/python3
"""test_profile_kinds.py - the default limits fit every kind of object (issue 12
item 4): on each kind of track, replayed by trajreplay with the default
settings (profile auto) and with the profile that matches it, at most 1 % of
the good fixes is refused; profile machine keeps every point of a toolpath
timed by feed rate, and its curve is scipy's CubicSpline through them.

The kinds, and where their fixes come from:
  hiking (GPX)        the real walks tests/data/gpxgo_visnjan.gpx and
                      gpxpy_cerknicko-jezero.csv (tests/data/ATTRIBUTION.md);
                      matching profile: road
  vessel (NMEA 2000)  the real 5 Hz figure-eight n2k_furuno_figure8_src52.csv
                      and the candump capture canboat_candumpSample3.log;
                      profile vessel
  airliner (ADS-B)    built here: 1 Hz fixes of a flight at 200..250 m/s
                      (pyproj.Geod steps along the heading), climbs at 10 m/s,
                      rate-one-half turns (1.5 deg/s) rolled in over 5 s, a
                      descent; received as a ground station logs them: 12 % of
                      the fixes lost, each stamped on arrival 0..0.2 s after
                      it was fixed (ADS-B's uncompensated latency), positions
                      on the airborne CPR grid (360 / (60 * 2^17) deg, 5 m)
                      and altitudes in 25 ft steps; profile air
  glider (IGC)        built here: an IGC file (B records, whole seconds,
                      thousandths of a minute: 1.9 m) of glides at 25..40 m/s
                      and thermals (circles of 60 m radius at 25 m/s: 10 m/s^2,
                      a 46 deg bank, climbing 2 m/s, drifting with a 5 m/s
                      wind); profile air
  toolpath (G-code)   a G-code program (pockets, fillets and circles with
                      G2/G3, a surfacing pass of 0.25 mm moves, a raster
                      of 0.2 mm zigzags at F9000, plunges and rapids) read
                      by LinuxCNC's own interpreter (rs274 -g, Debian
                      linuxcnc-uspace) and timed by its feed rates
                      here: each canonical move at its F (rapids at 5000
                      mm/min), arcs cut into chords of 0.002 mm sagitta; the
                      velocity steps at every corner and feed change, as a
                      toolpath timed by feed rate does; profile machine
"Good fixes": on the generated tracks every fix is good by construction; on
the real ones, every fix counts as good (the bound is then on all of them).
Limits checked: refused <= 1 % of the fixes (--summary's rejected over
waypoints), and profile machine refuses none; the airliner streams within
its profile's numbers under auto and air (peak speed and acceleration of
the output at most 400 m/s and 30 m/s^2, issue 27).  Control: profile road (no
free turns, 100 m/s) refuses more than 1 % of the airliner and of the
toolpath, so the tracks do tell limits apart.
"""
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pyproj
from scipy.interpolate import CubicSpline

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_trajreplay as tr  # noqa: E402  (replay, run, read_setpoints, checks)

MAX_REFUSED = 0.01
O_DEFAULT = 24  # engine.h: the overlap the default accuracy picks; fragment bound 100 * 0.268^(O/2)
GEOD = pyproj.Geod(ellps="WGS84")
G = 9.80665


def airliner(path, seed=1):
    """A 1 Hz ADS-B track as a ground station logs it (see the module doc)."""
    rnd = random.Random(seed)
    # (duration s, target speed m/s, vertical m/s, turn deg/s): a climb, turns,
    # cruise, a step climb, a descent with turns
    legs = [(600, 235, 10, 0), (60, 235, 8, 1.5), (300, 245, 5, 0), (90, 245, 0, -1.5),
            (900, 250, 0, 0), (120, 250, 0, 0.8), (200, 250, 5, 0), (600, 250, 0, 0),
            (500, 230, -8, 0), (120, 225, -6, -1.5), (300, 220, -5, 0), (60, 220, -4, 1.5),
            (200, 215, -4, 0)]
    lat, lon, h, v, hdg, rate = 47.0, 8.0, 1500.0, 200.0, 40.0, 0.0
    cpr = 360.0 / (60 * 2 ** 17)
    rows, t = [], 0.0
    dt = 0.1  # integration step
    for dur, vt, vz, turn in legs:
        for _ in range(int(round(dur / dt))):
            # roll in/out over 5 s, speed changes at 0.5 m/s^2 at most
            rate += max(-0.3 * dt, min(0.3 * dt, turn - rate))
            v += max(-0.5 * dt, min(0.5 * dt, vt - v))
            hdg = (hdg + rate * dt) % 360
            lon, lat, _ = GEOD.fwd(lon, lat, hdg, v * dt)
            h += vz * dt
            t += dt
            if abs(t - round(t)) < dt / 2 and rnd.random() > 0.12:
                stamp = round(t) + rnd.uniform(0.0, 0.2)
                rows.append((stamp, round(lat / cpr) * cpr, round(lon / cpr) * cpr,
                             round(h / 0.3048 / 25) * 25 * 0.3048))
    with open(path, "w") as f:
        f.write("t_s,lat_deg,lon_deg,alt_m\n")
        for r in rows:
            f.write("%.3f,%.9f,%.9f,%.2f\n" % r)
    return len(rows)


def igc_coord(x, pos, neg, width):
    s = pos if x >= 0 else neg
    x = abs(x)
    d = int(x)
    m = round((x - d) * 60000)
    if m == 60000:
        d, m = d + 1, 0
    return "%0*d%05d%s" % (width, d, m, s)


def glider(path):
    """An IGC flight log of glides and thermals (see the module doc)."""
    lat, lon, h, hdg = 46.3, 13.5, 1200.0, 90.0
    wind_to, wind = 70.0, 5.0
    # (duration s, speed m/s, sink m/s, turn rate deg/s)
    r_th, v_th = 60.0, 25.0
    w_th = math.degrees(v_th / r_th)
    legs = [(300, 30, -1.0, 0), (240, v_th, 2.0, w_th), (400, 40, -1.5, 0),
            (60, 35, -1.2, -3), (300, v_th, 2.5, -w_th), (500, 32, -1.0, 0)]
    lines = ["AXXX001 synthetic glider", "HFDTE150724"]
    t0 = 12 * 3600
    t, dt, rate, v = 0.0, 0.1, 0.0, 30.0
    for dur, vt, vz, turn in legs:
        for _ in range(int(round(dur / dt))):
            rate += max(-10 * dt, min(10 * dt, turn - rate))  # roll in over ~2.5 s
            v += max(-1.0 * dt, min(1.0 * dt, vt - v))
            hdg = (hdg + rate * dt) % 360
            lon, lat, _ = GEOD.fwd(lon, lat, hdg, v * dt)
            lon, lat, _ = GEOD.fwd(lon, lat, wind_to, wind * dt)
            h += vz * dt
            t += dt
            if abs(t - round(t)) < dt / 2:
                s = t0 + int(round(t))
                lines.append("B%02d%02d%02d%s%sA%05d%05d" % (
                    s // 3600, s // 60 % 60, s % 60, igc_coord(lat, "N", "S", 2),
                    igc_coord(lon, "E", "W", 3), int(round(h)) - 20, int(round(h))))
    with open(path, "w") as f:
        f.write("\r\n".join(lines) + "\r\n")
    return len(lines) - 2


GCODE = """(a toolpath: pocket, fillets, circle, surfacing, contour)
G21 G17 G90 G94
G0 Z5
G0 X0 Y0
G0 Z0.5
G1 Z-1 F150
(pocket: zigzag with fillets)
#1 = 0
O100 while [#1 LT 8]
  G1 X38 Y[#1 * 4] F1200
  G3 X40 Y[#1 * 4 + 2] R2 F800
  G1 X40 Y[#1 * 4 + 2] F1200
  G3 X38 Y[#1 * 4 + 4] R2 F800
  G1 X2 F1200
  G2 X0 Y[#1 * 4 + 6] R2 F800
  G1 Y[#1 * 4 + 6]
  #1 = [#1 + 1.5]
O100 endwhile
G0 Z5
(circle and a helix down)
G0 X70 Y20
G1 Z-0.5 F150
G2 X70 Y20 I-10 J0 F900
G2 X70 Y20 Z-1.5 I-10 J0 F600
G3 X60 Y30 R10 F900
G0 Z5
(surfacing: short moves along a wave, as CAM writes them)
G0 X0 Y50
G1 Z-0.2 F300
#2 = 0
O200 while [#2 LT 320]
  G1 X[#2 * 0.25] Y[50 + 3 * SIN[#2 * 2.25]] Z[-0.2 - 0.3 * COS[#2 * 4.5]] F2000
  #2 = [#2 + 1]
O200 endwhile
G1 Y58 F1000
#2 = 320
O300 while [#2 GT 0]
  G1 X[#2 * 0.25] Y[58 + 3 * SIN[#2 * 2.25]] Z[-0.2 - 0.3 * COS[#2 * 4.5]] F2000
  #2 = [#2 - 1]
O300 endwhile
G0 Z5
(finishing contour: lines and fillets of 1 mm at a low feed)
G0 X-2 Y-2
G1 Z-1 F150
G1 X41 F400
G3 X42 Y-1 R1
G1 Y40
G3 X41 Y41 R1
G1 X-1
G3 X-2 Y40 R1
G1 Y-2
G0 Z5
(high-speed raster: 0.2 mm zigzag steps at F9000, sharp corners)
G0 X60 Y60
G1 Z-0.1 F300
#3 = 0
O400 while [#3 LT 200]
  G1 X[60 + #3 * 0.2] Y[60 + [#3 MOD 2] * 0.2] F9000
  #3 = [#3 + 1]
O400 endwhile
G0 Z5
M2
"""


def arc_points(p0, end, centre, rot, z1, tol):
    """Chords of the arc p0 -> end about centre (rot > 0 ccw, < 0 cw, |rot| - 1
    extra turns), z linear in angle, no chord's sagitta above tol."""
    r = math.hypot(p0[0] - centre[0], p0[1] - centre[1])
    a0 = math.atan2(p0[1] - centre[1], p0[0] - centre[0])
    a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
    if rot > 0:
        sweep = (a1 - a0) % (2 * math.pi)
        if sweep < 1e-12:
            sweep = 2 * math.pi
        sweep += 2 * math.pi * (rot - 1)
    else:
        sweep = -((a0 - a1) % (2 * math.pi))
        if sweep > -1e-12:
            sweep = -2 * math.pi
        sweep -= 2 * math.pi * (-rot - 1)
    dmax = 2 * math.acos(max(-1.0, 1 - tol / r))
    n = max(1, math.ceil(abs(sweep) / dmax))
    return [(centre[0] + r * math.cos(a0 + sweep * k / n), centre[1] + r * math.sin(a0 + sweep * k / n),
             p0[2] + (z1 - p0[2]) * k / n) for k in range(1, n + 1)]


def toolpath(path, tmp):
    """The G-code above through rs274, timed by feed rate; xyz CSV in metres."""
    ngc = os.path.join(tmp, "toolpath.ngc")
    with open(ngc, "w") as f:
        f.write(GCODE)
    p = subprocess.run(["rs274", "-g", ngc], capture_output=True, text=True, timeout=60,
                       stdin=subprocess.DEVNULL)
    pos, feed, t = (0.0, 0.0, 0.0), None, 0.0
    pts = []
    rapid = 5000.0
    for line in p.stdout.splitlines():
        if "(" not in line:
            continue
        name, args = line.split("N.....", 1)[-1].strip().split("(", 1)
        args = [a.strip() for a in args.rstrip(")").split(",")]
        if name == "SET_FEED_RATE":
            feed = float(args[0])
        elif name in ("STRAIGHT_FEED", "STRAIGHT_TRAVERSE"):
            q = tuple(float(a) for a in args[:3])
            v = (rapid if name == "STRAIGHT_TRAVERSE" else feed) / 60.0
            d = math.dist(pos, q)
            if d > 0:
                t += d / v
                pts.append((t, q))
            pos = q
        elif name == "ARC_FEED":
            e1, e2, c1, c2, rot, z1 = (float(a) for a in args[:6])
            v = feed / 60.0
            for q in arc_points(pos, (e1, e2), (c1, c2), int(rot), z1, 0.002):
                t += math.dist(pos, q) / v
                pts.append((t, q))
                pos = q
    tr.check(p.returncode == 0 and len(pts) > 1000,
             f"rs274: exit {p.returncode}, {len(pts)} points: {p.stderr[-300:]}")
    with open(path, "w") as f:
        f.write("t_s,x_m,y_m,z_m\n")
        f.write("0,0,0,0\n")
        for t, q in pts:
            f.write("%.9f,%.9g,%.9g,%.9g\n" % (t, q[0] / 1e3, q[1] / 1e3, q[2] / 1e3))
    return len(pts) + 1


def refused(track, extra, tmp):
    """(waypoints, rejected, accepted, duplicates) of a replay with --summary."""
    p = tr.run(["--summary", "-q", "-o", "/dev/null"] + extra + [track])
    tr.check(p.returncode == 0, f"{os.path.basename(track)} {extra}: exit {p.returncode}: "
             f"{p.stderr[-300:]}")
    s = tr.replay_summary.parse(p.stderr)
    return tuple(int(s.get(k, -1)) for k in ("waypoints", "rejected", "accepted", "duplicates"))


def test_kinds(tmp):
    air = os.path.join(tmp, "airliner.csv")
    gli = os.path.join(tmp, "glider.igc")
    gco = os.path.join(tmp, "toolpath.csv")
    airliner(air)
    glider(gli)
    toolpath(gco, tmp)
    kinds = [("hiking", tr.VISNJAN_GPX, "road"), ("hiking", tr.CERKNICA, "road"),
             ("vessel", tr.FIGURE8, "vessel"),
             ("vessel", os.path.join(tr.DATA, "canboat_candumpSample3.log"), "vessel"),
             ("airliner", air, "air"), ("glider", gli, "air"), ("toolpath", gco, "machine")]
    seen = {}
    for kind, track, profile in kinds:
        for prof in ("auto", profile):
            n, rej, acc, dup = refused(track, ["--profile", prof], tmp)
            seen[(kind, os.path.basename(track), prof)] = (n, rej)
            frac = rej / n if n > 0 else 1
            print(f"{kind} {os.path.basename(track)} profile {prof}: {rej} of {n} refused "
                  f"({100 * frac:.2f} %), {acc} kept, {dup} duplicates")
            tr.check(n > 100 and acc + rej + dup == n, f"{kind} {prof}: counts {n} {rej} {acc} {dup}")
            tr.check(frac <= MAX_REFUSED, f"{kind} {os.path.basename(track)} profile {prof}: "
                     f"{rej} of {n} refused ({100 * frac:.2f} % > 1 %)")
            if prof == "machine":
                tr.check(rej == 0 and acc == n, f"{kind} machine: {rej} refused, {acc} of {n} kept")
    # the tracks are hard enough to tell limits apart: absolute limits for a
    # road vehicle (100 m/s, 30 m/s^2 with no free turns) refuse the airliner
    # and the toolpath's corners
    for kind, track in (("airliner", air), ("toolpath", gco)):
        n, rej, acc, dup = refused(track, ["--profile", "road"], tmp)
        print(f"{kind} profile road (control): {rej} of {n} refused ({100 * rej / n:.2f} %)")
        tr.check(rej > MAX_REFUSED * n, f"{kind} profile road: only {rej} of {n} refused")
        seen[(kind, "control", "road")] = (n, rej)
    doc_table_is_this_run(seen)
    return gco


BUILT = {"airliner": "airliner.csv", "glider": "glider.igc", "toolpath": "toolpath.csv"}


def same_share(shown, n, rej, what):
    """shown ('0.34 %', '6.3 %', '0 %') is 100 rej / n as rounded there."""
    num = shown.split()[0]
    decimals = len(num.split(".")[1]) if "." in num else 0
    tr.check("%.*f" % (decimals, 100 * rej / n) == num, f"lib/engine/DESIGN.md {what}: {shown} "
             f"stale, the run refuses {rej} of {n}")


def doc_table_is_this_run(seen):
    """lib/engine/DESIGN.md's profile table and control sentence are this run's
    (issue 14: no stale numbers): points, share refused (and the count given
    in parentheses) per profile."""
    import re
    with open(os.path.join(tr.DATA, "..", "..", "lib", "engine", "DESIGN.md"), encoding="utf-8") as f:
        doc = f.read()
    head = doc.index("| kind | track | points | auto | matching profile |")
    rows = doc[head:doc.index("\n\n", head)].split("\n")[2:]
    tr.check(len(rows) == 7, f"lib/engine/DESIGN.md profile table: {len(rows)} rows")
    for row in rows:
        kind, track, points, auto, match = [c.strip() for c in row.strip("|").split("|")]
        kind = kind.split()[0]
        name = BUILT.get(kind, track)
        prof = match.split()[0]
        for p, cell in (("auto", auto), (prof, match.split(" ", 1)[1])):
            n, rej = seen.get((kind, name, p), (-1, -1))
            tr.check(int(points) == n, f"lib/engine/DESIGN.md {kind} {name}: {points} points, run {n}")
            same_share(cell, n, rej, f"{kind} {name} {p}")
            count = re.search(r"\((\d+)", cell)
            tr.check(count is None or int(count.group(1)) == rej,
                     f"lib/engine/DESIGN.md {kind} {name} {p}: {cell}, run refuses {rej}")
    air, tool = re.search(r"`road`'s absolute limits refuse (\S+ %) of the airliner\s+\(100 m/s\) "
                          r"and (\S+ %) of the toolpath", doc).groups()
    same_share(air, *seen[("airliner", "control", "road")], "airliner road")
    same_share(tool, *seen[("toolpath", "control", "road")], "toolpath road")


def test_airliner_stale_then_jumps(tmp):
    """The issue's first track: an ADS-B airliner whose positions freeze, then
    jump.  Into the built flight, 4 runs of 10, 30, 20 and 15 fixes repeat the
    fix before them (lat, lon and altitude: what a receiver re-sends when the
    aircraft's position stops updating) with their own stamps.  Replayed at
    10 Hz with the default and with profile air: exit 0, exactly the repeats
    refused (as stale, every stale line one of theirs), every good fix kept
    (>= 99 % with the default profile since issue 27: it holds changes of
    speed to 30 m/s^2, and re-stamps most jittered fixes but not all), none
    of the fixes the runs repeat refused (the frozen copies, stamped later,
    outvoted the fix they copy: 4 good fixes were refused, 'accel')."""
    air = os.path.join(tmp, "airliner.csv")
    frozen_path = os.path.join(tmp, "airliner_frozen.csv")
    airliner(air)
    with open(air) as f:
        header, rows = f.readline(), f.read().splitlines()
    runs = {400: 10, 1200: 30, 2000: 20, 2800: 15}
    out, repeat_lines, i = [], set(), 0
    while i < len(rows):
        if i in runs:
            src = rows[i - 1].split(",")
            for j in range(i, i + runs[i]):
                repeat_lines.add(len(out) + 2)
                out.append(",".join([rows[j].split(",")[0]] + src[1:]))
            i += runs[i]
            continue
        out.append(rows[i])
        i += 1
    with open(frozen_path, "w") as f:
        f.write(header + "\n".join(out) + "\n")
    good = len(out) - len(repeat_lines)
    for prof in ("auto", "air"):
        p = tr.run(["--summary", "--rate", "10", "--profile", prof, "-o", "/dev/null", frozen_path])
        s = tr.replay_summary.parse(p.stderr)
        lines = {}
        for line in p.stderr.splitlines():
            if ": rejected (" in line:
                where, why = line.split(": rejected (")
                lines[int(where.rsplit(":", 1)[1])] = why.rstrip(")")
        label = f"airliner frozen then jumps, profile {prof}"
        print(f"{label}: exit {p.returncode}, {int(s.get('accepted', -1))} of {good} good fixes kept, "
              f"{int(s.get('rejected_stale', -1))} of {len(repeat_lines)} repeats refused as stale, "
              f"{int(s.get('rejected', -1))} refused in all")
        tr.check(p.returncode == 0, f"{label}: exit {p.returncode}: {p.stderr[-300:]}")
        # issue 27: the default profile holds a change of speed along the
        # track to max_accel_m_s2 (turns stay free) and re-stamps a fix whose
        # stamp is off; of the good fixes >= 99 % are kept (a few whose
        # jitter, 0..0.2 s at 1 Hz, no re-stamping absorbs are refused)
        tr.check(s.get("accepted") >= 0.99 * good and
                 s.get("rejected_stale") == len(repeat_lines) and
                 s.get("accepted") + s.get("rejected") == len(out), f"{label}: --summary {s}")
        stale = {l for l, w in lines.items() if w == "stale"}
        tr.check(lines and stale <= repeat_lines, f"{label}: reported {lines}")
        sources = {min(repeat_lines, key=lambda l: abs(l - (i + 2))) - 1 for i in runs}
        tr.check(not sources & set(lines), f"{label}: a fix a run repeats was refused: {lines}")


# lib/engine/engine_settings.c profile_limits (engine.h engine_profile_t):
# speed m/s, acceleration m/s^2
LIMITS = {"auto": (400.0, 30.0), "air": (400.0, 30.0)}


def test_airliner_streamed_within_limits(tmp):
    """Issue 27: the built airliner, replayed with the default profile and
    with profile air, streams within the profile's numbers: peak speed and
    peak acceleration (the norms of the output's vx/vy/vz and ax/ay/az
    columns, every row) at most the profile's limits, and >= 99 % of its
    fixes kept (every one is good).  Its stamps are times of arrival (0..0.2 s
    late): forced through each fix at its stamp, the curve reached 111.7
    m/s^2 (auto, 5 refused) and 255.7 (air); the fixes are re-stamped at the
    pace of the track instead (retime.c, ACCEPT_RULE_SMOOTH).  Six seeds of
    the same flight: the curve through the re-stamped fixes still bends up to
    31 m/s^2 in turns on the 5 m CPR grid (seeds 2, 4, 5 streamed up to 31.0,
    30.5 and 30.5 before), so the time scaling slows the output there along
    its path to keep its acceleration within the limit (engine_solve.c
    seg_ceiling: k'' r^2 within the limit less scale_accel_m_s2).  Issue 27."""
    for seed in range(1, 7):
        airliner_within_limits(tmp, seed)


def airliner_within_limits(tmp, seed):
    air = os.path.join(tmp, "airliner.csv")
    n = airliner(air, seed)
    # the floor the positions set: scipy's spline through the fixes at their
    # true times (whole seconds: the floor of the stamps), east/north/up
    # about the first fix (printed, not checked: the CPR grid and the 25 ft
    # steps alone bend the curve so much; lib/engine/DESIGN.md "Profiles")
    fx = np.genfromtxt(air, delimiter=",", names=True)
    enu = pyproj.Proj(proj="aeqd", lat_0=fx["lat_deg"][0], lon_0=fx["lon_deg"][0], datum="WGS84")
    east, north = enu(fx["lon_deg"], fx["lat_deg"])
    cs = CubicSpline(np.floor(fx["t_s"]), np.c_[east, north, fx["alt_m"]])
    tt = np.arange(np.floor(fx["t_s"][0]), np.floor(fx["t_s"][-1]), 0.01)
    a_true = np.linalg.norm(cs(tt, 2), axis=1)
    print(f"airliner seed {seed}: scipy CubicSpline through its fixes at their true times peaks at "
          f"{a_true.max():.1f} m/s^2 (t = {tt[a_true.argmax()]:.0f} s)")
    for prof in ("auto", "air"):
        vmax, amax = LIMITS[prof]
        sp, s, _ = tr.replay(air, ["--profile", prof], tmp, "airliner_" + prof)
        label = f"airliner seed {seed} streamed, profile {prof}"
        tr.check_positions(sp, label)
        acc = float(np.max(np.linalg.norm(sp["acc"], axis=1)))
        spd = float(np.max(np.linalg.norm(sp["vel"], axis=1)))
        kept = int(s.get("accepted", -1))
        print(f"{label}: peak speed {spd:.1f} m/s (limit {vmax:g}), "
              f"peak acceleration {acc:.1f} m/s^2 (limit {amax:g}), "
              f"{kept} of {n} fixes kept, {int(s.get('retimed', -1))} re-stamped "
              f"(at most {s.get('retime_max_s', -1):.3f} s)")
        tr.check(spd <= vmax, f"{label}: peak speed {spd:.1f} m/s > {vmax:g}")
        tr.check(acc <= amax, f"{label}: peak acceleration {acc:.1f} m/s^2 > {amax:g}")
        tr.check(kept >= 0.99 * n, f"{label}: {kept} of {n} fixes kept")


def test_machine_curve(tmp, gco):
    """profile machine: the curve passes through every toolpath point: scipy's
    CubicSpline through all of them (rest ends) on every streamed row the
    time scaling left alone (a toolpath's long slow lines after its short
    fast chords empty the time-based lookahead: the output slows down there,
    flagged SCALED or UNDERRUN, which the hit test below does not need)."""
    with open(gco) as f:
        next(f)
        pts = np.array([[float(x) for x in line.split(",")] for line in f])
    sp, s, _ = tr.replay(gco, ["--profile", "machine"], tmp, "toolpath_machine")  # not over its own input
    tr.check_positions(sp, "toolpath machine")
    ok = np.array([x == "streaming" for x in sp["state"]]) & ((sp["flags"] & tr.ENGINE_SP_SCALED) == 0)
    cs = CubicSpline(pts[:, 0], pts[:, 1:], bc_type="clamped")
    err = tr.spline_errors(sp, cs, ok)
    tol = 100 * 0.268 ** (O_DEFAULT / 2)
    print("toolpath machine: vs scipy CubicSpline through all %d points, on %d of %d rows: %s "
          "relative (bound %.2g)" % (len(pts), int(ok.sum()), len(ok),
                                    ", ".join(f"{k} {v:.2g}" for k, v in err.items()), tol))
    tr.check(ok.sum() > len(ok) / 2, f"toolpath machine: {int(ok.sum())} of {len(ok)} rows unscaled")
    for k, v in err.items():
        tr.check(v <= tol, f"toolpath machine: {k} differs from CubicSpline by {v:g} relative")
    tr.check(sp["state"][-1] == "finished" and np.max(np.abs(sp["pos"][-1] - pts[-1, 1:])) < 1e-9,
             "toolpath machine: not finished on the last point")


def main():
    if not os.access(tr.TRAJREPLAY, os.X_OK):
        print(f"{tr.TRAJREPLAY} not built")
        return 1
    if not shutil.which("rs274"):
        print("rs274 (Debian linuxcnc-uspace, tests/deps.sh) not installed")
        return 1
    with tempfile.TemporaryDirectory(prefix="profile-kinds-") as tmp:
        gco = test_kinds(tmp)
        test_machine_curve(tmp, gco)
        test_airliner_stale_then_jumps(tmp)
        test_airliner_streamed_within_limits(tmp)
    print(f"test_profile_kinds.py: {len(tr.failures)} failure(s)")
    return 1 if tr.failures else 0


if __name__ == "__main__":
    sys.exit(main())
