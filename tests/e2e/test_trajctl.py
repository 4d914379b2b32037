#!/usr/bin/python3
"""test_trajctl.py - trajctl against a running trajd, over its control socket.

Every command of trajctl(1), its exit statuses, and the protocol of
config/PROTOCOL.md "Control socket" read by an independent client (Python's
socket and json modules).  The subscription is checked against trajd's own
CSV output of the same run: a watch of a 1 kHz object for 10 s must hold the
very rows trajd wrote to its csv output for those ticks, byte for byte, none
missing.  A user outside the socket's group is refused (the kernel's check,
with the binary copied where that user can reach it), and admitted once the
socket's group is his.  Waits are for events (the notify socket's READY=1, a
line, a process exit) with bounded timeouts.
"""
import json
import math
import os
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time
import unittest
from unittest import mock

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_daemon import Daemon, write  # noqa: E402

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJCTL = os.path.join(BUILD, "bin", "trajctl")
RATE_HZ = 1000
PERIOD_NS = 1_000_000
TIMEOUT_S = 20.0
SKIPPED = 0x04  # ENGINE_SP_SKIPPED (lib/motion.h)


def read(path):
    with open(path) as f:
        return f.read()


def circle_track(path, seconds, hz=10, speed_m_s=5.0, radius_m=40.0):
    """A circle at constant speed: the object moves for the whole track."""
    lines = ["t,x,y,z"]
    for i in range(int(seconds * hz)):
        t = i / hz
        a = speed_m_s * t / radius_m
        lines.append("%.3f,%.6f,%.6f,0" % (t, radius_m * math.cos(a), radius_m * math.sin(a)))
    write(path, "\n".join(lines) + "\n")


def config(tmp, extra_daemon=""):
    track = os.path.join(tmp, "circle.csv")
    if not os.path.exists(track):
        circle_track(track, 300)
    return ("[daemon]\nrate_hz = %d\nstatus_interval_s = 0\ncontrol_socket = %s\n%s\n"
            "[object.boat]\nid = 0\ninput = replay\nwritable = yes\nreplay.track = %s\n"
            "output = csv\ncsv.path = %s\n\n"
            "[object.ro]\nid = 1\ninput = replay\nreplay.track = %s\noutput = csv\ncsv.path = %s\n"
            % (RATE_HZ, os.path.join(tmp, "ctl.sock"), extra_daemon, track,
               os.path.join(tmp, "boat.csv"), track, os.path.join(tmp, "ro.csv")))


class Client:
    """The protocol, read by Python: one request line, JSON lines back."""

    def __init__(self, path):
        self.s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.s.settimeout(TIMEOUT_S)
        self.s.connect(path)
        self.f = self.s.makefile("r")
        self.hello = self.read()

    def read(self):
        line = self.f.readline()
        if not line:
            raise AssertionError("trajd closed the connection")
        return json.loads(line)

    def send(self, req):
        self.s.sendall((req + "\n").encode())

    def status(self, obj=None):
        self.send("status" + (" " + obj if obj else ""))
        head, objs = self.read(), {}
        while True:
            m = self.read()
            if m.get("reply") == "end":
                return head, objs
            objs[m["object"]] = m

    def close(self):
        self.f.close()
        self.s.close()


class TrajctlTest(unittest.TestCase):
    extra_daemon = ""

    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        os.chmod(self.tmp, 0o755)  # another user reaches the socket (its mode decides)
        self.sock = os.path.join(self.tmp, "ctl.sock")
        self.conf = os.path.join(self.tmp, "t.conf")
        write(self.conf, config(self.tmp, self.extra_daemon))
        self.d = Daemon(self.tmp, self.conf)
        self.d.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)

    def tearDown(self):
        self.d.close()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def ctl(self, *args, **kw):
        r = subprocess.run([TRAJCTL, "-s", self.sock] + list(args), capture_output=True, text=True,
                           timeout=TIMEOUT_S, **kw)
        return r

    def wait_for(self, pred, what):
        """A watch of boat until pred(sp) holds: the event, not a delay."""
        c = Client(self.sock)
        c.send("watch boat")
        self.assertEqual(c.read()["reply"], "ok")
        for _ in range(int(TIMEOUT_S * RATE_HZ)):
            m = c.read()
            if "sp" in m and pred(m):
                c.close()
                return m
        c.close()
        self.fail("boat never " + what)

    def moving(self, m):
        return m["state"] == "streaming" and math.hypot(*m["vel"]) > 1.0


