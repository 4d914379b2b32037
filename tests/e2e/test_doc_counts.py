"""test_doc_counts.py - the counts and figures that a deterministic run gives,
as the docs state them, are those of that run (issue 14: no stale numbers).

Each check reads the number out of the doc's text (so a stale doc fails
here) and compares it with a real run of the product: trajreplay, the way
the doc says to run it.

The table under "**Measured.**" in daemon/REFERENCE.md's trajreplay part gives,
per bundled track, what `trajreplay --summary -o FILE TRACK` (default
settings) reports: waypoints read, accepted, gaps, setpoints, and the CSV's
size in bytes.  Each row is replayed here and compared exactly.
"""
import importlib.util
import math
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import replay_summary  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))


def table_rows():
    """[(track, {column: int})] of the table whose header starts '| track | read |'."""
    with open(os.path.join(ROOT, "daemon", "REFERENCE.md"), encoding="utf-8") as f:
        lines = f.read().split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("| track | read |"))
    head = [c.strip() for c in lines[start].strip("|").split("|")]
    rows = []
    for l in lines[start + 2:]:
        if not l.startswith("|"):
            break
        cells = [c.strip() for c in l.strip("|").split("|")]
        track = cells[0].strip("`")
        rows.append((track, {h: int(re.sub(r"[ ,]", "", c)) for h, c in zip(head[1:], cells[1:])}))
    return rows


def read(path):
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        return f.read()


def grab(text, pattern):
    """The groups of the one match of pattern in text (a doc rephrased so
    that the claim is gone fails here: remove the check with the claim)."""
    found = re.findall(pattern, text, re.S)
    assert len(found) == 1, "%r: %d matches, want 1" % (pattern, len(found))
    return found[0]


def trajreplay(args, cwd=None):
    """stderr of trajreplay ARGS (relative tests/data paths as from the root)."""
    args = [os.path.join(ROOT, a) if a.startswith("tests/data/") else a for a in args]
    r = subprocess.run([os.path.join(BUILD, "bin", "trajreplay")] + args, cwd=cwd,
                       capture_output=True, text=True, check=True)
    return r.stderr


_RUNS = {}


def replay(track, *opts):
    """(summary dict, setpoint records) of trajreplay --binary on tests/data/TRACK
    with OPTS at the default 100 Hz, run once per test process."""
    import numpy as np
    key = (track,) + opts
    if key not in _RUNS:
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "out.bin")
            err = trajreplay(["-q", "--summary", "--binary", "-o", out] + list(opts)
                             + ["tests/data/" + track])
            dt = np.dtype([("now_ns", "<i8"), ("t_s", "<f8"), ("pos_m", "<f8", 3),
                           ("vel_m_s", "<f8", 3), ("acc_m_s2", "<f8", 3), ("state", "<u4"),
                           ("flags", "<u4"), ("cycle", "<u4"), ("track", "<u4"), ("reserved", "<u8")])
            _RUNS[key] = (replay_summary.parse(err), np.fromfile(out, dtype=dt, offset=64), err)
    return _RUNS[key]


def peak(rows, field, mask=None):
    """(largest |field| of the rows where mask, its track time)."""
    import numpy as np
    mag = np.linalg.norm(rows[field], axis=1)
    if mask is not None:
        mag = np.where(mask, mag, 0.0)
    i = int(np.nanargmax(mag))
    return float(mag[i]), float(rows["t_s"][i])


def start_lookahead(*opts):
    """Lookahead in waypoints of trajreplay OPTS on regular input (a 1 Hz circle,
    100 waypoints): the output starts (lookahead + 1) intervals after the first
    waypoint (lib/engine/DESIGN.md)."""
    with tempfile.TemporaryDirectory() as tmp:
        track, out = os.path.join(tmp, "circle.csv"), os.path.join(tmp, "out.csv")
        with open(track, "w", encoding="utf-8") as f:
            f.write("t,x,y,z\n" + "".join("%d,%.6f,%.6f,0\n" % (i, 50 * math.cos(i / 20), 50 * math.sin(i / 20))
                                          for i in range(100)))
        trajreplay(["-q", "--rate", "10", "-o", out] + list(opts) + [track])
        with open(out, encoding="utf-8") as f:
            states = [l.split(",")[12] for l in f.read().split("\n")[1:-1]]
    start = next(i for i, st in enumerate(states) if st != "waiting")
    assert start % 10 == 0, start
    return start // 10 - 1


def enu(path):
    """(t, east/north/up) of a lat/lon CSV track about its first fix: pyproj's geodetic -> ECEF,
    then the local rotation (a missing altitude is 0, as trajreplay reads it)."""
    import numpy as np
    from pyproj import Transformer
    d = np.genfromtxt(path, delimiter=",", names=True)
    lat, lon, alt = d["lat_deg"], d["lon_deg"], np.nan_to_num(d["alt_m"])
    x, y, z = Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True).transform(lon, lat, alt)
    p = np.c_[x, y, z] - [x[0], y[0], z[0]]
    la, lo = np.radians(lat[0]), np.radians(lon[0])
    rot = np.array([[-np.sin(lo), np.cos(lo), 0],
                    [-np.sin(la) * np.cos(lo), -np.sin(la) * np.sin(lo), np.cos(la)],
                    [np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)]])
    return d["t_s"], p @ rot.T


def summary(track, out):
    r = subprocess.run([os.path.join(BUILD, "bin", "trajreplay"), "--summary", "-q", "-o", out,
                        os.path.join(ROOT, "tests", "data", track)],
                       capture_output=True, text=True, check=True)
    return replay_summary.parse(r.stderr)


