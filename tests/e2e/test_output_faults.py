"""test_output_faults.py - output failures are errors (issue 11, cases 2 and 3).

The real trajd, with faults made by the kernel, observed from outside:
1. csv.path = /dev/full (every write fails with ENOSPC): a warning-level log
   line names the error, the object's out_fault and out_lost registers and
   the daemon's out_fault register say so over Modbus, and trajd exits with
   74 (EX_IOERR) instead of 0.
2. csv.path on a 64 KiB tmpfs (mounted here if we may; skipped otherwise):
   the disk fills, every line in the file is whole (no torn "o,9"), and the
   exit status is 74.
3. stdout is a pipe whose reader goes away (`trajd | head -1`): trajd ends
   by itself, promptly, with status 141, not after being killed.
4. A restart or a reload (SIGHUP) appends to the CSV file after a marker line instead of
   truncating it; csv.truncate = yes empties it first.
5. The same /dev/full with the object's CAN output written as a candump
   log: python-can reads it, canmatrix decodes it with config/trajd.dbc:
   STATUS says output fault (bit 6, last error 0x45 "output lost lines") and
   STATUS2 page 1 counts the lines lost and the failed writes, never more
   than the exit line gives; exit 74.
6. An EIO from the kernel: csv.path (or stdout) is the slave side of a
   pseudo-terminal whose master is then closed, so every write fails with
   EIO (checked first with a write of our own to the same slave).  trajd
   says so at warning level while it runs on (naming the output and the
   error), sets out_fault over Modbus, and exits 74; trajreplay, which
   writes to a pty stdout or -o, stops with status 3 ("writing an output
   failed", daemon/doc/trajreplay.1) and a message naming the output.
7. The CAN output's candump log ([can] log_out) is an output too: on
   /dev/full a <4> line names it and the error and trajd exits 74 (it
   exited 0 without a word); log_out = - piped to `head -1` ends trajd with
   141 long before its track's end (it ran the whole track, exit 0); on a
   64 KiB tmpfs the file ends with a whole line and python-can reads all of
   it (the line a short write cut was left torn at the end).
8. The CAN output's candump log ([can] log_out) is appended to at a restart
   and at a reload, with no marker line (python-can's CanutilsLogReader
   reads the whole file; it raises on any other line) and stamps that never
   go back; log_out_truncate = yes empties it first, and so does
   log_time = engine at a start (its stamps start again from 0), not at a
   reload (engine time goes on).  Appending where the stamps do go back
   (speed 20 puts wall stamps ahead of the clock) is a warning naming both
   stamps.
Every wait is bounded; the daemon is stopped by pid.
"""
import errno
import os
import socket
import json
import re
import select
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402
import cantools_trajd as ct  # noqa: E402
import can  # noqa: E402
import canmatrix  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(mbsim.BUILD, "bin", "trajreplay")
DEMO = os.path.join(mbsim.ROOT, "config", "demo.conf")
WAIT_S = 30            # bound on a whole run (a loaded 2-core machine)
EX_IOERR = 74
EXIT_EPIPE = 141
EXIT_TRAJREPLAY_WRITE = 3   # daemon/doc/trajreplay.1, EXIT STATUS
EIO_TEXT = os.strerror(errno.EIO)   # "Input/output error", from Python's libc
# the error line's part for lines lost after the exit line, as the outputs drained
DRAINED = r"(?: \((\d+) after the exit line: queued as the outputs drained\))?"
FIELDS = 16            # columns of a setpoint line (daemon/csv/csv_format.c)


def track(path, n=400):
    mbsim.line_track(path, n)


def conf(tmp, csv_path, extra_daemon="", extra_obj="", modbus=False, output="csv", tail=""):
    """trajd.conf in tmp: object 'o' replays track.csv to output (csv_path
    for csv; None: no csv.path line); tail: sections appended."""
    text = ("[daemon]\nrate_hz = 100\nspeed = 20\nstatus_interval_s = 1\nstop_timeout_s = 2\n"
            + extra_daemon +
            "[object.o]\ninput = replay\nreplay.track = track.csv\noutput = %s\n" % output
            + ("csv.path = %s\n" % csv_path if csv_path is not None else "") + extra_obj)
    if modbus:
        text += "[modbus]\naddress = 127.0.0.1\nport = 0\n"
    text += tail
    path = os.path.join(tmp, "trajd.conf")
    with open(path, "w") as f:
        f.write(text)
    return path


