"""test_reload_nohold.py - a reload never holds up the tick (issue 28, item 2).

A configuration of two objects at 100 Hz: a replays a short track, b a
1 000 000-waypoint CSV written here.  The ticks and the missed deadlines are
read from the control socket's status (the core's stats, as the status line
and the Modbus/CAN status show them).

1. Three reloads, each with b's track touched (a new mtime: parsed again):
   ticks + missed over the seconds they span is at least 97 % of the wall
   time x rate, and missed at most 1 % (the track is parsed beside the
   running configuration, the new one swapped in between two ticks).
   trajd runs with [realtime] fifo_priority = 10 (as a deployment does; where
   it may not, it warns and runs on without).
2. A reload whose track file was replaced by another, with trajd stopped
   (SIGSTOP) for 0.3 s while it parses: the deadlines that passed are counted
   as missed, and ticks + missed follows the wall clock within 3 ticks (the
   output clock kept its phase: not restarted by the reload).
3. SIGTERM while a reload parses a 1e6-waypoint track: trajd brings its
   objects to rest and exits 0 at once; the reload is dropped, never swapped.
4. SIGHUPs while a reload parses: coalesced into one more reload after it.
5. Three reloads that change every one of 256 objects (a new engine each):
   missed at most 1 %, ticks + missed at least 97 % (the engines are built
   beside the running core, daemon/core/cfgload.c).
6. SIGTERM while the configuration is first read (the 1e6-waypoint track
   parsed at start): the parse is cancelled, trajd exits 0.

Before this work the parse ran in the event loop and core_start restarted the
clock: test 1 counted about 70 % of the deadlines, test 2 lost the parse's
deadlines uncounted, test 3 swapped the reload in before it stopped.
"""
import json
import os
import queue
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import unittest

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
RATE_HZ = 100
N_BIG = 1_000_000
WAIT_S = 30
# Whatever else runs beside trajd may stall it now and then, reload or not
# (even at SCHED_FIFO, a CPU taken from the whole guest): test 1 gives the
# <= 1 % of missed deadlines three attempts, and prints each.  Ticks + missed
# >= 97 % is required of every attempt (a deadline lost uncounted is trajd's
# fault, whatever stalled it).
ATTEMPTS = 3


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def big_csv(path, n=N_BIG, dt=0.01, y=0.0):
    """n fixes dt apart on a line at 1 m/s: t,x,y,z."""
    with open(path, "w") as f:
        f.write("t,x,y,z\n")
        step = 100000
        for k in range(0, n, step):
            f.write("".join("%.2f,%.2f,%g,1\n" % (i * dt, i * dt, y)
                            for i in range(k, min(n, k + step))))


def small_csv(path, n=3000, dt=0.1):
    rows = ["t,x,y,z"] + ["%.1f,%.2f,5,1" % (i * dt, 0.5 * i * dt) for i in range(n)]
    write(path, "\n".join(rows) + "\n")


def sigterm(d):
    """SIGTERM to trajd d: its exit status, the seconds it took and its log."""
    t0 = time.monotonic()
    d.p.send_signal(signal.SIGTERM)
    rc = d.p.wait(WAIT_S)
    return rc, time.monotonic() - t0, "\n".join(d.rest())


class Trajd:
    """trajd -f with its stderr read by a thread (lines with their arrival time)."""

    def __init__(self, tmp, conf):
        self.tmp = tmp
        self.sock = os.path.join(tmp, "ctl.sock")
        self.p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.q = queue.Queue()
        self.lines = []
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self):
        for line in self.p.stderr:
            self.q.put(line.rstrip("\n"))
        self.q.put(None)

    def wait_for(self, needle, timeout=WAIT_S):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                line = self.q.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                break
            if line is None:
                break
            self.lines.append(line)
            if needle in line:
                return line
        raise AssertionError("no %r in trajd's log:\n%s" % (needle, "\n".join(self.lines)))

    def rest(self):
        """The lines left, once trajd has exited."""
        while True:
            line = self.q.get(timeout=WAIT_S)
            if line is None:
                return self.lines
            self.lines.append(line)

    def status(self):
        """(monotonic time of the request's middle, ticks, missed) from the control socket."""
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(WAIT_S)
        s.connect(self.sock)
        f = s.makefile("r")
        f.readline()  # hello
        t0 = time.monotonic()
        s.sendall(b"status\n")
        while True:
            d = json.loads(f.readline())
            if d.get("reply") == "status":
                break
        t1 = time.monotonic()
        s.close()
        return (t0 + t1) / 2, d["ticks"], d["missed_ticks"]

    def stop(self):
        if self.p.poll() is None:
            self.p.send_signal(signal.SIGTERM)
        try:
            return self.p.wait(WAIT_S)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
            raise