class DocCounts(unittest.TestCase):
    def test_trajreplay_table(self):
        rows = table_rows()
        self.assertGreaterEqual(len(rows), 3)
        with tempfile.TemporaryDirectory() as tmp:
            for track, want in rows:
                out = os.path.join(tmp, "out.csv")
                s = summary(track, out)
                got = {"read": int(s["waypoints"]), "accepted": int(s["accepted"]),
                       "gaps": int(s["gaps"]), "setpoints": int(s["setpoints"]),
                       "CSV bytes": os.path.getsize(out)}
                self.assertEqual(got, want, "daemon/REFERENCE.md's row for %s is stale" % track)

    def test_smooth_table(self):
        """lib/spline/TOOLKIT.md: visnjan at 10 Hz, cubic and smooth: path length,
        p99 speed, p99 and max acceleration, as the doc rounds them."""
        import numpy as np
        with open(os.path.join(ROOT, "lib", "spline", "TOOLKIT.md"), encoding="utf-8") as f:
            doc = f.read()
        runs = {}
        with tempfile.TemporaryDirectory() as tmp:
            for method, label in (("cubic", "cubic (exact)"), ("smooth", "smooth (")):
                row = next(l for l in doc.split("\n") if l.startswith("| " + label))
                want = [float(x) for x in re.findall(r"\| ([0-9.]+) m", row)]
                out = os.path.join(tmp, method + ".csv")
                subprocess.run([os.path.join(BUILD, "bin", "trajreplay"), "-q", "--rate", "10",
                                "--method", method, "-o", out,
                                os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.csv")], check=True)
                d = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding=None)
                v = np.hypot(d["vx_m_s"], d["vy_m_s"])
                a = np.hypot(d["ax_m_s2"], d["ay_m_s2"])
                got = [round(float(np.nansum(np.hypot(np.diff(d["x_m"]), np.diff(d["y_m"]))))),
                       round(float(np.nanpercentile(v, 99)), 2), round(float(np.nanpercentile(a, 99)), 2),
                       round(float(np.nanmax(a)), 2)]
                self.assertEqual(got, want, "lib/spline/TOOLKIT.md's %s row is stale" % method)
                runs[method] = d
        # "At the fixes' own times the smoothed curve is a median 2.5 m from the fix (95 %: 7.4 m,
        # max 12.8 m)": the fixes are where the exact cubic passes at their times
        med, p95, worst = grab(doc, r"the smoothed curve is a median (\S+) m from the fix \(95 %:\s+(\S+) m, "
                                    r"max (\S+) m\)")
        fixes = np.genfromtxt(os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.csv"), delimiter=",",
                              names=True)["t_s"]

        def at_fixes(d):
            d = d[np.isfinite(d["x_m"])]
            d = d[np.r_[True, np.diff(d["t_s"]) > 0]]
            return np.c_[np.interp(fixes, d["t_s"], d["x_m"]), np.interp(fixes, d["t_s"], d["y_m"])]
        dist = np.linalg.norm(at_fixes(runs["smooth"]) - at_fixes(runs["cubic"]), axis=1)
        self.assertEqual(["%.1f" % x for x in (np.median(dist), np.percentile(dist, 95), dist.max())],
                         [med, p95, worst], "lib/spline/TOOLKIT.md's distances to the fixes are stale")

    def test_lsq_demo(self):
        """lib/spline/TOOLKIT.md's table of tests/pictures/make_pictures.py's least-squares demo
        (the library's cspline and lsq on its seeded track; the pictures are not written)."""
        doc = read("lib/spline/TOOLKIT.md")
        want = [re.findall(r"\| ([\d.]+) m", l) for l in doc.split("\n")
                if l.startswith("| exact cubic spline through every fix |")
                or l.startswith("| least-squares cubic B-spline, 14 control points")]
        self.assertEqual([len(w) for w in want], [3, 3])
        sys.path.insert(0, os.path.join(ROOT, "tests", "pictures"))
        os.environ.setdefault("BUILD", BUILD)
        import make_pictures
        make_pictures.Svg.save = lambda self, name: None
        se, de, re_, ss, ds, rs = make_pictures.pic_lsq()
        got = [["%.1f" % se, "%.2f" % de, "%.2f" % re_], ["%.1f" % ss, "%.2f" % ds, "%.2f" % rs]]
        self.assertEqual(got, want)


class DaemonReadme(unittest.TestCase):
    """daemon/REFERENCE.md's trajreplay part."""

    def test_figure_eight_example(self):
        """The example session (trajreplay at 10 Hz on the figure-eight, then
        sed on its CSV): every summary line and every row it shows."""
        doc = read("daemon/REFERENCE.md").split("\n")
        start = next(i for i, l in enumerate(doc) if l.startswith("    $ trajreplay --rate 10"))
        block = []
        for l in doc[start:]:
            if not l.startswith("    "):
                break
            block.append(l[4:])
        cmds = [i for i, l in enumerate(block) if l.startswith("$ ")]
        self.assertEqual(len(cmds), 2)
        with tempfile.TemporaryDirectory() as tmp:
            err = trajreplay(block[0][2:].split()[1:] + ["-q"], cwd=tmp)
            got = dict(re.findall(r"^summary: (\S+) (\S+)$", err, re.M))
            shown = [re.match(r"summary: (\S+) (\S+)", l).groups()
                     for l in block[1:cmds[1]] if l.startswith("summary:")]
            self.assertGreaterEqual(len(shown), 10)
            for k, v in shown:
                self.assertEqual(got.get(k), v, "daemon/REFERENCE.md's example: summary %s is stale" % k)
            rows = subprocess.run(block[cmds[1]][2:], shell=True, cwd=tmp, capture_output=True,
                                  text=True, check=True).stdout.split("\n")[:-1]
            self.assertEqual(rows, block[cmds[1] + 1:], "daemon/REFERENCE.md's example rows are stale")
            with open(os.path.join(tmp, "f8.csv"), encoding="utf-8") as f:
                states = [l.split(",")[12] for l in f.read().split("\n")[1:-1]]
        # "...: 48 ticks (4.8 s, 24 waypoints at 5 Hz; 66 with the former F=32/O=16 ...)"
        doc = read("daemon/REFERENCE.md")
        now, former = grab(doc, r"end waypoint: (\d+) ticks\s*\(.*?; (\d+) with the former")
        self.assertEqual(states.index("streaming"), int(now))
        self.assertEqual(set(states[:int(now)]), {"waiting"})
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "old.csv")
            trajreplay(["-q", "--rate", "10", "--fragment", "32", "--overlap", "16", "--start-slack",
                        "8", "-o", out, "tests/data/n2k_furuno_figure8_src52.csv"])
            with open(out, encoding="utf-8") as f:
                states = [l.split(",")[12] for l in f.read().split("\n")[1:-1]]
        self.assertEqual(states.index("streaming"), int(former))

    def test_flags_listed(self):
        """'`flags` are `ENGINE_SP_*` of `lib/motion.h`: 1 hold, 2 ...': every
        flag of lib/motion.h, with its value, and no other."""
        text = grab(read("daemon/REFERENCE.md"), r"`flags` are `ENGINE_SP_\*` of `lib/motion.h`:(.*?)\n\n")
        listed = sorted(int(v) for v in re.findall(r"(?:^|, )(\d+) [a-z]", " ".join(text.split())))
        defined = sorted(int(v, 16) for v in re.findall(r"#define ENGINE_SP_\w+\s+0x([0-9a-f]+)u",
                                                        read("lib/motion.h")))
        self.assertEqual(listed, defined)

    def test_waypoint_bytes(self):
        """'the waypoints, which take 68 bytes each (`engine_waypoint_t` ... and its line number;
        a geographic track keeps 24 more': lib/motion.h's struct as the C ABI lays it out."""
        import ctypes
        each, geo = grab(read("daemon/REFERENCE.md"), r"the waypoints, which take (\d+) bytes each\s+\("
                                                   r"`engine_waypoint_t`, with room for the source's velocity, "
                                                   r"and its line number; a geographic\s+"
                                                   r"track keeps (\d+) more")
        fields = grab(read("lib/motion.h"), r"typedef struct \{\n(    double t_s;.*?)\} engine_waypoint_t;")
        self.assertEqual(re.findall(r"^    (\w+) (\w+)", fields, re.M),
                         [("double", "t_s"), ("double", "pos_m"), ("uint32_t", "seq"),
                          ("uint32_t", "has_vel"), ("double", "vel_m_s")])

        class Waypoint(ctypes.Structure):
            _fields_ = [("t_s", ctypes.c_double), ("pos_m", ctypes.c_double * 3), ("seq", ctypes.c_uint32),
                        ("has_vel", ctypes.c_uint32), ("vel_m_s", ctypes.c_double * 3)]
        self.assertEqual(ctypes.sizeof(Waypoint) + 4, int(each))   # + uint32_t line
        self.assertEqual(3 * 8, int(geo))                          # double (*geo)[3]

    def test_uniform_irregular_example(self):
        """'... --param uniform ... gpxgo_visnjan.csv` reports 202 such
        waypoints, the worst 15x at t = 15 s'."""
        doc = read("daemon/REFERENCE.md")
        cmd, n, worst, t = grab(doc, r"`build/bin/(trajreplay [^`]*--param uniform[^`]*)`\s+reports "
                                     r"(\d+) such\s+waypoints, the worst (\S+)x at t = (\S+) s")
        err = trajreplay(cmd.split()[1:] + ["--summary"])
        self.assertIn("summary: uniform_irregular %s\n" % n, err)
        self.assertIn("(worst %sx, at t = %.3f s)" % (worst, float(t)), err)


