"""test_modbus_diagnostics.py - the per-object diagnostics block (input
registers at MBMAP_X_BASE(k) = 100 * (65 + k), config/PROTOCOL.md) read by
an independent Modbus client (pymodbus) from a running trajd.

Given a clean 5 Hz circle with injected faults (two 500 m spikes, a second
position at the same time, a frozen fix repeated while moving, three rows
stamped back in time), replayed by trajd with a Modbus server, then once
the object has finished:
  - the diagnostics block is one snapshot (generation == generation_tail ==
    the object block's generation read in the same tick);
  - each per-reason counter equals trajreplay's count for that reason on the
    same file (`--summary` rejected_<reason>), and they sum to the object
    block's `rejected`;
  - the FC 03 mirror (holding 20000 + a) reads the same registers;
  - a read spanning the object blocks and the diagnostics blocks, or past the
    last object's diagnostics block, is refused with exception 02.
Register numbers come from lib/proto/mbmap.h (mbsim.M), field names from the
table in config/PROTOCOL.md through trajreplay's names (the same strings).
"""
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(mbsim.BUILD, "bin", "trajreplay")
WAIT_S = 30
X_BASE0 = M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])


def x_base(k):
    return X_BASE0 + M["MBMAP_BLOCK"] * k


def u32(regs, off):
    return (regs[off] << 16) | regs[off + 1]


def faulty_track(path):
    out = []
    for i in range(300):
        t = 0.2 * i
        x, y = 50 * math.cos(2 * t / 50), 50 * math.sin(2 * t / 50)
        if i in (40, 140):
            x += 500.0                                  # spikes
        out.append("%.3f,%.6f,%.6f,1.0" % (t, x, y))
        if i == 60:
            out.append("%.3f,%.6f,%.6f,1.0" % (t, x + 3, y))  # same time, another position
        if i == 180:
            out.append("%.3f,%.6f,%.6f,1.0" % (t + 0.2, x, y))  # frozen while moving
        if i == 220:
            out += ["1.000,%d.0,0.0,1.0" % (1000 + k) for k in range(3)]  # backwards
    with open(path, "w") as f:
        f.write("t,x,y,z\n" + "\n".join(out) + "\n")


class Diagnostics(unittest.TestCase):
    def test_per_reason_counters(self):
        with tempfile.TemporaryDirectory() as tmp:
            track = os.path.join(tmp, "diag.csv")
            faulty_track(track)
            r = subprocess.run([TRAJREPLAY, "--summary", "-q", "-o", os.path.join(tmp, "r.csv"), track],
                               capture_output=True, text=True, timeout=WAIT_S)
            self.assertEqual(r.returncode, 0, r.stderr)
            want = {l.split()[1]: int(l.split()[2]) for l in r.stdout.splitlines() + r.stderr.splitlines()
                    if l.startswith("summary: rejected_")}
            self.assertGreaterEqual(sum(1 for v in want.values() if v), 4, want)
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nspeed = 20\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n"
                        "[object.first]\nid = 0\ninput = replay\nreplay.track = %s\noutput = csv\n"
                        "csv.path = a.csv\n"
                        "[object.boat]\nid = 1\ninput = replay\nreplay.track = %s\noutput = csv\n"
                        "csv.path = b.csv\n" % (track, track))
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                line = lines.wait_for("modbus: TCP on", WAIT_S)
                self.assertIsNotNone(line, "".join(lines.all))
                port = mbsim.port_of(line)
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
                self.assertTrue(c.connect())
                k = 1  # the second object (id 1): its block is not the first one
                deadline = time.monotonic() + WAIT_S
                while True:
                    o = c.read_input_registers(obj_base(k), mbsim.BLOCK, slave=1).registers
                    if o[M["MBMAP_O_STATE"]] == 3 or time.monotonic() > deadline:
                        break
                self.assertEqual(o[M["MBMAP_O_STATE"]], 3, "object did not finish")
                # one tick's snapshot of both blocks: read until the generations agree
                for _ in range(100):
                    o = c.read_input_registers(obj_base(k), mbsim.BLOCK, slave=1).registers
                    x = c.read_input_registers(x_base(k), mbsim.BLOCK, slave=1).registers
                    if u32(o, M["MBMAP_O_GEN"]) == u32(x, M["MBMAP_X_GEN"]):
                        break
                self.assertEqual(u32(x, M["MBMAP_X_GEN"]), u32(x, M["MBMAP_X_GEN_TAIL"]))
                self.assertEqual(u32(x, M["MBMAP_X_GEN"]), u32(o, M["MBMAP_O_GEN"]))
                got = {}
                for name, n in want.items():
                    reg = M["MBMAP_X_REJ_" + name[len("rejected_"):].upper().replace("_", "")]
                    got[name] = u32(x, reg)
                self.assertEqual(got, want)
                self.assertEqual(sum(got.values()), u32(o, M["MBMAP_O_REJECTED"]))
                # the FC 03 mirror reads the same registers
                h = c.read_holding_registers(M["MBMAP_MIRROR_BASE"] + x_base(k), mbsim.BLOCK,
                                             slave=1).registers
                self.assertEqual(u32(h, M["MBMAP_X_REJ_SPEED"]), want["rejected_speed"])
                # reads across the hole between the blocks, or past the last
                # object's diagnostics block, are refused with exception 02
                for addr, n in ((obj_base(2) - 2, 4), (X_BASE0 - 1, 2), (x_base(2) - 1, 2)):
                    rr = c.read_input_registers(addr, n, slave=1)
                    self.assertTrue(rr.isError(), addr)
                    self.assertEqual(rr.exception_code, 2, addr)
                self.assertFalse(c.read_input_registers(x_base(0), 125, slave=1).isError())
                c.close()
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(WAIT_S)


if __name__ == "__main__":
    unittest.main(verbosity=2)
