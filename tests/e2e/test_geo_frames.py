"""test_geo_frames.py - one datum per daemon, lat/lon/alt out, a heading axis that wraps
(issue 16, item 4), in the running daemon, against pyproj and scipy.

Tracks: tests/data/gpxgo_visnjan.gpx (ATTRIBUTION.md) as object a (id 0), and its
second half, written by this test as a GPX of its own, as object b (id 1): b starts
a few hundred metres from a, so before this work b had its own east/north/up origin
(its first fix) and the two were not in one frame.

0. trajreplay --geo writes a's rows with the same lat/lon/alt columns as trajd's csv.geo.
1. The datum is a's first fix (the geographic object with the lowest id).  b's
   setpoints are trajreplay's setpoints of b alone (east/north/up about b's own first
   fix) carried into the datum's frame by pyproj (topocentric inverse, then forward
   about the datum): the same curve in one shared frame, to 1 mm.
2. Relative geometry: at every tick, pyproj's geodesic distance and azimuth between a
   and b from trajd's lat/lon columns equal those between trajreplay's a and b
   positions converted to lat/lon by pyproj, each in its own frame.
3. The lat_deg/lon_deg/alt_m columns and the Modbus f64 registers (pymodbus) are
   pyproj's inverse of the east/north/up of the same row/block.
4. A heading column crossing +-180 (both ways) is output with no spin: every
   heading_deg equals scipy's PchipInterpolator of numpy-unwrapped headings at the
   row's track time, wrapped, and consecutive rows differ by the short way round;
   the Modbus diagnostics block (pymodbus) has it wrapped and continuous.
5. A reload that would move the datum is refused with file:line.
"""
import bisect
import csv
import math
import os
import signal
import struct
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np
import pyproj
from scipy.interpolate import PchipInterpolator

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402

ROOT = mbsim.ROOT
TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(mbsim.BUILD, "bin", "trajreplay")
GPX = os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.gpx")
GEOD = pyproj.Geod(ellps="WGS84")
TOL_M = 1e-3
TOL_DEG = 1e-8      # ~1 mm on the ground
WAIT_S = 60


