"""test_exit_when_done_held.py - exit_when_done ends a run whose object the safety monitor
holds, with exit 75, and a full buffer counts each waypoint once.

The real trajd replays a 60 s track at 5 m/s (10 Hz) at speed 20 with exit_when_done = yes
and a position box it leaves at x = 10 m: the monitor holds the object there (a speed or
acceleration bound would not do: one set is kept by the engine, which slows), and only a
clear would move it again. Its replay then offers the next row at every tick, each
refused with a full buffer. trajd must end by itself (the track takes 3 s of wall time, the
wait is bounded at 60 s) with exit 75 and an error line naming the held object, and the exit
line's count of waypoints refused "full" must be at most the track's 600 rows (each waypoint
once, not each offer again). Before: trajd never ended (killed after 30 s, exit 124) and
counted 57 134 refusals for a 600-row track.
"""
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
N = 600


class ExitWhenDoneHeld(unittest.TestCase):
    def test_held_object_ends_the_run(self):
        with tempfile.TemporaryDirectory() as tmp:
            with open(os.path.join(tmp, "line.csv"), "w") as f:
                f.write("t,x,y\n")
                for i in range(N):
                    f.write("%.1f,%.2f,0\n" % (0.1 * i, 0.5 * i))
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                        "status_interval_s = 0\ncontrol_socket = %s/ctl\n"
                        "[object.a]\ninput = replay\nreplay.track = line.csv\noutput = csv\n"
                        "csv.path = a.csv\nmax_speed_m_s = 10\nposition_min_m = -1000, -1000, -1000\n"
                        "position_max_m = 10, 1000, 1000\n" % tmp)
            try:
                p = subprocess.run([TRAJD, "-f", "-c", conf], cwd=tmp, capture_output=True,
                                   text=True, timeout=60)
            except subprocess.TimeoutExpired as e:
                self.fail("trajd did not end: %s" % (e.stderr or b"")[-2000:])
            self.assertEqual(p.returncode, 75, p.stderr[-3000:])
            self.assertTrue(any("ended held" in ln and "'a'" in ln for ln in p.stderr.splitlines()),
                            p.stderr[-3000:])
            m = re.search(r"; a [^;]*? t=[-\d.]+ s, wp (\d+) ok (\d+) rejected (\d+) full", p.stderr)
            self.assertIsNotNone(m, p.stderr[-3000:])
            self.assertLessEqual(int(m.group(3)), N, m.group(0))


if __name__ == "__main__":
    unittest.main(verbosity=2)
