"""test_can_reload.py - what a CAN peer counts by survives a reload, and is logged as it comes;
STATUS counts for the object (its reloads, its latch while stopped), as Modbus does.

trajd reads a real track (figure eight, NMEA 2000 GNSS) as waypoint frames from a candump
log ([can] log_in: the same codec and port as on a socket), built by canmatrix from
config/trajd.dbc, with faults in it: waypoint 50 missing (1 lost), two malformed frames
beside waypoint 60. It writes its frames to a candump log ([can] log_out), decoded here by
python-can and canmatrix. Half way, after the faults, it gets a SIGHUP with the file
unchanged (the object carried over without interruption).

- Every counter of the STATUS frames (lost, malformed, rejected, dropped) never goes back:
  they wrap at 256 on the wire, and a peer that counts by deltas read a reload that zeroed
  13 drops as 243 new ones. Before, the reload zeroed them (lost 1 -> 0, malformed 2 -> 0).
- The loss and the malformed frames are logged while trajd runs, with the frame id, before
  the reload (before, only the info line of the exit summary or of the reload named them).
"""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
NPOINTS = 150   # 30 s of track
SPEED = 6       # 5 s of wall time: the faults (waypoints 50, 60: 10 and 12 s) at 2 s
RELOAD_AT_S = 3.2


def write_conf(conf, extra="", exit_when_done=True):
    """trajd reading wp.log and writing sp.log (candump logs, engine time); extra: more
    lines for [object.boat]."""
    with open(conf, "w") as fh:
        fh.write("[daemon]\nrate_hz = 100\nspeed = %d\n%sstop_timeout_s = 1\n"
                 "status_interval_s = 0\n"
                 "[can]\nlog_in = wp.log\nlog_out = sp.log\nlog_ifname = vcan0\n"
                 "log_time = engine\nmax_late_ms = 0\n"
                 "[object.boat]\ninput = can\noutput = can\n%s"
                 % (SPEED, "exit_when_done = yes\n" if exit_when_done else "", extra))


def run_with_reload(d, at_s, extra=None):
    """trajd in d on wp.log, a SIGHUP after at_s seconds (with [object.boat] given extra
    first, if any: a changed object); its exit status, its stderr and the reload's line."""
    conf = os.path.join(d, "t.conf")
    write_conf(conf)
    p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=d, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(at_s)
        if extra is not None:
            write_conf(conf, extra)
        p.send_signal(signal.SIGHUP)
        _, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    reloaded = [l for l in err.splitlines() if "reloaded" in l]
    return p.returncode, err, reloaded[0] if reloaded else None


