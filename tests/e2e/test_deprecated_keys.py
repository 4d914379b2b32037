"""test_deprecated_keys.py - the former CiA 402 keys (issue 25 item 1) as trajd reads them.

(And a CiA 402 key that has no effect, can.cia402_cob_* with can.cia402 off, is said.)

trajd --check-config on configs written by hand, as a user upgrading one would:
* each former form (can.cia402 = yes, can.cia402 = no, can.cia402_feedback,
  can.cia402_enable) is still read, and says so: one line, with file:line, naming the
  form to write instead (config/trajd.conf: "Deprecated, still read (with a line in the
  log)");
* a former key that contradicts the mode given with the new key (can.cia402 = targets
  with can.cia402_feedback = yes) is refused, exit 78, whichever comes first: it used to
  set the mode anew, and an object configured for RPDOs only sent none.
"""
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
HEAD = ("[can]\nlog_out = /dev/null\nmax_load_percent = 0\n"
        "[object.boat]\ninitial_position = 1,2,0\ninput = replay\nreplay.track = track.csv\n"
        "output = can\ncan.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0\ncan.cia402_cob_z = 0\n")
FIRST = HEAD.count("\n") + 1  # the line of the first key after HEAD


def check(tmp, keys):
    mbsim.line_track(os.path.join(tmp, "track.csv"), 50)
    path = os.path.join(tmp, "t.conf")
    with open(path, "w") as f:
        f.write(HEAD + keys)
    return subprocess.run([TRAJD, "--check-config", path], cwd=tmp, capture_output=True,
                          text=True, timeout=60), path


class Deprecated(unittest.TestCase):
    def test_each_former_form_says_so(self):
        cases = (("can.cia402 = yes\n", "can.cia402 = yes is deprecated: write can.cia402 = "
                  "feedback"),
                 ("can.cia402 = no\n", "can.cia402 = no is deprecated: write can.cia402 = off"),
                 ("can.cia402 = yes\ncan.cia402_feedback = no\n",
                  "can.cia402_feedback = no is deprecated: write can.cia402 = feedback or "
                  "targets"),
                 ("can.cia402 = yes\ncan.cia402_enable = yes\n",
                  "can.cia402_enable = yes is deprecated: write can.cia402 = managed"))
        with tempfile.TemporaryDirectory() as tmp:
            for keys, want in cases:
                p, path = check(tmp, keys)
                self.assertEqual(p.returncode, 0, p.stderr)
                line = FIRST + keys.count("\n") - 1
                self.assertIn("%s:%d: %s" % (path, line, want), p.stderr, keys)

    def test_contradiction_refused(self):
        cases = ("can.cia402 = targets\ncan.cia402_feedback = yes\n",
                 "can.cia402_feedback = yes\ncan.cia402 = targets\n",
                 "can.cia402 = managed\ncan.cia402_enable = no\n",
                 "can.cia402_enable = yes\ncan.cia402 = feedback\n")
        with tempfile.TemporaryDirectory() as tmp:
            for keys in cases:
                p, path = check(tmp, keys)
                self.assertEqual(p.returncode, 78, (keys, p.stderr))
                self.assertIn("%s:%d:" % (path, FIRST + 1), p.stderr, keys)
                self.assertIn("contradicts can.cia402 = ", p.stderr, keys)
            # agreeing ones are read
            for keys in ("can.cia402 = targets\ncan.cia402_feedback = no\n",
                         "can.cia402_enable = yes\ncan.cia402 = managed\n"):
                p, _ = check(tmp, keys)
                self.assertEqual(p.returncode, 0, (keys, p.stderr))

    def test_cob_ids_without_cia402_said(self):
        # can.cia402_cob_* with can.cia402 off: accepted and ignored unsaid before
        with tempfile.TemporaryDirectory() as tmp:
            p, path = check(tmp, "can.cia402 = off\n")
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("%s:4: object 'boat': can.cia402_cob_* is set but has no effect: "
                          "can.cia402 is off" % path, p.stderr)
            p, _ = check(tmp, "can.cia402 = feedback\n")
            self.assertNotIn("has no effect", p.stderr)


if __name__ == "__main__":
    unittest.main()
