"""test_reload_changed_resumes.py - a reload that changes only the engine settings of a
replayed object goes on along its track: the object never drives back to the track's start
to play it all again.

The real trajd replays a 10 Hz track (60 s, 2.5 m/s along a circle of radius 20 m) into a
CSV file at speed 8. While the object streams, one engine key is added to its section
(method = bspline) and trajd is sent SIGHUP: the object is a changed one (not carried over),
its old engine brakes to rest along the path, and the new engine takes over there. Judged
from the CSV rows alone:
- no row after the reload goes back along the track: every streaming row's t_s is at least
  the t_s the old engine reached (the old code went back to t_s 0 and played the track again);
- the new engine reaches the track from where the old one rested by a short transfer: no row
  is farther than 1 m from that rest point before the new trajectory streams (the old code
  drove 17 m back to the first waypoint);
- consecutive rows move at most max_speed_m_s x the periods between them (no step);
- the last row rests on the track's last waypoint, and the log says where the replay resumed.
Every wait is bounded; trajd is stopped by pid.
"""
import csv
import io
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 60
R, V, H, N = 20.0, 2.5, 0.1, 300  # radius m, speed m/s, interval s, waypoints
VMAX = 4.0                        # max_speed_m_s
PERIOD_S = 0.01
TRANSFER = 0x08                   # ENGINE_SP_TRANSFER (lib/motion.h)


def rows_of(path):
    with open(path) as f:
        text = [ln for ln in f if not ln.startswith("#") and not ln.startswith("object,")]
    with open(path) as f:
        header = next(ln for ln in f if ln.startswith("object,")).strip().split(",")
    return list(csv.DictReader(io.StringIO("".join(text)), fieldnames=header))


def circle_setup(tmp, extra=""):
    """The circle track (N waypoints) and a config replaying it at speed 8 into a.csv, with
    the control socket tmp/ctl (extra: more keys of the object); its path and text."""
    with open(os.path.join(tmp, "circle.csv"), "w") as f:
        f.write("t,x,y\n")
        for i in range(N):
            a = V * H * i / R
            f.write("%.1f,%.9f,%.9f\n" % (H * i, R * math.cos(a), R * math.sin(a)))
    conf = os.path.join(tmp, "trajd.conf")
    text = ("[daemon]\nrate_hz = 100\nspeed = 8\nexit_when_done = yes\n"
            "status_interval_s = 0\ncontrol_socket = %s/ctl\n"
            "[object.a]\ninput = replay\nreplay.track = circle.csv\n%s"
            "max_speed_m_s = %g\noutput = csv\ncsv.path = a.csv\n" % (tmp, extra, VMAX))
    with open(conf, "w") as f:
        f.write(text)
    return conf, text


def start(tmp, conf):
    return subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


class ReloadChangedCounts(unittest.TestCase):
    def test_counts_go_on_over_the_reload(self):
        """The circle with one fix 50 m off its path (row 42, refused as too fast); once it
        is judged, a reload changes the object (method = bspline): the new engine's
        counters add to the old one's.  The exit line still counts the refused fix, and
        every good row once accepted (those the old engine accepted and dropped as it
        braked, offered again to the new one, are also counted as dropped).  Before, the
        counters started again at 0: the refusal vanished (rejected 0) and only the new
        engine's waypoints were counted."""
        with tempfile.TemporaryDirectory() as tmp:
            conf, text = circle_setup(tmp)
            with open(os.path.join(tmp, "circle.csv")) as f:
                lines = f.readlines()
            t, x, y = lines[41].strip().split(",")
            lines[41] = "%s,%.9f,%s\n" % (t, float(x) + 50.0, y)
            with open(os.path.join(tmp, "circle.csv"), "w") as f:
                f.writelines(lines)
            p = start(tmp, conf)
            try:
                err = mbsim.Lines(p.stderr)
                self.assertIsNotNone(err.wait_for("rejected (speed)", WAIT_S), "".join(err.all))
                time.sleep(0.3)
                with open(conf, "w") as f:
                    f.write(text.replace("[object.a]\n", "[object.a]\nmethod = bspline\n"))
                p.send_signal(signal.SIGHUP)
                self.assertIsNotNone(err.wait_for("reloaded:", WAIT_S), "".join(err.all))
                rc = p.wait(WAIT_S)
            finally:
                if p.poll() is None:
                    p.kill()
                    p.wait()
            err.wait_for("\0", 5)
            log = "".join(err.all)
        self.assertEqual(rc, 0, log[-2000:])
        m = re.search(r"; a \w+ t=[-\d.]+ s, wp (\d+) ok (\d+) rejected .*?(?:, (\d+) waypoints "
                      r"dropped by a stop, clear or reload)?", log)
        self.assertIsNotNone(m, log[-2000:])
        ok, rej, dropped = int(m.group(1)), int(m.group(2)), int(m.group(3) or 0)
        self.assertEqual(rej, 1, m.group(0))
        self.assertGreaterEqual(ok - dropped, N - 3, m.group(0))


