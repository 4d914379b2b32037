"""test_lifecycle_daemon.py - the lifecycle owner (lib/engine/LIFECYCLE.md) in trajd,
seen from outside: its setpoint rows and a Modbus client's commands.

- Stall: trajd replaying a track moving at 2 m/s in real time is frozen for 1 s
  (SIGSTOP). Its next setpoint goes on from the last one sent: no step between two
  rows beyond one period of motion at the object's speed bound (1.5 max_speed_m_s,
  engine.h). Before the owner, trajd stepped the engine through every missed
  deadline and sent a target a whole second ahead.
- Stop now, latched: a Modbus client streams a track, sends STOP, and goes on
  sending waypoints for 6 s. The object stays at rest (not one row moves) until
  START, then moves again, with no step. Before, the sender's next waypoints
  restarted the object about 2.5 s after the stop.
- Clear after a safety hold: the monitor's speed bound is below the track's speed,
  so the object is held; the client sends CLEAR and a slower track. The object
  resumes from the held position by a transfer (rows move again, none refused).
  Before, the engine kept moving while the output was held, and after the clear
  the monitor refused the jump back to the engine and held the object to the end.
Every command received is logged with the object and the client.
"""
import math
import os
import socket
import json
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 30
PERIOD_S = 0.01
MAX_SPEED = 5.0
STEP_MAX = 1.5 * MAX_SPEED * PERIOD_S * 1.0001 + 1e-9  # engine.h ENGINE_SPEED_CAP


def circle(t):
    return (10.0 * math.cos(0.2 * t), 10.0 * math.sin(0.2 * t), 0.0)


class Rows:
    """Setpoint rows (object,now_ns,t_s,x,y,z,...,state,flags,...) from a stream,
    read by a thread."""

    def __init__(self, stream):
        self.rows = []
        self.cv = threading.Condition()
        threading.Thread(target=self._run, args=(stream,), daemon=True).start()

    def _run(self, stream):
        for line in stream:
            f = line.strip().split(",")
            if len(f) < 14 or not f[1].isdigit():
                continue
            with self.cv:
                self.rows.append((int(f[1]), float(f[2]), float(f[3]), float(f[4]),
                                  float(f[5]), f[12], int(f[13])))
                self.cv.notify_all()

    def wait(self, n, timeout=WAIT_S):
        """Wait until at least n rows; returns them all."""
        end = time.monotonic() + timeout
        with self.cv:
            while len(self.rows) < n:
                left = end - time.monotonic()
                if left <= 0:
                    raise AssertionError("only %d of %d rows" % (len(self.rows), n))
                self.cv.wait(left)
            return list(self.rows)


class FileRows(Rows):
    """Rows of a CSV file trajd writes, followed as it grows."""

    def __init__(self, path):
        self.path = path
        super().__init__(self._follow())

    def _follow(self):
        while not os.path.exists(self.path):
            time.sleep(0.01)
        with open(self.path) as f:
            buf = ""
            while True:
                chunk = f.readline()
                if not chunk:
                    time.sleep(0.01)
                    continue
                buf += chunk
                if buf.endswith("\n"):
                    yield buf
                    buf = ""


def step(a, b):
    return math.dist(a[2:5], b[2:5])


def max_step(rows):
    return max((step(a, b), i) for i, (a, b) in enumerate(zip(rows, rows[1:])))