class TestStatus(TrajctlTest):
    def test_status_table_and_protocol(self):
        self.wait_for(lambda m: abs(math.hypot(*m["vel"]) - 5.0) < 0.1, "reached 5 m/s")
        r = self.ctl("status")
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = {l.split()[0]: l for l in r.stdout.splitlines()[3:]}
        self.assertEqual(set(rows), {"boat", "ro"})
        self.assertIn("streaming", rows["boat"])
        self.assertIn("(read-only)", rows["ro"])
        # The same, as JSON lines (every line parses), with every object and
        # its fields; the speed is that of the circle (5 m/s, time-scaled
        # within the engine's cap).
        c = Client(self.sock)
        self.assertEqual(c.hello["reply"], "hello")
        self.assertEqual(c.hello["peer_pid"], os.getpid())
        head, objs = c.status()
        self.assertEqual(head["objects"], 2)
        self.assertEqual(head["rate_hz"], RATE_HZ)
        for k in ("state", "t_s", "speed", "age_s", "delay_s", "lag_s", "ahead_s", "override",
                  "accepted", "rejected", "underruns", "health", "writable", "out_lost"):
            self.assertIn(k, objs["boat"])
        self.assertTrue(objs["boat"]["writable"])
        self.assertFalse(objs["ro"]["writable"])
        self.assertAlmostEqual(objs["boat"]["speed"], 5.0, delta=0.5)
        head, one = c.status("ro")
        self.assertEqual(list(one), ["ro"])
        c.close()
        # the peer was logged with its credentials
        self.d.err_line(lambda l: "control: client" in l and "pid %d uid %d gid %d" %
                        (os.getpid(), os.getuid(), os.getgid()) in l)

    def test_status_watch_redraws(self):
        # -w: the table again and again, each after a clear screen, until stopped
        p = subprocess.Popen([TRAJCTL, "-s", self.sock, "status", "-w", "-n", "0.2"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        seen = b""
        while seen.count(b"\033[H\033[2J") < 3:
            chunk = p.stdout.read1(65536)
            if not chunk:
                self.fail("trajctl status -w ended: %r" % p.stderr.read())
            seen += chunk
        p.send_signal(signal.SIGINT)
        p.wait(TIMEOUT_S)
        p.stdout.close()
        p.stderr.close()
        frames = seen.split(b"\033[H\033[2J")[1:3]
        for f in frames:
            self.assertIn(b"boat", f)
            self.assertIn(b"OBJECT", f)

    def test_too_many_clients(self):
        # 16 connections at once; the 17th is told "busy" and closed (logged),
        # trajctl says trajd cannot be reached; once one leaves, it can
        cs = [Client(self.sock) for _ in range(16)]
        r = self.ctl("status")
        self.assertEqual(r.returncode, 69)
        self.assertEqual(cs[0].status()[0]["busy_refused"], 1)
        self.assertIn("too many control clients", r.stderr)
        self.d.err_line(lambda l: "control: refused pid" in l and "16 clients already" in l)
        cs.pop().close()
        cs[0].status()  # the others are served meanwhile
        r = None
        for _ in range(100):  # its slot frees when trajd reads the end of that connection
            r = self.ctl("status")
            if r.returncode == 0:
                break
        self.assertEqual(r.returncode, 0, r.stderr)
        for c in cs:
            c.close()

    def test_pipelined_requests(self):
        """A client that sends 2 000 requests at once and reads its replies a
        second later gets every reply, in order, and no error.  Before: the lines
        held back while replies had no room were served with nothing to send them
        (379 of 400 answered), and a full input buffer of whole lines was taken
        for one line too long: an error, the connection cut, ~1 550 requests
        dropped."""
        c = Client(self.sock)
        c.send("\n".join(["status boat"] * 2000))
        time.sleep(1.0)
        ends = 0
        while ends < 2000:
            m = c.read()
            self.assertNotEqual(m.get("reply"), "error", m)
            if m.get("reply") == "end":
                ends += 1
        c.close()

    def test_unknown_object_and_request(self):
        r = self.ctl("status", "nosuch")
        self.assertEqual(r.returncode, 1)
        self.assertIn("no object 'nosuch'", r.stderr)
        c = Client(self.sock)
        c.send("frobnicate")
        m = c.read()
        self.assertEqual((m["reply"], m["error"]), ("error", "usage"))
        c.close()


class TestCommands(TrajctlTest):
    def test_override_stop_clear_start(self):
        self.wait_for(self.moving, "moved")
        p = subprocess.Popen([TRAJCTL, "-s", self.sock, "override", "50", "boat"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        out, err = p.communicate(timeout=TIMEOUT_S)
        self.assertEqual(p.returncode, 0, err)
        self.d.err_line(lambda l: "control: override 50 %% 'boat' from pid %d" % p.pid in l)
        # the engine runs at half speed once the ramp is done (the circle's 5 m/s)
        self.wait_for(lambda m: abs(math.hypot(*m["vel"]) - 2.5) < 0.05, "slowed to 2.5 m/s")
        c = Client(self.sock)
        self.assertEqual(c.status("boat")[1]["boat"]["override"], 0.5)
        self.assertEqual(self.ctl("override", "100", "boat").returncode, 0)
        # stop: brought to rest along its path, never a jump: the velocity
        # changes by little from tick to tick (scale_accel_m_s2 5 plus the
        # circle's 0.6 m/s^2 give 0.0056 m/s per 1 ms tick) down to rest
        # (the replay's next waypoints then start a new trajectory: engine.h)
        w = Client(self.sock)
        w.send("watch boat")
        self.assertEqual(w.read()["reply"], "ok")
        r = self.ctl("stop", "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        prev = None
        for _ in range(int(TIMEOUT_S * RATE_HZ)):
            m = w.read()
            if prev and not m["flags"] & SKIPPED:
                dv = math.dist(m["vel"], prev["vel"])
                self.assertLess(dv, 0.01, (prev, m))
            prev = m
            if m["state"] != "streaming" and math.hypot(*m["vel"]) == 0.0:
                break
        else:
            self.fail("boat never came to rest")
        w.close()
        self.d.err_line(lambda l: "control: stop 'boat'" in l)
        # the stop is latched by the object's owner (lib/engine/LIFECYCLE.md): its input
        # goes on, yet it stays at rest, stopped, until start or clear
        for _ in range(20):
            st = c.status("boat")[1]["boat"]
            self.assertEqual(st["lifecycle"], "stopped", st)
            self.assertEqual(st["speed"], 0, st)
            time.sleep(0.05)
        # and trajctl's table says so (it showed the engine's "finished", health ok)
        r = self.ctl("status", "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        row = [l for l in r.stdout.splitlines() if l.startswith("boat ")]
        self.assertTrue(row, r.stdout)
        self.assertEqual(row[0].split()[2], "stopped", r.stdout)
        self.assertIn("stopped", row[0].split("  ")[-1], r.stdout)
        # the other object was not touched
        self.assertEqual(c.status("ro")[1]["ro"]["state"], "streaming")
        # clear: the object takes waypoints again and moves on (a transfer)
        r = self.ctl("clear", "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.wait_for(self.moving, "moved again after clear")
        # the clear released the stop's latch: its line tells what the latch buffered
        self.d.err_line(lambda l: "object 'boat': command clear" in l and
                        "waypoints while stopped or held:" in l)
        # start on a moving object: nothing to do, accepted; its line tells no waypoints
        # of a latch (it told the stop's again, as if it had buffered them too)
        r = self.ctl("start", "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        line = self.d.err_line(lambda l: "object 'boat': command start" in l)
        self.assertNotIn("waypoints while stopped or held", line)
        c.close()

    def test_refused_not_writable(self):
        self.wait_for(self.moving, "moved")
        for args in (("stop", "ro"), ("clear", "ro"), ("start", "ro"), ("override", "0", "ro")):
            r = self.ctl(*args)
            self.assertEqual(r.returncode, 1, args)
            self.assertIn("not writable", r.stderr)
            self.assertIn("trajd refused", r.stderr)
        self.d.err_line(lambda l: "control: stop 'ro' from pid" in l and "refused: not writable" in l)
        c = Client(self.sock)
        st = c.status("ro")[1]["ro"]
        self.assertEqual((st["state"], st["override"]), ("streaming", 1.0))
        c.close()
        # out of range: a bad command line for trajctl (64, TestReach), and refused by
        # trajd too when it comes by the protocol; unknown: refused by trajd
        self.assertEqual(self.ctl("override", "201", "boat").returncode, 64)
        c = Client(self.sock)
        c.send("override 201 boat")
        m = c.read()
        self.assertEqual((m["reply"], m["error"]), ("error", "usage"))
        c.close()
        self.assertEqual(self.ctl("stop", "nosuch").returncode, 1)
        # logged as every refused command is (it was refused with no line)
        self.d.err_line(lambda l: "control: stop 'nosuch' from pid" in l and
                        "refused: no such object" in l)
        # and the four refused for 'ro' counted in its refused commands, as CAN's and
        # Modbus's are: the exit line (they were logged, not counted)
        self.d.p.send_signal(signal.SIGTERM)
        self.d.p.send_signal(signal.SIGTERM)
        self.d.wait(TIMEOUT_S)
        last = self.d.err_line(lambda l: "exit: " in l)
        self.assertRegex(last, r"\bro [^;]*, 4 commands refused")

    def test_reload(self):
        r = self.ctl("reload")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.d.err_line(lambda l: "reloaded: 2 object(s), 2 carried over" in l)
        good = read(self.conf)
        write(self.conf, good + "bogus_line_without_equals\n")
        r = self.ctl("reload")
        self.assertEqual(r.returncode, 1)
        self.assertIn("reload refused", r.stderr)
        self.assertIn("t.conf:", r.stderr)
        write(self.conf, good)
        c = Client(self.sock)
        self.assertEqual(c.status()[0]["objects"], 2)  # the old one runs on
        c.close()

    def test_check(self):
        r = self.ctl("check", self.conf)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("ok, 2 object(s)", r.stdout)
        bad = os.path.join(self.tmp, "bad.conf")
        write(bad, "[daemon]\nrate_hz = 0\n")
        r = self.ctl("check", bad)
        self.assertEqual(r.returncode, 78)
        self.assertIn("bad.conf:2:", r.stderr)


class TestLogDropped(TrajctlTest):
    """Log lines the log thread could not queue (its reader, stderr here,
    stopped reading) are counted and the count is shown: trajctl status, the
    status line (the log's and systemd's STATUS=) and the exit line."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        self.sock = os.path.join(self.tmp, "ctl.sock")
        self.conf = os.path.join(self.tmp, "t.conf")
        probe = socket.socket()
        probe.bind(("127.0.0.1", 0))
        self.mb_port = probe.getsockname()[1]   # free now; trajd binds it below
        probe.close()
        write(self.conf, config(self.tmp).replace("status_interval_s = 0", "status_interval_s = 1") +
              "\n[modbus]\naddress = 127.0.0.1\nport = %d\nsystemd_socket = no\n" % self.mb_port)
        self.d = Daemon(self.tmp, self.conf, read_stderr=False)
        self.d.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)

    def test_dropped_lines_are_counted_and_shown(self):
        # Refused commands, one warning line each, while nobody reads stderr:
        # the pipe fills, then the log thread's queue, then lines are dropped.
        c = Client(self.sock)
        for _ in range(30):
            c.send("\n".join(["stop ro"] * 100))
            for _ in range(100):
                self.assertEqual(c.read()["reply"], "error")
        head, _ = c.status()
        c.close()
        self.assertGreater(head["log_dropped"], 0, head)
        r = self.ctl("status")
        self.assertEqual(r.returncode, 0, r.stderr)
        shown = [int(w) for w in r.stdout.split("log lines dropped ")[1:2] for w in [w.split()[0]]]
        self.assertTrue(shown and shown[0] >= head["log_dropped"], r.stdout)
        fields, _ = self.d.msg(lambda f: "log lines dropped" in f.get("STATUS", ""), timeout=TIMEOUT_S)
        self.assertRegex(fields["STATUS"], r", log lines dropped [1-9]\d*")
        # and Modbus's daemon block (lib/proto/mbmap.h MBMAP_D_LOG_DROPPED)
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
        import mbsim
        m = mbsim.connect(self.mb_port)
        try:
            regs = mbsim.read_input(m, mbsim.M["MBMAP_D_LOG_DROPPED"], 2)
        finally:
            m.close()
        self.assertGreaterEqual(mbsim.u32(regs, 0), head["log_dropped"])
        # Read again: the log thread says how many it dropped, the status
        # lines carry the count, and so does the exit line.
        self.d.read_stderr_now()
        self.d.err_line(lambda l: "log lines dropped: the log's reader" in l)
        self.d.err_line(lambda l: "status: " in l and "log lines dropped" in l)
        self.d.p.send_signal(signal.SIGTERM)
        self.assertEqual(self.d.wait(TIMEOUT_S), 0)
        last = self.d.err_line(lambda l: "exit: " in l)
        n = int(last.split(", log lines dropped ")[1].split()[0].rstrip(",;"))
        self.assertGreaterEqual(n, head["log_dropped"])


class TestReach(unittest.TestCase):
    def test_unreachable(self):
        with tempfile.TemporaryDirectory() as tmp:
            r = subprocess.run([TRAJCTL, "-s", os.path.join(tmp, "none"), "status"],
                               capture_output=True, text=True, timeout=TIMEOUT_S)
            self.assertEqual(r.returncode, 69)
            self.assertIn("cannot reach trajd", r.stderr)
            # a socket file nobody listens on (a trajd that died)
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.bind(os.path.join(tmp, "stale"))
            s.close()
            r = subprocess.run([TRAJCTL, "-s", os.path.join(tmp, "stale"), "stop", "boat"],
                               capture_output=True, text=True, timeout=TIMEOUT_S)
            self.assertEqual(r.returncode, 69)
            self.assertIn("nobody listens", r.stderr)

    def test_usage(self):
        for args in ([], ["stop"], ["override", "boat"], ["frob"], ["watch", "-c", "0", "boat"]):
            r = subprocess.run([TRAJCTL] + args, capture_output=True, text=True, timeout=TIMEOUT_S)
            self.assertEqual(r.returncode, 64, args)

    def test_override_value(self):
        # a percent outside 0 .. 200, or not a whole number, is a bad command line (64),
        # said before any connection, naming the value (it was sent, and trajd's refusal
        # came back as exit 1; -1 was taken for an option)
        for n in ("201", "-1", "abc", "50.5", "", "1e2"):
            r = subprocess.run([TRAJCTL, "-s", "/nonexistent/ctl.sock", "override", n, "boat"],
                               capture_output=True, text=True, timeout=TIMEOUT_S)
            self.assertEqual(r.returncode, 64, (n, r.stderr))
            self.assertIn("override N OBJECT: N is a whole percent, 0 to 200, got '%s'" % n,
                          r.stderr)


class TestPlace(unittest.TestCase):
    """Where the socket goes, and two trajd on one socket."""

    def setUp(self):
        self.tmp = tempfile.mkdtemp()
        self.daemons = []

    def tearDown(self):
        for d in self.daemons:
            d.close()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def start(self, text, env=None):
        conf = os.path.join(self.tmp, "t%d.conf" % len(self.daemons))
        write(conf, text)
        with mock.patch.dict(os.environ, env or {}):
            d = Daemon(self.tmp, conf)
        self.daemons.append(d)
        return d

    def test_start_refused_while_held_says_why(self):
        # Given boat held by its safety monitor (a position box its circle leaves), when
        # trajctl start is sent, then it is refused (exit 1) naming the hold and the
        # command that releases it (it said "call not valid in this state")
        text = config(self.tmp).replace("output = csv\ncsv.path = %s\n" % os.path.join(
            self.tmp, "boat.csv"), "output = csv\ncsv.path = %s\nposition_min_m = -1000, -1000, "
            "-1000\nposition_max_m = 1000, 5, 1000\n" % os.path.join(self.tmp, "boat.csv"), 1)
        d = self.start(text)
        d.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        sock = os.path.join(self.tmp, "ctl.sock")
        end = time.monotonic() + TIMEOUT_S
        while True:
            c = Client(sock)
            st = c.status("boat")[1]["boat"]
            c.close()
            if st["lifecycle"] == "held":
                break
            self.assertLess(time.monotonic(), end, "never held: %s" % st)
            time.sleep(0.05)
        r = subprocess.run([TRAJCTL, "-s", sock, "start", "boat"], capture_output=True,
                           text=True, timeout=TIMEOUT_S)
        self.assertNotEqual(r.returncode, 0, r.stdout)
        self.assertIn("the object is held", r.stderr + r.stdout)
        self.assertIn("only clear releases it", r.stderr + r.stdout)

    def test_systemd_runtime_directory(self):
        # Given RuntimeDirectory= (systemd sets $RUNTIME_DIRECTORY) and no
        # control_socket, then the socket is $RUNTIME_DIRECTORY/control
        rundir = os.path.join(self.tmp, "run")
        os.mkdir(rundir)
        text = config(self.tmp).replace("control_socket = %s\n" % os.path.join(self.tmp, "ctl.sock"), "")
        d = self.start(text, {"RUNTIME_DIRECTORY": rundir})
        d.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        r = subprocess.run([TRAJCTL, "-s", os.path.join(rundir, "control"), "status"],
                           capture_output=True, text=True, timeout=TIMEOUT_S)
        self.assertEqual(r.returncode, 0, r.stderr)
        r = subprocess.run([TRAJCTL, "status"], capture_output=True, text=True, timeout=TIMEOUT_S,
                           env=dict(os.environ, TRAJCTL_SOCKET=os.path.join(rundir, "control")))
        self.assertEqual(r.returncode, 0, r.stderr)
        # gone with trajd
        d.p.send_signal(signal.SIGTERM)
        self.assertEqual(d.wait(TIMEOUT_S), 0)
        self.assertFalse(os.path.exists(os.path.join(rundir, "control")))

    def test_second_trajd_on_a_configured_socket(self):
        # Given a trajd answering on its configured socket, a second one
        # configured with the same socket does not start, and says why
        first = self.start(config(self.tmp))
        first.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        second = self.start(config(self.tmp))
        self.assertEqual(second.wait(TIMEOUT_S), 69)
        self.assertIn("another trajd answers on it", second.stderr())
        r = subprocess.run([TRAJCTL, "-s", os.path.join(self.tmp, "ctl.sock"), "status"],
                           capture_output=True, text=True, timeout=TIMEOUT_S)
        self.assertEqual(r.returncode, 0, r.stderr)  # the first one still has it
        self.assertIn("pid %d" % first.p.pid, r.stdout)

    def test_second_trajd_on_the_default_socket(self):
        # Given a trajd on the default place, a second one left to the default
        # runs without a control socket and warns
        rundir = os.path.join(self.tmp, "run")
        os.mkdir(rundir)
        text = config(self.tmp).replace("control_socket = %s\n" % os.path.join(self.tmp, "ctl.sock"), "")
        first = self.start(text, {"RUNTIME_DIRECTORY": rundir})
        first.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        second = self.start(text, {"RUNTIME_DIRECTORY": rundir})
        second.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        second.err_line(lambda l: "running WITHOUT a control socket" in l)

    def test_stale_socket_replaced(self):
        # Given a socket file a dead trajd left (nobody listens), then trajd
        # replaces it and says so
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.bind(os.path.join(self.tmp, "ctl.sock"))
        s.close()
        d = self.start(config(self.tmp))
        d.msg(lambda f: f.get("READY") == "1", timeout=TIMEOUT_S)
        d.err_line(lambda l: "replaced the stale socket" in l)
        r = subprocess.run([TRAJCTL, "-s", os.path.join(self.tmp, "ctl.sock"), "status"],
                           capture_output=True, text=True, timeout=TIMEOUT_S)
        self.assertEqual(r.returncode, 0, r.stderr)


def as_nobody(tmp, args):
    """trajctl run as uid/gid 65534, a copy of it where that user can reach it."""
    exe = os.path.join(tmp, "trajctl")
    shutil.copy(TRAJCTL, exe)
    os.chmod(exe, 0o755)
    return subprocess.run([exe] + args, capture_output=True, text=True, timeout=TIMEOUT_S,
                          user=65534, group=65534, extra_groups=[], cwd="/")


@unittest.skipUnless(os.geteuid() == 0, "needs root to run a client as another user")
class TestPermission(TrajctlTest):
    def test_outside_the_group(self):
        st = os.stat(self.sock)
        self.assertEqual(stat.S_IMODE(st.st_mode), 0o660)
        r = as_nobody(self.tmp, ["-s", self.sock, "stop", "boat"])
        self.assertEqual(r.returncode, 77, r.stderr)
        self.assertIn("permission denied", r.stderr)
        c = Client(self.sock)
        self.assertEqual(c.status("boat")[1]["boat"]["state"] in ("streaming", "waiting"), True)
        c.close()


@unittest.skipUnless(os.geteuid() == 0, "needs root to run a client as another user")
class TestPermissionGroup(TrajctlTest):
    extra_daemon = "control_group = nogroup\n"

    def test_member_of_the_group(self):
        # The same user, now in the socket's group: admitted (so the refusal
        # above is the group's doing), and logged with his credentials.
        self.assertEqual(os.stat(self.sock).st_gid, 65534)
        r = as_nobody(self.tmp, ["-s", self.sock, "status"])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("boat", r.stdout)
        self.d.err_line(lambda l: "control: client" in l and "uid 65534 gid 65534" in l)


class TestWatch(TrajctlTest):
    def test_every_setpoint_at_1khz_for_10_s(self):
        """10 000 setpoints at 1 kHz: exactly trajd's csv rows of those ticks."""
        self.wait_for(self.moving, "moved")
        n = 10 * RATE_HZ
        r = self.ctl("watch", "-c", str(n), "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("lost", r.stderr)
        got = r.stdout.splitlines()
        self.assertEqual(got[0].split(",")[:3], ["object", "now_ns", "t_s"])
        got = got[1:]
        self.assertEqual(len(got), n)
        self.d.p.send_signal(signal.SIGTERM)
        self.assertEqual(self.d.wait(TIMEOUT_S), 0)
        with open(os.path.join(self.tmp, "boat.csv")) as f:
            csv = f.read().splitlines()[1:]
        first = next(i for i, l in enumerate(csv) if l == got[0])
        self.assertEqual(csv[first:first + n], got)  # every row, byte for byte
        # and the ticks have no gap but the deadlines trajd missed (flagged
        # SKIPPED, absent from its csv too)
        ticks = [int(l.split(",")[1]) for l in got]
        flags = [int(l.split(",")[13]) for l in got]
        for k in range(1, n):
            if not flags[k] & SKIPPED:
                self.assertEqual(ticks[k] - ticks[k - 1], PERIOD_NS, got[k])
        moving = sum(1 for l in got if l.split(",")[12] == "streaming")
        self.assertGreater(moving, n // 2)

    def test_slow_watcher_overflows_its_own_ring(self):
        """A watcher that does not read: its ring fills, the newest setpoints
        are dropped, counted, logged and told where; the tick goes on, and so
        does another watcher, complete."""
        slow = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        slow.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        slow.settimeout(TIMEOUT_S)
        slow.connect(self.sock)
        slow.sendall(b"watch boat\n")
        fast_out = open(os.path.join(self.tmp, "fast.csv"), "w+")
        fast = subprocess.Popen([TRAJCTL, "-s", self.sock, "watch", "-c", "10000", "boat"],
                                stdout=fast_out, stderr=subprocess.PIPE, text=True)
        # the ring holds 8192 setpoints, 8.2 s at 1 kHz: then trajd says so
        self.d.err_line(lambda l: "reads 'boat' too slowly" in l, timeout=3 * TIMEOUT_S)
        f = slow.makefile("r")
        lines = [json.loads(f.readline()) for _ in range(12000)]
        f.close()
        slow.close()
        _, err = fast.communicate(timeout=TIMEOUT_S)
        self.assertEqual(fast.returncode, 0, err)
        fast_out.seek(0)
        out = fast_out.read()
        fast_out.close()
        self.assertEqual((lines[0]["reply"], lines[1]["reply"]), ("hello", "ok"))
        over = next(i for i, m in enumerate(lines) if "overflow" in m)
        m = lines[over]
        self.assertGreater(m["lost"], 0)
        self.assertEqual(m["ring"], 8192)
        c = Client(self.sock)  # and counted in the daemon's status
        self.assertGreaterEqual(c.status()[0]["watch_lost"], m["lost_total"])
        c.close()
        before, after = lines[over - 1], lines[over + 1]
        gap = after["tick"] - before["tick"]
        skipped = sum(1 for x in lines[over - 8192:over + 2] if "sp" in x and x["flags"] & SKIPPED)
        if not skipped:
            self.assertEqual(gap, m["lost"] + 1)  # exactly the ticks it was told of
        # the fast watcher got every tick of that time (its rows are contiguous)
        rows = [l.split(",") for l in out.splitlines()[1:]]
        ticks = [int(r[1]) for r in rows if r[0] == "boat"]
        for k in range(1, len(ticks)):
            if not int(rows[k][13]) & SKIPPED:
                self.assertEqual(ticks[k] - ticks[k - 1], PERIOD_NS)
        self.assertEqual(len(ticks), 10000)

    def test_spark(self):
        self.wait_for(self.moving, "moved")
        r = self.ctl("watch", "--spark", "-c", "500", "boat")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("boat ", r.stdout)
        self.assertTrue(any(ch in r.stdout for ch in "▁▂▃▄▅▆▇█"))
        self.assertIn("m/s", r.stdout)

    def test_object_gone_at_reload(self):
        c = Client(self.sock)
        c.send("watch ro")
        self.assertEqual(c.read()["reply"], "ok")
        good = read(self.conf)
        write(self.conf, good[:good.index("[object.ro]")])
        r = self.ctl("reload")
        self.assertEqual(r.returncode, 0, r.stderr)
        while True:
            m = c.read()
            if "sp" not in m:
                break
        self.assertEqual(m["reply"], "end")
        self.assertEqual(m["object"], "ro")
        c.close()


if __name__ == "__main__":
    unittest.main()