def topo(lat0, lon0, h0):
    """pyproj: geodetic (lat, lon, h) <-> east/north/up about an origin."""
    return pyproj.Transformer.from_pipeline(
        "+proj=pipeline +step +proj=axisswap +order=2,1 "
        "+step +proj=unitconvert +xy_in=deg +xy_out=rad "
        "+step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat0!r} +lon_0={lon0!r} +h_0={h0!r}")


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def second_half(src, dst):
    """The GPX src with only its second half of <trkpt>s (its own first fix)."""
    with open(src) as f:
        text = f.read()
    head, rest = text.split("<trkpt", 1)
    pts = ("<trkpt" + rest).split("</trkpt>")
    tail = pts.pop()
    keep = pts[len(pts) // 2:]
    write(dst, head + "</trkpt>".join(p.strip() for p in keep) + "</trkpt>\n" + tail)
    first = keep[0].split('lat="')[1]
    lat = float(first.split('"')[0])
    lon = float(keep[0].split('lon="')[1].split('"')[0])
    ele = float(keep[0].split("<ele>")[1].split("<")[0])
    return lat, lon, ele


def first_fix(src):
    with open(src) as f:
        pt = f.read().split("<trkpt", 1)[1]
    return (float(pt.split('lat="')[1].split('"')[0]), float(pt.split('lon="')[1].split('"')[0]),
            float(pt.split("<ele>")[1].split("<")[0]))


def rows(path):
    with open(path) as f:
        return [r for r in csv.DictReader(l for l in f if not l.startswith("#"))]


def finite(r):
    return all(math.isfinite(float(r[k])) for k in ("x_m", "y_m", "z_m"))


# lib/motion.h ENGINE_SP_HOLD | TRANSFER | NO_POSITION | SCALED: rows off the solved
# curve's own timing (the wait at the datum before the track, the transfer to its start)
OFF_CURVE = 0x01 | 0x08 | 0x10 | 0x40


def on_curve(r):
    return finite(r) and not int(r["flags"]) & OFF_CURVE


def on_path(r):
    """On the solved curve at the row's t_s, at whatever rate: a time-scaled
    row (SCALED, 0x40: a lag won back after a transfer, lib/engine/catchup.h)
    is where the curve is at its t_s; only its velocity is scaled."""
    return finite(r) and not int(r["flags"]) & (OFF_CURVE & ~0x40)


class GeoFrames(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.b_gpx = os.path.join(self.tmp, "b.gpx")
        self.b0 = second_half(GPX, self.b_gpx)
        self.a0 = first_fix(GPX)
        self.conf = os.path.join(self.tmp, "trajd.conf")

    def tearDown(self):
        self.tmpd.cleanup()

    def config(self, extra_daemon=""):
        return ("[daemon]\nrate_hz = 10\nspeed = 100\nexit_when_done = yes\nstatus_interval_s = 0\n"
                "%s[modbus]\nport = 0\nsystemd_socket = no\n"
                "[object.b]\nid = 1\ninput = replay\nreplay.track = %s\noutput = csv\n"
                "csv.path = b.csv\ncsv.geo = yes\n"
                "[object.a]\nid = 0\ninput = replay\nreplay.track = %s\noutput = csv\n"
                "csv.path = a.csv\ncsv.geo = yes\n" % (extra_daemon, self.b_gpx, GPX))

    def trajreplay(self, track, out, key, extra=()):
        p = subprocess.run([TRAJREPLAY, "-q", "--rate", "10", "-o", out] + list(extra) + [track],
                           capture_output=True, text=True, timeout=WAIT_S)
        self.assertEqual(p.returncode, 0, p.stderr)
        return {r[key]: r for r in rows(out) if on_curve(r)}

    def test_one_frame_latlon_and_modbus(self):
        write(self.conf, self.config())
        p = subprocess.Popen([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = mbsim.Lines(p.stderr)
        try:
            line = lines.wait_for("modbus: TCP on", WAIT_S)
            self.assertIsNotNone(line, "".join(lines.all))
            port = mbsim.port_of(line)
            blocks = self.read_blocks(port, lines)
        finally:
            rc = p.wait(timeout=WAIT_S)
            lines.wait_for("\0", 0.5)
        self.assertEqual(rc, 0, "".join(lines.all))
        datum = topo(*self.a0)
        a = {r["now_ns"]: r for r in rows(os.path.join(self.tmp, "a.csv")) if finite(r)}
        b = {r["now_ns"]: r for r in rows(os.path.join(self.tmp, "b.csv")) if finite(r)}
        self.assertGreater(len(a), 1000)
        self.assertGreater(len(b), 1000)
        # 3. lat/lon/alt columns: pyproj's inverse of the row's east/north/up about the datum
        for r in list(a.values()) + list(b.values()):
            lat, lon, h = datum.transform(float(r["x_m"]), float(r["y_m"]), float(r["z_m"]),
                                          direction="INVERSE")
            self.assertLess(abs(float(r["lat_deg"]) - lat), 1e-9, r)
            self.assertLess(abs(float(r["lon_deg"]) - lon), 1e-9, r)
            self.assertLess(abs(float(r["alt_m"]) - h), 1e-6, r)
            self.assertEqual(r["heading_deg"], "nan")
        # ... and the Modbus f64 registers of a snapshot, from its f32 east/north/up
        self.assertTrue(blocks)
        for x, y, z, lat, lon, h in blocks:
            plat, plon, ph = datum.transform(x, y, z, direction="INVERSE")
            self.assertLess(abs(lat - plat), TOL_DEG, (x, y, z, lat, lon, h))
            self.assertLess(abs(lon - plon), TOL_DEG)
            self.assertLess(abs(h - ph), TOL_M)
        # 1. a is trajreplay's a (its first fix is the datum), tick for tick; b, on its
        #    solved curve, is trajreplay's b moved from b's own frame into the datum's by
        #    pyproj, at the same track time (b first waits at the datum and comes to its
        #    start by a transfer, so its track time runs later than alone)
        ra = self.trajreplay(GPX, os.path.join(self.tmp, "ra.csv"), "now_ns", ["--geo"])
        rb = self.trajreplay(self.b_gpx, os.path.join(self.tmp, "rb.csv"), "t_s")
        own_b = topo(*self.b0)
        bt = [r for r in b.values() if on_curve(r)]
        self.assertGreater(len(bt), 1000)
        worst = 0.0
        # b's curve at trajd's track times: a cubic Hermite between trajreplay's
        # two rows around each (exact inside a segment): b in trajd comes to its
        # start by a transfer, so its tick grid of track times is offset from
        # trajreplay's by a fraction of a tick (and again after a slow-down)
        tb = sorted(float(t) for t in rb)
        by_t = {float(k): v for k, v in rb.items()}

        def b_at(t):
            i = bisect.bisect_right(tb, t) - 1
            if i < 0 or i + 1 >= len(tb) or tb[i + 1] - tb[i] > 0.1 + 1e-9:
                return None  # outside, or across a hole of trajreplay's rows
            a, c = by_t[tb[i]], by_t[tb[i + 1]]
            hh, u = tb[i + 1] - tb[i], (t - tb[i]) / (tb[i + 1] - tb[i])
            h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
            h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
            return {p: h00 * float(a[p]) + h10 * hh * float(a[v]) + h01 * float(c[p])
                    + h11 * hh * float(c[v])
                    for p, v in (("x_m", "vx_m_s"), ("y_m", "vy_m_s"), ("z_m", "vz_m_s"))}

        matched = 0
        for r in bt:
            q = b_at(float(r["t_s"]))
            if q is None:
                continue
            matched += 1
            lat, lon, h = own_b.transform(float(q["x_m"]), float(q["y_m"]), float(q["z_m"]),
                                          direction="INVERSE")
            e, n, u = datum.transform(lat, lon, h)
            worst = max(worst, abs(e - float(r["x_m"])), abs(n - float(r["y_m"])),
                        abs(u - float(r["z_m"])))
        self.assertGreater(matched, max(1000, len(bt) // 2))
        self.assertLess(worst, TOL_M)
        for k, r in a.items():
            if on_curve(r):
                # trajreplay --geo writes the same lat/lon/alt columns as csv.geo
                cols = ("t_s", "x_m", "y_m", "z_m", "lat_deg", "lon_deg", "alt_m", "heading_deg")
                self.assertEqual([r[c] for c in cols], [ra[k][c] for c in cols])
        # 2. relative geometry at every tick both are on their curves: pyproj's geodesic
        #    distance and azimuth from trajd's lat/lon columns, and from the references
        #    each in its own frame converted by pyproj
        both = [k for k in a if on_curve(a[k]) and k in b and on_path(b[k])]
        self.assertGreater(len(both), 1000)
        far = 0.0
        for k in both:
            az, _, d = GEOD.inv(float(a[k]["lon_deg"]), float(a[k]["lat_deg"]),
                                float(b[k]["lon_deg"]), float(b[k]["lat_deg"]))
            qa, qb = ra[k], b_at(float(b[k]["t_s"]))
            if qb is None:
                continue
            la, lo, _ = datum.transform(float(qa["x_m"]), float(qa["y_m"]), float(qa["z_m"]),
                                        direction="INVERSE")
            lb, lob, _ = own_b.transform(float(qb["x_m"]), float(qb["y_m"]), float(qb["z_m"]),
                                         direction="INVERSE")
            az_ref, _, d_ref = GEOD.inv(lo, la, lob, lb)
            self.assertLess(abs(d - d_ref), TOL_M, k)
            if d_ref > 10:
                self.assertLess(abs((az - az_ref + 180) % 360 - 180), 1e-5, k)
            far = max(far, d_ref)
        self.assertGreater(far, 100)  # the two are apart: the geometry means something
        print("test_geo_frames: %d ticks, b moved into the datum's frame within %.2g m, a-b up to "
              "%.0f m" % (len(both), worst, far), file=sys.stderr)

    def read_blocks(self, port, lines):
        """(x, y, z, lat, lon, alt) of object blocks 0 and 1, each read in one request
        by pymodbus (one snapshot) while it streams."""
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
        out = []
        if not c.connect():
            return out
        try:
            count = M["MBMAP_O_ALT"] + 4
            end = time.monotonic() + WAIT_S   # bounded; the daemon ends when done anyway
            while time.monotonic() < end:
                for k in (0, 1):
                    r = c.read_input_registers(obj_base(k), count=count)
                    if r.isError():
                        return out
                    regs = r.registers
                    if regs[M["MBMAP_O_STATE"]] != 1:  # streaming (published, on its track)
                        continue
                    pos = M["MBMAP_O_POS"]
                    f32 = [struct.unpack(">f", struct.pack(">HH", *regs[i:i + 2]))[0]
                           for i in (pos, pos + 2, pos + 4)]
                    f64 = [struct.unpack(">d", struct.pack(">HHHH", *regs[o:o + 4]))[0]
                           for o in (M["MBMAP_O_LAT"], M["MBMAP_O_LON"], M["MBMAP_O_ALT"])]
                    if all(math.isfinite(v) for v in f32 + f64):
                        out.append(tuple(f32 + f64))
                if len(out) >= 20:
                    break
        except Exception:  # the daemon exits when done: keep what was read
            pass
        finally:
            c.close()
        return out

    def test_heading_wraps_without_spin(self):
        # Given a track whose heading turns across +-180 one way and back the other
        t = np.arange(0.0, 60.0, 1.0)
        hdg = 150.0 + 60.0 * np.sin(2 * math.pi * t / 40.0)          # 90 .. 210, unwrapped
        wrapped = (hdg + 180.0) % 360.0 - 180.0                       # as a sensor writes it
        track = os.path.join(self.tmp, "h.csv")
        write(track, "t,x,y,z,heading\n" + "".join(
            "%g,%g,0,0,%.6f\n" % (ti, 2.0 * ti, wi) for ti, wi in zip(t, wrapped)))
        write(self.conf, "[daemon]\nrate_hz = 20\nspeed = 10\nexit_when_done = yes\n"
                         "status_interval_s = 0\n[modbus]\nport = 0\nsystemd_socket = no\n"
                         "[object.h]\ninput = replay\nreplay.track = h.csv\n"
                         "output = csv\ncsv.path = h_out.csv\ncsv.geo = yes\n")
        p = subprocess.Popen([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = mbsim.Lines(p.stderr)
        try:
            line = lines.wait_for("modbus: TCP on", WAIT_S)
            self.assertIsNotNone(line, "".join(lines.all))
            snaps = self.read_heading(mbsim.port_of(line))
        finally:
            rc = p.wait(timeout=WAIT_S)
            lines.wait_for("\0", 0.5)
        self.assertEqual(rc, 0, "".join(lines.all))
        out = [r for r in rows(os.path.join(self.tmp, "h_out.csv")) if finite(r)]
        self.assertGreater(len(out), 500)
        f = PchipInterpolator(t, np.unwrap(np.radians(wrapped.round(6)), period=2 * math.pi))
        prev, prev_t, crossings = None, None, 0
        for r in out:
            h = float(r["heading_deg"])
            self.assertTrue(-180.0 < h <= 180.0, r)
            ts = min(max(float(r["t_s"]), t[0]), t[-1])
            want = (math.degrees(float(f(ts))) + 180.0) % 360.0 - 180.0
            self.assertLess(abs((h - want + 180.0) % 360.0 - 180.0), 1e-6, r)
            if prev is not None:
                # no spin: between two rows (skipped ticks included) the heading turns
                # the short way round at most at the track's own rate (9.4 deg/s)
                step = (h - prev + 180.0) % 360.0 - 180.0
                self.assertLess(abs(step), 10.0 * (ts - prev_t) + 1e-6, r)
                crossings += abs(h - prev) > 180.0            # ... even where the value wraps
            prev, prev_t = h, ts
        self.assertGreaterEqual(crossings, 2)   # it did cross +-180, both ways
        # Modbus diagnostics block: heading (wrapped) and heading_unwrapped (continuous)
        # at the object block's track time of the same snapshot (same generation)
        self.assertGreater(len(snaps), 10)
        for ts, h, hu in snaps:
            want = math.degrees(float(f(min(max(ts, t[0]), t[-1]))))
            self.assertLess(abs(hu - want), 1e-6, (ts, h, hu))
            self.assertLess(abs(h - ((want + 180.0) % 360.0 - 180.0)), 1e-6, (ts, h, hu))
        self.assertGreater(max(s[2] for s in snaps), 180.0)   # unwrapped: past 180, no jump

    def read_heading(self, port):
        """(t_s, heading, heading_unwrapped) of object 0 from pymodbus reads of its
        object block and its diagnostics block in one tick (equal generations)."""
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
        out = []
        if not c.connect():
            return out
        xb = M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])      # MBMAP_X_BASE(0)
        f64 = lambda r, o: struct.unpack(">d", struct.pack(">HHHH", *r[o:o + 4]))[0]
        try:
            end = time.monotonic() + WAIT_S
            while time.monotonic() < end:
                a = c.read_input_registers(obj_base(0), count=M["MBMAP_O_T_S"] + 4)
                x = c.read_input_registers(xb, count=M["MBMAP_X_HEADING_UNWRAPPED"] + 4)
                if a.isError() or x.isError():
                    break
                if a.registers[:2] != x.registers[:2] or a.registers[M["MBMAP_O_STATE"]] != 1:
                    continue
                h = f64(x.registers, M["MBMAP_X_HEADING"])
                if math.isfinite(h):
                    out.append((f64(a.registers, M["MBMAP_O_T_S"]), h,
                                f64(x.registers, M["MBMAP_X_HEADING_UNWRAPPED"])))
        except Exception:  # the daemon exits when done: keep what was read
            pass
        finally:
            c.close()
        return out

    def test_explicit_origin_centres_the_frame(self):
        # Given [daemon] origin = 45.27,13.71,0 (not a's first fix, ~400 m away)
        origin = (45.27, 13.71, 0.0)
        write(self.conf, self.config("origin = 45.27,13.71,0\n"))
        p = subprocess.run([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                           capture_output=True, text=True, timeout=4 * WAIT_S, cwd=self.tmp)
        self.assertEqual(p.returncode, 0, p.stderr)
        a = [r for r in rows(os.path.join(self.tmp, "a.csv")) if on_curve(r)]
        self.assertGreater(len(a), 1000)
        # then a's first fix on its curve is at pyproj's east/north/up of that fix
        # about the origin (not at 0, 0, 0), and every row's lat/lon/alt is
        # pyproj's inverse of its east/north/up about the origin
        about = topo(*origin)
        # (a comes to its start by a transfer: its first row on the curve is a
        # fraction of a second into the track, no farther from the fix than the
        # distance its speed covers in that time)
        first = min(a, key=lambda r: float(r["t_s"]))
        ts = float(first["t_s"])
        self.assertLess(ts, 2.0, first)
        want = np.array(about.transform(*self.a0))
        self.assertGreater(math.hypot(want[0], want[1]), 100.0)
        got = np.array([float(first[k]) for k in ("x_m", "y_m", "z_m")])
        v = max(math.sqrt(sum(float(r[k]) ** 2 for k in ("vx_m_s", "vy_m_s", "vz_m_s")))
                for r in a if float(r["t_s"]) <= ts + 1e-9)
        self.assertLess(np.linalg.norm(got - want), v * ts + TOL_M, (first, want))
        for r in a:
            lat, lon, h = about.transform(float(r["x_m"]), float(r["y_m"]), float(r["z_m"]),
                                          direction="INVERSE")
            self.assertLess(abs(float(r["lat_deg"]) - lat), 1e-9, r)
            self.assertLess(abs(float(r["lon_deg"]) - lon), 1e-9, r)
            self.assertLess(abs(float(r["alt_m"]) - h), 1e-6, r)

    def test_no_altitude_far_from_the_datum(self):
        # Given a track with no altitude (nan, as the bundled N2K figure-8 has) 100 km
        # from the datum, then its lat/lon columns are its own fixes' where the curve
        # passes them (at rest on the first and the last), alt_m is nan (none came in),
        # and every row's lat/lon is where pyproj puts east/north of the row at the
        # datum's height.  They were the tangent plane's point under up = 0: 784 m
        # above the ellipsoid and 12 m off in latitude at 100 km (and alt_m 784).
        t = np.arange(0.0, 30.0, 0.2)
        lat = 46.17 + 1e-5 * t
        lon = 13.71 + 2e-5 * t
        write(os.path.join(self.tmp, "noalt.csv"), "t,lat,lon,alt\n" + "".join(
            "%r,%r,%r,nan\n" % (a, b, c) for a, b, c in zip(t, lat, lon)))
        origin = (45.27, 13.71, 12.0)
        write(self.conf, "[daemon]\nrate_hz = 50\nspeed = 20\nstatus_interval_s = 0\n"
                         "exit_when_done = yes\norigin = 45.27,13.71,12\n"
                         "[object.n]\nid = 0\ninput = replay\nreplay.track = noalt.csv\n"
                         "output = csv\ncsv.path = n.csv\ncsv.geo = yes\n")
        p = subprocess.run([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                           capture_output=True, text=True, timeout=4 * WAIT_S, cwd=self.tmp)
        self.assertEqual(p.returncode, 0, p.stderr)
        got = [r for r in rows(os.path.join(self.tmp, "n.csv")) if finite(r)]
        self.assertGreater(len(got), 500)
        about = topo(*origin)
        for r in got:
            self.assertEqual(r["alt_m"], "nan", r)
            e, n, _ = about.transform(float(r["lat_deg"]), float(r["lon_deg"]), origin[2])
            self.assertLess(math.hypot(e - float(r["x_m"]), n - float(r["y_m"])), 1e-6, r)
        for r, (la, lo) in ((got[-1], (lat[-1], lon[-1])),
                            (next(r for r in got if r["state"] == "streaming"),
                             (lat[0], lon[0]))):
            self.assertLess(abs(float(r["lat_deg"]) - la), 1e-9, r)
            self.assertLess(abs(float(r["lon_deg"]) - lo), 1e-9, r)

    def test_datum_move_refused_at_reload(self):
        write(self.conf, self.config().replace("exit_when_done = yes", "exit_when_done = no"))
        p = subprocess.Popen([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = mbsim.Lines(p.stderr)
        try:
            self.assertIsNotNone(lines.wait_for("modbus: TCP on", WAIT_S), "".join(lines.all))
            # Given an origin that differs from the running datum (a's first fix)
            text = self.config("origin = 45.27,13.71,0\n")
            write(self.conf, text)
            p.send_signal(signal.SIGHUP)
            line = lines.wait_for("reload refused", WAIT_S)
            self.assertIsNotNone(line, "".join(lines.all))
            n = text.split("\n").index("origin = 45.27,13.71,0") + 1
            self.assertIn("%s:%d: the datum would move" % (self.conf, n), line)
        finally:
            p.send_signal(signal.SIGTERM)
            rc = p.wait(timeout=WAIT_S)
        self.assertEqual(rc, 0)


if __name__ == "__main__":
    unittest.main()
