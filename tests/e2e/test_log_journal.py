"""test_log_journal.py - on journald's stream, trajd logs natively with structured fields.

In a private mount namespace (unshare -m; skipped where that is not allowed)
a tmpfs hides /run and this test binds its own datagram socket at
/run/systemd/journal/socket, where libsystemd's sd_journal_sendv sends; trajd
runs with JOURNAL_STREAM naming its stderr pipe, as systemd sets it.
Then, reading the datagrams as journald would (KEY=value lines):
- every line has MESSAGE, PRIORITY, SYSLOG_IDENTIFIER=trajd, CODE_FILE (a .c
  file of the tree), CODE_LINE (> 0) and CODE_FUNC;
- the start line is PRIORITY 6; a refused waypoint of the figure-eight track
  is a warning (4) with OBJECT=boat (the [object] name);
- nothing of it went to stderr (no duplicate "<N>" line).
Without the socket, lines go to stderr with "<N>" (tests/unit/test_log.c).
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")

INNER = r'''
import json, os, socket, subprocess, sys
trajd, conf = sys.argv[1], sys.argv[2]
subprocess.run(["mount", "-t", "tmpfs", "tmpfs", "/run"], check=True)
os.makedirs("/run/systemd/journal")
s = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
s.bind("/run/systemd/journal/socket")
s.settimeout(0.2)
r, w = os.pipe()
st = os.fstat(w)
env = dict(os.environ, JOURNAL_STREAM="%d:%d" % (st.st_dev, st.st_ino))
p = subprocess.Popen([trajd, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                     stdout=subprocess.DEVNULL, stderr=w, env=env)
os.close(w)
recs = []
def drain():
    while True:
        try:
            d = s.recv(65536)
        except socket.timeout:
            return
        recs.append(dict(l.split("=", 1) for l in d.decode().split("\n") if "=" in l))
while p.poll() is None:
    drain()
drain()
err = b""
while True:
    b = os.read(r, 65536)
    if not b:
        break
    err += b
print(json.dumps({"rc": p.returncode, "records": recs, "stderr": err.decode(errors="replace")}))
'''


def can_unshare():
    return (shutil.which("unshare") and os.geteuid() == 0 and
            subprocess.run(["unshare", "-m", "true"], capture_output=True).returncode == 0)


class JournalFields(unittest.TestCase):
    @unittest.skipUnless(can_unshare(), "needs root and unshare -m (a private mount namespace)")
    def test_native_fields(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "t.conf")
            # the track with one row stamped before the row it follows: refused
            # (backwards) and logged with its object, as a warning
            track = os.path.join(tmp, "track.csv")
            with open(TRACK) as f, open(track, "w") as g:
                rows = f.read().splitlines()
                rows.insert(200, rows[150])
                g.write("\n".join(rows) + "\n")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 20\nspeed = 400\nexit_when_done = yes\n"
                        "status_interval_s = 0\n[object.boat]\ninput = replay\n"
                        "replay.track = %s\noutput = csv\ncsv.path = %s/b.csv\n" % (track, tmp))
            out = subprocess.run(["unshare", "-m", sys.executable, "-c", INNER, TRAJD, conf],
                                 capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 0, out.stderr)
            res = json.loads(out.stdout)
            recs = res["records"]
            self.assertEqual(res["rc"], 0, res)
            self.assertTrue(recs, res)
            for r in recs:
                self.assertEqual(r.get("SYSLOG_IDENTIFIER"), "trajd", r)
                self.assertIn(r.get("PRIORITY"), list("01234567"), r)
                self.assertTrue(r.get("MESSAGE"), r)
                self.assertTrue(r.get("CODE_FILE", "").endswith(".c"), r)
                self.assertTrue(os.path.exists(os.path.join(ROOT, r["CODE_FILE"])), r)
                self.assertGreater(int(r.get("CODE_LINE", "0")), 0, r)
                self.assertTrue(r.get("CODE_FUNC"), r)
            started = [r for r in recs if r["MESSAGE"].startswith("started:")]
            self.assertEqual([r["PRIORITY"] for r in started], ["6"], recs)
            refused = [r for r in recs if r.get("OBJECT") == "boat"]
            self.assertTrue(refused, [r["MESSAGE"] for r in recs])
            self.assertTrue(all(r["PRIORITY"] == "4" for r in refused), refused)
            self.assertNotIn("started:", res["stderr"])


if __name__ == "__main__":
    unittest.main()
