"""test_reload_ids.py - addresses never move (issue 16, item 3), in the running daemon.

Every object replays its own track, offset by 1000 m x its owner number, so a
position read anywhere names the object it belongs to.  Its Modbus block is
read with pymodbus, its CAN setpoint frames and CiA 402 RPDO (candump logs
written by trajd's [can] log_out) are decoded by python-can and canmatrix with
config/trajd.dbc.

1. Objects a, b, c with id = 0, 1, 2: block k and CAN id 0x6A0+k carry the
   object whose id is k.
2. SIGHUP with the sections reordered and an object d (id = 3) inserted at the
   top: accepted; blocks 0..2 and CAN ids 0x6A0..0x6A2 keep their objects,
   d appears at block 3 and 0x6A3 (before this work d would have taken
   block 0 from a).
3. SIGHUP with a and b swapping ids, then with a's CiA 402 COB-ID moved:
   each refused with trajd.conf:LINE of the offending key or section, logged,
   and the old configuration keeps running (same Modbus port, same owners,
   the CAN log not reopened).
4. A file with two objects and no ids is refused by --check-config.
"""
import math
import os
import signal
import struct
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
OWNER = {"a": 1, "b": 2, "c": 3, "d": 4}   # x offset, km
WAIT_S = 30
STREAMING = 1                                # MBMAP_O_STATE (engine_state_t) while streaming
NO_POS_M = -214748.3648                      # SETPOINT position 0x80000000: no position


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def track(path, offset_m):
    """A circle at 2 m/s, 10 Hz for 300 s, shifted by offset_m in x."""
    rows = ["t,x,y,z"]
    for i in range(3000):
        t = i * 0.1
        a = 2.0 * t / 50.0
        rows.append("%.3f,%.6f,%.6f,1.0" % (t, offset_m + 50 * math.cos(a), 50 * math.sin(a)))
    write(path, "\n".join(rows) + "\n")


def obj(name, oid, cob=0x201):
    extra = ""
    if name == "a":  # a drives a CiA 402 node: its COB-ID is explicit
        # no drive feedback: trajd takes the drive to stand where it starts (initial_position)
        extra = "can.cia402 = yes\ncan.cia402_cob_x = 0x%X\ncan.cia402_cob_y = 0\n" \
                "can.cia402_cob_z = 0\ncan.cia402_counts_per_m = 10\ncan.cia402_feedback = no\n" \
                "initial_position = %g,0,1\n" % (cob, 1000.0 * OWNER[name] + 50)
    return ("[object.%s]\nid = %d\ninput = replay\nreplay.track = %s.csv\noutput = can\n%s"
            % (name, oid, name, extra))


def config(canlog, objs):
    return ("[daemon]\nrate_hz = 50\nspeed = 4\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
            "[modbus]\nport = 0\nsystemd_socket = no\n"
            "[can]\nlog_out = %s\nmax_load_percent = 0\n" % canlog) + "".join(objs)


def line_of(text, needle):
    return text.split("\n").index(needle) + 1


