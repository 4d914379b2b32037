"""test_modbus_accept_storm.py - trajd's Modbus listener when accept() runs out of
file descriptors (issue 28 item 3).

trajd runs with a soft and hard fd limit of 64 (setrlimit in the child before
exec), [modbus] max_clients = 200, and 120 clients connect at once and stay.
The connections beyond what the fds allow must not make the loop spin on the
listener that stays readable (EMFILE leaves the connection in the backlog):
  - trajd's CPU time (utime + stime of /proc/PID/stat, the kernel's own
    accounting) over the storm stays below a fifth of the wall time (the loop
    that polled the listener again at once used most of a core);
  - the clock keeps running: missed ticks at most 1 % of the deadlines (at
    10 Hz, so that a deadline is missed only by a stall of trajd, not by the
    scheduling noise of a busy machine, tens of ms; the CPU share is what
    tells the spinning loop);
  - each connection refused for want of an fd is closed by trajd (the client
    sees the end of its connection, read by the client here) and counted in
    mb_refused, read over Modbus afterwards (the register of lib/proto/mbmap.h);
  - a warning names the cause (strerror(EMFILE)) and the count.
The control socket's listener (daemon/ctl/ctl.c) the same, in test_control_in_the_storm:
a trajctl client that connects while the Modbus clients hold every fd is told why
(an error reply) and closed, trajd does not spin on that listener either (it did:
the connection stayed in the backlog, epoll_wait and accept4 EMFILE in turn, a whole
core, whenever any control client came during such a storm), the refusal is logged
with its cause and counted (busy_refused), and a client served once fds are back.
"""
import json
import os
import re
import resource
import select
import signal
import socket
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRACK = os.path.join(mbsim.ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
FD_LIMIT = 64
CLIENTS = 120
STORM_S = 3.0          # the clients hold their connections this long
CPU_MAX = 0.20         # of the wall time over the storm
MISSED_MAX = 0.01      # of the deadlines


def cpu_s(pid):
    """utime + stime of pid in seconds (proc(5): fields 14 and 15)."""
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def stop(p, lines, socks):
    """Close the clients left, stop trajd (SIGTERM): its exit code and its log."""
    for s in socks:
        s.close()
    p.send_signal(signal.SIGTERM)
    rc = p.wait(timeout=mbsim.WAIT_S + 10)
    lines.wait_for("\0", 1)
    p.stderr.close()
    return rc, "".join(lines.all)


def limit_fds():
    resource.setrlimit(resource.RLIMIT_NOFILE, (FD_LIMIT, FD_LIMIT))


class AcceptStormTest(unittest.TestCase):
    def test_emfile_storm(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 10\nstatus_interval_s = 0\nstop_timeout_s = 0\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nmax_clients = 200\n"
                        "systemd_socket = no\n"
                        "[object.boat]\ninput = replay\nreplay.track = %s\n"
                        "output = csv\ncsv.path = %s/boat.csv\n" % (TRACK, tmp))
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], preexec_fn=limit_fds)
            socks = []
            try:
                # Given trajd at its fd limit's edge, when 120 clients connect
                # at once and hold on for STORM_S ...
                cpu0, t0 = cpu_s(p.pid), time.monotonic()
                for _ in range(CLIENTS):
                    socks.append(socket.create_connection(("127.0.0.1", port), timeout=5))
                time.sleep(STORM_S)
                cpu1, t1 = cpu_s(p.pid), time.monotonic()
                share = (cpu1 - cpu0) / (t1 - t0)
                # ... then trajd did not spin on the listener,
                self.assertLess(share, CPU_MAX, "trajd used %.0f %% of a CPU" % (100 * share))
                # the refused clients saw their connection closed,
                r, _, _ = select.select(socks, [], [], 0)
                closed = [s for s in r if mbsim.closed_within(s, 0)]
                self.assertGreater(len(closed), CLIENTS - FD_LIMIT)
                self.assertLess(len(closed), CLIENTS)
                for s in socks:
                    s.close()
                socks = []
                # and mb_refused counts exactly them (read once trajd has fds again).
                refused = None
                for _ in range(50):
                    try:
                        c = mbsim.connect(port)
                        regs = mbsim.read_input(c, M["MBMAP_D_MB_REFUSED"], 2)
                        c.close()
                        refused = mbsim.u32(regs, 0)
                        break
                    except (OSError, ConnectionError):
                        time.sleep(0.1)
                self.assertEqual(refused, len(closed))
            finally:
                rc, log = stop(p, lines, socks)
            if os.environ.get("VERBOSE"):
                print("cpu %.1f %%, closed %d, refused %s\n%s" % (100 * share, len(closed), refused, log))
            self.assertEqual(rc, 0, log)
            # The warning with the cause and the count.
            self.assertRegex(log, r"modbus: accept: %s: \d+ connections refused"
                             % re.escape(os.strerror(24)))
            m = re.search(r"ticks (\d+), missed (\d+)", log)
            self.assertIsNotNone(m, log)
            ticks, missed = int(m.group(1)), int(m.group(2))
            self.assertLessEqual(missed, MISSED_MAX * (ticks + missed), m.group(0))