class Stall(unittest.TestCase):
    def test_stall_goes_on_from_last_sent(self):
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "circle.csv")
            with open(track, "w") as f:
                f.write("t,x,y,z\n")
                for i in range(600):
                    f.write("%.1f,%.6f,%.6f,%.6f\n" % ((0.1 * i,) + circle(0.1 * i)))
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 2\n"
                        "[object.boat]\ninput = replay\nreplay.track = %s\noutput = stdout\n"
                        "max_speed_m_s = %g\n" % (track, MAX_SPEED))
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            try:
                rows = Rows(p.stdout)
                # Given the object moving (rows flagged neither hold nor waiting),
                r = rows.wait(1)
                end = time.monotonic() + WAIT_S
                while not (r[-1][5] == "streaming" and step(r[-2], r[-1]) > 0.01):
                    self.assertLess(time.monotonic(), end, "never moving")
                    r = rows.wait(len(r) + 1)
                n0 = len(r)
                # when trajd is frozen for 1 s (100 periods),
                p.send_signal(signal.SIGSTOP)
                time.sleep(1.0)  # the fault itself, not a wait for an event
                p.send_signal(signal.SIGCONT)
                r = rows.wait(n0 + 200)
                # then the rows skip deadlines (now_ns jumps) but never a position
                gaps = [b[0] - a[0] for a, b in zip(r[n0 - 5:], r[n0 - 4:])]
                self.assertGreaterEqual(max(gaps), 50 * 10 ** 7, gaps)
                s, i = max_step(r[n0 - 5:])
                self.assertLessEqual(s, STEP_MAX, "step %.4f m at row %d" % (s, i))
                # and the object goes on moving
                self.assertGreater(step(r[n0 - 5], r[-1]), 1.0)
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(WAIT_S)
                p.stderr.close()


    def moving_circle(self, extra="", daemon="", n=600):
        """trajd replaying a circle (r = 20 m, 4 m/s) to stdout (and extra keys of
        the object, where "TMP" is its temporary directory), moving at speed:
        (process, its configuration's path and text, the rows, the log lines,
        an event set at each "reloaded:" line)."""
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        self.tmp = tmp.name
        os.mkdir(os.path.join(tmp.name, "out"))
        track = os.path.join(tmp.name, "circle.csv")
        with open(track, "w") as f:
            f.write("t,x,y,z\n")
            for i in range(n):
                t = 0.1 * i
                f.write("%.1f,%.6f,%.6f,0\n" % (t, 20 * math.cos(0.2 * t), 20 * math.sin(0.2 * t)))
        conf = os.path.join(tmp.name, "trajd.conf")
        base = ("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 2\n"
                "control_socket = %s\n" % os.path.join(tmp.name, "ctl.sock") + daemon +
                "[object.boat]\ninput = replay\nreplay.track = %s\n"
                "max_speed_m_s = %g\n" % (track, MAX_SPEED)) + extra.replace("TMP", tmp.name)
        if "output =" not in extra:
            base += "output = stdout\n"
        with open(conf, "w") as f:
            f.write(base)
        p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        reloaded = threading.Event()
        log = []

        def watch():
            for line in p.stderr:
                log.append(line)
                if "reloaded:" in line:
                    reloaded.set()
        threading.Thread(target=watch, daemon=True).start()
        rows = Rows(p.stdout)
        r = rows.wait(2)
        end = time.monotonic() + WAIT_S
        while not (r[-1][5] == "streaming" and step(r[-2], r[-1]) > 0.035):
            self.assertLess(time.monotonic(), end, "never moving at speed")
            r = rows.wait(len(r) + 1)
        return p, conf, base, rows, log, reloaded

    def test_stray_signals_ignored(self):
        """SIGUSR1, SIGUSR2 and SIGALRM, whose default would end trajd at once with
        its objects moving (no brake, no exit line), are logged and ignored; the
        rows go on without a step, and SIGTERM still brings the object to rest."""
        p, conf, base, rows, log, reloaded = self.moving_circle()
        try:
            n0 = len(rows.rows)
            for sig in (signal.SIGUSR1, signal.SIGUSR2, signal.SIGALRM):
                p.send_signal(sig)
            r = rows.wait(n0 + 100)
            self.assertIsNone(p.poll())
            s, i = max_step(r[n0 - 5:])
            self.assertLessEqual(s, STEP_MAX)
            self.assertGreater(step(r[n0], r[-1]), 1.0)
            for name in ("User defined signal 1", "User defined signal 2", "Alarm clock"):
                self.assertTrue(any(name in l and "ignored" in l for l in log), (name, log))
        finally:
            p.send_signal(signal.SIGTERM)
            self.assertEqual(p.wait(WAIT_S), 0)

    def test_reload_whose_output_cannot_reopen(self):
        """The object writes a CSV besides stdout; its directory is removed and
        trajd reloaded with the file unchanged: neither configuration can open
        that output again.  The object goes on moving on stdout with no step,
        the lost output is logged, and trajd exits 74 (output lost) at SIGTERM.
        Before, trajd ended at once with exit 70 (internal fault), no brake and
        no exit line."""
        p, conf, base, rows, log, reloaded = self.moving_circle(
            "output = stdout, csv\ncsv.path = TMP/out/boat.csv\n")
        try:
            n0 = len(rows.rows)
            shutil.rmtree(os.path.join(self.tmp, "out"))
            p.send_signal(signal.SIGHUP)
            r = rows.wait(n0 + 150)
            self.assertIsNone(p.poll(), "".join(log))
            s, i = max_step(r[n0 - 5:])
            self.assertLessEqual(s, STEP_MAX)
            self.assertGreater(step(r[n0], r[-1]), 1.0)
            self.assertTrue(any("did not reopen" in l for l in log), "".join(log))
        finally:
            p.send_signal(signal.SIGTERM)
            self.assertEqual(p.wait(WAIT_S), 74, "".join(log))

    def test_second_sigterm_while_moving(self):
        """A second SIGTERM exits at once (daemon/doc/trajd.8), here before the
        object came to rest: the exit status says its motion was cut short (75,
        with an error line naming it).  Before, it was 0."""
        p, conf, base, rows, log, reloaded = self.moving_circle()
        p.send_signal(signal.SIGTERM)
        end = time.monotonic() + WAIT_S  # (two at once would be one pending signal)
        while not any("bringing objects to rest" in l for l in log):
            self.assertLess(time.monotonic(), end, "".join(log))
            time.sleep(0.005)
        p.send_signal(signal.SIGTERM)
        rc = p.wait(WAIT_S)
        time.sleep(0.2)
        self.assertEqual(rc, 75, "".join(log))
        self.assertTrue(any("boat" in l and "still moving" in l for l in log), "".join(log))
        # said as moving, not as held (it said "1 object(s) ended held")
        self.assertTrue(any("1 object(s) ended still moving" in l for l in log), "".join(log))
        self.assertFalse(any("ended held" in l for l in log), "".join(log))

    def test_reload_offers_no_row_again(self):
        """Reloads of an unchanged file while the replayed object moves: the
        replay goes on after the last row it gave, so no row is offered twice
        (duplicates 0), whatever the acceptance still held.  Before, each reload
        gave the row after the last one accepted again: duplicates +1 per reload."""
        p, conf, base, rows, log, reloaded = self.moving_circle()
        try:
            for i in range(3):
                reloaded.clear()
                p.send_signal(signal.SIGHUP)
                self.assertTrue(reloaded.wait(WAIT_S), "no reload")
                rows.wait(len(rows.rows) + 20)
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.settimeout(WAIT_S)
            s.connect(os.path.join(self.tmp, "ctl.sock"))
            f = s.makefile("r")
            json.loads(f.readline())
            s.sendall(b"status boat\n")
            json.loads(f.readline())
            st = json.loads(f.readline())
            s.close()
            self.assertEqual(st["duplicates"], 0, st)
            self.assertEqual(st["rejected"], 0, st)
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)

    def test_exit_when_done_with_a_stop_latched(self):
        """exit_when_done: the operator stops the moving object and the replay gives
        its last row; the object is latched with waypoints it never played, so its
        motion was not delivered: trajd ends with exit 75 (an object ended held) and
        an error line naming it.  Before, it exited 0 with only an info line."""
        p, conf, base, rows, log, reloaded = self.moving_circle(
            "writable = yes\n", daemon="exit_when_done = yes\nspeed = 2\n", n=150)
        try:
            r = subprocess.run([os.path.join(os.path.dirname(TRAJD), "trajctl"), "-s",
                                os.path.join(self.tmp, "ctl.sock"), "stop", "boat"],
                               capture_output=True, text=True, timeout=WAIT_S)
            self.assertEqual(r.returncode, 0, r.stderr)
            rc = p.wait(120)
        finally:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                p.wait(WAIT_S)
        self.assertEqual(rc, 75, "".join(log))
        self.assertTrue(any("ended held" in l and "boat" in l and "stop" in l for l in log),
                        "".join(log))

    def reload_while_moving(self, extra, during=None, wait_rows=300, edit=None):
        """The moving circle; the configuration is rewritten with extra (a changed
        object: its old engine brakes to rest) and reloaded, during(p) runs, and the
        rows from shortly before the reload to wait_rows after are returned."""
        p, conf, base, rows, log, reloaded = self.moving_circle()
        try:
            n0 = len(rows.rows)
            with open(conf, "w") as f:
                f.write((edit(base) if edit else base) + extra)
            p.send_signal(signal.SIGHUP)
            self.assertTrue(reloaded.wait(WAIT_S), "no reload: " + "".join(log[-3:]))
            if during:
                during(p)
            return rows.wait(len(rows.rows) + wait_rows)[n0 - 5:]
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)

    def assert_follows(self, r, a_max):
        """No row held by the monitor, no step, and the acceleration by second
        differences of rows one period apart within a_max."""
        held = [row for row in r if row[6] & 0x20]
        self.assertEqual(held, [], "held by the monitor")
        s, i = max_step(r)
        self.assertLessEqual(s, STEP_MAX, "step %.4f m at row %d" % (s, i))
        for a, b, c in zip(r, r[1:], r[2:]):
            if b[0] - a[0] != 10 ** 7 or c[0] - b[0] != 10 ** 7:
                continue  # a missed deadline between them (a loaded machine)
            acc = math.dist([c[k] - 2 * b[k] + a[k] for k in (2, 3, 4)], (0, 0, 0)) / PERIOD_S ** 2
            self.assertLessEqual(acc, a_max, "%.1f m/s^2 at %s" % (acc, b))

    def test_tighter_limits_judge_the_new_engine_only(self):
        """A reload that tightens the moving object's speed limit below its speed
        (max_speed_m_s 5 -> 1.5, the monitor's default bound 3 m/s, the object at
        4 m/s): its old engine, planned at the old limits, brakes to rest along its
        path judged by the bounds it was planned for; the new ones judge the new
        engine from where it rests (whose acceptance refuses the 4 m/s track as too
        fast).  No row is held, none steps, and the acceleration stays within the
        braking's 5 m/s^2 (and the circle's 0.8).  Before, the monitor took the new bound at once
        and froze the object on the first braking row, 4 m/s to 0 in one tick
        (400 m/s^2), held until clear: trajd exited 75."""
        r = self.reload_while_moving("", wait_rows=400, edit=lambda b: b.replace(
            "max_speed_m_s = %g\n" % MAX_SPEED, "max_speed_m_s = 1.5\n"))
        self.assert_follows(r, 1.1 * 5.0 + 0.8 + 0.5)

    def test_tighter_bounds_while_a_reload_brakes(self):
        """The reload changes the object and bounds its acceleration below the old
        engine's braking (5 m/s^2): the old engine brakes judged by the bounds it
        was planned for, not held and frozen by the new ones (which judge the new
        engine, from rest).  Before, the monitor held the object at once, and (an
        earlier fix) every row from the hold on stayed at the held position."""
        r = self.reload_while_moving("scale_accel_m_s2 = 3\nsafety_max_accel_m_s2 = 2\n",
                                     wait_rows=60)
        self.assert_follows(r, 1.1 * 5.0 + 0.8 + 0.5)

    def test_tighter_safety_bound_alone_brakes(self):
        """A reload that only lowers safety_max_speed_m_s below the moving object's
        speed (4 m/s; the default bound 10 -> 2), its engine and input unchanged (an
        object carried over): it brakes to rest along its path, judged by the bounds
        it was planned for, says why, and goes on from there under the new ones: its
        new engine keeps the output within the bound (engine.h cap_speed_m_s), the
        4 m/s circle played slower.  No row is held, none steps, none is faster than
        the bound.  Before, the carried object was judged by the new bound at once:
        held by the monitor on the next row, 4 m/s to 0 in one tick, until clear (exit
        75); and then (its new engine planned without the bound) held again as it sped
        up through 2 m/s on its transfer back."""
        p, conf, base, rows, log, reloaded = self.moving_circle()
        try:
            n0 = len(rows.rows)
            with open(conf, "w") as f:
                f.write(base + "safety_max_speed_m_s = 2\n")
            p.send_signal(signal.SIGHUP)
            self.assertTrue(reloaded.wait(WAIT_S), "no reload: " + "".join(log[-3:]))
            r = rows.wait(len(rows.rows) + 700)[n0 - 5:]
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)
        self.assert_follows(r, 1.1 * 5.0 + 0.8 + 0.5)
        self.assertTrue(any("its new safety bounds refuse its motion: speed" in l for l in log),
                        "".join(log))
        # past the braking (4 m/s at 5 m/s^2: 0.8 s, judged by the old bounds)
        after = r[5 + 120:]
        fast = [(b[0], math.dist(a[2:5], b[2:5]) / PERIOD_S) for a, b in zip(after, after[1:])
                if b[0] - a[0] == 10 ** 7 and math.dist(a[2:5], b[2:5]) / PERIOD_S > 2.0]
        self.assertEqual(fast, [], "faster than the new bound")
        self.assertTrue(any(row[5] == "streaming" and not row[6] & 8 for row in after),
                        "the circle is played again after the transfer")

    def test_command_while_a_reload_brakes_says_so(self):
        """A stop sent while a reload's old engine still brakes the moving object is
        taken by the new engine (which starts where the old one rests, stopped) and
        its log line says so: the state it names is the new engine's.  Before, it
        read "in state waiting: stop -> stopped" while the object still moved."""
        def stop(p):
            r = subprocess.run([os.path.join(os.path.dirname(TRAJD), "trajctl"), "-s",
                                os.path.join(self.tmp, "ctl.sock"), "stop", "boat"],
                               capture_output=True, text=True, timeout=WAIT_S)
            self.assertEqual(r.returncode, 0, r.stderr)
        p, conf, base, rows, log, reloaded = self.moving_circle("writable = yes\n")
        try:
            n0 = len(rows.rows)
            with open(conf, "w") as f:
                f.write(base.replace("max_speed_m_s = %g\n" % MAX_SPEED, "max_speed_m_s = 4.5\n"))
            p.send_signal(signal.SIGHUP)
            self.assertTrue(reloaded.wait(WAIT_S), "no reload: " + "".join(log[-3:]))
            stop(p)
            r = rows.wait(len(rows.rows) + 60)[n0 - 5:]
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)
        self.assert_follows(r, 1.1 * 5.0 + 0.8 + 0.5)
        line = [l for l in log if "command stop from" in l]
        self.assertEqual(len(line), 1, "".join(log))
        self.assertIn("(the new engine's, which starts where the old one, still braking for a "
                      "reload, rests): stop -> stopped", line[0])

    def test_stall_while_a_reload_brakes(self):
        """A reload that changes the moving object keeps its old engine braking to
        rest along its path (daemon/REFERENCE.md); trajd frozen for 0.3 s meanwhile
        (SIGSTOP): the braking engine also goes on one period from its last setpoint
        sent.  Before, it was stepped to the newest deadline at once: a step of every
        period missed in one row (0.1 to 0.6 m at 5 m/s where 0.05 m is one period)."""
        def freeze(p):
            p.send_signal(signal.SIGSTOP)
            time.sleep(0.3)  # the fault itself, not a wait for an event
            p.send_signal(signal.SIGCONT)
        r = self.reload_while_moving("scale_accel_m_s2 = 3\n", freeze)
        s, i = max_step(r)
        self.assertLessEqual(s, STEP_MAX, "step %.4f m at row %d" % (s, i))


