#!/usr/bin/python3
"""test_trajreplay_faults.py - trajreplay (and trajd's replay) on tracks that
are wrong in the ways real logs are (issues 11 and 12):

  * a seconds-for-microseconds slip (rows 1e5 s apart) gives bounded output:
    gaps longer than max_gap_s are skipped, the row after each carries flag
    4 (ENGINE_SP_SKIPPED), and the rows kept are exactly the rows written
    without skipping (--keep-gaps);
  * --max-rows stops a runaway with exit 5 and says so;
  * a track with no usable waypoint ends with a clear message and exit 1
    (trajreplay) and trajd with exit_when_done exits;
  * every rejected waypoint is reported as file:line: rejected (reason), the
    line counted here from the file, rate-limited, with a per-reason total;
    --strict turns any rejection into exit 6.
Every process is bounded: output is read through a pipe with a byte limit
and the process is killed by its pid past it.
"""
import csv
import os
import re
import subprocess
import sys
import tempfile
import unittest

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
TRAJD = os.path.join(BUILD, "bin", "trajd")
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(REPO, "tests", "data")
CERKNICA = os.path.join(DATA, "gpxpy_cerknicko-jezero.csv")
FIGURE8 = os.path.join(DATA, "n2k_furuno_figure8_src52.csv")
FLAG_HOLD, FLAG_SKIPPED = 0x01, 0x04


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def bounded_run(args, limit_bytes=20_000_000, timeout=120):
    """Run with stdout through a pipe; kill (by pid) once more than
    limit_bytes came out.  Returns (returncode or None if killed, stdout
    bytes, stderr text)."""
    errf = tempfile.TemporaryFile()  # a file, not a pipe: no deadlock on a chatty stderr
    p = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=errf)
    out = bytearray()
    killed = False
    while True:
        b = p.stdout.read(1 << 16)
        if not b:
            break
        out += b
        if len(out) > limit_bytes:
            p.kill()
            killed = True
            break
    try:
        p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        killed = True
    errf.seek(0)
    err = errf.read().decode(errors="replace")
    errf.close()
    return (None if killed else p.returncode), bytes(out), err


def rows(data):
    lines = data.decode().splitlines()
    assert lines[0].startswith("object,now_ns,"), lines[:1]
    return [l.split(",") for l in lines[1:]]


