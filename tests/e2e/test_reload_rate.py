"""test_reload_rate.py - a reload that would change rate_hz while an object moves is refused;
at rest it is taken.

The real trajd replays a 10 Hz track at 5 m/s into a CSV file (rate_hz 100, speed 2). While
the object streams, rate_hz is changed to 250 and trajd is sent SIGHUP. The old engine's
braking runs on the period it was built for, so such a reload cannot keep the output
continuous: it must be refused with a line naming rate_hz and the moving object, and the
running configuration goes on. Judged from the rows: no row is held by the safety monitor
(flag FAULT), every row is one period (10 ms) after the one before (or flagged SKIPPED where the
machine made trajd miss deadlines), and no row moves more than max_speed_m_s x the periods. Before: the reload was taken, the first row after it was refused by trajd's
own monitor (977 m/s^2 against 70), the object froze, held until clear, and the run exited 75.
Then, with the object at rest at its track's end, the same reload is taken (rows 4 ms apart).
Every wait is bounded; trajd is stopped by pid.
"""
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 60
FAULT = 0x20  # ENGINE_SP_FAULT (lib/motion.h)
SKIPPED = 0x04  # ENGINE_SP_SKIPPED: deadlines missed before this row (a loaded machine)
VMAX = 8.0


def rows_of(path):
    with open(path) as f:
        return [ln.strip().split(",") for ln in f
                if not ln.startswith("#") and not ln.startswith("object,")]


class ReloadRate(unittest.TestCase):
    def test_rate_change_refused_while_moving(self):
        with tempfile.TemporaryDirectory() as tmp:
            with open(os.path.join(tmp, "line.csv"), "w") as f:
                f.write("t,x,y\n")
                for i in range(150):
                    f.write("%.1f,%.2f,0\n" % (0.1 * i, 0.5 * i))
            conf = os.path.join(tmp, "t.conf")
            text = ("[daemon]\nrate_hz = %d\nspeed = 2\nstatus_interval_s = 0\ncontrol_socket = %s/ctl\n"
                    "[object.a]\ninput = replay\nreplay.track = line.csv\noutput = csv\n"
                    "csv.path = a.csv\nmax_speed_m_s = %g\n")
            with open(conf, "w") as f:
                f.write(text % (100, tmp, VMAX))
            out = os.path.join(tmp, "a.csv")
            p, lines, _ = None, None, None
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                deadline = time.monotonic() + WAIT_S
                while True:  # streaming at speed
                    time.sleep(0.05)
                    self.assertLess(time.monotonic(), deadline, "never streamed")
                    try:
                        rows = rows_of(out)
                    except OSError:
                        continue
                    if rows and rows[-1][12] == "streaming" and float(rows[-1][2]) > 3.0:
                        break
                with open(conf, "w") as f:
                    f.write(text % (250, tmp, VMAX))
                p.send_signal(signal.SIGHUP)
                line = lines.wait_for("reload refused", WAIT_S)
                self.assertIsNotNone(line, "".join(lines.all))
                self.assertIn("rate_hz", line)
                self.assertIn("'a'", line)
                while rows_of(out)[-1][12] != "finished":  # the track plays to its end
                    self.assertLess(time.monotonic(), deadline, "never finished")
                    time.sleep(0.1)
                rows = rows_of(out)
                for b, a in zip(rows, rows[1:]):
                    self.assertFalse(int(a[13]) & FAULT, a)
                    if math.isnan(float(b[3])):
                        continue
                    k = (int(a[1]) - int(b[1])) // 10_000_000  # periods (missed: SKIPPED)
                    self.assertTrue(k == 1 or (k > 1 and int(a[13]) & SKIPPED), (b, a))
                    self.assertLessEqual(math.hypot(float(a[3]) - float(b[3]),
                                                    float(a[4]) - float(b[4])),
                                         VMAX * 0.01 * k + 1e-9, (b, a))
                # at rest: the same reload is taken
                n = len(rows)
                p.send_signal(signal.SIGHUP)
                line = lines.wait_for("reloaded:", WAIT_S)
                self.assertIsNotNone(line, "".join(lines.all))
                while len(rows_of(out)) < n + 10:
                    self.assertLess(time.monotonic(), deadline, "no rows after the reload")
                    time.sleep(0.05)
                rows = rows_of(out)
                # the new period (a row flagged SKIPPED: a deadline missed on a loaded machine)
                last = [(b, a) for b, a in zip(rows[n:], rows[n + 1:]) if not int(a[13]) & SKIPPED]
                self.assertTrue(last, rows[n:])
                b, a = last[-1]
                self.assertEqual(int(a[1]) - int(b[1]), 4_000_000, (b, a))
            finally:
                p.send_signal(signal.SIGTERM)
                rc = p.wait(WAIT_S)
            self.assertEqual(rc, 0, "".join(lines.all)[-3000:])


if __name__ == "__main__":
    unittest.main(verbosity=2)