class RealTracks(unittest.TestCase):
    """daemon/REFERENCE.md "What replaying the real tracks shows" and lib/engine/DESIGN.md's
    underrun counts."""
    F8, VIS, CER = "n2k_furuno_figure8_src52.csv", "gpxgo_visnjan.gpx", "gpxpy_cerknicko-jezero.csv"
    FORMER = ("--fragment", "32", "--overlap", "16", "--start-slack", "8")

    @classmethod
    def setUpClass(cls):
        doc = read("daemon/REFERENCE.md")
        a = doc.index("**What replaying the real tracks shows**")
        cls.doc = doc[a:doc.index("**Known limits.**", a)]

    def test_jitter(self):
        v, a, t0, t1, t2, n, shift, a2, v2 = grab(self.doc, (
            r"\(`--profile none`\)\s+the figure-eight boat peaks at (\S+) m/s and (\S+) m/s² around "
            r"t = 135 s\. Its log has a late\s+sample there: (\S+) → (\S+) → (\S+) s, so two fixes "
            r".*? keeps both with their\s+stamps re-estimated from the pace around them "
            r"\(`retimed (\d+)`, `retime_max_s (\S+)`: the\s+positions say 134.8 and 135.0\) and "
            r"the peak there drops to (\S+) m/s² \((\S+) m/s top speed\)"))
        s, rows, _ = replay(self.F8, "--profile", "none")
        near = (rows["t_s"] > 134) & (rows["t_s"] < 137)
        self.assertEqual(s["rejected"], 0)
        self.assertEqual("%.1f" % peak(rows, "vel_m_s", near)[0], v)
        self.assertEqual("%.0f" % peak(rows, "acc_m_s2", near)[0], a)
        with open(os.path.join(ROOT, "tests", "data", self.F8), encoding="utf-8") as f:
            stamps = [l.split(",")[0] for l in f.read().split("\n")]
        i = stamps.index(t0 + "000")
        self.assertEqual([float(x) for x in stamps[i:i + 3]], [float(t0), float(t1), float(t2)])
        s, rows, err = replay(self.F8)
        self.assertEqual((s["rejected"], s["retimed"]), (0, int(n)))
        self.assertEqual("%.3f" % s["retime_max_s"], shift)
        near = (rows["t_s"] > 134) & (rows["t_s"] < 137)
        self.assertEqual("%.1f" % peak(rows, "acc_m_s2", near)[0], a2)
        self.assertEqual("%.1f" % peak(rows, "vel_m_s")[0], v2)

    def test_underruns_visnjan(self):
        n, ticks = grab(self.doc, r"On visnjan \(fixes 1 to 41 s apart\) it runs dry (\d+) times?, "
                                  r"(\d+) ticks in all")
        s = replay(self.VIS)[0]
        self.assertEqual((s["underruns"], s["underrun_ticks"]), (int(n), int(ticks)))
        s, rows, _ = replay(self.VIS)
        self.assertEqual(s["hard_stops"], 0)
        import numpy as np
        t = np.genfromtxt(os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.csv"), delimiter=",",
                          names=True)["t_s"]
        self.assertEqual((np.diff(t).min(), np.diff(t).max()), (1.0, 41.0))

    def test_cerknicko(self):
        tracks, tv, v, jump, t0, line, n, nspeed, nunc, v10 = grab(self.doc, (
            r"gaps over 60 s make (\d+)\s+trajectories \(`tracks`\)\. The rest-to-rest transfers "
            r"between them peak at (\S+) m/s; the\s+fastest setpoint outside them is (\S+) m/s\. "
            r"Of a GPS jump in the log, (\d+) m in 2 s from\s+t = (\d+) s, the default profile "
            r"refuses the first fix \(line (\d+), `rejected_speed 1`\)\. With\s+`--max-speed 10`, "
            r"(\d+) waypoints are rejected \((\d+) for speed, (\d+) unconfirmed\) and the fastest"
            r"\s+setpoint is (\S+) m/s"))
        s, rows, err = replay(self.CER)
        self.assertEqual(s["tracks"], int(tracks))
        transfer = (rows["flags"] & 8) != 0
        self.assertEqual("%.1f" % peak(rows, "vel_m_s", transfer)[0], tv)
        self.assertEqual("%.1f" % peak(rows, "vel_m_s", ~transfer)[0], v)
        self.assertEqual((s["rejected"], s["rejected_speed"]), (1, 1))
        self.assertIn("%s:%s: rejected (speed)" % (self.CER, line), err)
        with open(os.path.join(ROOT, "tests", "data", self.CER), encoding="utf-8") as f:
            rec = [l.split(",") for l in f.read().split("\n")[int(line) - 1:int(line) + 1]]
        self.assertEqual(float(rec[0][0]), float(t0))
        self.assertEqual(float(rec[1][0]) - float(rec[0][0]), 2.0)
        from pyproj import Geod
        d = Geod(ellps="WGS84").inv(float(rec[0][2]), float(rec[0][1]), float(rec[1][2]), float(rec[1][1]))[2]
        self.assertEqual(round(d), int(jump))
        s, rows, _ = replay(self.CER, "--max-speed", "10")
        self.assertEqual((s["rejected"], s["rejected_speed"], s["rejected_unconfirmed"]),
                         (int(n), int(nspeed), int(nunc)))
        self.assertEqual("%.1f" % peak(rows, "vel_m_s")[0], v10)

    def test_engine_readme_underruns(self):
        """lib/engine/DESIGN.md "start_slack auto": underruns, default against the former F/O/slack."""
        vis, vis_s, vis0, vis0_s, former, cer, cer0, f8, f8_s, f80 = grab(read("lib/engine/DESIGN.md"), (
            r"`trajreplay --summary` on visnjan counts (\d+)\s+\((\S+) s slowed or held\) instead of "
            r"(\d+) \((\S+) s\) with the former `([^`]+)`, on cerknicko (\d+) instead of (\d+), on "
            r"the figure-8 (\d+) \((\S+) s: its 0.5 s hole\s+at t = 135 s, .*?\) instead of (\d+)"))
        self.assertEqual(tuple(" ".join(former.split()).split()), self.FORMER)
        for track, now, now_s, old in ((self.VIS, vis, vis_s, vis0), (self.CER, cer, None, cer0),
                                       (self.F8, f8, f8_s, f80)):
            s = replay(track)[0]
            self.assertEqual(s["underruns"], int(now), track)
            if now_s is not None:
                self.assertEqual("%g" % (s["underrun_ticks"] / 100), now_s, track)
            s = replay(track, *self.FORMER)[0]
            self.assertEqual(s["underruns"], int(old), track)
            if track == self.VIS:
                self.assertEqual("%g" % (s["underrun_ticks"] / 100), vis0_s, track)