class CanReload(unittest.TestCase):
    def test_counters_survive_a_reload_and_are_logged(self):
        with tempfile.TemporaryDirectory() as d:
            xyz = os.path.join(d, "track.csv")
            ct.to_xyz(TRACK, xyz, NPOINTS)
            ct.write_faulty_wplog(xyz, os.path.join(d, "wp.log"))
            rc, err, line = run_with_reload(d, RELOAD_AT_S)
            self.assertEqual(rc, 0, err)
            self.assertIsNotNone(line, err)
            self.assertIn("carried over without interruption", line)
            lines = err.splitlines()
            reload_at = lines.index(line)
            # logged as they came, before the reload, with the frame id
            before = "\n".join(lines[:reload_at])
            self.assertRegex(before, r"can: object 'boat': .*1 waypoint.* lost.*0x680", err)
            self.assertRegex(before, r"can: object 'boat': .*2 malformed frame.*0x680", err)
            st = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)
            self.assertGreater(len(st), 20)
            for name in ("ST_Lost", "ST_Malformed", "ST_Rejected", "ST_Dropped"):
                seq = [int(s[name]) for _, s in st]
                went_back = [(a, b) for a, b in zip(seq, seq[1:]) if b < a]
                self.assertEqual(went_back, [], "%s went back: %s" % (name, went_back))
            self.assertEqual(int(st[-1][1]["ST_Lost"]), 1)
            self.assertEqual(int(st[-1][1]["ST_Malformed"]), 2)

    def test_rejected_survive_a_changed_reload(self):
        """A fix 2 km off the track is refused once judged with its neighbours (the engine's
        count, not the port's); then a reload changes the object's settings (a new engine
        takes over).  STATUS's rejected count stays with the object, as on Modbus and the
        status line: it never goes back.  Before, STATUS read the new engine's own count,
        1 -> 0 at the reload."""
        with tempfile.TemporaryDirectory() as d:
            xyz = os.path.join(d, "track.csv")
            ct.to_xyz(TRACK, xyz, NPOINTS)
            with open(xyz) as fh:
                rows = fh.read().splitlines()
            f = rows[41].split(",")  # waypoint 40 (8 s of the track: 1.3 s of wall time)
            f[1] = "%.6f" % (float(f[1]) + 2000.0)
            rows[41] = ",".join(f)
            with open(xyz, "w") as fh:
                fh.write("\n".join(rows) + "\n")
            ct.write_wplog(xyz, os.path.join(d, "wp.log"))
            rc, err, line = run_with_reload(d, RELOAD_AT_S, "max_speed_m_s = 500\n")
            self.assertEqual(rc, 0, err)
            self.assertIsNotNone(line, err)
            self.assertIn("0 carried over", line)
            st = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)
            seq = [int(s["ST_Rejected"]) for _, s in st]
            self.assertIn(1, seq, err[-3000:])  # refused before the reload
            went_back = [(a, b) for a, b in zip(seq, seq[1:]) if b < a]
            self.assertEqual(went_back, [], "ST_Rejected went back: %s" % (went_back,))
            self.assertGreaterEqual(seq[-1], 1)

    def test_free_while_stopped_is_the_latch_room(self):
        """Stop now (CAN STOP) at waypoint 40, the sender going on: its waypoints wait in the
        object's latch, so STATUS's free is the latch's room, which falls by one a waypoint,
        as on Modbus.  Before, STATUS gave the engine's own free room, which no waypoint
        reached while stopped (it stayed put)."""
        with tempfile.TemporaryDirectory() as d:
            xyz = os.path.join(d, "track.csv")
            ct.to_xyz(TRACK, xyz, NPOINTS)
            wp = os.path.join(d, "wp.log")
            ct.write_wplog(xyz, wp)
            db = ct.load_db()
            with open(wp) as fh:
                lines = fh.read().splitlines()
            at = max(i for i, l in enumerate(lines) if "680#04" not in l and "680#" in l and
                     int(l.split("#")[1][2:4], 16) == 40)
            t_stop = float(lines[at].split()[0].strip("()"))
            lines.insert(at + 1, "(%.6f) vcan0 %s" % (t_stop, ct.fmt_frame(*ct.command_frame(db, 2))))
            with open(wp, "w") as fh:
                fh.write("\n".join(lines) + "\n")
            conf = os.path.join(d, "t.conf")
            write_conf(conf, exit_when_done=False)
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=d, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            time.sleep(NPOINTS * 0.2 / SPEED + 1.5)  # the whole log sent
            p.send_signal(signal.SIGTERM)
            _, err = p.communicate(timeout=60)
            st = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)
            after = [int(s["ST_Free"]) for ts, s in st if ts * 1e-9 > t_stop + 0.5]
            sent_after = NPOINTS - 40
            self.assertGreater(len(after), 20, err[-3000:])
            self.assertEqual([(a, b) for a, b in zip(after, after[1:]) if b > a], [],
                             "free rose while stopped: %s" % after)
            self.assertTrue(after[-1] == 0 or after[-1] <= after[0] - sent_after // 2,
                            "free while stopped, %d waypoints sent: %s ... %s" % (sent_after, after[:3], after[-3:]))

    def test_log_ending_after_a_changed_reload(self):
        """The log's last waypoint, then 6 s of the track's time with nothing, then FINISH;
        a reload that changes the object's settings comes in those 6 s (a new engine, which
        gets no waypoint before the log ends).  The object had its waypoints: trajd ends with
        status 0, without 'no usable waypoint', and STATUS's last accepted seq stays 40.
        Before, the log's end asked the new engine alone: '0 accepted', exit status 65; and
        STATUS's last seq went 40 -> 0 at the reload (a sender paced by it saw its waypoints
        untaken)."""
        with tempfile.TemporaryDirectory() as d:
            xyz = os.path.join(d, "track.csv")
            n = 40  # 8 s of track, 1.3 s of wall time at speed 6
            ct.to_xyz(TRACK, xyz, n)
            wp = os.path.join(d, "wp.log")
            ct.write_wplog(xyz, wp)
            with open(wp) as fh:
                lines = fh.read().splitlines()
            ts, rest = lines[-1].split(" ", 1)  # FINISH: 6 s after the last waypoint
            lines[-1] = "(%.6f) %s" % (float(ts.strip("()")) + 6.0, rest)
            with open(wp, "w") as fh:
                fh.write("\n".join(lines) + "\n")
            # the reload after the last waypoint, before FINISH
            rc, err, line = run_with_reload(d, (8.0 + 2.5) / SPEED + 0.2, "max_speed_m_s = 500\n")
            self.assertIn("0 carried over", line or "", err[-3000:])
            self.assertNotIn("no usable waypoint", err)
            # the last waypoint taken stays the object's (40) when the new engine has none
            seq = [int(x["ST_LastSeq"]) for _, x in ct.decode_by_id(os.path.join(d, "sp.log"),
                                                                       0x6C0)]
            self.assertEqual([(a, b) for a, b in zip(seq, seq[1:]) if b < a], [],
                             "ST_LastSeq went back: ... %s" % seq[-40:])
            self.assertEqual(seq[-1], n)
            self.assertEqual(rc, 0, err[-3000:])


if __name__ == "__main__":
    unittest.main()
