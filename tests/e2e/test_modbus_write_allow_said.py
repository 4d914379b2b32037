"""test_modbus_write_allow_said.py - a [modbus] write_allow that cannot act is said.

trajd --check-config on a file written by hand: `write_allow` names the clients that may
write, but with `writes = no` (the default) no client may, so the list has no effect. The
check says so, one warning line with the file and the section's line, as it does for the
other keys set without effect (can.cia402_cob_*, start_vel_m_s), and passes (exit 0). It
said nothing. With writes = yes, or no write_allow, no such line.
"""
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
OBJ = ("[object.a]\ninput = replay\nreplay.track = track.csv\noutput = csv\n"
       "csv.path = a.csv\n")


def check(tmp, modbus):
    mbsim.line_track(os.path.join(tmp, "track.csv"), 20)
    path = os.path.join(tmp, "t.conf")
    with open(path, "w") as f:
        f.write("[modbus]\naddress = 127.0.0.1\n" + modbus + OBJ)
    return subprocess.run([TRAJD, "--check-config", path], cwd=tmp, capture_output=True,
                          text=True, timeout=60), path


class WriteAllowSaid(unittest.TestCase):
    def test_write_allow_without_writes_said(self):
        with tempfile.TemporaryDirectory() as tmp:
            p, path = check(tmp, "write_allow = 127.0.0.1\n")
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("%s:1: [modbus] write_allow is set but has no effect: writes = no"
                          % path, p.stderr)
            for modbus in ("writes = yes\nwrite_allow = 127.0.0.1\n", "writes = no\n"):
                p, _ = check(tmp, modbus)
                self.assertEqual(p.returncode, 0, p.stderr)
                self.assertNotIn("has no effect", p.stderr, modbus)


if __name__ == "__main__":
    unittest.main()