class EngineReadme(unittest.TestCase):
    """lib/engine/DESIGN.md's replays of the real tracks."""
    TRACKS = {"figure-8": RealTracks.F8, "gpxgo_visnjan": RealTracks.VIS,
              "gpxpy_cerknicko-jezero": RealTracks.CER}

    def same(self, shown, value, what):
        """shown (the doc's text of a number, '37 890' or '7.1') is value as rounded there."""
        shown = shown.replace(" ", "")
        decimals = len(shown.split(".")[1]) if "." in shown else 0
        self.assertEqual("%.*f" % (decimals, value), shown, what)

    def test_max_accel_table(self):
        """'After (engine, `trajreplay` at 100 Hz, transfers excluded; before: `--profile none`,
        after: `--profile none --max-accel 30`': each row of the table."""
        import numpy as np
        doc = read("lib/engine/DESIGN.md")
        before, after = grab(doc, r"transfers excluded; before: `([^`]+)`, after:\s+`([^`]+)`")
        head = doc.index("| track | waypoints rejected (`rejected_accel`)")
        rows = doc[head:doc.index("\n\n", head)].split("\n")[2:]
        self.assertEqual(len(rows), 3)
        num = r"(\d[\d .]*\d|\d)"
        for row in rows:
            name, rej, acc, vel = [c.strip() for c in row.strip("|").split("|")]
            track = self.TRACKS[name]
            rb = replay(track, *before.split())[1]
            sa, ra, err = replay(track, *after.split())
            n, total = re.match(r"(\d+) of (\d+)", rej).groups()
            self.assertEqual((sa["rejected_accel"], sa["rejected"], sa["waypoints"]),
                             (int(n), int(n), int(total)), name)
            with open(os.path.join(ROOT, "tests", "data", track), encoding="utf-8") as f:
                stamps = f.read().split("\n")
            refused = [float(stamps[int(l) - 1].split(",")[0])
                       for l in re.findall(r":(\d+): rejected \(accel\)", err)]
            self.assertEqual(refused, [float(t) for t in re.findall(r"[\d.]+", rej.split("(")[1])]
                             if "(" in rej else [], name)

            def top(rows_, field, near=False):
                m = (rows_["flags"] & 8) == 0
                if near:
                    m &= (rows_["t_s"] > 134) & (rows_["t_s"] < 137)
                return peak(rows_, field, m)[0]

            v0, v1 = re.findall(r"[\d.]+", vel)
            self.same(v0, top(rb, "vel_m_s"), name)
            self.same(v1, top(ra, "vel_m_s"), name)
            if name != "figure-8":
                a0, a1 = re.findall(r"[\d.]+", acc)
                self.same(a0, top(rb, "acc_m_s2"), name)
                self.same(a1, top(ra, "acc_m_s2"), name)
                continue
            # "647 → 7.1 m/s² near 135 s (jerk 37 890 → 70 m/s³); 24.4 overall"
            a0, a1, j0, j1, overall = grab(acc, num + r" → ([\d.]+) m/s² near 135 s \(jerk " + num
                                           + r" → " + num + r" m/s³\); ([\d.]+) overall")
            self.same(a0, top(rb, "acc_m_s2", True), name)
            self.same(a1, top(ra, "acc_m_s2", True), name)
            self.same(overall, top(ra, "acc_m_s2"), name)
            for shown, rr in ((j0, rb), (j1, ra)):
                m = (rr["t_s"][1:] > 134) & (rr["t_s"][1:] < 137)
                jerk = np.max(np.abs(np.diff(rr["acc_m_s2"], axis=0)), axis=1)[m].max() / 0.01
                self.assertEqual(round(jerk, -1), int(shown.replace(" ", "")), name + " jerk")

    def test_jitter_data(self):
        """'Jitter and outliers': the short intervals, the burst and the implied accelerations,
        recomputed from the files (ENU by pyproj, about the first fix, as trajreplay frames them),
        and the unlimited replay's peaks."""
        import numpy as np
        doc = flat("lib/engine/DESIGN.md")
        a = doc.index("**Jitter and outliers.**")
        doc = doc[a:doc.index("**Bound**", a)]
        burst, step, late0, late1, vis, cer = grab(doc, (
            r"the figure-8 has two, a late burst (\S+ → \S+ → \S+ → \S+ → \S+) s whose positions are "
            r"evenly spaced \((\S+) m each: the fixes of 134.8 and 135.0 were stamped (\d+) and (\d+) ms "
            r"late\); visnjan has (\d+) \(.*?\) and cerknicko (\d+) \("))
        tracks = {}
        for name, want in ((RealTracks.F8, 2), (RealTracks.VIS.replace(".gpx", ".csv"), int(vis)),
                           (RealTracks.CER, int(cer))):
            t, p = enu(os.path.join(ROOT, "tests", "data", name))
            h = np.diff(t)
            short = [i for i in range(len(h)) if h[i] < 0.5 * np.median(h[max(0, i - 8):i + 9])]
            self.assertEqual(len(short), want, name)
            tracks[name] = (t, p)
        t, p = tracks[RealTracks.F8]
        times = [float(x) for x in burst.split(" → ")]
        i = int(np.argmin(np.abs(t - times[0])))
        self.assertEqual(list(t[i:i + 5]), times)
        for k in range(3):   # the steps of the burst proper
            self.assertEqual("%.2f" % np.linalg.norm(p[i + k + 1] - p[i + k]), step)
        self.assertEqual((round((t[i + 1] - 134.8) * 1000), round((t[i + 2] - 135.0) * 1000)),
                         (int(late0), int(late1)))

        def implied(t, p, i, j, k):
            v1, v2 = (p[j] - p[i]) / (t[j] - t[i]), (p[k] - p[j]) / (t[k] - t[j])
            return 2 * np.linalg.norm(v2 - v1) / (t[k] - t[i])
        f8, vis_a, cer_a, j120, j201 = grab(doc, (
            r"genuine samples reach (\S+) m/s² \(figure-8, GNSS noise at 5 Hz\), (\S+) \(visnjan, its "
            r"altitude\), (\S+) \(cerknicko\); the jittered ones (\S+) \(135.120\) and (\S+) \(135.201"))
        self.assertEqual("%.1f" % implied(t, p, i, i + 1, i + 2), j120)
        self.assertEqual("%.1f" % implied(t, p, i, i + 1, i + 3), j201)
        burst_idx = set(range(i + 1, i + 4))   # the three fixes stamped in the burst
        genuine = max(implied(t, p, k - 2, k - 1, k) for k in range(2, len(t))
                      if not burst_idx & {k - 2, k - 1, k})
        self.assertEqual("%.1f" % genuine, f8)
        t, p = tracks[RealTracks.VIS.replace(".gpx", ".csv")]
        self.assertEqual("%.1f" % max(implied(t, p, k - 2, k - 1, k) for k in range(2, len(t))), vis_a)
        # cerknicko: every triple but the one ending on the fix refused after its GPS jump (4565 s)
        t, p = tracks[RealTracks.CER]
        self.assertEqual("%.1f" % max(implied(t, p, k - 2, k - 1, k) for k in range(2, len(t))
                                      if t[k] != 4565.0), cer_a)
        margin = grab(doc, r"30 keeps a (\S+)× margin over the noisiest genuine sample")
        self.assertEqual("%.1f" % (30 / genuine), margin)
        # "(`trajreplay --profile none` at 100 Hz) the figure-8 streams 647 m/s² and 37 890 m/s³
        # at t = 135.12 (a boat that never exceeds 24.4 m/s² elsewhere)"
        acc, jerk, at, elsewhere = grab(doc, r"the figure-8 streams (\S+) m/s² and (\d[\d ]*\d) m/s³ at t = "
                                             r"(\S+) \(a boat that never exceeds (\S+) m/s² elsewhere\)")
        rows = replay(RealTracks.F8, "--profile", "none")[1]
        mag = np.linalg.norm(rows["acc_m_s2"], axis=1)
        k = int(np.nanargmax(mag))
        self.assertEqual(("%.0f" % mag[k], "%.2f" % rows["t_s"][k]), (acc, at))
        jr = np.max(np.abs(np.diff(rows["acc_m_s2"], axis=0)), axis=1) / 0.01
        self.assertEqual(round(float(np.nanmax(jr)), -1), int(jerk.replace(" ", "")))
        far = (rows["t_s"] < 134) | (rows["t_s"] > 137)
        self.assertEqual("%.1f" % np.nanmax(mag[far]), elsewhere)

    def test_start_lookahead_figure8(self):
        """'the figure-8 boat, up to 9 m/s at 5 Hz: 22 waypoints at 100 Hz instead of 33 before'."""
        now, before = grab(read("lib/engine/DESIGN.md"), r"the figure-8 boat, up to 9 m/s at\s+5\s+Hz:\s+"
                                                         r"(\d+)\s+waypoints\s+at\s+100\s+Hz\s+instead\s+of\s+(\d+)")
        for opts, want in (((), now), (RealTracks.FORMER, before)):
            rows = replay(RealTracks.F8, *opts)[1]
            first = next(i for i, f in enumerate(rows["flags"]) if f & 2)   # NEW_TRACK: streaming
            self.assertEqual(first / 20, int(want), opts)   # 100 Hz, 5 Hz waypoints: 20 ticks each