class ReloadIds(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        for n, k in OWNER.items():
            track(os.path.join(self.tmp, n + ".csv"), 1000.0 * k)
        self.conf = os.path.join(self.tmp, "trajd.conf")

    def tearDown(self):
        self.tmpd.cleanup()

    def owners(self, port, nblocks):
        """{block k: owner name} from the x position of each block (pymodbus),
        waiting (bounded) until every block has a position."""
        inv = {v: n for n, v in OWNER.items()}
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
        self.assertTrue(c.connect())
        try:
            for _ in range(WAIT_S * 20):
                r = c.read_input_registers(0, count=3)
                self.assertFalse(r.isError(), r)
                self.assertEqual(r.registers[0], M["MBMAP_MAGIC"])
                self.assertEqual(r.registers[M["MBMAP_D_OBJECTS"]], nblocks)
                got = {}
                for k in range(nblocks):
                    r = c.read_input_registers(obj_base(k), count=M["MBMAP_O_POS"] + 2)
                    self.assertFalse(r.isError(), r)
                    x = struct.unpack(">f", struct.pack(">HH", *r.registers[-2:]))[0]
                    if r.registers[M["MBMAP_O_STATE"]] == STREAMING and math.isfinite(x):
                        got[k] = inv.get(round(x / 1000.0), "?%g" % x)
                if len(got) == nblocks:
                    return got
                self.lines.wait_for("\0", 0.05)  # a bounded pause that also collects the log
            self.fail("blocks without a position after %d s: %r" % (WAIT_S, got))
        finally:
            c.close()

    def can_owners(self, log):
        """{CAN id: set of owners} of every SETPOINT (0x6A0..0x6A3, x axis) and
        of the CiA 402 RPDO 0x201 in a candump log."""
        inv = {v: n for n, v in OWNER.items()}
        out = {}
        for k in range(4):
            rows, _ = ct.decode_setpoints(log, 0x6A0 + k)
            xs = [r["x"] for r in rows.values() if "x" in r and r["x"] > NO_POS_M + 1]
            if xs:
                out[0x6A0 + k] = {inv.get(round(x / 1000.0), "?") for x in xs}
        rp = [v["Target_Position_607A"] / 10.0 for _, v in ct.decode_by_id(log, 0x201)]
        if rp:
            out[0x201] = {inv.get(round(x / 1000.0), "?") for x in rp}
        return out

    def test_reorder_keeps_addresses_and_moves_are_refused(self):
        log1, log2 = os.path.join(self.tmp, "can1.log"), os.path.join(self.tmp, "can2.log")
        write(self.conf, config(log1, [obj("a", 0), obj("b", 1), obj("c", 2)]))
        p = subprocess.Popen([TRAJD, "-f", "-c", self.conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.lines = mbsim.Lines(p.stderr)
        try:
            line = self.lines.wait_for("modbus: TCP on", WAIT_S)
            self.assertIsNotNone(line, "".join(self.lines.all))
            port = mbsim.port_of(line)
            # 1. block k is the object with id k
            self.assertEqual(self.owners(port, 3), {0: "a", 1: "b", 2: "c"})

            # 2. reordered, d inserted at the top: every address stays
            write(self.conf, config(log2, [obj("d", 3), obj("c", 2), obj("b", 1), obj("a", 0)]))
            p.send_signal(signal.SIGHUP)
            line = self.lines.wait_for("modbus: TCP on", WAIT_S)
            self.assertIsNotNone(line, "".join(self.lines.all))
            port = mbsim.port_of(line)
            self.assertIsNotNone(self.lines.wait_for("reloaded:", WAIT_S), "".join(self.lines.all))
            self.assertEqual(self.owners(port, 4), {0: "a", 1: "b", 2: "c", 3: "d"})

            # 3a. a and b swap ids: refused at b's id line (b comes first in the file)
            text = config(os.path.join(self.tmp, "can3.log"),
                          [obj("d", 3), obj("b", 0), obj("c", 2), obj("a", 1)])
            write(self.conf, text)
            p.send_signal(signal.SIGHUP)
            line = self.lines.wait_for("reload refused", WAIT_S)
            self.assertIsNotNone(line, "".join(self.lines.all))
            want = "%s:%d: [object.b] id: 0, running as 1" % (
                self.conf, line_of(text, "[object.b]") + 1)
            self.assertIn(want, line)
            self.assertIn("still running the old configuration", line)
            # 3b. a's COB-ID moved: refused at a's section
            text = config(os.path.join(self.tmp, "can3.log"),
                          [obj("d", 3), obj("c", 2), obj("b", 1), obj("a", 0, cob=0x205)])
            write(self.conf, text)
            p.send_signal(signal.SIGHUP)
            line = self.lines.wait_for("reload refused", WAIT_S)
            self.assertIsNotNone(line, "".join(self.lines.all))
            self.assertIn("%s:%d: [object.a]: its CiA 402 COB-ID x id would move from 0x201 to "
                          "0x205" % (self.conf, line_of(text, "[object.a]")), line)
            # the old configuration runs on: same server, same owners
            self.assertEqual(self.owners(port, 4), {0: "a", 1: "b", 2: "c", 3: "d"})
        finally:
            p.send_signal(signal.SIGTERM)
            rc = p.wait(timeout=WAIT_S)
            self.lines.wait_for("\0", 0.5)
        self.assertEqual(rc, 0, "".join(self.lines.all))
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "can3.log")))
        # CAN: each id carried one object only, the same before and after the reload
        self.assertEqual(self.can_owners(log1),
                         {0x6A0: {"a"}, 0x6A1: {"b"}, 0x6A2: {"c"}, 0x201: {"a"}})
        self.assertEqual(self.can_owners(log2), {0x6A0: {"a"}, 0x6A1: {"b"}, 0x6A2: {"c"},
                                                 0x6A3: {"d"}, 0x201: {"a"}})

    def test_ids_required(self):
        # Given two objects, one without an id, then --check-config refuses with its line.
        text = config("/dev/null", [obj("a", 0), obj("b", 1).replace("id = 1\n", "")])
        write(self.conf, text)
        r = subprocess.run([TRAJD, "--check-config", self.conf], capture_output=True, text=True,
                           timeout=WAIT_S)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("%s:%d: [object.b]: 'id' is missing" % (self.conf, line_of(text, "[object.b]")),
                      r.stdout + r.stderr)
        # and CiA 402 without explicit COB-IDs
        text = config("/dev/null", [obj("a", 0).replace("can.cia402_cob_y = 0\n", "")])
        write(self.conf, text)
        r = subprocess.run([TRAJD, "--check-config", self.conf], capture_output=True, text=True,
                           timeout=WAIT_S)
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("needs every COB-ID explicit", r.stdout + r.stderr)


if __name__ == "__main__":
    unittest.main()