class ReloadChangedResumes(unittest.TestCase):
    def test_changed_object_goes_on_along_its_track(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf, text = circle_setup(tmp)
            out = os.path.join(tmp, "a.csv")
            p = start(tmp, conf)
            try:
                deadline = time.monotonic() + WAIT_S
                while True:  # streaming 20 s into the track
                    time.sleep(0.1)
                    self.assertLess(time.monotonic(), deadline, "never streamed to t_s 10")
                    try:
                        rows = rows_of(out)
                    except (OSError, StopIteration):
                        continue
                    if any(r["state"] == "streaming" and float(r["t_s"]) > 10.0 for r in rows):
                        break
                with open(conf, "w") as f:
                    f.write(text + "method = bspline\n")
                p.send_signal(signal.SIGHUP)
                _, err = p.communicate(timeout=WAIT_S)
            finally:
                if p.poll() is None:
                    p.kill()
                    p.wait()
            self.assertEqual(p.returncode, 0, err[-3000:])
            self.assertIn("0 carried over", err)
            rows = rows_of(out)
            # the old engine's rows: up to the new engine's first, which waits or
            # transfers (ENGINE_SP_TRANSFER) after the old one rested
            moving = next(i for i, r in enumerate(rows) if float(r["t_s"]) > 10.0)
            first_new = next(i for i in range(moving, len(rows))
                             if rows[i]["state"] == "waiting" or int(rows[i]["flags"]) & TRANSFER)
            rest = rows[first_new - 1]
            t_rest = float(rest["t_s"])
            self.assertGreater(t_rest, 9.0)
            p0 = (float(rest["x_m"]), float(rest["y_m"]))
            streamed = False
            for r in rows[first_new:]:
                if r["state"] == "streaming" and not int(r["flags"]) & TRANSFER:
                    streamed = True
                    self.assertGreaterEqual(float(r["t_s"]), t_rest - 1e-9, r)
                elif not streamed:
                    d = math.hypot(float(r["x_m"]) - p0[0], float(r["y_m"]) - p0[1])
                    self.assertLessEqual(d, 1.0, ("the transfer went %.2f m from where the old "
                                                  "engine rested" % d, r))
            self.assertTrue(streamed, "the new engine never streamed")
            placed = [r for r in rows if not math.isnan(float(r["x_m"]))]
            for b, a in zip(placed, placed[1:]):
                k = round((int(a["now_ns"]) - int(b["now_ns"])) * 1e-9 / PERIOD_S)
                d = math.hypot(float(a["x_m"]) - float(b["x_m"]), float(a["y_m"]) - float(b["y_m"]))
                self.assertLessEqual(d, VMAX * PERIOD_S * max(k, 1) + 1e-9, (b, a))
            last = rows[-1]
            a_end = V * H * (N - 1) / R
            self.assertLessEqual(math.hypot(float(last["x_m"]) - R * math.cos(a_end),
                                            float(last["y_m"]) - R * math.sin(a_end)), 1e-6)
            self.assertRegex(err, r"object 'a': its replay resumes after the row where its old "
                                  r"engine comes to rest \(it has played to t = [\d.]+ s\)")


class ReloadChangedWhileStopped(unittest.TestCase):
    def test_latched_rows_are_not_offered_again(self):
        """Stopped (latched) first, then the changed reload, then start: the rows the latch
        kept are played once, and the replay goes on after the newest of them (before: the
        replay began again at row 1 beside them: 'a clock stepped back', the object went
        back to the track's start)."""
        with tempfile.TemporaryDirectory() as tmp:
            conf, text = circle_setup(tmp, "writable = yes\n")
            ctl = os.path.join(tmp, "ctl")
            out = os.path.join(tmp, "a.csv")
            trajctl = os.path.join(os.path.dirname(TRAJD), "trajctl")
            p = start(tmp, conf)
            try:
                deadline = time.monotonic() + WAIT_S

                def wait_row(pred, what):
                    while True:
                        time.sleep(0.05)
                        self.assertLess(time.monotonic(), deadline, what)
                        try:
                            rows = rows_of(out)
                        except (OSError, StopIteration):
                            continue
                        if rows and pred(rows[-1]):
                            return rows

                wait_row(lambda r: r["state"] == "streaming" and float(r["t_s"]) > 6.0,
                         "never streamed to t_s 6")
                subprocess.run([trajctl, "-s", ctl, "stop", "a"], check=True, timeout=WAIT_S)
                rows = wait_row(lambda r: r["state"] == "finished", "never stopped")  # at rest
                t_stop = float(rows[-1]["t_s"])
                time.sleep(1.0)  # the latch keeps the rows that come meanwhile
                with open(conf, "w") as f:
                    f.write(text + "method = bspline\n")
                p.send_signal(signal.SIGHUP)
                time.sleep(0.2)  # soon: the rows kept and any offered again lie within D
                subprocess.run([trajctl, "-s", ctl, "start", "a"], check=True, timeout=WAIT_S)
                _, err = p.communicate(timeout=WAIT_S)
            finally:
                if p.poll() is None:
                    p.kill()
                    p.wait()
            self.assertEqual(p.returncode, 0, err[-3000:])
            self.assertIn("0 carried over", err)
            self.assertNotIn("stepped back", err)
            m = re.search(r"; a [^;]*? t=[-\d.]+ s, wp (\d+) ok (\d+) rejected", err)
            self.assertIsNotNone(m, err[-3000:])
            self.assertEqual(int(m.group(2)), 0, "a row offered twice is refused: " + m.group(0))
            rows = rows_of(out)
            i0 = next(i for i, r in enumerate(rows) if r["state"] == "finished")
            for r in rows[i0:]:
                if r["state"] == "streaming" and not int(r["flags"]) & TRANSFER:
                    self.assertGreaterEqual(float(r["t_s"]), t_stop - 1e-9, r)
            last = rows[-1]
            a_end = V * H * (N - 1) / R
            self.assertLessEqual(math.hypot(float(last["x_m"]) - R * math.cos(a_end),
                                            float(last["y_m"]) - R * math.sin(a_end)), 1e-6)


class ReloadChangedEdges(unittest.TestCase):
    def run_line(self, tmp, extra, reloads, gap_s, first_wait):
        """A line along x at 5 m/s (10 Hz, 30 s) replayed at speed 8; after first_wait(rows)
        holds, reloads changed reloads gap_s apart, each toggling method; returns the rows
        and the log."""
        with open(os.path.join(tmp, "line.csv"), "w") as f:
            f.write("t,x,y\n")
            for i in range(301):
                f.write("%.1f,%.2f,0\n" % (0.1 * i, 0.5 * i))
        conf = os.path.join(tmp, "t.conf")
        text = ("[daemon]\nrate_hz = 100\nspeed = 8\nexit_when_done = yes\n"
                "status_interval_s = 0\ncontrol_socket = %s/ctl\n"
                "[object.a]\ninput = replay\nreplay.track = line.csv\noutput = csv\n"
                "csv.path = a.csv\n%s" % (tmp, extra))
        with open(conf, "w") as f:
            f.write(text)
        out = os.path.join(tmp, "a.csv")
        p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            deadline = time.monotonic() + WAIT_S
            while True:
                time.sleep(0.02)
                self.assertLess(time.monotonic(), deadline, "never ready to reload")
                try:
                    if first_wait(rows_of(out)):
                        break
                except (OSError, StopIteration):
                    continue
            for k in range(reloads):
                with open(conf, "w") as f:
                    f.write(text + ("method = bspline\n" if k % 2 == 0 else ""))
                p.send_signal(signal.SIGHUP)
                time.sleep(gap_s)
            _, err = p.communicate(timeout=WAIT_S)
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
        self.assertEqual(p.returncode, 0, err[-3000:])
        return rows_of(out), err

    def test_reloads_during_the_transfer_never_go_back(self):
        """Changed reloads 1.1 s of track apart, each landing in the transfer of the one before: the
        object never moves back along the line (it went back 8.8 m: the resume point was
        taken from the transfer's own t_s, which trails the track), and the line is
        played to its end."""
        with tempfile.TemporaryDirectory() as tmp:
            rows, err = self.run_line(
                tmp, "", 3, 0.1375,
                lambda r: r and r[-1]["state"] == "streaming" and float(r[-1]["t_s"]) > 5.0)
            xs = [float(r["x_m"]) for r in rows if not math.isnan(float(r["x_m"]))]
            back = max((hi - x for hi, x in zip(
                [max(xs[:i + 1]) for i in range(len(xs))], xs)), default=0.0)
            self.assertLessEqual(back, 1e-6, "went back %.3f m along the line" % back)
            self.assertLessEqual(abs(xs[-1] - 150.0), 1e-6)
            self.assertNotIn("stepped back", err)

    def test_waiting_object_keeps_its_first_row(self):
        """A changed reload while the object still waits at its initial_position (it played
        nothing): the replay starts from the track's first row again, none skipped (it
        resumed 'after t = 0' and lost row 1: wp 300 of 301).  Rows the old engine took
        before the reload are counted in both: accepted, and dropped by the reload."""
        with tempfile.TemporaryDirectory() as tmp:
            rows, err = self.run_line(tmp, "initial_position = -30,0,0\n", 1, 0.05,
                                      lambda r: len(r) > 5)
            m = re.search(r"; a [^;]*? t=[-\d.]+ s, wp (\d+) ok", err)
            self.assertIsNotNone(m, err[-2000:])
            # the rows the old engine took before the reload (none, or a few
            # where the reload comes late on a loaded machine) are counted as
            # accepted and as dropped by the reload; the new engine takes all
            # 301 again
            d = re.search(r"(\d+) waypoints? dropped by a stop, clear or reload", err)
            dropped = int(d.group(1)) if d else 0
            self.assertEqual(int(m.group(1)) - dropped, 301, m.group(0) + (d.group(0) if d else ""))


if __name__ == "__main__":
    unittest.main(verbosity=2)