class Lookahead(unittest.TestCase):
    def test_fo_table(self):
        """lib/engine/DESIGN.md's F/O table: lookahead (waypoints) and latency at 1 Hz / 5 Hz."""
        doc = read("lib/engine/DESIGN.md")
        head = doc.index("| F | O | lookahead (waypoints) |")
        rows = doc[head:doc.index("\n\n", head)].split("\n")[2:]
        self.assertGreaterEqual(len(rows), 10)
        for row in rows:
            f, o, look, lat = [c.strip().strip("*") for c in row.strip("|").split("|")][:4]
            self.assertEqual(start_lookahead("--fragment", f, "--overlap", o), int(look), row)
            self.assertEqual(lat, "%d s / %.1f s" % (int(look), int(look) * 0.2), row)
            if row.startswith("| **"):   # "the bold row today's": the defaults
                self.assertEqual(start_lookahead(), int(look), row)
        # tests/bench/RESULTS.md repeats two rows: "| 32/16 (former default; ...) | 26 |", "| **28/24 (default)** | **18** |"
        res = read("tests/bench/RESULTS.md")
        for f, o, look in re.findall(r"^\| \**(\d+)/(\d+) \(.*?\)\** \| \**(\d+)\** \|", res, re.M):
            self.assertEqual(start_lookahead("--fragment", f, "--overlap", o), int(look), "RESULTS.md " + f + "/" + o)
        # the error columns (walks, figure-8, rho^(O/2)): bench_engine --errors, deterministic
        out = subprocess.run([os.path.join(BUILD, "tests", "bench_engine"), "--errors"], cwd=ROOT,
                             capture_output=True, text=True, check=True).stdout
        run = {}
        for line in out.splitlines():
            if re.match(r"\| \d", line):
                cells = [c.strip() for c in line.strip("|").split("|")]
                run[(cells[0], cells[1])] = cells[4:9]
        for row in rows:
            cells = [c.strip().strip("*") for c in row.strip("|").split("|")]
            self.assertEqual(cells[4:9], run[(cells[0], cells[1])], "bench_engine --errors: " + row)
        for f, o, reg, irr in re.findall(r"^\| \**(\d+)/(\d+) \(.*?\)\** \| \**\d+\** \| \**(\S+?)\** \| "
                                         r"\**(\S+?)\** \|", res, re.M):
            want = run[(f, o)]
            self.assertEqual([float(reg), float(irr)], [float(want[2]), float(want[0])], "RESULTS.md " + f + "/" + o)
        former = grab(doc, r"The first row is the former default \((\d+) waypoints with its start_slack 8\)")
        self.assertEqual(start_lookahead("--fragment", "32", "--overlap", "16", "--start-slack", "8"),
                         int(former))

    def test_spline_readme_smooth(self):
        """lib/spline/TOOLKIT.md: 'engine defaults, on regular input: 18 waypoints for `cubic`,
        30 for `smooth` with the default window, 24 with a window of 12'."""
        cubic, smooth, w, small = grab(read("lib/spline/TOOLKIT.md"), (
            r"engine defaults, on regular input: (\d+) waypoints for `cubic`, (\d+) for\s+`smooth` "
            r"with\s+the default window, (\d+) with a window of (\d+)"))
        self.assertEqual(start_lookahead(), int(cubic))
        self.assertEqual(start_lookahead("--method", "smooth"), int(smooth))
        self.assertEqual(start_lookahead("--method", "smooth", "--smooth-window", small), int(w))


