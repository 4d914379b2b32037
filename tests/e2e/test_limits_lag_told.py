"""test_limits_lag_told.py - time lost to the object's own speed/acceleration limits is told.

A straight line at 3 m/s, 10 Hz, its stamps jittered by up to +-30 ms (seeded): the curve
through them bends harder than profile auto's acceleration limit almost everywhere, so the
time scaling plays it slower than its track (it holds the output to the limit: DESIGN.md)
and the output falls behind its input, further as the track goes on. That lag is timing
yielding (the lifecycle's precedence) and must be told: it was not (summary underruns 0,
lag_s 0, trajd "lags won back (now +0.000 s)", with the last waypoint reached 53 s late on
a 200 s track).

- trajreplay --summary: limits_lost_s is the time the output lost: within 10 % of how late
  the last waypoint is reached beyond D, measured on the output rows; a warning names the
  limits and the time lost. With --profile none: 0 lost, no warning, the last waypoint
  reached within D and a second.
- trajd on the same track (replay, speed 50): its exit line says the time lost.
"""
import csv
import os
import random
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

BIN = os.path.join(mbsim.BUILD, "bin")


def jittered(path):
    rnd = random.Random(1)
    with open(path, "w") as f:
        f.write("t,x,y\n")
        for i in range(2000):
            t = 0.1 * i
            j = rnd.uniform(-0.03, 0.03) if i else 0.0
            f.write("%.3f,%.4f,0\n" % (t + j, 3.0 * t))


def replay(track, out, *opts):
    p = subprocess.run([os.path.join(BIN, "trajreplay"), "-q", "--summary", *opts, "-o", out,
                        track], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    summ = dict(re.findall(r"^summary: (\S+) (\S+)$", p.stderr, re.M))
    with open(out) as f:
        fin = next(r for r in csv.DictReader(f) if r["state"] == "finished")
    late = int(fin["now_ns"]) * 1e-9 - float(fin["t_s"])   # the last waypoint reached this late
    return p.stderr, summ, late


class LimitsLagTold(unittest.TestCase):
    def test_time_lost_told(self):
        with tempfile.TemporaryDirectory() as tmp:
            track, out = os.path.join(tmp, "jit.csv"), os.path.join(tmp, "o.csv")
            jittered(track)
            err, s, late = replay(track, out)
            lost, d = float(s["limits_lost_s"]), float(s["delay_s"])
            self.assertGreater(late - d, 20.0, "the jittered line no longer falls behind")
            self.assertLess(abs(lost - (late - d)), 0.1 * (late - d), (lost, late, d))
            self.assertGreater(int(s["limits_slowed"]), 0)
            print("profile auto: %.1f s lost to the limits (limits_lost_s), the last waypoint "
                  "reached %.1f s late with D %.2f s" % (lost, late, d), file=sys.stderr)
            self.assertRegex(err, r"warning: the curve exceeds the object's speed or acceleration "
                                  r"limit .* lost %.1f s over" % lost)
            err, s, late = replay(track, out, "--profile", "none")
            self.assertEqual(float(s["limits_lost_s"]), 0.0)
            self.assertNotIn("exceeds the object's speed", err)
            self.assertLess(late, float(s["delay_s"]) + 1.0)
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nspeed = 50\nexit_when_done = yes\n"
                        "status_interval_s = 0\n[object.line]\ninput = replay\n"
                        "replay.track = jit.csv\noutput = csv\ncsv.path = d.csv\n")
            p = subprocess.run([os.path.join(BIN, "trajd"), "-f", "-c", conf], cwd=tmp,
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(p.returncode, 0, p.stderr[-2000:])
            m = re.search(r"line finished [^;]*, ([\d.]+) s lost to its speed/acceleration "
                          r"limits", p.stderr)
            self.assertIsNotNone(m, p.stderr[-2000:])
            self.assertGreater(float(m.group(1)), 20.0)
            self.assertIn("its curve exceeds its own speed or acceleration limit", p.stderr)


if __name__ == "__main__":
    unittest.main()
