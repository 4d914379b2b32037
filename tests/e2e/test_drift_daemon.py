#!/usr/bin/python3
"""A relative-time sender whose clock runs fast or slow, through the real
daemon (issue 26 item 3, lib/engine/catchup.h): trajd replays a candump
log_in of waypoint frames, each logged at its arrival on trajd's clock, at
speed 200: 30 minutes of a 2 Hz GNSS-like track (x = 300 sin(t/60),
y = 200 sin(t/97)) from a sender whose clock runs 500 ppm fast or slow,
each waypoint arriving 20..80 ms late (the issue's 24 h run, shortened;
500 ppm is drift_max_ppm's default).  With 1 % of the waypoints lost as
well, a lost one is a hole of two intervals against the start's slack of
one: such holes are slowdowns (reserve_slowed: the fixes after them came on
time, a whole number of intervals after the one before, lib/engine/delay.h),
won back like the drift, D kept: the delay at the end is the delay at the
start within one interval, with no underrun.

Given that log, when trajd plays the object out (relative time, [daemon]
catchup at its default 5 %), then the delay on the sender's clock at the end
is the delay at the start within one input interval and no waypoint-late
underrun occurs while the sender sends; with catchup = 0 (the old pace of
the stamps) the fast sender's delay grows by its drift (0.9 s) instead, so
the test can fail.  canmatrix encodes the frames from config/trajd.dbc.

`python3 tests/e2e/test_drift_daemon.py --day` runs the issue's 24 h scenario itself
(100 ppm, 1 % lost, at speed 100: about 15 minutes; not part of make check) and prints
its figures (day())."""
import csv
import decimal
import math
import os
import random
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
H = 0.5           # the sender's interval, s
N = 3600          # 30 minutes
SPEED = 200
RATE_HZ = 10


def write_log(path, ppm, loss=0.0, seed=7, n=None):
    rnd = random.Random(seed)
    db = ct.load_db()
    lines = []
    n = N if n is None else n
    for i in range(n):
        t = H * i
        if rnd.random() < loss and 0 < i < n - 1:
            continue  # lost
        x, y = 300 * math.sin(t / 60), 200 * math.sin(t / 97)
        arrive = t / (1 + ppm * 1e-6) + rnd.uniform(0.02, 0.08)
        dec = [decimal.Decimal("%.6f" % v) for v in (t, x, y, 0.0)]
        for can_id, data, is_fd in ct.waypoint_frames(db, i + 1, *dec):
            lines.append("(%.6f) can0 %s\n" % (arrive, ct.fmt_frame(can_id, data, is_fd)))
    with open(path, "w") as fh:
        fh.write("# a sender %+g ppm off, %g %% lost, 20..80 ms late\n" % (ppm, 100 * loss))
        fh.writelines(lines)


def write_conf(d, catchup=None, speed=None):
    conf = os.path.join(d, "t.conf")
    with open(conf, "w") as fh:
        fh.write("[daemon]\nrate_hz = %d\nspeed = %d\nclock = relative\nexit_when_done = yes\n"
                 "status_interval_s = 0\nstop_timeout_s = 1\n%s"
                 "[can]\nlog_in = wp.log\nlog_ifname = vcan0\nmax_late_ms = 0\n"
                 "[object.gnss]\ninput = can\noutput = csv\ncsv.path = sp.csv\n"
                 % (RATE_HZ, speed or SPEED,
                    "catchup = %g\n" % catchup if catchup is not None else ""))
    return conf


def read_rows(d, track=False):
    rows = []
    with open(os.path.join(d, "sp.csv")) as fh:
        for r in csv.DictReader(fh):
            rows.append((int(r["now_ns"]) * 1e-9, float(r["t_s"]), r["state"])
                        + ((int(r["track"]),) if track else ()))
    return rows


def run(d, ppm, catchup, timeout=120):
    conf = write_conf(d, catchup)
    p = subprocess.run([TRAJD, "-f", "-c", conf], cwd=d, capture_output=True, text=True,
                       timeout=timeout)
    return p, read_rows(d)


