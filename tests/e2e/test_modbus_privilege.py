"""test_modbus_privilege.py - who may change what (issue 11, privilege and scope).

The real trajd with Modbus on 127.0.0.1, written to with raw Modbus/TCP frames:
1. writes = yes no longer lets a client STOP or CLEAR an object fed by
   replay: that object answers exception 02 and keeps streaming; an object
   with writable = yes takes the command.
2. write_allow without 127.0.0.1: reads are answered, writes get
   exception 01 (as with writes off).
3. Started as root (outside systemd): without [daemon] user a warning-level
   line says so; with user = nobody, trajd runs as nobody once its sockets
   are open (read from /proc).  Skipped when not root.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import pwd
import signal
import struct
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 20


class Trajd:
    def __init__(self, tmp, text, env=None):
        self.conf = os.path.join(tmp, "trajd.conf")
        with open(self.conf, "w") as f:
            f.write(text)
        self.p, self.lines, self.port = mbsim.start_trajd([TRAJD, "-f", "-c", self.conf], WAIT_S, env=env)

    def stop(self):
        self.p.send_signal(signal.SIGTERM)
        return self.p.wait(WAIT_S)


def write_command(s, k, cmd, tid=1):
    """FC 06 to object k's command register: None if accepted, else the exception code."""
    pdu = mbsim.transact(s, struct.pack(">BHH", 6, obj_base(k) + M["MBMAP_H_COMMAND"], cmd), tid)
    return None if pdu[0] == 6 else pdu[1]


def state(s, k):
    return mbsim.read_input(s, obj_base(k) + M["MBMAP_O_STATE"], 1)[0]


def wait_streaming(s, k):
    deadline = time.monotonic() + WAIT_S
    while state(s, k) != 1:
        if time.monotonic() > deadline:
            raise AssertionError("object %d never streamed" % k)


CONF = """[daemon]
rate_hz = 100
speed = 1
status_interval_s = 0
stop_timeout_s = 1
[modbus]
address = 127.0.0.1
port = 0
writes = yes
systemd_socket = no
%s
[object.replayed]
id = 0
input = replay
replay.track = track.csv
output = stdout
stdout.header = no
[object.operated]
id = 1
input = replay
replay.track = track.csv
output = stdout
writable = yes
"""


class Scope(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        mbsim.line_track(os.path.join(self.tmp, "track.csv"))

    def tearDown(self):
        self.tmpd.cleanup()

    def test_commands_need_writable(self):
        # Given two replayed objects, writes = yes, only the second writable,
        d = Trajd(self.tmp, CONF % "")
        try:
            s = mbsim.connect(d.port)
            wait_streaming(s, 0)
            wait_streaming(s, 1)
            # when a client writes CLEAR and STOP to the first, then exception
            # 02 (not writable for this object) and it keeps streaming;
            self.assertEqual(write_command(s, 0, M["MBMAP_CMD_CLEAR"]), 2)
            self.assertEqual(write_command(s, 0, M["MBMAP_CMD_STOP"], tid=2), 2)
            self.assertEqual(state(s, 0), 1)
            # the writable one takes CLEAR and waits.
            self.assertIsNone(write_command(s, 1, M["MBMAP_CMD_CLEAR"], tid=3))
            deadline = time.monotonic() + WAIT_S
            while state(s, 1) != 0 and time.monotonic() < deadline:
                pass
            self.assertEqual(state(s, 1), 0)
            self.assertEqual(state(s, 0), 1)
            s.close()
        finally:
            d.stop()

    def test_write_allow_list(self):
        # Given write_allow = 10.0.0.0/8 (not loopback), when a loopback client
        # reads and then writes CLEAR to the writable object, then the read is
        # answered and the write gets exception 01, the object streams on.
        d = Trajd(self.tmp, CONF % "write_allow = 10.0.0.0/8")
        try:
            s = mbsim.connect(d.port)
            self.assertEqual(mbsim.read_input(s, 0, 1)[0], M["MBMAP_MAGIC"])
            wait_streaming(s, 1)
            self.assertEqual(write_command(s, 1, M["MBMAP_CMD_CLEAR"]), 1)
            self.assertEqual(state(s, 1), 1)
            s.close()
        finally:
            d.stop()


@unittest.skipUnless(os.geteuid() == 0, "needs root (starts trajd as root)")
class Root(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        mbsim.line_track(os.path.join(self.tmp, "track.csv"))
        # outside systemd: no INVOCATION_ID, no NOTIFY_SOCKET
        self.env = {k: v for k, v in os.environ.items()
                    if k not in ("INVOCATION_ID", "NOTIFY_SOCKET")}

    def tearDown(self):
        self.tmpd.cleanup()

    def uid_of(self, pid):
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith("Uid:"):
                    return [int(x) for x in line.split()[1:]]
        return None

    def test_warns_when_staying_root(self):
        d = Trajd(self.tmp, CONF % "", env=self.env)
        try:
            line = d.lines.wait_for("RUNNING AS ROOT", WAIT_S)
            self.assertIsNotNone(line, "".join(d.lines.all))
            self.assertTrue(line.startswith("<4>"), line)
        finally:
            d.stop()

    def test_drops_to_user(self):
        nobody = pwd.getpwnam("nobody")
        d = Trajd(self.tmp, CONF.replace("[daemon]\n", "[daemon]\nuser = nobody\n") % "",
                  env=self.env)
        try:
            line = d.lines.wait_for("dropped privileges", WAIT_S)
            self.assertIsNotNone(line, "".join(d.lines.all))
            # real, effective, saved and filesystem uid: all nobody's
            self.assertEqual(self.uid_of(d.p.pid), [nobody.pw_uid] * 4)
            # and it still serves: the listening socket was opened before
            s = mbsim.connect(d.port)
            self.assertEqual(mbsim.read_input(s, 0, 1)[0], M["MBMAP_MAGIC"])
            s.close()
        finally:
            self.assertEqual(d.stop(), 0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
