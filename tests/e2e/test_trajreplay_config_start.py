#!/usr/bin/python3
"""test_trajreplay_config_start.py - `trajreplay -c trajd.conf --object NAME`
starts the object as trajd does (daemon/REFERENCE.md: "what trajd streams for
NAME", byte-identical).

- initial_position: trajd's output stands there at rest from the first row
  and reaches the first waypoint by a transfer; trajreplay -c writes the same
  rows (it started with NaN rows, flag NO_POSITION, and waited at the first
  waypoint: no transfer, and no word of it);
- [daemon] catchup (how fast a lag is won back, relative time too):
  trajreplay -c gives the engine the config's, as trajd does;
- can.cia402 = feedback or managed (trajd starts the object where its drives
  stand): no file says where that is, so trajreplay says in one line that it
  ignores the key.

Each comparison runs the real trajd (a replay input, CSV output,
exit_when_done) and trajreplay on the same config, and compares the rows
tick by tick as tests/e2e/test_daemon.py does: a deadline trajd missed on
this shared machine leaves no row, and its next row carries the SKIPPED flag.
"""
import math
import os
import subprocess
import sys
import tempfile
import unittest

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
N2K = os.path.join(REPO, "tests", "data", "n2k_furuno_figure8_src52.csv")
PERIOD_NS = 10_000_000  # rate_hz = 100
F_HOLD, F_SKIPPED, F_TRANSFER, F_NOPOS = 0x01, 0x04, 0x08, 0x10
# The transfer's limits, given (not derived from the track): its peak speed is
# at most TRANSFER_V (lib/engine/transfer.h), and the lag won back adds at most
# catchup (0.05 by default) to its rate.
TRANSFER_V, TRANSFER_A, CATCHUP = 2.0, 1.0, 0.05
START = (12.0, -9.0, 0.0)  # 15 m from the track's first fix, the origin of its local frame


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def conf_text(obj_keys, daemon_keys=""):
    return ("[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\nstatus_interval_s = 0\n"
            + daemon_keys + "[object.boat]\ninput = replay\nreplay.track = fig8.csv\n"
            "output = csv\ncsv.path = out.csv\n" + obj_keys)