def delays(rows, ppm, lo, hi):
    """now - t_s on the sender's clock (what D is stated in), streaming rows
    with now in [lo, hi)."""
    d = sorted(now * (1 + ppm * 1e-6) - t for now, t, st in rows
               if st == "streaming" and lo <= now < hi)
    return d[len(d) // 2] if d else float("nan")


class DriftDaemon(unittest.TestCase):
    def check(self, ppm, catchup=None, loss=0.0):
        with tempfile.TemporaryDirectory() as d:
            write_log(os.path.join(d, "wp.log"), ppm, loss)
            p, rows = run(d, ppm, catchup)
        self.assertEqual(p.returncode, 0, p.stderr[-2000:])
        end_in = (N - 1) * H / (1 + ppm * 1e-6)
        start, end = delays(rows, ppm, 120, 300), delays(rows, ppm, end_in - 200, end_in - 20)
        late = sum(1 for now, t, st in rows if st == "underrun" and now < end_in)
        print("sender %+d ppm, %g %% lost, catchup %s: delay %.3f s at 2..5 min, %.3f s at the end; "
              "%d underrun rows while it sends" % (ppm, 100 * loss, catchup, start, end, late), file=sys.stderr)
        return start, end, late, p.stderr

    def test_fast_sender_followed(self):
        start, end, late, err = self.check(500)
        self.assertLessEqual(abs(end - start), H)
        self.assertEqual(late, 0)
        self.assertIn("lags won back", err)

    def test_slow_sender_followed(self):
        start, end, late, _ = self.check(-500)
        self.assertLessEqual(abs(end - start), H)
        self.assertEqual(late, 0)

    def test_lost_waypoints_followed(self):
        # a regular sender's lost fixes are slowed for and won back, D kept
        # (lib/engine/delay.h engine_input_regular): before, D learnt an interval
        # for them and the delay ended 0.54 s above its start
        start, end, late, err = self.check(500, loss=0.01)
        self.assertLessEqual(abs(end - start), H)
        self.assertEqual(late, 0)
        self.assertIn(", 0 underruns", err)

    def test_without_catchup_the_drift_is_lag(self):
        start, end, _, _ = self.check(500, catchup=0)
        self.assertGreater(end - start, 0.7)  # 500 ppm of 30 min: 0.9 s


class MissedDeadlines(unittest.TestCase):
    """Frames of a log_in due within deadlines trajd missed reach the engine at their own
    step.  trajd, replaying 5 minutes of the 2 Hz track at speed 50, is stopped (SIGSTOP)
    for 1 s while it streams: 50 s of the sender's time, five times its D.  On SIGCONT it
    steps through every deadline it missed (speed != 1), and each step is given the frames
    due by then: the object streams on, one trajectory, no underrun and no silent end.  With
    the input drained once per tick instead, those 50 s of frames waited for the next tick,
    the engine saw a silence longer than its slack and ended the trajectory there (a silent
    end), and the waypoints then became a second trajectory reached by a transfer."""

    def test_frames_due_in_missed_deadlines(self):
        n, speed = 600, 50
        with tempfile.TemporaryDirectory() as d:
            write_log(os.path.join(d, "wp.log"), 0, n=n)
            conf = write_conf(d, speed=speed)
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=d, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            try:
                time.sleep(2.0)  # 100 s of the sender's time: streaming (D is about 11 s)
                p.send_signal(signal.SIGSTOP)
                time.sleep(1.0)
                p.send_signal(signal.SIGCONT)
                _, err = p.communicate(timeout=120)
            finally:
                if p.poll() is None:
                    p.kill()
            rows = read_rows(d, track=True)
        self.assertEqual(p.returncode, 0, err[-2000:])
        # the stop came mid-motion: the widest step between rows (trajd writes no rows for
        # the deadlines it missed) is the stop's, streaming on both sides
        gaps = [(rows[i + 1][0] - rows[i][0], i) for i in range(len(rows) - 1)]
        gap, i = max(gaps)
        print("stopped %.1f s of the sender's time at t_s %.1f; %s" % (
            gap, rows[i][1], [l for l in err.splitlines() if "exit:" in l][-1][:160]),
            file=sys.stderr)
        self.assertGreater(gap, 0.5 * speed, "no deadline missed: the stop did not happen")
        self.assertTrue(rows[i][2] == "streaming" and rows[i + 1][2] == "streaming",
                        "not streaming across the stop: %r, %r" % (rows[i], rows[i + 1]))
        self.assertLess(rows[i][1], (n - 1) * H - gap, "stopped after the input's end")
        self.assertEqual({r[3] for r in rows if r[2] != "waiting"}, {1}, "one trajectory")
        self.assertEqual(sum(1 for r in rows if r[2] == "underrun"), 0)
        self.assertIn(", 0 underruns", err)
        self.assertNotIn("silent end", err)


def day():
    """The issue's 24 h run itself (issue 26 item 3), not a test: 172 800 fixes at 0.5 s
    from a sender 100 ppm fast, 1 % lost, 20..80 ms late, at speed 100 (about 15 minutes),
    with trajd's log.  Prints the delay at 2..5 min and at the end on the sender's clock,
    the underrun rows while it sends, and trajd's log lines about D and underruns.
    Run: BUILD=$PWD/build python3 tests/e2e/test_drift_daemon.py --day"""
    global N, SPEED
    N, SPEED, ppm = 172800, 100, 100
    with tempfile.TemporaryDirectory() as d:
        write_log(os.path.join(d, "wp.log"), ppm, 0.01)
        p, rows = run(d, ppm, None, timeout=3600)
    end_in = (N - 1) * H / (1 + ppm * 1e-6)
    print("trajd exit %d; delay %.3f s at 2..5 min, %.3f s at the end; %d underrun rows while "
          "it sends" % (p.returncode, delays(rows, ppm, 120, 300),
                        delays(rows, ppm, end_in - 200, end_in - 20),
                        sum(1 for now, t, st in rows if st == "underrun" and now < end_in)))
    for line in p.stderr.splitlines():
        if "play-out delay D" in line or "underrun" in line or line.startswith("<6>exit"):
            print(line)


if __name__ == "__main__":
    if sys.argv[1:] == ["--day"]:
        day()
    else:
        unittest.main()