def write_wp(s, seq, t, pos, tid):
    regs = struct.pack(">Idddd", seq, t, *pos)
    n = len(regs) // 2
    pdu = struct.pack(">BHHB", 16, obj_base(0) + M["MBMAP_H_WP"], n, len(regs)) + regs
    rsp = mbsim.transact(s, pdu, tid)
    return None if rsp[0] == 16 else rsp[1]


def command(s, cmd, tid):
    pdu = struct.pack(">BHH", 6, obj_base(0) + M["MBMAP_H_COMMAND"], cmd)
    rsp = mbsim.transact(s, pdu, tid)
    return None if rsp[0] == 6 else rsp[1]


def start_modbus_trajd(tmp, obj_extra=""):
    csv = os.path.join(tmp, "fed.csv")
    conf = os.path.join(tmp, "trajd.conf")
    with open(conf, "w") as f:
        f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                "[modbus]\naddress = 127.0.0.1\nport = 0\nwrites = yes\nsystemd_socket = no\n"
                "[object.fed]\ninput = modbus\noutput = csv\ncsv.path = %s\nmax_speed_m_s = %g\n%s"
                % (csv, MAX_SPEED, obj_extra))
    p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)
    return p, lines, port, csv


class Commands(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.p = None

    def tearDown(self):
        if self.p:
            self.p.send_signal(signal.SIGTERM)
            self.p.wait(WAIT_S)
            self.p.stderr.close()
        self.tmpd.cleanup()

    def wait_moving(self, rows, n=0):
        r = rows.wait(n + 2)
        end = time.monotonic() + WAIT_S
        while not (step(r[-2], r[-1]) > 0.005 and not r[-1][6] & 0x20):
            self.assertLess(time.monotonic(), end, "never moving")
            r = rows.wait(len(r) + 1)
        return r

    def test_stop_latches_until_start(self):
        self.p, lines, port, csv = start_modbus_trajd(self.tmpd.name)
        s = mbsim.connect(port)
        tid = 0
        # Given a client streaming a track, 6 s of it at once,
        seq = 0
        for i in range(60):
            seq += 1
            tid += 1
            self.assertIsNone(write_wp(s, seq, 0.1 * i, circle(0.1 * i), tid))
        rows = FileRows(csv)
        r = self.wait_moving(rows)
        # when it sends STOP and goes on sending the track for 6 s,
        tid += 1
        self.assertIsNone(command(s, M["MBMAP_CMD_STOP"], tid))
        n_stop = len(rows.wait(1))
        for i in range(60, 120):
            seq += 1
            tid += 1
            self.assertIsNone(write_wp(s, seq, 0.1 * i, circle(0.1 * i), tid))
            time.sleep(0.1)  # a sender in real time: the fault is its going on
        i = 120
        r = rows.wait(n_stop + 600)
        # then the object came to rest and stays there: the last 300 rows (3 s)
        # do not move, though waypoints kept coming
        tail = r[-300:]
        self.assertLessEqual(max_step(tail)[0], 1e-9, "moved while stopped")
        self.assertLessEqual(max_step(r[n_stop - 2:])[0], STEP_MAX)
        # and START joins the live track by a transfer (flag 0x08), no step
        n_start = len(r)
        tid += 1
        self.assertIsNone(command(s, M["MBMAP_CMD_START"], tid))
        for _ in range(40):
            seq += 1
            tid += 1
            self.assertIsNone(write_wp(s, seq, 0.1 * i, circle(0.1 * i), tid))
            i += 1
        r = self.wait_moving(rows, n_start)
        self.assertTrue(any(row[6] & 0x08 for row in r[n_start:]), "no transfer")
        self.assertLessEqual(max_step(r[n_stop - 2:])[0], STEP_MAX)
        # every command logged with the object and the client
        me = "modbus %s:%d" % s.getsockname()[:2]
        line = lines.wait_for("object 'fed': command start", WAIT_S)
        self.assertIsNotNone(line, "".join(lines.all))
        self.assertIn(" from %s in state stopped" % me, line)
        self.assertTrue(any("object 'fed': command stop from %s" % me in l for l in lines.all))
        s.close()

    def test_waypoints_refused_while_stopping_told(self):
        # Given a client streaming, when trajd gets SIGTERM (the object braking
        # to rest, slowly: scale_accel_m_s2 0.2) and the client writes on, then
        # each waypoint is refused (exception 03, config/PROTOCOL.md), the first
        # one said with the object and the client, and the count is on the exit
        # line (the transport counted them as refused and nothing said why)
        self.p, lines, port, csv = start_modbus_trajd(
            self.tmpd.name, "scale_accel_m_s2 = 0.2\n")
        s = mbsim.connect(port)
        tid, seq = 0, 0
        for i in range(60):
            seq, tid = seq + 1, tid + 1
            self.assertIsNone(write_wp(s, seq, 0.1 * i, circle(0.1 * i), tid))
        self.wait_moving(FileRows(csv))
        self.p.send_signal(signal.SIGTERM)
        self.assertIsNotNone(lines.wait_for("bringing objects to rest", WAIT_S))
        for i in range(60, 63):
            seq, tid = seq + 1, tid + 1
            self.assertEqual(write_wp(s, seq, 0.1 * i, circle(0.1 * i), tid), 3)
        me = "modbus %s:%d" % s.getsockname()[:2]
        line = lines.wait_for("object 'fed': waypoint from %s refused: trajd is stopping" % me,
                              WAIT_S)
        self.assertIsNotNone(line, "".join(lines.all))
        s.close()
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(WAIT_S)
        exit_line = lines.wait_for("exit: ", WAIT_S)
        self.assertRegex(exit_line, r"fed [^;]*, 3 waypoints refused while stopping")
        self.p.stderr.close()
        self.p = None

    def test_clear_after_safety_hold_resumes(self):
        self.p, lines, port, csv = start_modbus_trajd(
            self.tmpd.name, "position_min_m = -100, -100, -100\nposition_max_m = 3, 100, 100\n"
            "transfer_speed_m_s = 1\ntransfer_accel_m_s2 = 1\n")
        s = mbsim.connect(port)
        tid = 0
        # Given a track at 2 m/s that leaves the monitor's position box at x = 3 m
        # (a speed bound would not do: a configured one the engine keeps, slowing
        # along the path: tests/oracle/test_safety_speed_cap.py),
        seq = 0
        for i in range(40):
            seq += 1
            tid += 1
            self.assertIsNone(write_wp(s, seq, 0.1 * i, (0.2 * i, 0.0, 0.0), tid))
        rows = FileRows(csv)
        # when the monitor holds the object (flag 0x20),
        r = rows.wait(1)
        end = time.monotonic() + WAIT_S
        while not r[-1][6] & 0x20:
            self.assertLess(time.monotonic(), end, "never held")
            r = rows.wait(len(r) + 1)
        held = r[-1]
        self.assertIsNotNone(lines.wait_for("safety monitor", WAIT_S))
        # and the client clears it and sends a track at 1 m/s from there, back in the box,
        tid += 1
        self.assertIsNone(command(s, M["MBMAP_CMD_CLEAR"], tid))
        n_clear = len(rows.wait(1))
        for i in range(60):
            seq += 1
            tid += 1
            self.assertIsNone(write_wp(s, seq, 20.0 + 0.1 * i,
                                       (held[2] - 1.0 - 0.1 * i, 0.0, 0.0), tid))
        # then it resumes from the held position (rows without the fault flag
        # that move), joined by a transfer, and is never refused again
        r = rows.wait(n_clear + 1)
        end = time.monotonic() + WAIT_S
        while not (r[-1][2] < held[2] - 2.0):
            self.assertLess(time.monotonic(), end, "never resumed: %r" % (r[-1],))
            r = rows.wait(len(r) + 1)
        after = r[n_clear + 2:]
        self.assertFalse(any(row[6] & 0x20 for row in after), "refused again")
        self.assertTrue(any(row[6] & 0x08 for row in after), "no transfer")
        self.assertLessEqual(max_step(r[n_clear - 1:])[0], 1.5 * PERIOD_S * 1.0001 + 1e-9)
        self.assertLessEqual(abs(r[n_clear][2] - held[2]), 1e-6)  # from where it was held
        s.close()


if __name__ == "__main__":
    unittest.main(verbosity=2)
