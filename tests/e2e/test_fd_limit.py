"""test_fd_limit.py - the file descriptors a configuration needs, against RLIMIT_NOFILE.

A configuration of 100 objects, each replaying a small track into its own CSV file, holds
about 150 descriptors open. trajd runs under limits set in the child before exec
(setrlimit, as `ulimit -n` or systemd's LimitNOFILE= would):
* a hard limit of 64: `--check-config` refuses it (exit 78) and says how many descriptors it
  needs, against which limit, and what to raise. It used to say "ok", and the start then
  failed opening the 50th file;
* a soft limit of 64 under a hard one of 4096: `--check-config` passes with a note, and
  trajd raises its soft limit at start: every object runs to its end (exit_when_done, exit
  0) and every CSV file holds its rows. It used to exit 69 (an output could not open).
"""
import os
import resource
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
OBJECTS = 100


def limits(soft, hard):
    def set_them():
        resource.setrlimit(resource.RLIMIT_NOFILE, (soft, hard))
    return set_them


def config(tmp):
    with open(os.path.join(tmp, "t.csv"), "w") as f:
        f.write("t,x,y\n")
        for i in range(30):
            f.write("%.1f,%.2f,0\n" % (0.1 * i, 0.1 * i))
    os.mkdir(os.path.join(tmp, "out"))
    path = os.path.join(tmp, "many.conf")
    with open(path, "w") as f:
        f.write("[daemon]\nrate_hz = 50\nspeed = 10\nexit_when_done = yes\n"
                "status_interval_s = 0\n")
        for i in range(OBJECTS):
            f.write("[object.o%d]\nid = %d\ninput = replay\nreplay.track = t.csv\n"
                    "output = csv\ncsv.path = out/o%d.csv\n" % (i, i, i))
    return path


class FdLimit(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.conf = config(self.tmp)

    def tearDown(self):
        self.tmpd.cleanup()

    def test_check_config_refuses_beyond_the_hard_limit(self):
        r = subprocess.run([TRAJD, "--check-config", self.conf], cwd=self.tmp,
                           capture_output=True, text=True, timeout=60,
                           preexec_fn=limits(64, 64))
        self.assertEqual(r.returncode, 78, r.stdout + r.stderr)
        self.assertIn("file descriptors", r.stderr)
        self.assertIn("hard limit of 64", r.stderr)
        self.assertIn("LimitNOFILE", r.stderr)
        need = int(r.stderr.split("holds about ")[1].split()[0])
        self.assertGreaterEqual(need, OBJECTS)

    def test_start_raises_the_soft_limit(self):
        r = subprocess.run([TRAJD, "--check-config", self.conf], cwd=self.tmp,
                           capture_output=True, text=True, timeout=60,
                           preexec_fn=limits(64, 4096))
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
        self.assertIn("note:", r.stderr)
        self.assertIn("soft limit of 64", r.stderr)
        r = subprocess.run([TRAJD, "-f", "-c", self.conf], cwd=self.tmp, capture_output=True,
                           text=True, timeout=120, preexec_fn=limits(64, 4096))
        self.assertEqual(r.returncode, 0, r.stderr[-2000:])
        for i in range(OBJECTS):
            with open(os.path.join(self.tmp, "out", "o%d.csv" % i)) as f:
                rows = f.read().splitlines()
            self.assertGreater(len(rows), 100, "o%d" % i)


if __name__ == "__main__":
    unittest.main()
