"""test_user_files.py - the files trajd creates belong to its [daemon] user.

trajd is started as root with [daemon] user = nobody: it opens its outputs, then drops to
that user (config/trajd.conf). A CSV output it creates itself is then nobody's, so a reload
(SIGHUP, the configuration unchanged) opens it again, the rows go on after it, and trajd exits
0. Before, it created the file as root (0644) before the drop; the first reload could not open
it ("Permission denied"), the running output was left closed, its setpoints counted lost, trajd
exited 74, and the exit line named the last write error "Success".

Needs root (as `make check` runs); skipped otherwise, saying so.
"""
import os
import pwd
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


@unittest.skipUnless(os.geteuid() == 0, "needs root: trajd drops from root to [daemon] user")
class UserFiles(unittest.TestCase):
    def test_reload_reopens_a_file_trajd_created(self):
        with tempfile.TemporaryDirectory() as d:
            os.chmod(d, 0o755)
            # the track beside it: a reload reads it again as nobody, who may not enter
            # the tree (a clone under a directory only root may enter)
            track = os.path.join(d, "track.csv")
            shutil.copy(os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv"), track)
            conf = os.path.join(d, "t.conf")
            out = os.path.join(d, "boat.csv")
            with open(conf, "w") as f:
                f.write("[daemon]\nstatus_interval_s = 0\nspeed = 20\nuser = nobody\n"
                        "control_socket = %s\n[object.boat]\ninput = replay\nreplay.track = %s\n"
                        "output = csv\ncsv.path = %s\n" % (os.path.join(d, "ctl"), track, out))
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            try:
                end = time.monotonic() + 20
                while not (os.path.exists(out) and os.path.getsize(out) > 1000):
                    self.assertLess(time.monotonic(), end, "no rows")
                    time.sleep(0.05)
                self.assertEqual(os.stat(out).st_uid, pwd.getpwnam("nobody").pw_uid)
                p.send_signal(signal.SIGHUP)
                time.sleep(1.0)
                n = os.path.getsize(out)
                time.sleep(1.0)
                self.assertGreater(os.path.getsize(out), n, "no rows after the reload")
            finally:
                p.send_signal(signal.SIGTERM)
                _, err = p.communicate(timeout=30)
            self.assertIn("reloaded:", err)
            self.assertNotIn("did not reopen", err)
            self.assertEqual(p.returncode, 0, err[-2000:])


if __name__ == "__main__":
    unittest.main()