class BytesPerRow(unittest.TestCase):
    """tests/bench/RESULTS.md's bytes/row: the output of the same replay as
    tests/bench/bench_trajreplay.sh's second table (30 000 waypoints at 1 Hz on a
    circle, --rate 100: 3 001 918 rows), its size counted through a pipe, over its rows;
    every form, the former %.17g default (--precision g17) too."""

    N = 30000
    LINE = '{i},{1000*math.cos(i/500):.3f},{1000*math.sin(i/500):.3f},{i%7}\\n'

    def per_row(self, track, *opts):
        size = 0
        with subprocess.Popen([os.path.join(BUILD, "bin", "trajreplay"), "-q", "--rate", "100"] + list(opts)
                              + ["-o", "/dev/stdout", track], stdout=subprocess.PIPE) as p:
            for block in iter(lambda: p.stdout.read(1 << 20), b""):
                size += len(block)
        self.assertEqual(p.returncode, 0)
        return size / 3001918

    def test_bytes_per_row(self):
        self.assertIn("f.write(f\"" + self.LINE + "\")", read("tests/bench/bench_trajreplay.sh"),
                      "the bench's track is the one replayed here")
        doc = read("tests/bench/RESULTS.md")
        first = [int(b) for b in grab(doc, r"\| default \(shortest round trip\) \| [^|\n]+\| [^|\n]+\| (\d+) \|\n"
                                           r"\| `--precision 9` \| [^|\n]+\| [^|\n]+\| (\d+) \|\n"
                                           r"\| `--binary` \| [^|\n]+\| [^|\n]+\| (\d+) \|")]
        second = grab(doc, r"\| former default `%\.17g` \| [^|\n]+\| [^|\n]+\| (\d+\.\d) \|\n"
                           r"\| default \(shortest round trip\) \| [^|\n]+\| [^|\n]+\| (\d+\.\d) \|\n"
                           r"\| `--precision 9` \| [^|\n]+\| [^|\n]+\| (\d+\.\d) \|\n"
                           r"\| `--binary` \| [^|\n]+\| [^|\n]+\| (\d+\.\d) \|")
        prose = grab(" ".join(doc.split()), r"its (\d+) bytes per row cost about \S+ µs of kernel copy each; "
                                            r"`--precision 9` \((\d+) bytes\)")
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "rows.csv")
            with open(track, "w") as f:
                f.write("t,x,y,z\n")
                for i in range(self.N):
                    f.write(f"{i},{1000*math.cos(i/500):.3f},{1000*math.sin(i/500):.3f},{i%7}\n")
            g17 = self.per_row(track, "--precision", "g17")
            got = [self.per_row(track), self.per_row(track, "--precision", "9"), self.per_row(track, "--binary")]
        self.assertEqual(second[0], "%.1f" % g17, "former default %.17g (second table)")
        for form, a, b, g in zip(("default", "--precision 9", "--binary"), first, second[1:], got):
            self.assertEqual(a, round(g), form + " (first table)")
            self.assertEqual(b, "%.1f" % g, form + " (second table)")
        self.assertEqual([int(x) for x in prose], first[:2], "the prose's bytes per row")


class BusLoad(unittest.TestCase):
    def test_protocol_table(self):
        """config/PROTOCOL.md's bus-load table is what `bench_can_busload` computes
        (the product's estimate, lib/proto/canproto.h), as the doc rounds it."""
        doc = read("config/PROTOCOL.md")
        head = doc.index("| configuration | 125k | 250k | 500k | 1M |")
        rows = doc[head:doc.index("\n\n", head)].split("\n")[2:]
        self.assertGreaterEqual(len(rows), 4)
        r = subprocess.run([os.path.join(BUILD, "tests", "bench_can_busload")], capture_output=True,
                           text=True, check=True)
        bench = {}
        for line in r.stdout.split("\n"):
            m = re.match(r"(\S.*?)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)\s+([\d.]+)$", line)
            if m:
                bench[m.group(1)] = [float(x) for x in m.groups()[1:]]
        for row in rows:
            cells = [c.strip() for c in row.strip("|").split("|")]
            name = cells[0].replace("×", "x")
            self.assertIn(name, bench, row)
            for shown, value in zip(cells[1:], bench[name]):
                shown = shown.strip("*% ")
                unit = 10 ** -len(shown.split(".")[1]) if "." in shown else 1
                # the bench prints 0.1 %: the doc's rounding of it, within its half unit
                self.assertLessEqual(abs(float(shown) - value), unit / 2 + 0.05, row)


class OracleFigures(unittest.TestCase):
    """daemon/REFERENCE.md's figures that an oracle test prints: the test's own run."""

    def test_gpsbabel_rounding(self):
        """'(worst 0.926 m north against the 0.932 m bound of 0.0005' rounding)'."""
        worst, bound = grab(read("daemon/REFERENCE.md"), r"\(worst ([\d.]+) m north against the ([\d.]+) m bound")
        r = subprocess.run([os.path.join(BUILD, "tests", "test_track_logs")], cwd=ROOT,
                           capture_output=True, text=True, check=True)
        got = re.findall(r"\|d north\| ([\d.]+) m \(([\d.]+)\)", r.stdout + r.stderr)
        self.assertEqual(len(got), 2, r.stdout + r.stderr)   # NMEA and IGC
        self.assertEqual(max(got), (worst, bound))

    def test_pyproj(self):
        """'Compared with pyproj over 2400 points up to 200 km from the origin, the largest
        difference is 4e-9 m.'"""
        n, worst = grab(read("daemon/REFERENCE.md"), r"Compared with pyproj over (\d+) points up to\s+200 km "
                                                  r"from the origin, the largest difference is (\S+) m\.")
        r = subprocess.run([sys.executable, os.path.join(ROOT, "tests", "oracle", "test_geo.py")],
                           capture_output=True, text=True, check=True, env=dict(os.environ, BUILD=BUILD))
        got_n, got = grab(r.stdout + r.stderr, r"test_geo.py: (\d+) ENU points \+ ECEF points, "
                                               r"worst difference to pyproj (\S+) m")
        self.assertEqual(got_n, n)
        self.assertEqual(float("%.0e" % float(got)), float(worst))


_UNITS = {}


def setUpModule():
    # test_clock simulates 24 h (seconds): started now, it runs beside the replays
    unit_start("test_clock")