class TestGapsAndBounds(unittest.TestCase):
    def setUp(self):
        self.tmpdir = tempfile.TemporaryDirectory()
        self.tmp = self.tmpdir.name

    def tearDown(self):
        self.tmpdir.cleanup()

    def test_seconds_for_microseconds_slip_is_bounded(self):
        # Given 60 rows 1e5 s apart (timestamps in seconds where microseconds
        # were meant: 69 days of track), when replayed at the default 100 Hz,
        # then trajreplay ends by itself with about one transfer per waypoint
        # (3.6 m at 1.5 x 1 m/s: 5.4 s, 540 rows; nothing of the object's
        # motion is known, lib/engine/transfer.h), not the 590 million hold
        # rows of the gaps, exit 0,
        slip = os.path.join(self.tmp, "slip.csv")
        write(slip, "t,x,y,z\n" + "".join("%d,%d,%d,0\n" % (i * 100000, 3 * i, 2 * (i % 7))
                                          for i in range(60)))
        rc, out, err = bounded_run([TRAJREPLAY, "-q", "--summary", slip], limit_bytes=10_000_000)
        self.assertEqual(rc, 0, err[-500:])
        r = rows(out)
        self.assertLess(len(r), 60 * 800)
        # and each of the 59 gaps is skipped twice, each marked on the row after
        # it: to its waypoint's silence of max_gap_s (a lone waypoint's
        # trajectory ends there and plays out, lib/engine/silence.h), then to
        # the next waypoint
        skipped = [x for x in r if int(x[13]) & FLAG_SKIPPED]
        self.assertEqual(len(skipped), 2 * 59)
        self.assertIn("summary: skipped_gaps %d\n" % (2 * 59), err)
        # and the output still ends at rest on the last waypoint
        self.assertEqual(r[-1][12], "finished")
        self.assertEqual((float(r[-1][3]), float(r[-1][4])), (177.0, 6.0))

    def test_skipping_keeps_every_number(self):
        # Given the real cerknicko track (18 intervals above the 60 s
        # max_gap_s) and a small slip (10 rows 1000 s apart), then the rows
        # written when gaps are skipped are the rows written through them
        # (--keep-gaps) for the same ticks, equal but for flag 4 on the row
        # after each skip; the rows left out are all hold rows.
        slip = os.path.join(self.tmp, "slip10.csv")
        write(slip, "t,x,y,z\n" + "".join("%d,%d,%d,0\n" % (i * 1000, 3 * i, 2 * (i % 7))
                                          for i in range(10)))
        for track in (CERKNICA, slip):
            with self.subTest(track=os.path.basename(track)):
                self.skip_equals_keep(track)

    def skip_equals_keep(self, track):
        args = ["-q", "--summary", "--rate", "10", track]
        rc, skip, err = bounded_run([TRAJREPLAY] + args)
        self.assertEqual(rc, 0, err[-500:])
        rc, keep, err_keep = bounded_run([TRAJREPLAY, "--keep-gaps"] + args)
        self.assertEqual(rc, 0, err_keep[-500:])
        skip, keep = rows(skip), rows(keep)
        by_ns = {x[1]: x for x in keep}
        kept_ns = set()
        flagged = 0
        for x in skip:
            ref = by_ns[x[1]]
            flags = int(x[13])
            self.assertEqual(x[:13] + x[14:], ref[:13] + ref[14:], "row at now_ns " + x[1])
            self.assertEqual(flags & ~FLAG_SKIPPED, int(ref[13]))
            flagged += bool(flags & FLAG_SKIPPED)
            kept_ns.add(x[1])
        left_out = [x for x in keep if x[1] not in kept_ns]
        self.assertTrue(left_out)
        self.assertTrue(all(int(x[13]) & FLAG_HOLD for x in left_out))
        gaps = int(re.search(r"summary: skipped_gaps (\d+)", err).group(1))
        self.assertEqual(flagged, gaps)
        self.assertGreaterEqual(gaps, 1)
        self.assertIn("summary: skipped_gaps 0\n", err_keep)

    def test_max_rows(self):
        # Given --max-rows 100, then exactly 100 rows, exit 5 and a message
        rc, out, err = bounded_run([TRAJREPLAY, "-q", "--max-rows", "100", FIGURE8])
        self.assertEqual(rc, 5, err)
        self.assertEqual(len(rows(out)), 100)
        self.assertIn("--max-rows", err)
        # and the default cap is documented
        h = subprocess.run([TRAJREPLAY, "--help"], capture_output=True, text=True)
        self.assertIn("--max-rows N", h.stdout)
        self.assertIn("5 --max-rows", h.stdout.replace("\n", " "))

    def test_nothing_usable(self):
        # Given a track whose every x is 1e300 (above max_abs_m), then a
        # clear message and exit 1, and a bounded output (never exit 4 "engine bug")
        bad = os.path.join(self.tmp, "huge.csv")
        write(bad, "t,x,y,z\n" + "".join("%d,1e300,0,0\n" % i for i in range(60)))
        rc, out, err = bounded_run([TRAJREPLAY, "-q", "--rate", "10", bad], limit_bytes=1_000_000)
        self.assertEqual(rc, 1, err[-500:])
        self.assertIn(bad + ": no usable waypoint: all 60 rejected", err)
        self.assertNotIn("engine bug", err)
        self.assertLess(len(rows(out)), 1000)

    def test_hostile_tracks_exit_honestly(self):
        # Given tracks that are wrong in every way a log is (out of range,
        # backwards, one time for all, teleporting, a seconds-for-us slip, one
        # row, duplicates, a 97 km jump after silence, alternating absurd
        # speeds), then trajreplay ends with exit 0 or 1 (nothing usable),
        # never 4 (memory), 5 (a runaway) or 7 (the engine did what it
        # documents cannot happen), its --summary counts 0 numeric refusals,
        # and no message speaks of a bug or an internal
        # fault; and trajd replaying each one (exit_when_done) exits 0, or 78
        # for a track with nothing usable, never 70 (EX_SOFTWARE).  trajd
        # follows its clock through gaps: the slip (22 days of track) is
        # trajreplay's case only
        cases = {
            "range": "".join("%d,1e300,0,0\n" % i for i in range(40)),
            "backwards": "".join("%d,%d,0,0\n" % (100 - i, i) for i in range(40)),
            "same_time": "".join("5,%d,0,0\n" % (1000 * i) for i in range(40)),
            "teleport": "".join("%d,%g,0,0\n" % (i, (i % 2) * 1e6) for i in range(40)),
            "slip": "".join("%d,%d,%d,0\n" % (i * 100000, i, i) for i in range(20)),
            "one_row": "3,1,2,3\n",
            "duplicates": "".join("%d,%d,0,0\n" % (i // 2, i // 2) for i in range(40)),
            "jump": "".join("%d,%d,0,0\n" % (i, i) for i in range(10))
                    + "".join("%d,%d,0,0\n" % (110 + i, 97000 + i) for i in range(10)),
            "zigzag": "".join("%g,%g,%g,0\n" % (0.01 * i, (-1) ** i * 50.0, 0.3 * i)
                              for i in range(60)),
        }
        for name, body in cases.items():
            path = os.path.join(self.tmp, name + ".csv")
            write(path, "t,x,y,z\n" + body)
            rc, out, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--rate", "50",
                                        "--max-rows", "2000000", path], limit_bytes=300_000_000)
            self.assertIn(rc, (0, 1), "%s: %s" % (name, err[-800:]))
            self.assertIn("summary: rejected_numeric 0\n", err, name)
            for word in ("bug", "internal fault"):
                self.assertNotIn(word, err, name)
            if name == "duplicates":  # each said at its line, as a rejection is (only counted)
                self.assertIn(path + ":3: duplicate of a waypoint before it", err)
            if name == "slip":
                continue
            conf = os.path.join(self.tmp, name + ".conf")
            write(conf, "[daemon]\nrate_hz = 50\nspeed = 1000\nexit_when_done = yes\n"
                        "status_interval_s = 0\nstop_timeout_s = 1\n[object.o]\ninput = replay\n"
                        "replay.track = %s\noutput = csv\ncsv.path = %s.out\n" % (path, path))
            p = subprocess.run([TRAJD, "-f", "-c", conf], capture_output=True, text=True,
                               timeout=120)
            self.assertIn(p.returncode, (0, 78) if name == "range" else (0,),
                          "%s: %s" % (name, p.stderr[-800:]))
            self.assertNotIn("internal fault", p.stderr, name)

    def test_long_transfer_finishes(self):
        # Given an ADS-B-like jump: 10 fixes, silence for 100 s (a gap), then
        # 10 fixes 97 km away, with --max-speed 0 (the old transfer ran at
        # 10 m/s: about 4 h for 97 km, longer than the old bound of twice
        # the 190 s track plus an hour, which exited 4 "engine bug"), then
        # the transfer follows the object's own pace across the gap (it
        # covered 97 km in 100 s: a derived transfer lasts at most 1.5 x the
        # gap, lib/engine/transfer.h, plus its ramps) and trajreplay finishes
        # on the last fix, exit 0
        jump = os.path.join(self.tmp, "jump.csv")
        rows_ = ["%d,%d,0,0" % (5 * i, 10 * i) for i in range(10)]
        rows_ += ["%d,%d,0,0" % (145 + 5 * i, 97000 + 10 * i) for i in range(10)]
        write(jump, "t,x,y,z\n" + "\n".join(rows_) + "\n")
        rc, out, err = bounded_run([TRAJREPLAY, "-q", "--rate", "1", "--max-speed", "0", jump],
                                   limit_bytes=20_000_000)
        self.assertEqual(rc, 0, err[-500:])
        self.assertNotIn("engine bug", err)
        r = rows(out)
        xfer = [x for x in r if int(x[13]) & 0x08]  # ENGINE_SP_TRANSFER
        self.assertGreater(len(xfer), 0)
        # the transfer is entered and left at rate 0, ramping within
        # scale_accel_m_s2 (a = 5) at its peak speed v = 1.5 D / T_x
        # (lib/engine/TIMESCALE.md "Handovers"): at most T_x + 2 v / a
        t_x = 1.5 * 100
        self.assertLessEqual(len(xfer), t_x + 2 * (1.5 * 97000 / t_x) / 5.0 + 1)
        self.assertEqual(r[-1][12], "finished")
        self.assertAlmostEqual(float(r[-1][3]), 97090.0, delta=1e-6)


