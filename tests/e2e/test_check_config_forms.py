"""test_check_config_forms.py - the ways a user writes trajd's configuration check.

trajd(8): `trajd --check-config FILE`, and `trajd -c FILE --check-config` (no file after
--check-config: the -c one), which a user who runs `trajd -c FILE` writes by adding the
option; it was a usage error (exit 64, "option '--check-config' requires an argument").
Both check the same file the same way: exit 0 and "FILE: ok" for a good one, exit 78
(EX_CONFIG) and FILE:LINE for a bad one. A directory given as the file is refused as one
(exit 78, "Is a directory"); it was read as an empty file ("no [object.NAME] section").
"""
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
GOOD = ("[object.a]\ninput = replay\nreplay.track = track.csv\noutput = csv\n"
        "csv.path = a.csv\n")


def run(*args, cwd):
    return subprocess.run([TRAJD, *args], cwd=cwd, capture_output=True, text=True, timeout=60)


class CheckConfigForms(unittest.TestCase):
    def test_forms(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "track.csv"), 20)
            good, bad = os.path.join(tmp, "good.conf"), os.path.join(tmp, "bad.conf")
            with open(good, "w") as f:
                f.write(GOOD)
            with open(bad, "w") as f:
                f.write("[daemon]\nrate_hz = 0\n" + GOOD)
            for args in (("--check-config", good), ("-c", good, "--check-config"),
                         ("--check-config", "-c", good), ("--check-config=" + good,)):
                p = run(*args, cwd=tmp)
                self.assertEqual(p.returncode, 0, (args, p.stderr))
                self.assertIn("%s: ok, 1 object(s): a" % good, p.stdout + p.stderr, args)
            for args in (("--check-config", bad), ("-c", bad, "--check-config")):
                p = run(*args, cwd=tmp)
                self.assertEqual(p.returncode, 78, (args, p.stderr))
                self.assertIn("%s:2: [daemon] rate_hz: expected a number in" % bad, p.stderr)
            p = run("--check-config", tmp, cwd=tmp)
            self.assertEqual(p.returncode, 78, p.stderr)
            self.assertIn("%s: Is a directory" % tmp, p.stderr)
            p = run("--check-config", good, "other", cwd=tmp)
            self.assertEqual(p.returncode, 64, p.stderr)
            self.assertIn("unexpected argument 'other'", p.stderr)

    def test_no_config_says_what_to_do(self):
        """trajd with no -c and nothing at /etc/trajd/trajd.conf says how to give one (it said
        only 'No such file or directory'), exit 78."""
        if os.path.exists("/etc/trajd/trajd.conf"):
            self.skipTest("this machine has a trajd installed at /etc/trajd/trajd.conf")
        with tempfile.TemporaryDirectory() as tmp:
            for args in (("-f",), ("--check-config",)):
                p = run(*args, cwd=tmp)
                self.assertEqual(p.returncode, 78, (args, p.stderr))
                self.assertIn("give one with -c FILE", p.stderr, args)

    def test_hash_after_a_value_said(self):
        """'#' starts a comment only at the start of a line (trajd.conf's first lines): a
        path written 'out.csv   # the output file' is taken whole, and the check says so
        at its line.  It passed with nothing said, and trajd wrote a file of that name."""
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "track.csv"), 20)
            conf = os.path.join(tmp, "h.conf")
            with open(conf, "w") as f:
                f.write(GOOD.replace("csv.path = a.csv", "csv.path = a.csv   # the output"))
            p = run("--check-config", conf, cwd=tmp)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("%s:5: [object.a] csv.path: 'a.csv   # the output' is taken whole"
                          % conf, p.stderr)
            with open(conf, "w") as f:
                f.write(GOOD.replace("csv.path = a.csv", "csv.path = a.csv ; the output"))
            p = run("--check-config", conf, cwd=tmp)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertNotIn("taken whole", p.stderr)


if __name__ == "__main__":
    unittest.main()
