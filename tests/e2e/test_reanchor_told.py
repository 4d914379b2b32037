"""test_reanchor_told.py - a new trajectory begun by a clock stepped back is said at its line.

The bundled visnjan track (gpxgo_visnjan.csv), its first 199 fixes, then its first 99 again
(a log recorded twice: the time goes back to 0 at file line 201). The engine does not reject
the second lap row by row (its rows continue among themselves): it begins a new trajectory
there (`reanchors` 1) and the output reaches it by a transfer (REFERENCE.md "Duplicate and
backward rows"). That was only counted: no line said where or why.

- trajreplay says it at file line 201, with the new time (0) and the last kept one (the
  199th fix's, from the file), and "clock stepped back";
- trajd, replaying the same file, logs it with the waypoint's seq (200) and the times.
"""
import csv
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

BIN = os.path.join(mbsim.BUILD, "bin")
VIS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "gpxgo_visnjan.csv")


class ReanchorTold(unittest.TestCase):
    def test_clock_back_said(self):
        with open(VIS) as f:
            lines = f.read().splitlines()
        head, rows = lines[0], lines[1:]
        last_t = float(next(csv.reader([rows[198]]))[0])
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "twice.csv")
            with open(track, "w") as f:
                f.write("\n".join([head] + rows[:199] + rows[:99]) + "\n")
            p = subprocess.run([os.path.join(BIN, "trajreplay"), "-q", "--summary", "-o",
                                os.path.join(tmp, "o.csv"), track],
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("summary: reanchors 1\n", p.stderr)
            self.assertIn("%s:201: a new trajectory: t = 0.000 s, %.3f s before the last "
                          "waypoint kept (%.3f s)" % (track, last_t, last_t), p.stderr)
            self.assertIn("a clock stepped back", p.stderr)
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 20\nspeed = 200\nexit_when_done = yes\n"
                        "status_interval_s = 0\n[object.walk]\ninput = replay\n"
                        "replay.track = twice.csv\noutput = csv\ncsv.path = d.csv\n")
            p = subprocess.run([os.path.join(BIN, "trajd"), "-f", "-c", conf], cwd=tmp,
                               capture_output=True, text=True, timeout=120)
            self.assertEqual(p.returncode, 0, p.stderr[-2000:])
            self.assertRegex(p.stderr, r"object 'walk': a new trajectory at its waypoint seq 200, "
                                       r"t = 0\.000 s: %.3f s before the last waypoint kept"
                             % last_t)


if __name__ == "__main__":
    unittest.main()
