"""test_safety_told_after_clear.py - once a clear released a safety hold, the log never says
the object is still held.

The real trajd replays a figure-eight (5 Hz, up to 14 m/s) at speed 2 with
a position box it leaves at x = 20 m (a bound the engine does not keep; a speed or an
acceleration bound it keeps, slowing along the path): the monitor holds the object early on,
refusing a setpoint every tick. The box is widened by a reload (the object is carried over,
still held) and trajctl clear releases it. The monitor's count of refused setpoints is told once a second; the line
told after the clear must not say "holding at ... until 'clear'" (it did, every time: an
operator reading the journal believed the object still held).
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

BIN = os.path.join(mbsim.BUILD, "bin")


def conf(tmp, bound):
    with open(os.path.join(tmp, "t.conf"), "w") as f:
        f.write("[daemon]\nrate_hz = 100\nspeed = 2\nstatus_interval_s = 0\nstop_timeout_s = 10\n"
                "control_socket = %s/ctl\n[object.obj]\nid = 0\ninput = replay\n"
                "replay.track = track.csv\noutput = csv\ncsv.path = out.csv\nwritable = yes\n"
                "profile = vessel\nmax_speed_m_s = 20\nmax_accel_m_s2 = 10\n"
                "position_min_m = -1000, -1000, -1000\nposition_max_m = %d, 1000, 1000\n"
                % (tmp, bound))


class SafetyToldAfterClear(unittest.TestCase):
    def test_no_hold_said_after_the_clear(self):
        with tempfile.TemporaryDirectory() as tmp:
            R, v = 60.0, 10.0
            with open(os.path.join(tmp, "track.csv"), "w") as f:
                f.write("t,x,y,z\n")
                for i in range(201):
                    t = 0.2 * i
                    f.write("%.6f,%.6f,%.6f,0.0\n" % (t, R * math.sin(v / R * t),
                                                       0.5 * R * math.sin(2 * v / R * t)))
            conf(tmp, 20)
            p = subprocess.Popen([os.path.join(BIN, "trajd"), "-f", "-c", "t.conf"], cwd=tmp,
                                 stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                self.assertIsNotNone(lines.wait_for("safety monitor", 30), "".join(lines.all))
                time.sleep(1)
                conf(tmp, 1000)
                p.send_signal(signal.SIGHUP)
                self.assertIsNotNone(lines.wait_for("reloaded:", 30), "".join(lines.all))
                time.sleep(0.5)
                r = subprocess.run([os.path.join(BIN, "trajctl"), "-s", os.path.join(tmp, "ctl"),
                                    "clear", "obj"], capture_output=True, text=True, timeout=30)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertIsNotNone(lines.wait_for("command clear", 30), "".join(lines.all))
                time.sleep(1.5)  # the next counts told (once a second)
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(30)
            lines.wait_for("\0", 30)
            log = "".join(lines.all)
            after = log[log.index("command clear"):]
            self.assertNotIn("until 'clear'", after, after[:2000])


if __name__ == "__main__":
    unittest.main(verbosity=2)