def config(tmp, big, note=""):
    return ("# %s\n[daemon]\nrate_hz = %d\nstatus_interval_s = 0\nstop_timeout_s = 0.5\n"
            "control_socket = %s\n[realtime]\nfifo_priority = 10\n"
            "[object.a]\nid = 0\ninput = replay\nreplay.track = %s\noutput = csv\ncsv.path = %s\n"
            "[object.b]\nid = 1\ninput = replay\nreplay.track = %s\noutput = csv\ncsv.path = %s\n"
            % (note, RATE_HZ, os.path.join(tmp, "ctl.sock"), os.path.join(tmp, "a.csv"),
               os.path.join(tmp, "a.out"), big, os.path.join(tmp, "b.out")))


class ReloadNoHold(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmpdir = tempfile.TemporaryDirectory()
        cls.tmp = cls.tmpdir.name
        small_csv(os.path.join(cls.tmp, "a.csv"))
        cls.big = os.path.join(cls.tmp, "big.csv")
        big_csv(cls.big)

    @classmethod
    def tearDownClass(cls):
        cls.tmpdir.cleanup()

    def start(self, big):
        conf = os.path.join(self.tmp, "trajd.conf")
        write(conf, config(self.tmp, big))
        d = Trajd(self.tmp, conf)
        self.addCleanup(d.stop)
        d.wait_for("started:")
        time.sleep(0.3)
        return d, conf

    def counted(self, s0, s1):
        wall = (s1[0] - s0[0]) * RATE_HZ
        return wall, (s1[1] - s0[1]) + (s1[2] - s0[2]), s1[2] - s0[2]

    def test_three_reloads(self):
        d, conf = self.start(self.big)
        seen = []
        for attempt in range(ATTEMPTS):
            s0 = d.status()
            for i in range(3):
                now = time.time()
                os.utime(self.big, (now, now + 10 * attempt + i + 1))  # changed: parsed again
                write(conf, config(self.tmp, self.big, "reload %d.%d" % (attempt, i)))
                d.p.send_signal(signal.SIGHUP)
                d.wait_for("reloaded:")
                time.sleep(0.5)
            s1 = d.status()
            wall, counted, missed = self.counted(s0, s1)
            seen.append("%.0f deadlines of wall time, ticks + missed %d, missed %d"
                        % (wall, counted, missed))
            print("3 reloads, attempt %d: %s" % (attempt + 1, seen[-1]))
            self.assertGreaterEqual(counted, 0.97 * wall)  # none lost, whatever the machine
            if missed <= 0.01 * wall:
                break
        else:
            self.fail("missed > 1 %% in each of %d attempts: %s" % (ATTEMPTS, "; ".join(seen)))
        self.assertEqual(d.stop(), 0)

    def test_reload_changes_many(self):
        # Given 256 objects streaming at 100 Hz, when three reloads each change every
        # object's max_speed_m_s (a new engine for each: none carried over), then ticks +
        # missed follow the wall clock and at most 1 % of the deadlines are missed: the
        # new engines are built beside the running core, not in the loop.  Before, the
        # loop built them (memory zeroed, settings resolved) between two ticks: 54 to 62
        # of about 450 deadlines missed.  The objects move when the reloads come (each
        # old engine brakes to rest beside its new one): while the loop still faulted in
        # the new object array and latches (9 to 22 ms a reload) and freed the 256
        # braking engines as they came to rest (an munmap each), 7 to 12 of about 500
        # were missed in every first attempt (daemon/core/grave.h).
        n = 256
        conf = os.path.join(self.tmp, "many.conf")

        def many(k):
            head = ("[daemon]\nrate_hz = %d\nstatus_interval_s = 0\nstop_timeout_s = 0.5\n"
                    "control_socket = %s\nlog_level = notice\n"
                    % (RATE_HZ, os.path.join(self.tmp, "ctl.sock")))
            return head + "".join(
                "[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\noutput = stdout\n"
                "max_speed_m_s = %g\n" % (i, i, os.path.join(self.tmp, "a.csv"), 50 + k)
                for i in range(n))
        write(conf, many(0))
        d = Trajd(self.tmp, conf)
        self.addCleanup(d.stop)
        end = time.monotonic() + WAIT_S
        while True:  # started: its status answers (the log says notice and above)
            try:
                d.status()
                break
            except OSError:
                self.assertLess(time.monotonic(), end, "trajd did not start")
                time.sleep(0.1)
        time.sleep(3.0)  # streaming: every object has played (its start slack behind it)
        seen = []
        for attempt in range(ATTEMPTS):
            s0 = d.status()
            for i in range(3):
                write(conf, many(3 * attempt + i + 1))
                k0 = len(d.lines)
                d.p.send_signal(signal.SIGHUP)
                line = d.wait_for("reloaded:")
                self.assertIn("%d object(s), 0 carried over" % n, line)
                # a few objects named, the rest in one line: before, a line for each
                # of the 256 outran a slow reader of the log and lines were dropped
                # (the "reloaded:" line with them)
                key = "more objects' replays resume likewise"
                rest = [x for x in d.lines[k0:] if key in x]
                rest = rest[0] if rest else d.wait_for(key)
                said = d.lines[k0:]
                named = [x for x in said if "its replay resumes after the row" in x]
                self.assertLessEqual(len(named), 4, "\n".join(said))
                self.assertIn("%d more objects'" % (n - len(named)), rest)
                time.sleep(0.5)
            s1 = d.status()
            wall, counted, missed = self.counted(s0, s1)
            seen.append("%.0f deadlines of wall time, ticks + missed %d, missed %d"
                        % (wall, counted, missed))
            print("3 reloads changing %d objects, attempt %d: %s" % (n, attempt + 1, seen[-1]))
            self.assertGreaterEqual(counted, 0.97 * wall)
            if missed <= 0.01 * wall:
                break
        else:
            self.fail("missed > 1 %% in each of %d attempts: %s" % (ATTEMPTS, "; ".join(seen)))
        self.assertEqual(d.stop(), 0)

    def test_changed_track_keeps_phase(self):
        d, conf = self.start(self.big)
        other = os.path.join(self.tmp, "other.csv")
        big_csv(other, y=2.0)
        s0 = d.status()
        shutil.copyfile(other, self.big + ".new")
        os.replace(self.big + ".new", self.big)  # another file: parsed again
        d.p.send_signal(signal.SIGHUP)
        d.wait_for("reloading")
        d.p.send_signal(signal.SIGSTOP)
        time.sleep(0.3)
        d.p.send_signal(signal.SIGCONT)
        d.wait_for("reloaded:")
        time.sleep(0.2)
        s1 = d.status()
        wall, counted, missed = self.counted(s0, s1)
        print("changed track, 0.3 s stopped: %.1f deadlines of wall time, ticks + missed %d, "
              "missed %d" % (wall, counted, missed))
        self.assertGreaterEqual(missed, 25)  # the 0.3 s stopped are counted
        self.assertLessEqual(abs(counted - wall), 3)  # none lost: the clock kept its phase
        self.assertEqual(d.stop(), 0)
        os.unlink(other)

    def test_sigterm_during_parse(self):
        small = os.path.join(self.tmp, "a.csv")
        d, conf = self.start(small)
        long_track = os.path.join(self.tmp, "long.csv")
        shutil.copyfile(self.big, long_track)
        write(conf, config(self.tmp, long_track, "long"))
        d.p.send_signal(signal.SIGHUP)
        d.wait_for("reloading")
        rc, took, log = sigterm(d)
        print("SIGTERM during a reload's parse: exit %d after %.2f s" % (rc, took))
        self.assertEqual(rc, 0, log)
        self.assertIn("bringing objects to rest", log)
        self.assertNotIn("reloaded:", log)  # dropped, never swapped in
        self.assertIn("dropped", log)
        self.assertLess(took, 5.0, log)
        os.unlink(long_track)

    def test_sighup_storm_coalesced(self):
        d, conf = self.start(self.big)
        now = time.time()
        os.utime(self.big, (now, now + 100))  # changed: parsed again
        d.p.send_signal(signal.SIGHUP)
        d.wait_for("SIGHUP: reloading")
        for _ in range(5):  # while it parses: one more reload after it
            d.p.send_signal(signal.SIGHUP)
            time.sleep(0.01)
        d.wait_for("reloaded:")
        d.wait_for("reloaded:")
        time.sleep(0.5)
        self.assertEqual(d.stop(), 0)
        log = "\n".join(d.rest())
        self.assertEqual(log.count("SIGHUP: reloading"), 2, log)
        self.assertEqual(log.count("reloaded:"), 2, log)
        # each signal that arrived while the first one parsed is logged as coalesced
        # (signals arriving together are one read: "N SIGHUPs at once")
        self.assertGreaterEqual(log.count("coalesced"), 1, log)

    def test_sigterm_during_start_parse(self):
        conf = os.path.join(self.tmp, "start.conf")
        write(conf, config(self.tmp, self.big))
        d = Trajd(self.tmp, conf)
        self.addCleanup(d.stop)
        time.sleep(0.1)  # reading the 1e6-waypoint track
        rc, took, log = sigterm(d)
        print("SIGTERM while the configuration is first read: exit %d after %.2f s" % (rc, took))
        self.assertEqual(rc, 0, log)
        self.assertIn("its parse cancelled", log)
        self.assertNotIn("started:", log)


if __name__ == "__main__":
    unittest.main()
