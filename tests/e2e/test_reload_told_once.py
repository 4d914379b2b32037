"""test_reload_told_once.py - what a carried-over object's log already told is not told again.

trajd replays a line (writable, so trajctl commands it) with its control socket in the test's
directory. trajctl stop, then (after waypoints came while it was stopped) start: the start's
line says how many waypoints the latch buffered and dropped. Then trajctl reload with the file
unchanged (the object is carried over with its owner's counters), then trajctl clear while it
moves: the clear's line says nothing of waypoints while stopped or held, since none came
since the start's line (it repeated the start's figures after a reload, which read as that
many dropped again). Each trajectory's "trajectory N streams" line is told once (the reload
told it again).
"""
import os
import re
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

BIN = os.path.join(mbsim.BUILD, "bin")
WAIT_S = 30


class ToldOnce(unittest.TestCase):
    def test_clear_after_reload_tells_no_old_latch(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "track.csv"), 3000)
            sock = os.path.join(tmp, "ctl.sock")
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 0\n"
                        "control_socket = %s\n[object.boat]\ninput = replay\n"
                        "replay.track = track.csv\noutput = csv\ncsv.path = o.csv\n"
                        "writable = yes\n" % sock)
            p = subprocess.Popen([os.path.join(BIN, "trajd"), "-f", "-c", conf],
                                 stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                def ctl(*args):
                    r = subprocess.run([os.path.join(BIN, "trajctl"), "-s", sock, *args],
                                       capture_output=True, text=True, timeout=WAIT_S)
                    self.assertEqual(r.returncode, 0, (args, r.stdout, r.stderr))
                self.assertIsNotNone(lines.wait_for("trajectory 1 streams", WAIT_S))
                time.sleep(1.0)
                ctl("stop", "boat")
                time.sleep(2.0)               # waypoints come while it is stopped
                ctl("start", "boat")
                start = lines.wait_for("object 'boat': command start", WAIT_S)
                self.assertIsNotNone(start)
                self.assertRegex(start, r"waypoints while stopped or held: [1-9]\d* buffered")
                ctl("reload")
                self.assertIsNotNone(lines.wait_for("carried over", WAIT_S))
                time.sleep(1.0)
                ctl("clear", "boat")
                clear = lines.wait_for("object 'boat': command clear", WAIT_S)
                self.assertIsNotNone(clear)
                self.assertRegex(clear, r"in state (streaming|transfer)")
                self.assertNotIn("waypoints while stopped or held", clear)
            finally:
                p.terminate()
                p.wait(WAIT_S)
            lines.wait_for("\0", WAIT_S)  # the rest, to the end
            # each trajectory's start told once: the reload that carried the object over
            # told "trajectory N streams" again, as if it had restarted
            told = re.findall(r"object 'boat': trajectory (\d+) streams", "".join(lines.all))
            self.assertTrue(told)
            self.assertEqual(len(told), len(set(told)), told)


if __name__ == "__main__":
    unittest.main()