def run(path, timeout=WAIT_S):
    p = subprocess.run([TRAJD, "-f", "-c", path], stdin=subprocess.DEVNULL,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                       timeout=timeout)
    return p.returncode, p.stderr


def small_tmpfs(test):
    """A 64 KiB tmpfs mounted on a new directory for the test (unmounted and
    removed at its cleanups, which run after tearDown); skips the test where
    no tmpfs can be mounted."""
    mnt = tempfile.mkdtemp(prefix="trajd-small-")
    test.addCleanup(os.rmdir, mnt)
    m = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", mnt],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if m.returncode != 0:
        test.skipTest("cannot mount a tmpfs here (%s)" % m.stderr.strip())
    test.addCleanup(subprocess.run, ["umount", mnt], check=False)
    return mnt


def started(test, path):
    """trajd -f -c path, once it says 'started:': (process, Lines of its stderr)."""
    p = subprocess.Popen([TRAJD, "-f", "-c", path], stdin=subprocess.DEVNULL,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    lines = mbsim.Lines(p.stderr)
    if lines.wait_for("started:", WAIT_S) is None:
        p.kill()
        p.wait()
        test.fail("trajd did not start: " + "".join(lines.all))
    return p, lines


def piped_to_head(test, path):
    """`trajd -f -c path | head -1`: trajd must end by itself once head has
    left, with status 141 and a line saying why; returns head's line."""
    p = subprocess.Popen([TRAJD, "-f", "-c", path], stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        head = subprocess.run(["head", "-1"], stdin=p.stdout, stdout=subprocess.PIPE,
                              timeout=WAIT_S)
        p.stdout.close()
        rc = p.wait(WAIT_S)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    err = p.stderr.read().decode()
    p.stderr.close()
    test.assertEqual(rc, EXIT_EPIPE, err)
    test.assertIn("reader went away", err)
    return head.stdout


def check_out_lost_on_modbus(test, port):
    """Object 0's Modbus block, read until it counts lost output lines (bounded),
    shows the output fault and the lines lost, and the daemon's block the fault;
    returns the daemon's block."""
    s = mbsim.connect(port)
    deadline = time.monotonic() + WAIT_S
    while True:
        r = mbsim.read_input(s, obj_base(0), mbsim.BLOCK)
        if mbsim.u32(r, M["MBMAP_O_OUT_LOST"]) > 0 or time.monotonic() > deadline:
            break
    d = mbsim.read_input(s, 0, mbsim.BLOCK)
    s.close()
    test.assertEqual(r[M["MBMAP_O_OUT_FAULT"]], 1)
    test.assertGreater(mbsim.u32(r, M["MBMAP_O_OUT_LOST"]), 0)
    test.assertEqual(d[M["MBMAP_D_OUT_FAULT"]], 1)
    return d


class HungUpPty:
    """A pseudo-terminal whose slave is handed to a process; hang_up()
    closes the master so the kernel fails every write to the slave with EIO
    (and checks that it does, with a write of its own)."""

    def __init__(self):
        self.master, self.slave = os.openpty()
        self.name = os.ttyname(self.slave)
        self.probe = os.open(self.name, os.O_WRONLY | os.O_NOCTTY)

    def read_until(self, text, timeout=WAIT_S):
        """Read the master until text came (True) or timeout s passed."""
        got, end = b"", time.monotonic() + timeout
        while text not in got and time.monotonic() < end:
            if select.select([self.master], [], [], 0.2)[0]:
                got += os.read(self.master, 4096)
        return text in got

    def hang_up(self, test):
        os.close(self.slave)
        os.close(self.master)
        with test.assertRaises(OSError) as e:
            os.write(self.probe, b"x")
        test.assertEqual(e.exception.errno, errno.EIO)

    def close(self):
        for fd in (self.probe, self.slave, self.master):
            try:
                os.close(fd)
            except OSError:
                pass


class OutputEIO(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.pty = HungUpPty()

    def tearDown(self):
        self.pty.close()
        self.tmpd.cleanup()

    def test_csv_path_eio_is_loud(self):
        # Given csv.path = a pty slave and Modbus on, when the pty hangs up
        # mid-stream (writes fail with EIO), then while trajd runs on a <4>
        # line names the output and the error, the object's and the
        # daemon's out_fault = 1 and out_lost grows, and after SIGTERM the
        # exit status is 74 with an error line saying why.
        track(os.path.join(self.tmp, "track.csv"), n=3000)
        path = conf(self.tmp, self.pty.name, modbus=True)
        p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", path], WAIT_S)
        try:
            self.assertTrue(self.pty.read_until(b"\no,"), "no setpoint row on the pty")
            self.pty.hang_up(self)
            warn = lines.wait_for(EIO_TEXT, WAIT_S)
            self.assertIsNotNone(warn, "".join(lines.all))
            self.assertTrue(warn.startswith("<4>"), warn)
            self.assertIn("object 'o' csv.path %s" % self.pty.name, warn)
            self.assertIsNone(p.poll())                  # runs on, loudly
            check_out_lost_on_modbus(self, port)
        finally:
            p.send_signal(signal.SIGTERM)
            rc = p.wait(WAIT_S)
        lines.wait_for("\0", WAIT_S)                     # the rest, to EOF
        err = "".join(lines.all)
        self.assertEqual(rc, EX_IOERR, err)
        self.assertRegex(err, r"<3>\d+ setpoint lines were lost by the outputs" + DRAINED
                         + ", last write error: " + EIO_TEXT)

    def test_stdout_eio_exits_74(self):
        # Given output = stdout on a pty slave and exit_when_done, when the
        # pty hangs up mid-stream, then trajd still ends at the track's end
        # with status 74 and a <4> "stdout: write failed: <EIO>" line.
        track(os.path.join(self.tmp, "track.csv"), n=1200)
        path = conf(self.tmp, None, extra_daemon="exit_when_done = yes\n", output="stdout")
        errf = tempfile.TemporaryFile(mode="w+")
        self.addCleanup(errf.close)
        p = subprocess.Popen([TRAJD, "-f", "-c", path], stdin=subprocess.DEVNULL,
                             stdout=self.pty.slave, stderr=errf)
        try:
            self.assertTrue(self.pty.read_until(b"\no,"), "no setpoint row on the pty")
            self.pty.hang_up(self)
            rc = p.wait(WAIT_S)
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
        errf.seek(0)
        err = errf.read()
        self.assertEqual(rc, EX_IOERR, err)
        self.assertIn("<4>stdout: write failed: %s" % EIO_TEXT, err)
        # rate-limited: one warning at once, then at most one per 10 s and
        # one at the end, however many writes failed (one per tick or more)
        warns = re.findall(r"<4>stdout: write failed: .*\((\d+) failed writes", err)
        self.assertLessEqual(len(warns), 3, err)
        self.assertGreaterEqual(int(warns[-1]), 100, err)

    def trajreplay_eio(self, args, stdout, name):
        track(os.path.join(self.tmp, "track.csv"), n=3000)
        p = subprocess.Popen([TRAJREPLAY, "-q"] + args + [os.path.join(self.tmp, "track.csv")],
                             stdin=subprocess.DEVNULL, stdout=stdout, stderr=subprocess.PIPE,
                             text=True)
        try:
            self.assertTrue(self.pty.read_until(b"\nreplay,"), "no setpoint row on the pty")
            self.pty.hang_up(self)
            err = p.communicate(timeout=WAIT_S)[1]
        finally:
            if p.poll() is None:
                p.kill()
                p.wait()
        self.assertEqual(p.returncode, EXIT_TRAJREPLAY_WRITE, err)
        self.assertIn("trajreplay: %s: write error: %s" % (name, EIO_TEXT), err)

    def test_trajreplay_stdout_eio(self):
        # Given trajreplay writing a 300 s track to a pty stdout, when the pty
        # hangs up, then it stops with status 3 and says "stdout: ... <EIO>".
        self.trajreplay_eio([], self.pty.slave, "stdout")

    def test_trajreplay_output_eio(self):
        # The same with -o naming the pty slave.
        self.trajreplay_eio(["-o", self.pty.name], subprocess.DEVNULL, self.pty.name)


class CanLogOutFaults(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name

    def tearDown(self):
        self.tmpd.cleanup()

    def conf(self, log_out, n):
        track(os.path.join(self.tmp, "track.csv"), n=n)
        path = os.path.join(self.tmp, "can.conf")
        with open(path, "w") as f:
            f.write("[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                    "status_interval_s = 0\n[can]\nlog_out = %s\nmax_load_percent = 0\n"
                    "[object.boat]\ninput = replay\nreplay.track = track.csv\noutput = can\n"
                    % log_out)
        return path

    def test_log_out_dev_full(self):
        # Given [can] log_out = /dev/full, when a 40 s track (2 s of wall
        # time) streams to its end, then a <4> line names log_out and
        # ENOSPC, and the exit status is 74 with the error line
        rc, err = run(self.conf("/dev/full", 400))
        self.assertEqual(rc, EX_IOERR, err)
        self.assertRegex(err, r"<4>can: log_out /dev/full: write failed: %s \(\d+ failed writes, "
                         r"\d+ frames lost so far\)" % os.strerror(errno.ENOSPC))
        self.assertRegex(err, r"<3>\d+ setpoint lines were lost by the outputs" + DRAINED
                         + r", last write error: " + os.strerror(errno.ENOSPC))

    def test_log_out_small_disk_no_torn_line(self):
        # Given log_out on a 64 KiB tmpfs, when a 40 s track streams to its
        # end, then the file ends with a whole line, python-can reads every
        # line of it (a torn "6A0#11D" at the end raised, or would be read
        # as a wrong frame), and the exit status is 74.
        mnt = small_tmpfs(self)
        out = os.path.join(mnt, "o.log")
        rc, err = run(self.conf(out, 400))
        self.assertEqual(rc, EX_IOERR, err)
        with open(out, "rb") as f:
            data = f.read()
        self.assertGreater(len(data), 32 * 1024)      # the disk did fill
        self.assertTrue(data.endswith(b"\n"), data[-80:])
        msgs = list(can.CanutilsLogReader(out))
        self.assertEqual(len(msgs), data.count(b"\n"))

    def test_log_out_stdout_pipe(self):
        # Given log_out = - and a 2000 s track (100 s of wall time), when
        # `head -1` has read its line and left, then trajd ends by itself
        # within WAIT_S with status 141 and says why
        first = piped_to_head(self, self.conf("-", 20000))
        self.assertRegex(first, rb"^\(\d+\.\d{6}\) can0 [0-9A-F]{3}#")


class OutputFaults(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        track(os.path.join(self.tmp, "track.csv"))

    def tearDown(self):
        self.tmpd.cleanup()

    def test_dev_full_is_loud(self):
        # Given csv.path = /dev/full and Modbus on, when trajd streams, then
        # the object's out_fault = 1 and out_lost grows, the daemon's out_fault
        # = 1, a <4> (warning) line says "No space left on device"; after
        # SIGTERM the exit status is 74.
        path = conf(self.tmp, "/dev/full", modbus=True)
        p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", path], WAIT_S)
        try:
            warn = lines.wait_for("No space left on device", WAIT_S)
            self.assertIsNotNone(warn, "".join(lines.all))
            self.assertTrue(warn.startswith("<4>"), warn)
            self.assertIn("csv.path /dev/full", warn)
            # Lines are kept for a retry until the buffer is full (256 KiB,
            # about half a second here), then lost: wait for that, bounded.
            d = check_out_lost_on_modbus(self, port)
            self.assertGreater(mbsim.u32(d, M["MBMAP_D_OUT_LOST"]), 0)
        finally:
            p.send_signal(signal.SIGTERM)
            rc = p.wait(WAIT_S)
        self.assertEqual(rc, EX_IOERR)

    def test_reload_lines_lost_are_the_objects(self):
        # Given csv.path = /dev/full (lines held for a retry, then lost) and a
        # reload while lines are held, then after the reload the object's
        # out_lost equals the daemon's (its CSV is the only output): the lines
        # its CSV still held when the reload closed it are the object's too.
        # Before, they went to the daemon's total only (object 0 where the
        # daemon had 87).
        track(os.path.join(self.tmp, "track.csv"), n=2000)
        sock = os.path.join(self.tmp, "ctl.sock")
        path = conf(self.tmp, "/dev/full", extra_daemon="control_socket = %s\n" % sock)
        p, lines = started(self, path)
        try:
            time.sleep(0.2)  # lines held for the retry (the buffer fills in about 0.5 s)
            p.send_signal(signal.SIGHUP)
            self.assertIsNotNone(lines.wait_for("reloaded:", WAIT_S), "".join(lines.all))
            s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            s.settimeout(WAIT_S)
            s.connect(sock)
            f = s.makefile("r")
            json.loads(f.readline())  # hello
            s.sendall(b"status o\n")
            head = json.loads(f.readline())
            objs = {}
            while True:
                m = json.loads(f.readline())
                if m.get("reply") == "end":
                    break
                objs[m["object"]] = m
            s.close()
            self.assertGreater(head["out_lost"], 0, head)
            self.assertEqual(objs["o"]["out_lost"], head["out_lost"], (head, objs))
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)
            lines.wait_for("\0", 1)

    def test_dev_full_on_can_status(self):
        # Given csv.path = /dev/full and the object's CAN output as a
        # candump log, when the track streams to its end, then STATUS
        # frames carry the output fault (bit 6) and error 0x45, STATUS2 page
        # 1 counts lost lines and failed writes (both > 0, at most the exit
        # line's count), and the exit status is 74.  A track long enough that
        # the lines held for /dev/full overflow the output's buffer
        # (CSV_TRANSPORT_BUF_BYTES) while it streams, not only at the exit
        track(os.path.join(self.tmp, "track.csv"), n=1200)
        path = conf(self.tmp, "/dev/full", extra_daemon="exit_when_done = yes\n", output="csv, can",
                    tail="[can]\nlog_out = %s\nlog_time = engine\nmax_late_ms = 0\n"
                    % os.path.join(self.tmp, "can.log"))
        rc, err = run(path)
        self.assertEqual(rc, EX_IOERR, err)
        m = re.search(r"(\d+) setpoint lines were lost by the outputs" + DRAINED, err)
        self.assertIsNotNone(m, err)
        lost_total = int(m.group(1))
        # the exit line's count (taken before the outputs drain) and the lines
        # lost as they drained add up to the total the error line gives (two
        # totals that did not agree, and no word of why)
        at_exit = re.search(r"<6>exit: .*FAULT, (\d+) lines lost by outputs", err)
        self.assertIsNotNone(at_exit, err)
        self.assertEqual(int(at_exit.group(1)) + int(m.group(2) or 0), lost_total, err[-2000:])
        db = ct.load_db()
        st = db.frame_by_id(canmatrix.ArbitrationId(0x6C0))
        st2 = db.frame_by_id(canmatrix.ArbitrationId(0x6D0))
        status, page1 = [], []
        reader = can.CanutilsLogReader(os.path.join(self.tmp, "can.log"))
        for msg in reader:
            if msg.arbitration_id == 0x6C0:
                status.append({k: int(v.phys_value) for k, v in st.decode(bytes(msg.data)).items()})
            elif msg.arbitration_id == 0x6D0:
                d = {k: int(v.phys_value) for k, v in st2.decode(bytes(msg.data)).items()}
                if d["ST2_Page"] == 1:
                    page1.append(d)
        reader.stop()
        faulted = [d for d in status if d["ST_OutFault"] == 1]
        self.assertGreater(len(faulted), 0, "no STATUS with the output fault bit")
        self.assertIn(0x45, [d["ST_LastErr"] for d in faulted])
        self.assertGreater(len(page1), 0, "no STATUS2 page 1")
        last = page1[-1]
        self.assertGreater(last["ST2_OutLost"], 0)
        self.assertLessEqual(last["ST2_OutLost"], lost_total)
        self.assertGreater(last["ST2_OutErrors"], 0)
        self.assertEqual([d["ST2_OutLost"] for d in page1], sorted(d["ST2_OutLost"] for d in page1))

    def test_small_disk_no_torn_line(self):
        # Given csv.path on a 64 KiB tmpfs, when the track (~40 000 lines)
        # streams to its end (exit_when_done), then every line in the file
        # is whole, the last one too, and the exit status is 74.
        mnt = small_tmpfs(self)
        out = os.path.join(mnt, "o.csv")
        rc, err = run(conf(self.tmp, out, extra_daemon="exit_when_done = yes\n"))
        self.assertEqual(rc, EX_IOERR, err)
        self.assertIn("No space left on device", err)
        with open(out, "rb") as f:
            data = f.read()
        self.assertGreater(len(data), 32 * 1024)      # the disk did fill
        self.assertTrue(data.endswith(b"\n"), data[-80:])
        rows = data.decode().splitlines()
        self.assertTrue(rows[0].startswith("object,"))
        for row in rows[1:]:
            self.assertEqual(len(row.split(",")), FIELDS, row)

    def test_broken_stdout_pipe_ends_trajd(self):
        # Given `trajd -f -c config/demo.conf | head -1`, when head has read
        # its line and exits, then trajd ends by itself within the bound,
        # with status 141, and says why.
        first = piped_to_head(self, DEMO)
        self.assertTrue(first.startswith(b"object,"), first)

    def test_restart_appends_with_marker(self):
        # Given a CSV file written by one run, when trajd runs again on the
        # same path, then the first run's rows are kept, a marker line
        # starting with '#' follows them, then the second run's rows (no
        # second header); with csv.truncate = yes only the new run is left.
        out = os.path.join(self.tmp, "o.csv")
        path = conf(self.tmp, out, extra_daemon="exit_when_done = yes\n")
        self.assertEqual(run(path)[0], 0)
        with open(out) as f:
            first = f.read().splitlines()
        self.assertEqual(run(path)[0], 0)
        with open(out) as f:
            both = f.read().splitlines()
        self.assertEqual(both[:len(first)], first)
        marker = both[len(first)]
        self.assertTrue(marker.startswith("# trajd: appended at "), marker)
        rest = both[len(first) + 1:]
        self.assertGreater(len(rest), len(first) // 2)   # a whole second run
        for row in rest:
            self.assertTrue(row.startswith("o,"), row)   # rows only, no second header
            self.assertEqual(len(row.split(",")), FIELDS, row)
        path = conf(self.tmp, out, extra_daemon="exit_when_done = yes\n",
                    extra_obj="csv.truncate = yes\n")
        self.assertEqual(run(path)[0], 0)
        with open(out) as f:
            again = f.read().splitlines()
        self.assertEqual(again[0], first[0])           # the header, at the top
        self.assertFalse(any(row.startswith("#") for row in again))
        self.assertLess(len(again), len(both) * 3 // 4)

    def test_reload_appends_with_marker(self):
        # Given trajd streaming to a CSV file, when SIGHUP reloads it (the
        # csv output is closed and reopened), then the rows written before
        # are kept, a marker line follows, and rows go on after it.
        out = os.path.join(self.tmp, "o.csv")
        path = conf(self.tmp, out)
        p, lines = started(self, path)
        try:
            deadline = time.monotonic() + WAIT_S
            while os.path.getsize(out) < 10000 and time.monotonic() < deadline:
                lines.wait_for("\0", 0.1)
            before = os.path.getsize(out)
            p.send_signal(signal.SIGHUP)
            self.assertIsNotNone(lines.wait_for("reloaded", WAIT_S), "".join(lines.all))
            while time.monotonic() < deadline:
                with open(out) as f:
                    rows = f.read().splitlines()
                marks = [i for i, r in enumerate(rows) if r.startswith("# trajd: appended at ")]
                if marks and len(rows) > marks[0] + 10:
                    break
                lines.wait_for("\0", 0.1)
            self.assertEqual(len(marks), 1, rows[:3])
            self.assertGreater(len("\n".join(rows[:marks[0]])), before - 4096)  # kept
            self.assertTrue(rows[0].startswith("object,"))
            self.assertTrue(all(r.startswith("o,") for r in rows[marks[0] + 1:-1]))
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)


class CanLogOutAppend(unittest.TestCase):
    """[can] log_out is appended to at start and at reload (issue 11), with
    no marker line: python-can's CanutilsLogReader (4.1) raises on any
    line that is not a frame, so the boundary shows only in the stamps."""

    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.out = os.path.join(self.tmp, "out.log")

    def tearDown(self):
        self.tmpd.cleanup()

    def conf(self, extra_can="", n=15, done=True, speed=1):
        # speed 1: wall stamps run with the wall clock (speed 20 puts them
        # ahead of it), so a later run's stamps are later
        track(os.path.join(self.tmp, "track.csv"), n=n)
        path = os.path.join(self.tmp, "can.conf")
        with open(path, "w") as f:
            f.write("[daemon]\nrate_hz = 100\nspeed = %g\nstatus_interval_s = 0\n" % speed
                    + ("exit_when_done = yes\n" if done else "") +
                    "[can]\nlog_out = %s\nmax_load_percent = 0\nmax_late_ms = 0\n%s"
                    "[object.boat]\ninput = replay\nreplay.track = track.csv\noutput = can\n"
                    % (self.out, extra_can))
        return path

    def lines(self):
        with open(self.out) as f:
            return f.read().splitlines()

    def stamps(self):
        """python-can reads the whole file (it raises on a non-frame line);
        the stamps, one per frame, in file order."""
        msgs = list(can.CanutilsLogReader(self.out))
        self.assertEqual(len(msgs), len(self.lines()))
        return [m.timestamp for m in msgs]

    def assert_non_decreasing(self, ts):
        back = [(i, a, b) for i, (a, b) in enumerate(zip(ts, ts[1:])) if b < a]
        self.assertEqual(back, [], "stamps go back in time")

    def run_twice(self, path, path2=None):
        rc, err = run(path)
        self.assertEqual(rc, 0, err)
        first = self.lines()
        self.assertGreater(len(first), 100, err)   # 1.4 s of SYNC-less setpoints at 100 Hz
        t_between = time.time()
        rc, err = run(path2 or path)
        self.assertEqual(rc, 0, err)
        return first, t_between, err

    def test_restart_appends(self):
        # Given a log_out written by one run (wall stamps, the default), when
        # trajd runs again, then the first run's lines are still there, the
        # second run's frames follow them (no marker line: python-can reads
        # the whole file), its stamps start after the restart's wall time,
        # and no stamp goes back; an info line says the file was appended to.
        first, t_between, err = self.run_twice(self.conf())
        both = self.lines()
        self.assertEqual(both[:len(first)], first)
        self.assertGreater(len(both), len(first) * 3 // 2)   # a whole second run
        ts = self.stamps()
        self.assert_non_decreasing(ts)
        self.assertLessEqual(ts[len(first) - 1], t_between)
        self.assertGreaterEqual(ts[len(first)], t_between)
        self.assertRegex(err, r"can: log_out %s: appending" % re.escape(self.out))
        self.assertNotIn("goes back in time", err)

    def test_stamps_back_warned(self):
        # Given a log_out written at speed 20 (wall stamps run 20 times
        # faster than the clock: a 40 s track in 2 s), when trajd runs again
        # at once, then its stamps start before the first run's last: a <4>
        # line says so with both stamps, as python-can reads them.
        first, _, err = self.run_twice(self.conf(n=400, speed=20))
        ts = self.stamps()
        self.assertGreater(len(ts), len(first))
        m = re.search(r"<4>can: log_out \S+: its last stamp \(([\d.]+)\) is later than this "
                      r"run's first \(([\d.]+)\): the log goes back in time here", err)
        self.assertIsNotNone(m, err)
        self.assertAlmostEqual(float(m.group(1)), ts[len(first) - 1], delta=1e-6)
        # this run's start, at its open: the first frame's stamp or before it (the
        # ticks between the open and the first frame; at speed 20 a stamp moves
        # 20 ms per ms of them, which a busy machine stretches: 0.16 s seen), within
        # 50 ms of wall time
        self.assertLessEqual(float(m.group(2)), ts[len(first)] + 1e-6)
        self.assertLess(ts[len(first)] - float(m.group(2)), 1.0)
        self.assertLess(ts[len(first)], ts[len(first) - 1])

    def test_torn_last_line_cut(self):
        # Given a log_out whose last line was cut short (a full disk), when
        # trajd appends to it, then the torn head is cut off (a warning says
        # so), the whole lines before it are kept, and python-can reads the
        # file: the next run's first frame is on a line of its own.
        whole = "(1000000000.000000) can0 123#1122\n"
        torn = "(1000000000.010000) can0 12"
        with open(self.out, "w") as f:
            f.write(whole + torn)
        rc, err = run(self.conf())
        self.assertEqual(rc, 0, err)
        rows = self.lines()
        self.assertEqual(rows[0] + "\n", whole)
        self.assertGreater(len(rows), 100)
        ts = self.stamps()
        self.assert_non_decreasing(ts)
        self.assertRegex(err, r"<4>can: log_out \S+: %d bytes of a torn last line cut off"
                         % len(torn))

    def test_truncate_yes(self):
        # Given a log_out written by one run, when trajd runs again with
        # log_out_truncate = yes, then only the second run's frames are left
        # (every stamp after the restart) and an info line says truncated.
        first, t_between, err = self.run_twice(self.conf(),
                                                self.conf("log_out_truncate = yes\n"))
        ts = self.stamps()
        self.assertGreater(len(ts), 100)
        self.assertGreaterEqual(min(ts), t_between)
        self.assertRegex(err, r"can: log_out %s: truncated" % re.escape(self.out))

    def test_engine_stamps_truncate_by_default(self):
        # Given log_time = engine (stamps from 0 at each start), when trajd
        # runs twice, then the file holds one run (stamps from 0, never going
        # back); with log_out_truncate = no it holds both, and the second
        # run's stamps start again from 0 (why auto truncates).
        path = self.conf("log_time = engine\n")
        first, _, err = self.run_twice(path)
        ts = self.stamps()
        self.assert_non_decreasing(ts)
        self.assertLess(ts[0], 1.0)
        self.assertLess(len(ts), len(first) * 3 // 2)   # one run, not two
        self.assertRegex(err, r"can: log_out %s: truncated" % re.escape(self.out))
        second = self.lines()
        rc, err = run(self.conf("log_time = engine\nlog_out_truncate = no\n"))
        self.assertEqual(rc, 0, err)
        both = self.lines()
        self.assertEqual(both[:len(second)], second)
        self.assertGreater(len(both), len(second) * 3 // 2)
        ts = self.stamps()
        self.assertLess(ts[len(second)], ts[len(second) - 1])
        self.assertIn("goes back in time", err)

    def reload_run(self, extra_can=""):
        """Run trajd on a 40 s track, SIGHUP once the log holds 100 lines;
        the bytes written before the reload, and stderr."""
        path = self.conf(extra_can, n=400, done=False)
        p, lines = started(self, path)
        try:
            deadline = time.monotonic() + WAIT_S
            while len(self.lines()) < 100 and time.monotonic() < deadline:
                lines.wait_for("\0", 0.1)
            p.send_signal(signal.SIGSTOP)   # nothing written while we read
            with open(self.out, "rb") as f:
                before = f.read()
            p.send_signal(signal.SIGCONT)
            p.send_signal(signal.SIGHUP)
            self.assertIsNotNone(lines.wait_for("reloaded", WAIT_S), "".join(lines.all))
            n = len(self.lines())
            while len(self.lines()) < n + 100 and time.monotonic() < deadline:
                lines.wait_for("\0", 0.1)
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)
        lines.wait_for("\0", WAIT_S)   # to EOF
        p.stderr.close()
        return before, "".join(lines.all)

    def test_reload_appends(self):
        # Given trajd writing log_out, when SIGHUP reloads it (the CAN
        # transport is closed and reopened), then what was written before is
        # kept, frames go on after it, python-can reads the whole file and no
        # stamp goes back.
        before, err = self.reload_run()
        with open(self.out, "rb") as f:
            after = f.read()
        self.assertGreater(len(before), 0)
        self.assertEqual(after[:len(before)], before)
        self.assertGreater(len(after.splitlines()), len(before.splitlines()) + 100)
        self.assert_non_decreasing(self.stamps())
        self.assertEqual(len(re.findall(r"can: log_out \S+: appending", err)), 2, err)

    def test_reload_engine_stamps_append(self):
        # Given log_time = engine, when SIGHUP reloads, then the log is kept
        # and appended to: engine time goes on across a reload
        # (daemon/REFERENCE.md), so the stamps do too.
        before, err = self.reload_run("log_time = engine\n")
        with open(self.out, "rb") as f:
            after = f.read()
        self.assertEqual(after[:len(before)], before)
        self.assertGreater(len(after.splitlines()), len(before.splitlines()) + 100)
        ts = self.stamps()
        self.assert_non_decreasing(ts)
        self.assertLess(ts[0], 1.0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