class TestRejectionsReported(unittest.TestCase):
    def setUp(self):
        self.tmpdir = tempfile.TemporaryDirectory()
        self.tmp = self.tmpdir.name

    def tearDown(self):
        self.tmpdir.cleanup()

    def track(self, name, bad_every, n=200, comment_every=0):
        """A straight walk at 1 m/s, 1 s apart; every bad_every-th row has
        x = 1e300 (rejected: range) and every comment_every-th line is a
        comment.  Returns the path and the file line numbers of the bad rows."""
        lines, bad = ["t,x,y,z"], []
        for i in range(n):
            if comment_every and i % comment_every == 0:
                lines.append("# note")
            if bad_every and i % bad_every == bad_every - 1:
                lines.append("%d,1e300,0,0" % i)
                bad.append(len(lines))  # 1-based line number of this row
            else:
                lines.append("%d,%d,0,0" % (i, i))
        path = os.path.join(self.tmp, name)
        write(path, "\n".join(lines) + "\n")
        return path, bad

    def test_each_rejection_has_its_line(self):
        # Given 12 rows out of range among 120, with comment lines in between
        # (so row number != line number), then each is reported once as
        # file:line: rejected (range), at its own line, and the total says
        # 12 of 120 with the reason
        path, bad = self.track("some.csv", 10, n=120, comment_every=7)
        rc, _, err = bounded_run([TRAJREPLAY, "-q", "--rate", "10", path])
        self.assertEqual(rc, 0, err)
        got = [int(m) for m in re.findall(re.escape(path) + r":(\d+): rejected \(range\)", err)]
        self.assertEqual(got, bad)
        self.assertIn(path + ": rejected 12 of 120 waypoints (range 12), the first at line %d"
                      % bad[0], err)

    def test_rate_limited(self):
        # Given 3000 rejected rows, then the first 20 are shown, then one in
        # 1000, with a note, and the total counts all 3000
        path, bad = self.track("many.csv", 2, n=6000)
        rc, _, err = bounded_run([TRAJREPLAY, "-q", "--rate", "1", path])
        self.assertEqual(rc, 0, err[-500:])
        got = [int(m) for m in re.findall(r":(\d+): rejected \(range\)", err)]
        self.assertEqual(got, bad[:20] + [bad[999], bad[1999], bad[2999]])
        self.assertIn("one in 1000 shown", err)
        self.assertIn("rejected 3000 of 6000 waypoints (range 3000)", err)

    def test_real_track_jitter_reported(self):
        # Given the real figure-8 log, whose late burst around t = 135 s has
        # two intervals below 0.1 s after a fix stamped 0.296 s late, then
        # nothing is refused: that fix and the next (0.120 s late) are kept
        # with their stamps re-estimated (issue 27, lib/engine/retime.c),
        # counted in --summary's retimed (before: the first was refused)
        with open(FIGURE8) as f:
            lines = f.read().splitlines()
        t = [float(l.split(",")[0]) for l in lines[1:]]
        short = [i + 2 for i in range(1, len(t)) if t[i] - t[i - 1] < 0.1 and 130 < t[i] < 140]
        self.assertEqual(len(short), 2)
        rc, _, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--rate", "10", FIGURE8])
        self.assertEqual(rc, 0, err)
        got = [int(m) for m in re.findall(r":(\d+): rejected \((?:speed|accel)\)", err)]
        self.assertEqual(got, [])
        self.assertIn("summary: retimed 2\n", err)

    def test_strict(self):
        # Given rejections, then --strict exits 6 (the output is still
        # complete); a clean track exits 0 with --strict; a skipped bad line
        # (--skip-bad) counts as a rejection for --strict
        path, _ = self.track("some.csv", 10, n=60)
        out = os.path.join(self.tmp, "o.csv")
        p = subprocess.run([TRAJREPLAY, "-q", "--strict", "-o", out, path],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(p.returncode, 6, p.stderr)
        self.assertIn("--strict", p.stderr)
        with open(out) as f:
            self.assertEqual(f.read().splitlines()[-1].split(",")[12], "finished")
        clean, _ = self.track("clean.csv", 0, n=60)
        p = subprocess.run([TRAJREPLAY, "-q", "--strict", "-o", out, clean],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertNotIn("rejected", p.stderr)
        with open(clean, "a") as f:
            f.write("61,abc,0,0\n")
        p = subprocess.run([TRAJREPLAY, "-q", "--strict", "--skip-bad", "-o", out, clean],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(p.returncode, 6, p.stderr)
        p = subprocess.run([TRAJREPLAY, "-q", "--skip-bad", "-o", out, clean],
                           capture_output=True, text=True, timeout=120)
        self.assertEqual(p.returncode, 0, p.stderr)


class TestTrajdNothingUsable(unittest.TestCase):
    def test_exit_when_done(self):
        # Given trajd replaying a track with no usable waypoint (every x is
        # 1e300, above max_abs_m), then --check-config refuses it
        # (exit 78, EX_CONFIG) at the replay.track line with the counts per
        # reason and the first line, and trajd refuses to start with the same
        # message instead of running with nothing (it exited 0, or waited for
        # ever without exit_when_done)
        with tempfile.TemporaryDirectory() as tmp:
            write(os.path.join(tmp, "huge.csv"),
                  "t,x,y,z\n" + "".join("%d,1e300,0,0\n" % i for i in range(60)))
            conf = os.path.join(tmp, "t.conf")
            write(conf, "[daemon]\nspeed = 100\nexit_when_done = yes\nstatus_interval_s = 0\n"
                        "[object.boat]\ninput = replay\nreplay.track = huge.csv\n"
                        "output = stdout\n")
            msg = ("%s:7: [object.boat] replay.track: %s/huge.csv: no usable waypoint: "
                   "all 60 rejected (range 60, not_finite 0; max_abs_m = 1e+07), the first at "
                   "line 2" % (conf, tmp))
            p = subprocess.run([TRAJD, "--check-config", conf], capture_output=True, text=True,
                               timeout=60)
            self.assertEqual(p.returncode, 78, p.stdout + p.stderr)
            self.assertIn(msg, p.stdout + p.stderr)
            for when_done in ("yes", "no"):
                write(conf + ".2", open(conf).read().replace("exit_when_done = yes",
                                                             "exit_when_done = " + when_done))
                rc, _, err = bounded_run([TRAJD, "-f", "-c", conf + ".2"],
                                         limit_bytes=5_000_000, timeout=60)
                self.assertEqual(rc, 78, err[-500:])
                self.assertIn(msg.replace(conf, conf + ".2"), err)
            # one usable row among them: accepted by the check, the object
            # rests there, the 59 others are reported, exit 0
            write(os.path.join(tmp, "huge.csv"),
                  "t,x,y,z\n" + "".join("%d,1e300,0,0\n" % i for i in range(59)) + "59,1,2,3\n")
            rc, _, err = bounded_run([TRAJD, "-f", "-c", conf], limit_bytes=5_000_000, timeout=60)
            self.assertEqual(rc, 0, err[-500:])


class TestUniformIrregular(unittest.TestCase):
    def test_warned_once_with_the_numbers(self):
        """Given the Visnjan walk (fixes 1 to 20 s apart, every one kept), when
        replayed with param = uniform, then trajreplay warns once that the
        velocity steps at the waypoints between intervals differing by more
        than 1.1x, with their count, the worst ratio and its time as computed
        here from the file; with param = time (the default) it says nothing."""
        import csv
        with open(os.path.join(DATA, "gpxgo_visnjan.csv")) as f:
            t = [float(r["t_s"]) for r in csv.DictReader(f)]
        h = [b - a for a, b in zip(t, t[1:])]
        ratios = [(max(a, b) / min(a, b), t[i + 1]) for i, (a, b) in enumerate(zip(h, h[1:]))]
        worst = max(ratios, key=lambda r: r[0])   # the first of the largest, as the engine keeps it
        worst = next(r for r in ratios if r[0] == worst[0])
        n = sum(1 for r, _ in ratios if r > 1.1)
        self.assertGreater(n, 0)
        track = os.path.join(DATA, "gpxgo_visnjan.csv")
        rc, _, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--method", "bspline",
                                  "--param", "uniform", "-o", os.devnull, track])
        self.assertEqual(rc, 0, err)
        lines = [l for l in err.splitlines() if "param = uniform on irregular intervals" in l]
        self.assertEqual(len(lines), 1, err)
        self.assertIn(": %d waypoints between intervals differing by more than 1.1x" % n, lines[0])
        self.assertIn("(worst %.3gx, at t = %.3f s)" % worst, lines[0])
        self.assertIn("summary: uniform_irregular %d\n" % n, err)
        self.assertIn("summary: accepted %d\n" % len(t), err)  # the count is over kept fixes
        rc, _, err = bounded_run([TRAJREPLAY, "-q", "-o", os.devnull, track])
        self.assertEqual(rc, 0, err)
        self.assertNotIn("param = uniform", err)


class TestNoHardStops(unittest.TestCase):
    def test_every_track_method_param(self):
        """Given every real track in tests/data replayed with every method and
        parameterisation (the replay underruns where a track's hole is longer
        than the lookahead; bspline + uniform on gpxpy_cerknicko-jezero.csv
        made a curve 8x faster in the last segment solved, and the output,
        braking at limits converted at the slower speed behind it, reached
        the end moving), then no hard stop: the summary says hard_stops 0 and
        no warning says 'hard stop'."""
        tracks = sorted(f for f in os.listdir(DATA) if f.endswith(".csv") and
                        f.startswith(("gpx", "n2k")))
        self.assertGreaterEqual(len(tracks), 3)
        for track in tracks:
            for method in ("bspline", "cubic", "smooth"):
                for param in ("uniform", "time"):
                    with self.subTest(track=track, method=method, param=param):
                        rc, _, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--method",
                                                  method, "--param", param, "-o", os.devnull,
                                                  os.path.join(DATA, track)])
                        self.assertEqual(rc, 0, err[-500:])
                        self.assertIn("summary: hard_stops 0\n", err)
                        self.assertNotIn("hard stop", err)

    def test_cerknicko_east_north_10hz(self):
        """Given the cerknicko hike converted to east/north/up metres about its
        first fix (pyproj: WGS84 to ECEF, then the local ENU rotation), as t,x,y,z
        in file order, replayed with the defaults at 10, 20 and 100 Hz: its
        underruns end the creep towards the end of the solved curve at rest,
        not moving (at 10 Hz it reached the end at 0.133 m/s and was set to 0
        in one tick, a hard stop at t = 2974 s)."""
        import math
        import pyproj
        rows = list(csv.DictReader(open(os.path.join(DATA, "gpxpy_cerknicko-jezero.csv"))))
        ecef = pyproj.Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True)
        lat0, lon0 = math.radians(float(rows[0]["lat_deg"])), math.radians(float(rows[0]["lon_deg"]))
        x0 = ecef.transform(float(rows[0]["lon_deg"]), float(rows[0]["lat_deg"]),
                            float(rows[0]["alt_m"]))
        sl, cl, so, co = math.sin(lat0), math.cos(lat0), math.sin(lon0), math.cos(lon0)
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "cerknicko_enu.csv")
            with open(track, "w") as f:
                f.write("t,x,y,z\n")
                for r in rows:
                    x = ecef.transform(float(r["lon_deg"]), float(r["lat_deg"]), float(r["alt_m"]))
                    d = [x[i] - x0[i] for i in range(3)]
                    east = -so * d[0] + co * d[1]
                    north = -sl * co * d[0] - sl * so * d[1] + cl * d[2]
                    up = cl * co * d[0] + cl * so * d[1] + sl * d[2]
                    f.write("%s,%.4f,%.4f,%.4f\n" % (r["t_s"], east, north, up))
            for rate in (10, 20, 100):
                with self.subTest(rate=rate):
                    rc, _, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--rate", str(rate),
                                              "-o", os.devnull, track])
                    self.assertEqual(rc, 0, err[-500:])
                    self.assertIn("summary: hard_stops 0\n", err)
                    self.assertNotIn("hard stop", err)

    def test_stop_track_low_rates(self):
        """Given the stop track (10 Hz fixes, 1 m/s along x for 10 s, standing 10 s,
        on again) replayed at 10, 20 and 50 Hz: the output waits for the verdict
        on the repeats short of the stop and creeps up to the end of its solved
        curve; that creep ends at rest with no tick changing the velocity by more
        than scale_accel_m_s2 (5) x T, and no hard stop is counted (it was, at
        7.8 mm/s, 8.6 mm/s and 0.7 mm/s)."""
        import numpy as np
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "stop.csv")
            with open(track, "w") as f:
                f.write("t,x,y,z\n")
                for i in range(301):
                    t = i / 10
                    x = t if i <= 100 else 10.0 if i <= 200 else t - 10.0
                    f.write("%.1f,%.3f,0,0\n" % (t, x))
            for rate in (10, 20, 50):
                with self.subTest(rate=rate):
                    out = os.path.join(tmp, "out.csv")
                    rc, _, err = bounded_run([TRAJREPLAY, "-q", "--summary", "--rate", str(rate),
                                              "-o", out, track])
                    self.assertEqual(rc, 0, err[-500:])
                    self.assertIn("summary: hard_stops 0\n", err)
                    d = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding=None)
                    # the creep lies between t_s = 5 and 9 s, where the curve itself runs at
                    # 1 m/s: every change of velocity there is the time scaling's
                    v = d["vx_m_s"][(d["t_s"] > 5.0) & (d["t_s"] < 9.0)]
                    self.assertGreater(len(v), 4 * rate)
                    self.assertLessEqual(np.max(np.abs(np.diff(v))), 5.0 / rate * (1 + 1e-9))
                    self.assertGreaterEqual(np.min(d["vx_m_s"]), 0.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