def unit_start(name):
    if name not in _UNITS:
        _UNITS[name] = subprocess.Popen([os.path.join(BUILD, "tests", name)], cwd=ROOT, text=True,
                                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


def unit_output(name):
    """What the unit test build/tests/NAME prints (its figures), run once per process."""
    unit_start(name)
    if name not in _RUNS:
        out = _UNITS[name].communicate()[0]
        assert _UNITS[name].returncode == 0, out
        _RUNS[name] = out
    return _RUNS[name]


def flat(path):
    return " ".join(read(path).split())


class UnitTestFigures(unittest.TestCase):
    """lib/engine/TIMESCALE.md, CLOCK.md and README.md quote what the unit tests print:
    each figure, as the doc rounds it, is that run's."""

    def shown(self, doc_value, run_value, what):
        decimals = len(doc_value.split(".")[1]) if "." in doc_value else 0
        self.assertEqual("%.*f" % (decimals, float(run_value)), doc_value, what)

    def shown_e(self, doc_value, run_value, what):
        """doc_value '2.6e-10' is run_value with as many digits."""
        mant = doc_value.split("e")[0]
        decimals = len(mant.split(".")[1]) if "." in mant else 0
        self.assertEqual(float("%.*e" % (decimals, float(run_value))), float(doc_value), what)

    def test_fdiff_drift(self):
        small, big = grab(flat("lib/engine/DESIGN.md"), r"without re-seeding: (\S+) m at 1e3 m, (\S+) m at "
                                                               r"1e7 m \(test_fdiff.c")
        got = grab(unit_output("test_fdiff"), r"drift over 600000 steps: pos (\S+) \S+ (\S+) m "
                                              r"\(\|c0\| 1e3, 5e6, 1e7\)")
        self.shown_e(small, got[0], "drift at 1e3 m")
        self.shown_e(big, got[1], "drift at 1e7 m")

    def test_toolkit(self):
        doc = flat("lib/spline/TOOLKIT.md")
        self.shown_e(grab(doc, r"max \\\|r − 1\\\| = \*\*(\S+)\*\*"),
                     grab(unit_output("test_nurbs"), r"seed circle: max \|radius - 1\| = (\S+) over 1e5 points"),
                     "NURBS circle")
        self.shown_e(grab(doc, r"forward differences against direct evaluation \(max difference (\S+)\)"),
                     grab(unit_output("test_surf"), r"surface forward differences: max \|fd - direct\| = (\S+)"),
                     "surface forward differences")

    def test_csv_fixed_count(self):
        """daemon/REFERENCE.md: '`tests/unit/test_csv_fixed.c` compares 1.3 M values with printf'."""
        shown = grab(read("daemon/REFERENCE.md"), r"`tests/unit/test_csv_fixed.c` compares (\S+) M values with printf")
        n = grab(unit_output("test_csv_fixed"), r"(\d+) values compared with printf")
        self.shown(shown, int(n) / 1e6, "test_csv_fixed's count")

    def test_csv_shortest_counts(self):
        """daemon/REFERENCE.md: test_csv_shortest.c 'reads 6 M values back', test_csv_shortest.py
        'compares 0.9 M values': the unit test's counts read from its source (it takes 7 s), the
        oracle's from its own values() (what it sends to the printer)."""
        doc = flat("daemon/REFERENCE.md")
        unit, oracle = grab(doc, r"`tests/unit/test_csv_shortest.c` reads (\S+) M values back.*?"
                                 r"`tests/oracle/test_csv_shortest.py` compares (\S+) M values")
        src = read("tests/unit/test_csv_shortest.c")
        loops = [int(grab(src, r"static void %s\(.*?for \(long i = 0; i < (\d+); i\+\+\)" % f))
                 for f in ("test_random_bits", "test_typical")]
        # test_random_bits reads back each (finite) pattern, test_typical two values per turn
        self.shown(unit, (loops[0] + 2 * loops[1]) / 1e6, "test_csv_shortest.c's count")
        spec = importlib.util.spec_from_file_location(
            "oracle_csv_shortest", os.path.join(ROOT, "tests", "oracle", "test_csv_shortest.py"))
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        self.shown(oracle, len(mod.values()) / 1e6, "test_csv_shortest.py's count")

    def test_timescale(self):
        doc = flat("lib/engine/TIMESCALE.md")
        out = unit_output("test_timescale")
        acc, jerk = grab(doc, r"`build/tests/test_timescale`: worst tick (\S+) of the acceleration bound, "
                              r"(\S+) of the jerk bound\)")
        got = grab(out, r"worst dv/T (\S+) of the accel limit, da/T (\S+) of the jerk limit")
        self.shown(acc, got[0], "random stalls, acceleration")
        self.shown(jerk, got[1], "random stalls, jerk")
        both = grab(doc, r"on every tick \(worst (\S+) of both: the limits are reached")
        for v in grab(out, r"straight line, random overrides: worst \|da\| (\S+) of j T, \|dv\| (\S+) of a T"):
            self.shown(both, v, "straight line")
        self.shown(grab(doc, r"worst d is (\S+) v·T beyond v²/\(2a\)"),
                   grab(out, r"beyond v\^2/\(2a\) at most (\S+) v T"), "stop distance")

    def test_property_outputs(self):
        doc = flat("lib/engine/TIMESCALE.md")
        out = unit_output("test_property_outputs")
        n, step, dv, fd, da, third = grab(doc, (
            r"over (\d+) random sequences of a real-time sender.*?`build/tests/test_property_outputs`: worst "
            r"(\S+) of the speed bound, (\S+) of the velocity bound, (\S+) by finite differences, (\S+) of "
            r"the jerk bound in Δacceleration, (\S+) by third differences"))
        got = grab(out, r"(\d+) random sequences, .*? worst ratios to the limits: step (\S+), dv (\S+), "
                        r"finite-difference dv (\S+), da (\S+), CSV jerk by third differences (\S+) ")
        self.assertEqual(n, got[0])
        for want, run, what in zip((step, dv, fd, da, third), got[1:], ("step", "dv", "fd", "da", "third")):
            self.shown(want, run, what)
        self.shown(grab(flat("lib/engine/DESIGN.md"), r"`build/tests/test_property_outputs`: worst tick "
                                                      r"(\S+) of the jerk bound"), got[4], "README da")

    def test_speed_cap(self):
        curve, out_v, cap = grab(flat("lib/engine/TIMESCALE.md"), r"`build/tests/test_engine`: curve (\S+) m/s, "
                                                                  r"output at most (\S+) m/s, cap (\S+) m/s")
        got = grab(unit_output("test_engine"), r"speed cap: curve (\S+) m/s, output (\S+) m/s \(cap (\S+)\)")
        for want, run in zip((curve, out_v, cap), got):
            self.shown(want, run, "speed cap")

    def test_clock(self):
        doc = flat("lib/engine/CLOCK.md")
        out = unit_output("test_clock")
        self.shown(grab(doc, r"100 ppm is estimated as (\S+) ppm"),
                   grab(out, r"eps \+100.0 ppm: estimate \+(\S+) ppm"), "drift")
        lag, lock = grab(doc, r"fall up to (\S+) s behind and are both locked (\S+) s after the start")
        for run_lag, run_lock in re.findall(r"lag up to (\S+) s, both locked (\S+) s later", out):
            self.shown(lag, run_lag, "24 h lag")
            self.shown(lock, run_lock, "24 h lock")
        moved = grab(doc, r"uncorrected, it would have moved by (\S+) s over the 23 hours")
        for a, b in re.findall(r"\(uncorrected (\S+) -> (\S+)\)", out):
            self.shown(moved, abs(float(b) - float(a)), "uncorrected margin")
        lag5, lock5, lag1, lock1, da5, da1 = grab(doc, (
            r"falls (\S+) s behind and is locked (\S+) s after its start \((\S+) s and (\S+) s with a = 1 "
            r"m/s², j = 5 m/s³\), its \|Δacceleration\| per tick within (\S+) \((\S+)\) of"))
        runs = re.findall(r"\|da\| (\S+); by finite.*?lag max (\S+) s, locked (\S+) s after the start", out)
        self.assertEqual(len(runs), 2)
        for (da, lag, lock), want in zip(runs, ((da5, lag5, lock5), (da1, lag1, lock1))):
            for w, r in zip(want, (da, lag, lock)):
                self.shown(w, r.rstrip(";"), "clocked start")
        rate, jt = grab(doc, r"the rate peaks at (\S+) for a target of 1.05, \|Δacceleration\| per tick at "
                             r"most (\S+) j T")
        got = grab(out, r"stall 20 s: rate max (\S+), .*?\|da\| max (\S+) m/s2 per tick")
        self.shown(rate, got[0], "catch-up rate")
        self.shown(jt, float(got[1]) / (50 * 0.02), "catch-up jerk (j = 50 m/s3, T = 20 ms)")


class ManPages(unittest.TestCase):
    def test_numeric_defaults(self):
        """Every '(default N' of an option in a man page source (daemon/doc/*.1) is what the
        program's --help says for that option."""
        checked = 0
        for page, prog in (("trajreplay.1", "trajreplay"), ("trajsurf.1", "trajsurf")):
            text = read(os.path.join("daemon", "doc", page)).replace("\\-", "-")
            r = subprocess.run([os.path.join(BUILD, "bin", prog), "--help"], capture_output=True, text=True)
            helptext = r.stdout + r.stderr
            for item in text.split(".TP")[1:]:
                opt = re.search(r"--([a-z][a-z-]*)", item)
                for n in re.findall(r"\(default (\d+)", item):
                    # the option's --help entry: its line and the continuation lines after it
                    entry = re.search(r"^  (?:-\w, )?--%s\b.*?(?=^  -|\n\n|\Z)" % re.escape(opt.group(1)),
                                      helptext, re.M | re.S)
                    self.assertIsNotNone(entry, "%s: --%s not in --help" % (page, opt.group(1)))
                    self.assertRegex(" ".join(entry.group(0).split()), r"default %s\b" % n,
                                     "%s --%s" % (page, opt.group(1)))
                    checked += 1
        self.assertGreaterEqual(checked, 4)


class DelayMeasured(unittest.TestCase):
    """lib/engine/DESIGN.md "The delay measured" (issue 26 item 5): its table is the one
    tests/bench/bench_delay.py prints (D per configuration on three synthetic tracks, the
    steady delay, underruns, the distance to scipy's CubicSpline), line for line, and the
    figures of the paragraphs below it are that run's (about 30 trajreplay runs of at most
    3600 s of input each, --binary: about a second)."""
    maxDiff = None

    def test_readme_frontier(self):
        """The top-level README's accuracy/latency frontier (issue 31): the rows of the
        delay table for the 10 Hz track and the bundled figure-8 at bench_delay.FRONTIER's
        settings."""
        spec = importlib.util.spec_from_file_location(
            "bench_delay", os.path.join(ROOT, "tests", "bench", "bench_delay.py"))
        bench = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(bench)
        doc = read("README.md")
        shown = doc.split("<!-- frontier:begin -->\n")[1].split("\n<!-- frontier:end -->")[0]
        with tempfile.TemporaryDirectory() as tmp:
            want = bench.table_a(os.path.join(BUILD, "bin", "trajreplay"), tmp,
                                 bench.FRONTIER_TRACKS, bench.FRONTIER)
        self.assertEqual(shown.split("\n"), [l for l in want if l], "README.md's frontier is stale")

    def test_delay_table(self):
        spec = importlib.util.spec_from_file_location(
            "bench_delay", os.path.join(ROOT, "tests", "bench", "bench_delay.py"))
        bench = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(bench)
        exe = os.path.join(BUILD, "bin", "trajreplay")
        doc = read("lib/engine/DESIGN.md")
        a = doc.index("| track | configuration | method | D s |")
        shown = doc[a:doc.index("\n\n", doc.index("\n\n(1) ", a) + 2)].split("\n")
        with tempfile.TemporaryDirectory() as tmp:
            self.assertEqual(shown, bench.table_a(exe, tmp), "DESIGN.md's delay table is stale")

            def m(track, *opts):
                return bench.measure(exe, track, opts, tmp)
            text = flat("lib/engine/DESIGN.md")
            text = text[text.index("**The delay measured**"):text.index("**Forward differences.**")]
            one, ten, method, picked, median, held = grab(text, (
                r"([+-]\S+) s at 1 Hz, ([+-]\S+) s at 10 Hz with `--delay`.*the longest lookahead that "
                r"fits \(`(\S+)`, D (\S+) s;.*\(median (\S+) s\); with `--capacity 8192` the steady "
                r"delay is (\S+) s"))
            for shown, d in ((one, m("1 Hz")), (ten, m("10 Hz", "--max-speed", "10", "--delay", "5"))):
                # the difference of the table's two columns, as rounded there
                self.assertEqual("%+.3f" % (float("%.3f" % d["steady"]) - float("%.3f" % d["D"])), shown)
            p = m("1 Hz", "--max-speed", "10", "--delay", "5")
            self.assertEqual((p["method"], "%.3f" % p["D"]), (method, picked))
            self.assertEqual("%.3f" % m("200 Hz", "--max-speed", "10", "--delay", "25")["steady"], median)
            self.assertEqual("%.3f" % m("200 Hz", "--max-speed", "10", "--delay", "25", "--capacity",
                                        "8192")["steady"], held)
            # the lag over the track with gaps
            s, _, pieces = bench.lag_trace(exe, tmp)
        first, d1, d2, start, won, end, last, cost = grab(text, (
            r"The first piece starts (\S+) s behind, .*? streams at its D, (\S+) s\..*D stays (\S+) s "
            r"for the others\. Each later\s+"
            r"piece's transfer sets off once two of its waypoints are kept.*so the piece starts (\S+) s "
            r"behind after its transfer and ramp, wins back (\S+) s at 5 % until its input ends and "
            r"closes its tail, and ends (\S+) s\s+behind, \S+ s short of winning all of it back \(the "
            r"last piece, whose input runs on, (\S+) s\):\s+40 s at 5 % win back (?:most of )?what the "
            r"transfer adds to the lookahead's wait, (\S+) s"))
        # the first piece starts where its ramp from rest leaves it (a lag won back: delay.h)
        self.assertEqual(("%.3f" % pieces[0]["D"], "%.3f" % pieces[0]["start"]), (d1, first))
        self.assertEqual(s["underruns"], 0)  # the input's end is no underrun (silence.c)
        later = pieces[1:]
        for what, want in (("D", d2), ("start", start), ("end", end)):
            self.assertEqual({"%.3f" % p[what] for p in later[:-1]}, {want}, what)
        self.assertEqual("%.3f" % later[-1]["end"], last)
        self.assertEqual({"%.3f" % (p["start"] - p["end"]) for p in later[:-1]}, {won})
        self.assertEqual({"%.3f" % (p["start"] - p["D"]) for p in later}, {cost})
        self.assertEqual(len({"%.3f" % p["start"] for p in later}), 1)   # the lag does not add up


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