def run_both(tmp, obj_keys, daemon_keys=""):
    """trajd's and trajreplay -c's lines (header first), trajreplay's stderr and trajd's."""
    with open(N2K) as f:
        write(os.path.join(tmp, "fig8.csv"), "".join(f.readlines()[:152]))  # its first 30 s
    conf = os.path.join(tmp, "t.conf")
    write(conf, conf_text(obj_keys, daemon_keys))
    d = subprocess.run([TRAJD, "-f", "-c", conf], capture_output=True, text=True, timeout=120)
    assert d.returncode == 0, d.stderr
    ref = os.path.join(tmp, "ref.csv")
    r = subprocess.run([TRAJREPLAY, "-q", "-c", conf, "--object", "boat", "-o", ref],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    with open(os.path.join(tmp, "out.csv")) as f:
        dl = f.read().splitlines()
    with open(ref) as f:
        rl = f.read().splitlines()
    return dl, rl, r.stderr, d.stderr


def rows(lines):
    """[(now_ns, (x, y, z), (vx, vy, vz), (ax, ay, az), flags)] of CSV lines."""
    out = []
    for l in lines[1:]:
        c = l.split(",")
        out.append((int(c[1]), tuple(map(float, c[3:6])), tuple(map(float, c[6:9])),
                    tuple(map(float, c[9:12])), int(c[13])))
    return out


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


class ConfigStart(unittest.TestCase):
    def assert_rows_equal(self, dl, rl):
        """Every row trajd wrote is trajreplay's row of that tick, byte for
        byte, but for the SKIPPED flag of a row after a missed deadline."""
        self.assertEqual(dl[0], rl[0])  # header
        ref = {l.split(",", 2)[1]: l for l in rl[1:]}
        compared, prev = 0, -PERIOD_NS
        for l in dl[1:]:
            a = l.split(",")
            skipped = int(a[1]) - prev != PERIOD_NS
            prev = int(a[1])
            if a[1] not in ref:
                continue  # trajd ran on past trajreplay's last tick
            b = ref[a[1]].split(",")
            self.assertEqual(int(a[13]) & ~F_SKIPPED, int(b[13]), "tick %s: flags" % a[1])
            self.assertEqual(bool(int(a[13]) & F_SKIPPED), skipped, "tick %s: skip" % a[1])
            self.assertEqual(a[:13] + a[14:], b[:13] + b[14:], "tick %s" % a[1])
            compared += 1
        # the most of trajreplay's rows were compared (trajd's first included:
        # tick 0, or on a loaded machine the first deadline trajd woke for, a
        # few periods late, its row flagged SKIPPED, compared as the others)
        self.assertGreater(compared, 100)
        first = dl[1].split(",")
        self.assertTrue(first[1] == "0" or (int(first[1]) <= 50 * PERIOD_NS
                                            and int(first[13]) & F_SKIPPED), first)
        return compared

    def test_initial_position_as_trajd(self):
        with tempfile.TemporaryDirectory() as tmp:
            # Given an object that stands 15 m from its track's first fix at
            # start, with its transfers' speed and acceleration given,
            dl, rl, err, derr = run_both(tmp, "initial_position = %g,%g,%g\n" % START +
                                   "transfer_speed_m_s = %g\ntransfer_accel_m_s2 = %g\n"
                                   % (TRANSFER_V, TRANSFER_A))
            # (a) then trajreplay -c writes trajd's rows,
            n = self.assert_rows_equal(dl, rl)
            self.assertNotIn("notice", err)
            # and trajd's log says where it holds (it said "no position, nan, before its
            # first waypoint" while its rows stood at initial_position)
            self.assertIn("object 'boat': holds (state waiting) at rest at its initial_position "
                          "%g,%g,%g" % START, derr)
            self.assertNotIn("no position, nan", derr)
            rr = rows(rl)
            # (b) the first of which stands at initial_position, at rest,
            # holding, with a position (never NaN, NO_POSITION),
            t0, p0, v0, a0, f0 = rr[0]
            self.assertEqual((t0, p0, v0, a0), (0, START, (0.0,) * 3, (0.0,) * 3))
            self.assertTrue(f0 & F_HOLD and not f0 & F_NOPOS, f0)
            self.assertFalse([r for r in rr if r[4] & F_NOPOS or not all(map(math.isfinite, r[1]))])
            # (c) and a transfer (flagged) takes it from there to the first fix,
            xfer = [i for i, r in enumerate(rr) if r[4] & F_TRANSFER]
            self.assertTrue(xfer)
            self.assertEqual(xfer, list(range(xfer[0], xfer[-1] + 1)))  # one, unbroken
            self.assertEqual(rr[xfer[0] - 1][1], START)  # it leaves from there
            self.assertLess(dist(rr[xfer[-1]][1], (0, 0, 0)), TRANSFER_V * PERIOD_NS * 1e-9)
            # continuously: from the first row to the transfer's end no row
            # moves further than the transfer's speed bound allows in one tick
            bound = TRANSFER_V * (1 + CATCHUP) * PERIOD_NS * 1e-9
            worst = 0.0
            for a, b in zip(rr[:xfer[-1] + 1], rr[1:xfer[-1] + 2]):
                self.assertEqual(b[0] - a[0], PERIOD_NS)  # every tick written
                worst = max(worst, dist(a[1], b[1]))
            print("initial_position 15 m off: %d rows equal to trajd's, %d transfer rows, "
                  "largest step %.4f m (bound %.4f m)" % (n, len(xfer), worst, bound),
                  file=sys.stderr)
            self.assertLessEqual(worst, bound + 1e-12)
            self.assertGreater(worst, 0.5 * bound)  # it did move at about that speed

    def test_catchup_as_trajd(self):
        with tempfile.TemporaryDirectory() as tmp:
            # Given [daemon] catchup = 0 (the lag after the transfer from
            # initial_position is never won back; the engine's default wins it
            # back at 5 %), then trajreplay -c writes trajd's rows
            dl, rl, _, _ = run_both(tmp, "initial_position = %g,%g,%g\n" % START,
                                 "catchup = 0\n")
            n = self.assert_rows_equal(dl, rl)
            # (and the key does change them: not the same rows as by default)
            default = os.path.join(tmp, "default.csv")
            write(os.path.join(tmp, "d.conf"), conf_text("initial_position = %g,%g,%g\n" % START))
            r = subprocess.run([TRAJREPLAY, "-q", "-c", os.path.join(tmp, "d.conf"), "-o", default],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(default) as f:
                self.assertNotEqual(f.read().splitlines(), rl)
            print("catchup = 0: %d rows equal to trajd's" % n, file=sys.stderr)

    def test_drive_feedback_noticed(self):
        with tempfile.TemporaryDirectory() as tmp:
            with open(N2K) as f:
                write(os.path.join(tmp, "fig8.csv"), "".join(f.readlines()[:30]))
            base = ("[can]\nlog_out = /dev/null\nmax_load_percent = 0\n[object.b]\ninput = replay\n"
                    "replay.track = fig8.csv\noutput = can\ncan.cia402_cob_x = 0x201\n"
                    "can.cia402_cob_y = 0\ncan.cia402_cob_z = 0\ninitial_position = 1,2,0\n")
            conf = os.path.join(tmp, "c.conf")
            for mode, said in (("feedback", True), ("managed", True), ("targets", False),
                               ("off", False)):
                # Given an object whose drives tell trajd where they stand (or not),
                write(conf, base + "can.cia402 = %s\n" % mode)
                r = subprocess.run([TRAJREPLAY, "-q", "-c", conf, "-o", os.devnull],
                                   capture_output=True, text=True, timeout=120)
                self.assertEqual(r.returncode, 0, r.stderr)
                notes = [l for l in r.stderr.splitlines() if "notice" in l]
                # then trajreplay names the key it cannot apply, in one line
                if said:
                    self.assertEqual(len(notes), 1, r.stderr)
                    self.assertIn("object b: can.cia402 = %s ignored" % mode, notes[0])
                    self.assertIn("starts at initial_position", notes[0])
                else:
                    self.assertEqual(notes, [], r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
