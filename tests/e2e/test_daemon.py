#!/usr/bin/python3
"""test_daemon.py - the real trajd binary, started as a process.

Checked against independent observers: the systemd notify protocol is read
from a unix datagram socket this test binds (as systemd would), setpoints
from the daemon's stdout pipe, exit codes from the kernel, and the replay
output against the trajreplay program on the same input.  Every wait is for
an event (a datagram, a line, process exit) with a bounded timeout; the
only sleep is the fault injected in test_missed_ticks (the daemon is
SIGSTOPped for a set time).
"""
import math
import os
import queue
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
N2K = os.path.join(REPO, "tests", "data", "n2k_furuno_figure8_src52.csv")

# Bounds for waiting on events. Generous: the machine is shared and slow.
START_TIMEOUT_S = 10.0
EVENT_TIMEOUT_S = 10.0
PERIOD_NS = 10_000_000  # 100 Hz in these configs


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def xyz_track(path, n, dt_s, speed_m_s=2.0, radius_m=50.0):
    """A circle at constant speed sampled every dt_s: a smooth, long input."""
    lines = ["t,x,y,z"]
    for i in range(n):
        t = i * dt_s
        a = speed_m_s * t / radius_m
        lines.append("%.3f,%.6f,%.6f,%.3f" % (t, radius_m * math.cos(a), radius_m * math.sin(a), 1.0))
    write(path, "\n".join(lines) + "\n")


