"""test_modbus_gate.py - the feed override passes the one gate of commands (issue 24 item 1).

The real trajd with Modbus on 127.0.0.1 and writes = yes, written to by a real
client (pymodbus, FC 06 write_register):
1. the override register (object block offset 1) of an object that is not
   writable answers exception 02, as its command register does, and the
   object keeps streaming at 100 % (the old code acknowledged it: the
   object froze at override 0);
2. write_allow without 127.0.0.1: the override gets exception 01;
3. after SIGTERM (the objects braking to rest), the override of a writable
   object answers exception 03, as its commands do (the old code
   acknowledged it; config/PROTOCOL.md says 03);
4. an unknown command code or an override above 200 % answers exception 03
   and is logged and counted as a refused command of its object.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import signal
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 20


# The operated object brakes at 0.05 m/s^2 (scale_accel_m_s2): from 2 m/s a
# stop takes 40 s, inside stop_timeout_s, so the daemon is stopping, not gone,
# while the test writes.
CONF = """[daemon]
rate_hz = 100
speed = 1
status_interval_s = 0
stop_timeout_s = 60
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
scale_accel_m_s2 = 0.05
"""


class Gate(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        mbsim.line_track(os.path.join(self.tmp, "track.csv"))
        self.p = None

    def start(self, extra):
        conf = os.path.join(self.tmp, "trajd.conf")
        with open(conf, "w") as f:
            f.write(CONF % extra)
        self.p, self.lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        return c

    def tearDown(self):
        if self.p and self.p.poll() is None:
            self.p.send_signal(signal.SIGTERM)
            self.p.send_signal(signal.SIGTERM)   # a second one exits at once
            self.p.wait(WAIT_S)
        self.tmpd.cleanup()

    def reg(self, c, k, off):
        return mbsim.input_reg(c, obj_base(k) + off)

    def override(self, c, k, pct):
        """FC 06 to object k's override register: None if acknowledged, else the exception code."""
        rr = c.write_register(obj_base(k) + M["MBMAP_H_OVERRIDE"], pct, slave=1)
        return rr.exception_code if rr.isError() else None

    def wait_streaming(self, c, k):
        mbsim.wait_input(c, obj_base(k) + M["MBMAP_O_STATE"], 1, "object %d never streamed" % k,
                         WAIT_S)

    def test_override_needs_writable(self):
        # Given a replayed object that is not writable, streaming,
        c = self.start("")
        self.wait_streaming(c, 0)
        # when a client (writes = yes) writes override 0, then exception 02,
        self.assertEqual(self.override(c, 0, 0), 2)
        # as for its commands, and it streams on at 100 %;
        rr = c.write_register(obj_base(0) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_STOP"], slave=1)
        self.assertTrue(rr.isError())
        self.assertEqual(rr.exception_code, 2)
        self.assertEqual(self.reg(c, 0, M["MBMAP_O_OVERRIDE"]), 100)
        self.assertEqual(self.reg(c, 0, M["MBMAP_O_STATE"]), 1)
        # each refusal logged with the object, the command and the peer (the
        # exception alone said nothing per object);
        for what in ("override 0 %", "stop"):
            self.assertIsNotNone(self.lines.wait_for(
                "object 'replayed': command %s from modbus 127.0.0.1" % what, WAIT_S), what)
        # the writable object takes it,
        self.wait_streaming(c, 1)
        self.assertIsNone(self.override(c, 1, 50))
        mbsim.wait_input(c, obj_base(1) + M["MBMAP_O_OVERRIDE"], 50, "override 50 never shown",
                         WAIT_S)
        # and its reset counters too, logged as every command is (it was not)
        rr = c.write_register(obj_base(1) + M["MBMAP_H_COMMAND"],
                              M["MBMAP_CMD_RESET_COUNTERS"], slave=1)
        self.assertFalse(rr.isError(), rr)
        self.assertIsNotNone(self.lines.wait_for(
            "object 'operated': command reset counters from modbus 127.0.0.1", WAIT_S))
        c.close()
        # the refusals counted, in the exit line
        self.p.send_signal(signal.SIGTERM)
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(WAIT_S)
        exit_line = self.lines.wait_for("exit: ", WAIT_S)
        self.assertIsNotNone(exit_line)
        self.assertRegex(exit_line, r"replayed [^;]*, 2 commands refused")

    def test_refused_values_logged(self):
        # Given the writable object streaming, when a client writes an unknown
        # command code and an override above 200 %, then each gets exception 03,
        # is logged with the object, the value and the client, and counts in the
        # object's refused commands on the exit line (they were counted in
        # mb_rejected alone: the log said nothing per object, as CAN does)
        c = self.start("")
        self.wait_streaming(c, 1)
        rr = c.write_register(obj_base(1) + M["MBMAP_H_COMMAND"], 7, slave=1)
        self.assertEqual(rr.exception_code if rr.isError() else None, 3)
        self.assertEqual(self.override(c, 1, 201), 3)
        self.assertIsNotNone(self.lines.wait_for(
            "object 'operated': command 7 from modbus 127.0.0.1", WAIT_S))
        self.assertIsNotNone(self.lines.wait_for(
            "object 'operated': command override 201 % from modbus 127.0.0.1", WAIT_S))
        self.assertEqual(self.reg(c, 1, M["MBMAP_O_STATE"]), 1)   # streams on
        c.close()
        self.p.send_signal(signal.SIGTERM)
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(WAIT_S)
        exit_line = self.lines.wait_for("exit: ", WAIT_S)
        self.assertIsNotNone(exit_line)
        self.assertRegex(exit_line, r"operated [^;]*, 2 commands refused")

    def test_override_needs_write_allow(self):
        c = self.start("write_allow = 10.0.0.0/8")
        self.wait_streaming(c, 1)
        self.assertEqual(self.override(c, 1, 50), 1)
        self.assertEqual(self.reg(c, 1, M["MBMAP_O_OVERRIDE"]), 100)
        c.close()

    def test_override_refused_while_stopping(self):
        # Given the writable object streaming,
        c = self.start("")
        self.wait_streaming(c, 1)
        # when trajd gets SIGTERM and says it brings the objects to rest,
        self.p.send_signal(signal.SIGTERM)
        self.assertIsNotNone(self.lines.wait_for("bringing objects to rest", WAIT_S))
        # then (still braking) an override answers exception 03, as a command does.
        self.assertIsNone(self.p.poll())
        self.assertEqual(self.override(c, 1, 200), 3)
        rr = c.write_register(obj_base(1) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_CLEAR"], slave=1)
        self.assertEqual(rr.exception_code if rr.isError() else None, 3)
        self.assertIsNone(self.p.poll(), "trajd ended before the writes: the stop was too short")
        self.assertNotEqual(self.reg(c, 1, M["MBMAP_O_OVERRIDE"]), 200)
        c.close()


if __name__ == "__main__":
    unittest.main(verbosity=2)
