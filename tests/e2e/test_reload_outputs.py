"""test_reload_outputs.py - what a reload does to outputs and inputs (issue 24 item 7).

The real trajd, reloaded by SIGHUP while its object moves:
1. A reload that turns on csv.geo and csv.age appends its 21-field rows under a
   new 21-field header line (after the "# trajd: appended" marker): every row
   of the file has the fields of the last header above it (the old code wrote
   them under the old 16-field header).  csv.truncate = yes applies at start
   only: the rows from before the reload are still there (the old code emptied
   the file at every reload).
2. A reload that carries a CAN-input object over goes on reading its candump
   log_in where it was: no waypoint is offered twice (the old code played the
   file again from its start, moving the object back to its first waypoint),
   so the 300 waypoints are accepted once in all and none refused, and x
   never goes back.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 30


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def rows_of(path):
    with open(path) as f:
        return [line.rstrip("\n") for line in f]


def wait_rows(path, n):
    deadline = time.monotonic() + WAIT_S
    while True:
        if os.path.exists(path) and len(rows_of(path)) >= n:
            return
        if time.monotonic() > deadline:
            raise AssertionError("%s: fewer than %d lines" % (path, n))
        time.sleep(0.05)


def start(conf):
    p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    lines = mbsim.Lines(p.stderr)
    if lines.wait_for("started:", WAIT_S) is None:
        p.kill()
        raise AssertionError("trajd did not start: " + "".join(lines.all))
    return p, lines


def reload(p, lines):
    p.send_signal(signal.SIGHUP)
    if lines.wait_for("reloaded:", WAIT_S) is None:
        raise AssertionError("no reload: " + "".join(lines.all))


def rest(lines):
    """Every line until trajd's stderr ends (after it exited)."""
    while lines.wait_for("\0", WAIT_S) is not None:
        pass
    return "".join(lines.all)


def stop(p):
    if p.poll() is None:
        p.send_signal(signal.SIGTERM)
    return p.wait(WAIT_S)


def walk_csv(path, n=600, dt=0.1):
    """x = t at 1 m/s for n fixes."""
    write(path, "t,x,y,z\n" + "".join("%.3f,%.3f,0,0\n" % (i * dt, i * dt) for i in range(n)))


CSV_CONF = """[daemon]
rate_hz = 50
speed = 1
status_interval_s = 0
stop_timeout_s = 1
[object.a]
input = replay
replay.track = walk.csv
output = csv
csv.path = out.csv
csv.truncate = yes
%s
"""


def le48(v):
    return (v & ((1 << 48) - 1)).to_bytes(6, "little").hex().upper()


def waypoint_frames(seq, t_s, pos_m):
    """The 4 WAYPOINT frames (config/PROTOCOL.md): mux 0 time (us, uint48),
    1..3 x, y, z (um, int48); byte 1 the low 8 bits of seq."""
    out = ["00%02X%s" % (seq & 0xFF, le48(round(t_s * 1e6)))]
    for a in range(3):
        out.append("%02X%02X%s" % (a + 1, seq & 0xFF, le48(round(pos_m[a] * 1e6))))
    return out


class Reload(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.p = None

    def tearDown(self):
        if self.p and self.p.poll() is None:
            self.p.kill()
            self.p.wait(WAIT_S)
        self.tmpd.cleanup()

    def test_new_columns_new_header_and_no_truncate(self):
        walk_csv(os.path.join(self.tmp, "walk.csv"))
        conf = os.path.join(self.tmp, "trajd.conf")
        out = os.path.join(self.tmp, "out.csv")
        write(out, "old,content\n")          # truncate = yes: emptied at start
        write(conf, CSV_CONF % "")
        self.p, lines = start(conf)
        wait_rows(out, 20)
        write(conf, CSV_CONF % "csv.geo = yes\ncsv.age = yes")
        reload(self.p, lines)
        n = len(rows_of(out))
        wait_rows(out, n + 20)
        self.assertEqual(stop(self.p), 0, rest(lines))
        rows = rows_of(out)
        # truncated at start only: the first header and row 0 are still there
        self.assertTrue(rows[0].startswith("object,now_ns,"), rows[:2])
        self.assertNotIn("old,content", rows)
        self.assertTrue(rows[1].startswith("a,0,"), rows[1])
        headers = [r for r in rows if r.startswith("object,")]
        self.assertEqual([len(h.split(",")) for h in headers], [16, 21], headers)
        self.assertTrue(headers[1].endswith(",lat_deg,lon_deg,alt_m,heading_deg,age_s"), headers[1])
        width = None
        for i, r in enumerate(rows):
            if r.startswith("#"):
                continue
            if r.startswith("object,"):
                width = len(r.split(","))
                continue
            self.assertEqual(len(r.split(",")), width, "line %d: %s" % (i + 1, r))

    def test_log_in_not_played_again(self):
        # 30 s of waypoints at 10 Hz, x = t, on the default WAYPOINT id 0x680
        log = []
        for k in range(300):
            t = 0.1 * k
            for f in waypoint_frames(k + 1, t, (t, 0.0, 0.0)):
                log.append("(%.6f) can0 680#%s" % (t, f))
        write(os.path.join(self.tmp, "in.log"), "\n".join(log) + "\n")
        conf = os.path.join(self.tmp, "trajd.conf")
        out = os.path.join(self.tmp, "out.csv")
        write(conf, "[daemon]\nrate_hz = 50\nspeed = 3\nstatus_interval_s = 0\n[can]\nlog_in = in.log\n"
                    "[object.a]\ninput = can\noutput = csv\ncsv.path = out.csv\n")
        self.p, lines = start(conf)
        wait_rows(out, 200)                # moving (a few seconds in)
        reload(self.p, lines)
        deadline = time.monotonic() + 60
        while float(rows_of(out)[-1].split(",")[3]) < 28.4:   # the log played to its end
            self.assertLess(time.monotonic(), deadline, "never finished")
            time.sleep(0.1)
        self.assertEqual(stop(self.p), 0, rest(lines))
        text = rest(lines)
        self.assertIn("going on after its", text)
        # one summary per CAN transport that closed (the reload's, then the exit's); the
        # object's counters go on over the reload (test_can_reload.py): the last one
        # counts every waypoint once
        summaries = [x for x in lines.all if "setpoints sent" in x]
        self.assertEqual(len(summaries), 2, text)
        accepted = int(summaries[-1].split("waypoints ")[1].split(" accepted")[0])
        self.assertEqual(accepted, 300, text)
        for x in summaries:
            self.assertIn(" accepted, 0 rejected", x)
            self.assertIn("0 duplicate frames, 0 out of order", x)
        xs = [float(r.split(",")[3]) for r in rows_of(out)
              if r.startswith("a,") and r.split(",")[3] != "nan"]
        self.assertGreater(xs[-1], 28.0)   # where its lookahead ends (no FINISH)
        back = max(xs[i] - xs[i + 1] for i in range(len(xs) - 1))
        self.assertLess(back, 1e-6, "x went back by %g m" % back)


if __name__ == "__main__":
    unittest.main(verbosity=2)
