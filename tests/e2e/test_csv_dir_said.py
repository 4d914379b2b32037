"""test_csv_dir_said.py - a csv.path in a directory that does not exist is said, with file:line.

trajd --check-config passes such a file (the directory may be made before the start: a
systemd RuntimeDirectory is made before the unit's check runs), but says it in a warning
naming the file, the object's line and the directory. The start then fails (exit 69,
EX_UNAVAILABLE) with an error naming the file, the object's line and the key, not only the
path (it said "csv: object 'a': csv.path ./nodir/a.csv: No such file or directory", after a
check that said nothing).
"""
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")


class CsvDirSaid(unittest.TestCase):
    def test_missing_directory_said_at_check_and_start(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "track.csv"), 20)
            path = os.path.join(tmp, "t.conf")
            with open(path, "w") as f:
                f.write("[daemon]\nexit_when_done = yes\nstatus_interval_s = 0\n\n"
                        "[object.a]\ninput = replay\nreplay.track = track.csv\noutput = csv\n"
                        "csv.path = nodir/a.csv\n")
            p = subprocess.run([TRAJD, "--check-config", path], cwd=tmp, capture_output=True,
                               text=True, timeout=60)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertRegex(p.stderr, r"%s:5: \[object\.a\] csv\.path \S*nodir/a\.csv: its "
                                       r"directory \S*nodir is not a directory that exists"
                             % path)
            p = subprocess.run([TRAJD, "-f", "-c", path], cwd=tmp, capture_output=True,
                               text=True, timeout=60)
            self.assertEqual(p.returncode, 69, p.stderr)
            self.assertRegex(p.stderr, r"cannot start: csv: %s:5: \[object\.a\] csv\.path "
                                       r"\S*nodir/a\.csv: No such file or directory" % path)
            os.mkdir(os.path.join(tmp, "nodir"))
            p = subprocess.run([TRAJD, "--check-config", path], cwd=tmp, capture_output=True,
                               text=True, timeout=60)
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertNotIn("not a directory that exists", p.stderr)


if __name__ == "__main__":
    unittest.main()