class Daemon:
    """trajd with a notify socket, stdout/stderr read by threads into queues."""

    def __init__(self, tmp, conf, watchdog_usec=None, wrapper=(), read_stdout=True, read_stderr=True):
        self.tmp = tmp
        self.sock_path = os.path.join(tmp, "notify-%d.sock" % id(self))
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind(self.sock_path)
        env = dict(os.environ, NOTIFY_SOCKET=self.sock_path)
        env.pop("WATCHDOG_PID", None)
        env.pop("WATCHDOG_USEC", None)
        if watchdog_usec:
            env["WATCHDOG_USEC"] = str(watchdog_usec)
        self.p = subprocess.Popen(list(wrapper) + [TRAJD, "-f", "-c", conf], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, env=env, text=True)
        self.out = queue.Queue()
        self.err = queue.Queue()
        self.notes = queue.Queue()
        self.err_lines = []
        for stream, q in ((self.p.stdout, self.out), (self.p.stderr, self.err)):
            if stream is self.p.stdout and not read_stdout:
                continue  # a reader that never reads
            if stream is self.p.stderr and not read_stderr:
                continue  # a reader that reads late: read_stderr_now()
            threading.Thread(target=self._pump, args=(stream, q), daemon=True).start()
        # Read the notify socket all the time, as systemd does: sd_notify()
        # blocks when a datagram socket's queue is full.
        self.sock.settimeout(0.2)
        self.closing = False
        threading.Thread(target=self._pump_notify, daemon=True).start()

    def read_stderr_now(self):
        """Start reading stderr (a Daemon made with read_stderr=False)."""
        threading.Thread(target=self._pump, args=(self.p.stderr, self.err), daemon=True).start()

    def _pump_notify(self):
        while not self.closing:
            try:
                self.notes.put(self.sock.recv(4096).decode())
            except socket.timeout:
                continue
            except OSError:
                return

    @staticmethod
    def _pump(stream, q):
        for line in stream:
            q.put(line.rstrip("\n"))
        q.put(None)

    def msg(self, pred, timeout=EVENT_TIMEOUT_S):
        """Next notify datagram for which pred(fields) holds; all seen are returned too."""
        seen = []
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError("no matching notify message in %.1f s; saw %r" % (timeout, seen))
            try:
                data = self.notes.get(timeout=left)
            except queue.Empty:
                continue
            fields = dict(l.split("=", 1) for l in data.split("\n") if "=" in l)
            seen.append(fields)
            if pred(fields):
                return fields, seen

    def line(self, pred=lambda l: True, timeout=EVENT_TIMEOUT_S):
        """Next stdout line satisfying pred."""
        end = time.monotonic() + timeout
        while True:
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError("no matching stdout line in %.1f s" % timeout)
            try:
                l = self.out.get(timeout=left)
            except queue.Empty:
                continue
            if l is None:
                raise AssertionError("stdout closed (exit %r); stderr: %s" % (self.p.poll(), self.stderr()))
            if pred(l):
                return l

    def lines_until_eof(self, timeout=EVENT_TIMEOUT_S):
        rows = []
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                l = self.out.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                continue
            if l is None:
                return rows
            rows.append(l)
        raise AssertionError("stdout not closed in %.1f s" % timeout)

    def err_line(self, pred, timeout=EVENT_TIMEOUT_S):
        """Next stderr line satisfying pred."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            try:
                l = self.err.get(timeout=max(0.01, end - time.monotonic()))
            except queue.Empty:
                continue
            if l is None:
                break
            self.err_lines.append(l)
            if pred(l):
                return l
        raise AssertionError("no matching stderr line; got:\n" + "\n".join(self.err_lines))

    def stderr(self):
        """stderr so far; once the process has exited, all of it (read to its
        end by the pump thread, bounded: under load the thread lags behind)."""
        exited = self.p.poll() is not None and not getattr(self, "err_eof", False)
        end = time.monotonic() + EVENT_TIMEOUT_S
        while True:
            try:
                l = self.err.get(timeout=max(0.0, end - time.monotonic())) if exited \
                    else self.err.get_nowait()
            except queue.Empty:
                break
            if l is None:
                self.err_eof = True
                break
            self.err_lines.append(l)
        return "\n".join(self.err_lines)

    def wait(self, timeout):
        try:
            return self.p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise AssertionError("trajd did not exit in %.1f s" % timeout)

    def close(self):
        if self.p.poll() is None:
            self.p.kill()  # by pid: only our child
            self.p.wait()
        self.closing = True
        self.p.stdout.close()
        self.p.stderr.close()
        self.sock.close()
        try:
            os.unlink(self.sock_path)
        except FileNotFoundError:
            pass


# lib/motion.h ENGINE_SP_SKIPPED: deadlines were missed before this setpoint
SKIPPED_FLAG = 0x04
SCALED_FLAG = 0x40


def assert_track_step(tc, b, a, k, period_ns):
    """Row a follows row b k periods later in engine time: one period of
    track time on at rate 1 (k == 1); after a stall of k > 1 periods (a
    reload on a loaded machine), the target one period after the last one
    sent, never k periods ahead, flagged skipped, at a rate up to the 5 %
    the catch-up may then run at (lib/engine/LIFECYCLE.md, "stall").  A row
    one period on that is time-scaled (a stall before this one on a loaded
    machine, still being won back) is at such a rate too."""
    dt = float(a[2]) - float(b[2])
    T = period_ns * 1e-9
    if k == 1 and int(a[13]) & SCALED_FLAG:
        tc.assertGreaterEqual(dt, T * (1 - 1e-6), "%s\n%s" % (b, a))
        tc.assertLessEqual(dt, 1.05 * T * (1 + 1e-6), "%s\n%s" % (b, a))
        return
    if k == 1:
        tc.assertAlmostEqual(dt, T, delta=1e-9, msg="%s\n%s" % (b, a))
        return
    tc.assertTrue(int(a[13]) & SKIPPED_FLAG, "%s\n%s" % (b, a))
    tc.assertGreaterEqual(dt, T * (1 - 1e-6), "%s\n%s" % (b, a))
    tc.assertLessEqual(dt, 1.05 * T * (1 + 1e-6), "%s\n%s" % (b, a))


def rows_of(lines, obj):
    return [l.split(",") for l in lines if l.startswith(obj + ",")]


class TestCommandLine(unittest.TestCase):
    def test_check_config(self):
        with tempfile.TemporaryDirectory() as tmp:
            good = os.path.join(tmp, "good.conf")
            write(good, "[object.b]\ninput = replay\nreplay.track = %s\noutput = stdout\n" % N2K)
            # Given a valid file, when checked, then exit 0 and "ok".
            r = subprocess.run([TRAJD, "--check-config", good], capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("ok", r.stdout)
            # Given a bad value on line 4, then a non-zero exit and "file:4:" first.
            bad = os.path.join(tmp, "bad.conf")
            write(bad, "[daemon]\nrate_hz = 100\n\nspeed = fast\n[object.b]\ninput = replay\n")
            r = subprocess.run([TRAJD, "--check-config", bad], capture_output=True, text=True, timeout=10)
            self.assertNotEqual(r.returncode, 0)
            self.assertTrue(r.stderr.startswith(bad + ":4: "), r.stderr)
            self.assertIn("speed", r.stderr)
            # Given an unknown key, the same, with the key named.
            write(bad, "[object.b]\ninput = replay\nreplay.track = %s\noutput = stdout\nfoo = 1\n" % N2K)
            r = subprocess.run([TRAJD, "--check-config", bad], capture_output=True, text=True, timeout=10)
            self.assertNotEqual(r.returncode, 0)
            self.assertTrue(r.stderr.startswith(bad + ":5: "), r.stderr)
            self.assertIn("foo", r.stderr)
            # Given an initial_position the engine would refuse at start (beyond
            # max_abs_m, given after it), --check-config names its line.
            write(bad, "[object.b]\ninput = replay\nreplay.track = %s\noutput = stdout\n"
                       "initial_position = 0,0,150\nmax_abs_m = 100\n" % N2K)
            r = subprocess.run([TRAJD, "--check-config", bad], capture_output=True, text=True, timeout=10)
            self.assertNotEqual(r.returncode, 0)
            self.assertTrue(r.stderr.startswith(bad + ":5: "), r.stderr)
            self.assertIn("initial_position", r.stderr)
            write(bad, "[object.b]\ninput = replay\nreplay.track = %s\noutput = stdout\nfoo = 1\n" % N2K)
            # Given a bad config to run, trajd refuses to start, with the message.
            r = subprocess.run([TRAJD, "-f", "-c", bad], capture_output=True, text=True, timeout=10)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn(bad + ":5:", r.stderr)

    def test_options(self):
        r = subprocess.run([TRAJD, "--version"], capture_output=True, text=True, timeout=10)
        self.assertEqual(r.returncode, 0)
        self.assertTrue(r.stdout.startswith("trajd "))
        r = subprocess.run([TRAJD, "--help"], capture_output=True, text=True, timeout=10)
        self.assertEqual(r.returncode, 0)
        self.assertIn("--check-config", r.stdout)
        r = subprocess.run([TRAJD, "--no-such-option"], capture_output=True, text=True, timeout=10)
        self.assertNotEqual(r.returncode, 0)

    def test_open_failure_is_not_ready(self):
        # Given an output file in a directory that does not exist, trajd
        # exits non-zero with the reason and never says READY=1.
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "t.conf")
            write(conf, "[object.b]\ninput = replay\nreplay.track = %s\noutput = csv\n"
                        "csv.path = %s/no/such/dir/out.csv\n" % (N2K, tmp))
            d = Daemon(tmp, conf)
            try:
                rc = d.wait(START_TIMEOUT_S)
                self.assertNotEqual(rc, 0)
                msgs = []
                while not d.notes.empty():
                    msgs.append(d.notes.get_nowait())
                self.assertFalse(any("READY=1" in m for m in msgs), msgs)
                # wait for the line (bounded, up to EOF): after exit the
                # reader thread may not have queued stderr yet
                d.err_line(lambda l: "no/such/dir" in l)
            finally:
                d.close()


class TestBackground(unittest.TestCase):
    def test_detaches_once_ready(self):
        """Without -f: the command returns 0 once the daemon is ready, the
        daemon (another process, found from the notify datagram's sender
        credentials, as systemd finds it) runs on and finishes the replay."""
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "fig8.csv")
            with open(N2K) as f:
                write(track, "".join(f.readlines()[:52]))  # 10 s of the real track
            conf = os.path.join(tmp, "t.conf")
            write(conf, "[daemon]\nspeed = 10\nexit_when_done = yes\nstatus_interval_s = 0\n"
                        "[object.b]\ninput = replay\nreplay.track = fig8.csv\noutput = csv\n"
                        "csv.path = out.csv\n")
            sock_path = os.path.join(tmp, "notify.sock")
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
            sock.bind(sock_path)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_PASSCRED, 1)
            env = dict(os.environ, NOTIFY_SOCKET=sock_path)
            try:
                # (output to files: a pipe would make run() wait for the daemon's end)
                with open(os.path.join(tmp, "err.txt"), "w") as ef:
                    r = subprocess.run([TRAJD, "-c", conf], env=env, stdout=subprocess.DEVNULL,
                                       stderr=ef, timeout=START_TIMEOUT_S)
                self.assertEqual(r.returncode, 0)
                sock.settimeout(EVENT_TIMEOUT_S)
                pid = None
                while pid is None:
                    data, anc, _, _ = sock.recvmsg(4096, socket.CMSG_SPACE(12))
                    if b"READY=1" in data:
                        for lvl, typ, cd in anc:
                            if lvl == socket.SOL_SOCKET and typ == socket.SCM_CREDENTIALS:
                                pid = int.from_bytes(cd[0:4], sys.byteorder)
                self.assertTrue(pid > 0)
                # the daemon is not the process that returned; it ends by itself
                def alive():
                    try:
                        with open("/proc/%d/stat" % pid) as f:
                            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
                    except FileNotFoundError:
                        return False
                self.assertTrue(alive())  # still running after the command returned
                end = time.monotonic() + 30
                while time.monotonic() < end and alive():
                    sock.settimeout(0.2)
                    try:
                        sock.recv(4096)
                    except socket.timeout:
                        pass
                if alive():
                    os.kill(pid, signal.SIGKILL)
                    self.fail("detached trajd did not finish")
                with open(os.path.join(tmp, "out.csv")) as f:
                    last = f.read().splitlines()[-1].split(",")
                self.assertEqual(last[12], "finished")
                # a config that cannot open makes the command itself fail
                write(conf, "[object.b]\ninput = replay\nreplay.track = fig8.csv\noutput = csv\n"
                            "csv.path = no/such/dir/out.csv\n")
                r = subprocess.run([TRAJD, "-c", conf], env=env, capture_output=True, text=True,
                                   timeout=START_TIMEOUT_S)
                self.assertNotEqual(r.returncode, 0)
                self.assertIn("no/such/dir", r.stderr)
            finally:
                sock.close()


class TestRunning(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.track = os.path.join(self.tmp, "circle.csv")
        xyz_track(self.track, 3000, 0.1)  # 10 Hz for 300 s: streams for the whole test
        self.conf = os.path.join(self.tmp, "trajd.conf")

    def tearDown(self):
        self.tmpd.cleanup()

    def config(self, name, extra_daemon="", extra_obj=""):
        return ("[daemon]\nrate_hz = 100\nstatus_interval_s = 1\nstop_timeout_s = 5\n%s"
                "[object.%s]\ninput = replay\nreplay.track = circle.csv\noutput = stdout\n%s"
                % (extra_daemon, name, extra_obj))

    def test_notify_watchdog_reload_and_stop(self):
        write(self.conf, self.config("boat"))
        # WATCHDOG_USEC = 200 ms: trajd must ping at least every 100 ms.
        d = Daemon(self.tmp, self.conf, watchdog_usec=200000)
        try:
            # Given a start, then READY=1 comes, and STATUS= with a summary.
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            d.msg(lambda f: "STATUS" in f and "boat" in f["STATUS"])
            # Then WATCHDOG=1 keeps coming (5 pings within the bound).
            for _ in range(5):
                d.msg(lambda f: f.get("WATCHDOG") == "1", 2.0)
            # Then setpoints of 'boat' stream on stdout, on the 10 ms grid.
            l1 = d.line(lambda l: l.startswith("boat,"))
            l2 = d.line(lambda l: l.startswith("boat,"))
            t1, t2 = int(l1.split(",")[1]), int(l2.split(",")[1])
            self.assertEqual(t1 % PERIOD_NS, 0)
            self.assertGreater(t2, t1)
            self.assertEqual((t2 - t1) % PERIOD_NS, 0)

            # Given the object streaming and a new config that leaves it
            # unchanged (only the status interval differs), when SIGHUP, then
            # RELOADING=1 ... READY=1 and the object is carried over: its next
            # row (after the header the reopened stdout writes) continues the
            # old one by exactly one period of engine and track time, on the
            # same trajectory, with no jump in position.
            # on the unit grid: past the start, which is entered at rate 0
            # (flag SCALED 0x40 while the time scaling ramps up)
            before = d.line(lambda l: l.startswith("boat,") and ",streaming," in l and
                            not int(l.split(",")[13]) & 0x40)
            write(self.conf, self.config("boat").replace("status_interval_s = 1",
                                                         "status_interval_s = 2"))
            d.p.send_signal(signal.SIGHUP)
            _, seen = d.msg(lambda f: f.get("READY") == "1")
            self.assertTrue(any(f.get("RELOADING") == "1" for f in seen), seen)
            while True:
                l = d.line()
                if l.startswith("object,"):
                    break
                before = l
            self.assertIsNotNone(before)
            after = d.line(lambda l: l.startswith("boat,"))
            b, a = before.split(","), after.split(",")
            # A reload on a loaded machine may take longer than one period:
            # the clock then skips whole deadlines (never bunches), so the
            # next row is k >= 1 periods on in engine time, and in track time
            # one period on (a stall is no step: assert_track_step).
            dt_ns = int(a[1]) - int(b[1])
            self.assertGreater(dt_ns, 0)
            self.assertEqual(dt_ns % PERIOD_NS, 0)
            k = dt_ns // PERIOD_NS
            self.assertEqual(b[12], "streaming")
            self.assertEqual(a[12], "streaming")
            assert_track_step(self, b, a, k, PERIOD_NS)
            self.assertEqual(a[15], b[15])             # same trajectory number
            self.assertEqual(int(a[13]) & 0x02, 0)     # no NEW_TRACK flag
            step_m = math.dist([float(x) for x in a[3:6]], [float(x) for x in b[3:6]])
            # track speed 2 m/s: k 10 ms steps are 0.02 k m; allow 50 % more
            self.assertLess(step_m, 1.5 * 2.0 * k * PERIOD_NS * 1e-9)
            d.err_line(lambda l: "1 carried over" in l)

            # Given a good new config (object renamed), when SIGHUP, then
            # RELOADING=1 then READY=1, and the new object streams.
            write(self.conf, self.config("boat2"))
            d.p.send_signal(signal.SIGHUP)
            _, seen = d.msg(lambda f: f.get("READY") == "1")
            self.assertTrue(any(f.get("RELOADING") == "1" for f in seen), seen)
            self.assertIn("MONOTONIC_USEC", [k for f in seen for k in f if f.get("RELOADING") == "1"])
            d.line(lambda l: l.startswith("boat2,"))

            # Given a broken config, when SIGHUP, then RELOADING=1, READY=1
            # with STATUS "reload refused", and the old config keeps running.
            write(self.conf, self.config("boat3", extra_obj="fragment = lots\n"))
            d.p.send_signal(signal.SIGHUP)
            f, seen = d.msg(lambda f: f.get("READY") == "1")
            self.assertTrue(any(x.get("RELOADING") == "1" for x in seen), seen)
            self.assertIn("reload refused", f.get("STATUS", ""))
            self.assertIn("trajd.conf:", f.get("STATUS", ""))
            self.assertIsNone(d.p.poll())
            # drain what was queued before, then the old object must still stream
            n_before = d.out.qsize()
            for _ in range(n_before):
                d.out.get_nowait()
            l = d.line(lambda l: l.startswith("boat"))
            self.assertTrue(l.startswith("boat2,"), l)
            d.err_line(lambda l: "reload refused" in l)

            # Given SIGTERM, then STOPPING=1, exit 0 within stop_timeout_s + margin,
            # and (the track being dense) the object came to rest: last state finished.
            t0 = time.monotonic()
            d.p.send_signal(signal.SIGTERM)
            d.msg(lambda f: f.get("STOPPING") == "1")
            rows = d.lines_until_eof(timeout=5 + 5)
            rc = d.wait(5)
            self.assertEqual(rc, 0, d.stderr())
            self.assertLess(time.monotonic() - t0, 5 + 5)
            last = rows_of(rows, "boat2")[-1]
            self.assertEqual(last[12], "finished", last)
            # velocity zero at rest
            self.assertEqual([float(v) for v in last[6:9]], [0.0, 0.0, 0.0])
        finally:
            d.close()

    def test_realtime_options(self):
        # Given [realtime] fifo_priority, mlockall and cpu_affinity, then the
        # kernel reports them for the process (/proc), or, without the
        # privilege, trajd warns and runs on.
        write(self.conf, self.config("boat", extra_daemon="[realtime]\nfifo_priority = 10\n"
                                                          "mlockall = yes\ncpu_affinity = 0\n"))
        d = Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            d.line(lambda l: l.startswith("boat,"))  # a tick ran after the settings
            with open("/proc/%d/stat" % d.p.pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            # fields[0] is field 3 (state): rt_priority is field 40, policy 41
            rt_priority, policy = int(fields[37]), int(fields[38])
            with open("/proc/%d/status" % d.p.pid) as f:
                status = dict(l.split(":", 1) for l in f.read().splitlines() if ":" in l)
            if os.geteuid() == 0:
                self.assertEqual(policy, 1)  # SCHED_FIFO
                self.assertEqual(rt_priority, 10)
                self.assertGreater(int(status["VmLck"].split()[0]), 0)
                self.assertEqual(status["Cpus_allowed_list"].strip(), "0")
            else:
                d.err_line(lambda l: "realtime settings not applied" in l)
            d.p.send_signal(signal.SIGTERM)
            self.assertEqual(d.wait(10), 0)
        finally:
            d.close()

    def test_reload_that_cannot_open_falls_back(self):
        # Given a new config that parses but cannot open (its CSV directory
        # does not exist), when SIGHUP, then the reload is refused after the
        # old transports were closed: the old core reopens them and streams
        # again (a fresh header, then its object's rows; continuity at that
        # instant: tests/e2e/test_reload_cells.py).
        write(self.conf, self.config("boat"))
        d = Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            d.line(lambda l: l.startswith("boat,"))
            write(self.conf, self.config("boat").replace(
                "output = stdout", "output = csv\ncsv.path = no/such/dir/x.csv"))
            d.p.send_signal(signal.SIGHUP)
            f, seen = d.msg(lambda f: f.get("READY") == "1")
            self.assertIn("reload refused", f.get("STATUS", ""))
            self.assertIn("no/such/dir", f.get("STATUS", ""))
            d.err_line(lambda l: "still running the old configuration" in l)
            d.line(lambda l: l.startswith("object,"))   # stdout reopened
            d.line(lambda l: l.startswith("boat,"))
            self.assertIsNone(d.p.poll())
            d.p.send_signal(signal.SIGTERM)
            self.assertEqual(d.wait(10), 0)
        finally:
            d.close()

    def test_stalled_reader_does_not_stall_the_tick(self):
        # Given 4 objects at 1 kHz writing to a stdout pipe nobody reads,
        # then the pipe and trajd's buffer fill, lines are dropped and
        # counted ("out dropped"), and the clock keeps ticking (the tick count
        # in STATUS grows by about the rate between two status lines).
        objs = "".join("[object.o%d]\nid = %d\ninput = replay\nreplay.track = circle.csv\n"
                       "output = stdout\n" % (i, i) for i in range(4))
        write(self.conf, "[daemon]\nrate_hz = 1000\nstatus_interval_s = 1\nstop_timeout_s = 0\n" + objs)
        d = Daemon(self.tmp, self.conf, read_stdout=False)
        ticks = lambda f: int(f["STATUS"].split("ticks ")[1].split(",")[0])
        try:
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            f1, _ = d.msg(lambda f: "out dropped" in f.get("STATUS", ""), 15)
            f2, _ = d.msg(lambda f: "STATUS" in f and "up " in f["STATUS"], 5)
            # one status second apart: >= half the rate, allowing for a loaded machine
            self.assertGreater(ticks(f2) - ticks(f1), 500, (f1, f2))
            d.p.send_signal(signal.SIGTERM)
            # exits although the reader never reads (bounded drain at close),
            # with 74 (EX_IOERR): lines were lost (issue 11: never silently)
            self.assertEqual(d.wait(10), 74)
        finally:
            d.close()

    def test_second_signal_exits_at_once(self):
        # stop_timeout_s large: only the second signal can end it quickly.
        write(self.conf, self.config("boat").replace("stop_timeout_s = 5", "stop_timeout_s = 600"))
        d = Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            d.line(lambda l: l.startswith("boat,"))
            d.p.send_signal(signal.SIGTERM)
            d.msg(lambda f: f.get("STOPPING") == "1")
            d.p.send_signal(signal.SIGINT)
            self.assertEqual(d.wait(5), 0)
        finally:
            d.close()

    def test_missed_ticks_are_skipped_not_bunched(self):
        write(self.conf, self.config("boat"))
        d = Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", START_TIMEOUT_S)
            d.line(lambda l: l.startswith("boat,"))
            # Given the daemon frozen for 300 ms (30 deadlines at 100 Hz),
            while not d.out.empty():  # forget older rows: start from a fresh one
                d.out.get_nowait()
            times = [int(d.line(lambda l: l.startswith("boat,")).split(",")[1])]
            d.p.send_signal(signal.SIGSTOP)
            time.sleep(0.3)  # the fault itself, not a wait for an event
            d.p.send_signal(signal.SIGCONT)
            # when it resumes, then the missed deadlines are skipped: now_ns
            # jumps forward once, ticks stay on the grid, no burst of rows.
            for _ in range(150):
                times.append(int(d.line(lambda l: l.startswith("boat,")).split(",")[1]))
            steps = [b - a for a, b in zip(times, times[1:])]
            self.assertTrue(all(s > 0 and s % PERIOD_NS == 0 for s in steps), steps)
            self.assertGreaterEqual(max(steps), 20 * PERIOD_NS, steps)
            # and the status counts them (>= 20: some of the 30 may have been
            # served before the stop took effect).
            f, _ = d.msg(lambda f: "STATUS" in f and "missed" in f["STATUS"]
                         and int(f["STATUS"].split("missed ")[1].split(",")[0]) >= 20, 5)
            # and an overrun is work that ended after the NEXT deadline
            # (core.h): the freeze makes at most a few, a shared machine a
            # few more, never half of the ticks (counting against the tick's
            # own deadline, which has always passed when it runs, would make
            # every tick one).
            st = f["STATUS"]
            ticks = int(st.split("ticks ")[1].split(",")[0])
            overruns = int(st.split("overruns ")[1].split(",")[0])
            self.assertGreater(ticks, 50, st)
            self.assertLess(overruns, ticks // 2, st)
            d.p.send_signal(signal.SIGTERM)
            self.assertEqual(d.wait(10), 0)
        finally:
            d.close()


class TestReloadUnderValgrind(unittest.TestCase):
    def test_reloads_leak_nothing(self):
        """Given trajd under valgrind memcheck, when it is reloaded with an
        unchanged object (carried over), a renamed one, a broken file and a
        file that cannot open (fallback), and stopped, then it exits 0 with
        no memcheck error and nothing in use at exit."""
        with tempfile.TemporaryDirectory() as tmp:
            xyz_track(os.path.join(tmp, "circle.csv"), 600, 0.1)
            conf = os.path.join(tmp, "trajd.conf")
            base = ("[daemon]\nstatus_interval_s = 1\nstop_timeout_s = 1\n[object.%s]\ninput = replay\n"
                    "replay.track = circle.csv\noutput = stdout\n%s")
            write(conf, base % ("boat", ""))
            d = Daemon(tmp, conf, wrapper=["valgrind", "--error-exitcode=9", "--leak-check=full",
                                           "--log-file=%s/vg.log" % tmp])
            try:
                d.msg(lambda f: f.get("READY") == "1", 60)
                for name, extra in (("boat", "max_gap_s = 60\n"), ("other", ""),
                                    ("other", "fragment = x\n"),
                                    ("other", "output = csv\ncsv.path = no/such/x.csv\n")):
                    text = base % (name, extra)
                    if "csv.path" in extra:
                        text = text.replace("output = stdout\n", "")
                    write(conf, text)
                    d.p.send_signal(signal.SIGHUP)
                    d.msg(lambda f: f.get("READY") == "1", 60)
                d.line(lambda l: l.startswith("other,"), 30)
                d.p.send_signal(signal.SIGTERM)
                rc = d.wait(60)
            finally:
                d.close()
            with open(os.path.join(tmp, "vg.log")) as f:
                vg = f.read()
            print(vg[-600:], file=sys.stderr)
            self.assertEqual(rc, 0, vg)
            self.assertIn("in use at exit: 0 bytes in 0 blocks", vg)
            self.assertIn("ERROR SUMMARY: 0 errors", vg)


class TestReplayMatchesTrajreplay(unittest.TestCase):
    def compare(self, name, dl, rl, missed):
        """Every row trajd wrote for object name equals trajreplay's row for
        that tick, byte for byte.  A deadline trajd missed on this shared
        machine leaves no row, but trajd still steps its input and engine
        through it, so the next row it writes is trajreplay's row for that
        tick too, except for the SKIPPED flag (0x04) that marks it."""
        self.assertEqual(dl[0], rl[0])  # header
        ref_by_t = {l.split(",", 2)[1]: l.split(",", 1)[1] for l in rl[1:]}
        compared = 0
        prev_ns = -PERIOD_NS
        rows = [l for l in dl[1:] if l.startswith(name + ",")]
        for l in rows:
            rest = l.split(",", 1)[1]
            t = rest.split(",", 1)[0]
            skipped = int(t) - prev_ns != PERIOD_NS
            prev_ns = int(t)
            if t not in ref_by_t:
                continue  # trajd ran on past trajreplay's last tick
            a, b = rest.split(","), ref_by_t[t].split(",")
            flags_a, flags_b = int(a[12]), int(b[12])
            self.assertEqual(flags_a & ~0x04, flags_b, "%s tick %s: flags" % (name, t))
            self.assertEqual(bool(flags_a & 0x04), skipped, "%s tick %s: skip flag" % (name, t))
            self.assertEqual(a[:12] + a[13:], b[:12] + b[13:], "%s tick %s" % (name, t))
            compared += 1
        self.assertGreater(compared, 0.9 * (len(rl) - 1) if missed == 0 else 100)
        # and trajd reached the end of the track, as trajreplay did.
        self.assertEqual(rows[-1].split(",")[12], "finished")
        return compared

    def run_and_compare(self, speed):
        with tempfile.TemporaryDirectory() as tmp:
            # Given two objects with their own tracks, engine settings and
            # outputs: 'track', the first 60 s of the real 5 Hz figure-eight,
            # default engine, to a CSV file; 'walk', the first 80 s of the
            # irregularly sampled Visnjan walk (1-20 s between points), with
            # the Hoang B-spline, F=16/O=8, natural ends, start slack 3, due
            # from 1.5 s, to stdout;
            fig8 = os.path.join(tmp, "fig8.csv")
            with open(N2K) as f:
                write(fig8, "".join(f.readlines()[:302]))
            walk = os.path.join(tmp, "walk.csv")
            with open(os.path.join(REPO, "tests", "data", "gpxgo_visnjan.csv")) as f:
                lines = f.readlines()
            write(walk, "".join([lines[0]] + [l for l in lines[1:] if float(l.split(",")[0]) <= 80]))
            conf = os.path.join(tmp, "t.conf")
            # replayed by trajd `speed` times faster than real time, exiting when done,
            write(conf, ("[daemon]\nrate_hz = 100\nspeed = %g\nexit_when_done = yes\n" % speed) +
                        "status_interval_s = 0\n"
                        "[object.track]\nid = 0\ninput = replay\nreplay.track = fig8.csv\n"
                        "output = csv\ncsv.path = d.csv\n"
                        "[object.walk]\nid = 1\ninput = replay\nreplay.track = walk.csv\n"
                        "output = stdout\nmethod = bspline\nparam = uniform\nends = natural\n"
                        "fragment = 16\noverlap = 8\nstart_slack = 3\nreplay.start_s = 1.5\n")
            d = Daemon(tmp, conf)
            try:
                self.assertEqual(d.wait(120), 0, d.stderr())
                stdout_lines = d.lines_until_eof()
                summary = d.stderr()
            finally:
                d.close()
            missed = int(summary.split("missed ")[-1].split(",")[0])
            # 'walk' (param = uniform, 1-20 s between fixes) is warned about once
            uni = [l for l in summary.splitlines() if "param = uniform on irregular" in l]
            self.assertEqual(len(uni), 1, summary)
            self.assertIn("object 'walk'", uni[0])
            # and by trajreplay on the same files with the same settings
            # (given as options for 'track', read from the config for 'walk'),
            refs = {}
            for name, args in (("track", ["--rate", "100", fig8]),
                               ("walk", ["-c", conf])):
                ref = os.path.join(tmp, name + ".ref.csv")
                r = subprocess.run([TRAJREPLAY, "--object", name, "-q", "-o", ref] + args,
                                   capture_output=True, text=True, timeout=120)
                self.assertEqual(r.returncode, 0, r.stderr)
                with open(ref) as f:
                    refs[name] = f.read().splitlines()
            # then each object's rows are trajreplay's rows.
            with open(os.path.join(tmp, "d.csv")) as f:
                n1 = self.compare("track", f.read().splitlines(), refs["track"], missed)
            n2 = self.compare("walk", stdout_lines, refs["walk"], missed)
            print("replay == trajreplay: %d + %d rows compared, %d deadlines missed"
                  % (n1, n2, missed), file=sys.stderr)
            # and the two objects' settings really differ (not one curve twice)
            self.assertNotEqual(refs["track"][-1].split(",")[3], refs["walk"][-1].split(",")[3])
            return missed, len(refs["track"]) + len(refs["walk"]) - 2


    def test_identical_output(self):
        self.run_and_compare(20)

    def test_identical_output_when_many_deadlines_are_missed(self):
        # Given a replay 1000x faster than real time (a 10 us wall period:
        # many deadlines pass while trajd is busy, including the ones around
        # each trajectory's start), then trajd still steps every missed
        # deadline and writes trajreplay's rows (only the skip flag differs).
        missed, ticks = self.run_and_compare(1000)
        self.assertGreater(missed, ticks // 4)

class TestRejectionsLogged(unittest.TestCase):
    def test_rejections_logged_like_trajreplay(self):
        """Given a clean 5 Hz circle with 3 fixes moved 500 m away and 12 rows
        stamped back at t = 0 in one burst, when trajd replays it, then each
        refusal it logs names the file:line and reason trajreplay reports for
        that row, at most REJLOG_LINES (5) lines per second and object are
        logged in full, the rest are counted by reason in a "more ... not
        shown" line, and shown + counted equals trajreplay's total."""
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "bad.csv")
            xyz_track(track, 400, 0.2)
            with open(track) as f:
                rows = f.read().splitlines()
            for i in (50, 150, 250):  # row i is on line i + 2 (header on line 1)
                t, x, y, z = rows[i + 1].split(",")
                rows[i + 1] = ",".join((t, "%.6f" % (float(x) + 500.0), y, z))
            rows[301:301] = ["0.000,%d.0,0.0,1.0" % (1000 + k) for k in range(12)]
            write(track, "\n".join(rows) + "\n")
            conf = os.path.join(tmp, "t.conf")
            write(conf, "[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                        "status_interval_s = 0\n[object.boat]\ninput = replay\n"
                        "replay.track = bad.csv\noutput = csv\ncsv.path = d.csv\n")
            d = Daemon(tmp, conf)
            try:
                self.assertEqual(d.wait(120), 0, d.stderr())
                log = d.stderr()
            finally:
                d.close()
            r = subprocess.run([TRAJREPLAY, "--rate", "100", "-q", "-o", os.path.join(tmp, "r.csv"),
                                track], capture_output=True, text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
        want = {}  # "bad.csv:LINE" -> reason, as trajreplay reports them
        for l in r.stderr.splitlines():
            if ": rejected (" in l:
                where, why = l.split(": rejected (")
                want[os.path.basename(where)] = why.rstrip(")")
        self.assertEqual(len(want), 15, r.stderr)
        shown, more = 0, 0
        for l in log.splitlines():
            if ": rejected (" in l:
                where = l.split("object 'boat': ")[1].split(": rejected (")[0]
                why = l.split(": rejected (")[1].split(")")[0]
                self.assertEqual(want.get(os.path.basename(where)), why, l)
                shown += 1
            elif "more rejected waypoints not shown" in l:
                n = int(l.split("object 'boat': ")[1].split(" ")[0])
                by = l.split("(")[1].rstrip(")").split(", ")
                self.assertEqual(sum(int(b.split(" ")[1]) for b in by), n, l)
                more += n
        self.assertEqual(shown + more, 15, log)
        self.assertGreater(more, 0, log)  # the burst of 12 in one second was cut short
        # daemon/REFERENCE.md shows this run's lines (issue 14: no stale numbers); how many a
        # "more" line counts depends on where the wall-clock seconds fall: its form only
        with open(os.path.join(REPO, "daemon", "REFERENCE.md"), encoding="utf-8") as f:
            doc = f.read()
        start = doc.index("    object 'boat': bad.csv:")
        example = doc[start:doc.index("\n\n", start)].split("\n")
        self.assertEqual(len(example), 3)
        logged = {l.split("<4>")[-1].replace(os.path.join(tmp, ""), "") for l in log.splitlines()}
        for l in example[:2]:
            self.assertIn(l.strip(), logged)
        self.assertRegex(example[2], r"^    object 'boat': (\d+) more rejected waypoints not shown "
                                     r"\(backwards \1\)$")


class TestStopsAndRestampsOnStatus(unittest.TestCase):
    def test_status_line_counts_stops_and_restamps(self):
        """Given two replay objects, a machine that moves 1 m/s along x at
        10 Hz, stands 10 s (its position repeated), and moves on, and a
        straight line whose 1 s chords alternate 100 m / 280 m (ADS-B
        arrival-time stamps), when trajd replays them, then its exit status
        line says '1 stops, 0 re-stamped' for the first and '0 stops, N
        re-stamped (largest X s)' for the second, N and X as trajreplay
        --summary counts them (issue 27)."""
        with tempfile.TemporaryDirectory() as tmp:
            stop = ["t,x,y,z"] + ["%.1f,%r,0,0" % (k / 10, k / 10 if k <= 100 else 10.0 if k <= 200
                                                   else 10.0 + (k - 200) / 10) for k in range(301)]
            write(os.path.join(tmp, "stop.csv"), "\n".join(stop) + "\n")
            x, jit = 0.0, ["t,x,y,z"]
            for k in range(60):
                jit.append("%d,%r,0,0" % (k, x))
                x += 100.0 if k % 2 == 0 else 280.0
            write(os.path.join(tmp, "jit.csv"), "\n".join(jit) + "\n")
            conf = os.path.join(tmp, "t.conf")
            write(conf, "[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                        "status_interval_s = 0\n"
                        "[object.m]\nid = 1\ninput = replay\nreplay.track = stop.csv\noutput = csv\n"
                        "csv.path = m.csv\n"
                        "[object.j]\nid = 2\ninput = replay\nreplay.track = jit.csv\noutput = csv\n"
                        "csv.path = j.csv\n")
            d = Daemon(tmp, conf)
            try:
                self.assertEqual(d.wait(120), 0, d.stderr())
                log = d.stderr()
            finally:
                d.close()
            r = subprocess.run([TRAJREPLAY, "-q", "--summary", "-o", os.devnull,
                                os.path.join(tmp, "jit.csv")], capture_output=True, text=True,
                               timeout=120)
        summ = dict(l.split()[1:3] for l in r.stderr.splitlines() if l.startswith("summary: "))
        exit_line = [l for l in log.splitlines() if "exit: " in l]
        self.assertEqual(len(exit_line), 1, log)
        self.assertIn("; m ", exit_line[0])
        m_part = exit_line[0].split("; m ")[1].split(";")[0]
        j_part = exit_line[0].split("; j ")[1].split(";")[0]
        self.assertIn(", 1 stops, 0 re-stamped", m_part, exit_line[0])
        self.assertIn(", 0 stops, %d re-stamped (largest %.3f s)"
                      % (int(summ["retimed"]), float(summ["retime_max_s"])), j_part, exit_line[0])


if __name__ == "__main__":
    unittest.main(verbosity=2)
