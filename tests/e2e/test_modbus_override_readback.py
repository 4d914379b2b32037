"""test_modbus_override_readback.py - the override holding register reads the override in
force, whoever set it.

The real trajd replays a line with Modbus on 127.0.0.1 (writes on, the object writable) and
its control socket in a temporary directory. An operator writes override 150 % on Modbus
(pymodbus, FC 06): the holding register reads 150, and the object block's override in force
too. Then trajctl sets 50 %: the holding register must read 50 as the input register does;
it read 150 (the last value written over Modbus) while the object ran at 50 %. A write trajd
refuses (201 %, exception 03) leaves it at 50.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRAJCTL = os.path.join(mbsim.BUILD, "bin", "trajctl")
WAIT_S = 30


class OverrideReadback(unittest.TestCase):
    def wait_both(self, c, want):
        """The holding register and the input register 'override in force' both read want."""
        base = mbsim.obj_base(0)
        deadline = time.monotonic() + WAIT_S
        while True:
            rr = c.read_holding_registers(base + M["MBMAP_H_OVERRIDE"], 1, slave=1)
            self.assertFalse(rr.isError(), rr)
            held = rr.registers[0]
            in_force = mbsim.input_reg(c, base + M["MBMAP_O_OVERRIDE"])
            if (held, in_force) == (want, want):
                return
            self.assertLess(time.monotonic(), deadline,
                            "holding %d, in force %d, wanted %d" % (held, in_force, want))
            time.sleep(0.05)

    def test_holding_register_reads_the_override_in_force(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "line.csv"))
            sock = os.path.join(tmp, "ctl.sock")
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\ncontrol_socket = %s\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n"
                        "writes = yes\n"
                        "[object.a]\nid = 0\nwritable = yes\ninput = replay\n"
                        "replay.track = line.csv\noutput = csv\ncsv.path = a.csv\n" % sock)
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S, cwd=tmp)
            try:
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                addr = mbsim.obj_base(0) + M["MBMAP_H_OVERRIDE"]
                self.wait_both(c, 100)
                w = c.write_register(addr, 150, slave=1)
                self.assertFalse(w.isError(), w)
                self.wait_both(c, 150)
                r = subprocess.run([TRAJCTL, "-s", sock, "override", "50", "a"],
                                   capture_output=True, text=True, timeout=WAIT_S)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.wait_both(c, 50)
                w = c.write_register(addr, 201, slave=1)
                self.assertTrue(w.isError(), w)
                self.wait_both(c, 50)
                c.close()
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(WAIT_S)


if __name__ == "__main__":
    unittest.main(verbosity=2)