class ControlStormTest(unittest.TestCase):
    def test_control_in_the_storm(self):
        with tempfile.TemporaryDirectory() as tmp:
            ctl = os.path.join(tmp, "control")
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 10\nstatus_interval_s = 0\nstop_timeout_s = 0\n"
                        "control_socket = %s\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nmax_clients = 200\n"
                        "systemd_socket = no\n"
                        "[object.boat]\ninput = replay\nreplay.track = %s\n"
                        "output = csv\ncsv.path = %s/boat.csv\n" % (ctl, TRACK, tmp))
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], preexec_fn=limit_fds)
            socks = []
            try:
                # Given every fd of trajd's taken by Modbus clients (the ones beyond
                # refused and gone) ...
                for _ in range(CLIENTS):
                    socks.append(socket.create_connection(("127.0.0.1", port), timeout=5))
                lines.wait_for("connections refused", 5)
                time.sleep(0.5)
                # ... when a control client connects and waits,
                cpu0, t0 = cpu_s(p.pid), time.monotonic()
                c = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                c.settimeout(5)
                c.connect(ctl)
                time.sleep(STORM_S)
                cpu1, t1 = cpu_s(p.pid), time.monotonic()
                share = (cpu1 - cpu0) / (t1 - t0)
                # then trajd did not spin on the control listener,
                self.assertLess(share, CPU_MAX, "trajd used %.0f %% of a CPU" % (100 * share))
                # the client was told why and its connection closed,
                got = b""
                while True:
                    b = c.recv(4096)
                    if not b:
                        break
                    got += b
                c.close()
                reply = json.loads(got.decode().splitlines()[0])
                self.assertEqual(reply["reply"], "error")
                self.assertIn(os.strerror(24), reply["message"])
                # and, the fds back, a control client is served and sees the count.
                for s in socks:
                    s.close()
                socks = []
                status = None
                for _ in range(50):
                    try:
                        c = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                        c.settimeout(5)
                        c.connect(ctl)
                        f = c.makefile("rw")
                        hello = json.loads(f.readline())
                        if hello.get("reply") != "hello":
                            c.close()
                            time.sleep(0.1)
                            continue
                        f.write("status\n")
                        f.flush()
                        status = json.loads(f.readline())
                        c.close()
                        break
                    except OSError:
                        time.sleep(0.1)
                self.assertIsNotNone(status)
            finally:
                rc, log = stop(p, lines, socks)
            self.assertEqual(rc, 0, log)
            self.assertRegex(log, r"control: accept: %s: \d+ connections refused \(told why and closed\)" % re.escape(os.strerror(24)))
            self.assertGreaterEqual(status["busy_refused"], 1, status)


if __name__ == "__main__":
    unittest.main()
