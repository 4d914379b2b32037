"""test_can_clamped.py - a value that does not fit its CAN field is never silent (issue 24 item 2).

The real trajd replays a road track at 40 m/s (profile road) onto a candump
log_out with its own classic SETPOINT frames, whose velocity field holds
+-32.767 m/s (int16 mm/s), with Modbus on 127.0.0.1:
1. at start a warning names the object and the remedies (can.fd = yes,
   max_speed_m_s);
2. while it streams, the object's diagnostics register tx_clamped (read with
   pymodbus) counts the clipped setpoints, and a warning line says so;
3. the STATUS frames in the log (decoded by python-can and canmatrix with
   config/trajd.dbc, not by our decoder) carry ST_Clamped = 1.
The old code clipped 1 426 of 3 203 frames with exit 0 and nothing logged;
tx_clamped was counted and never read.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import signal
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 30


class Clamped(unittest.TestCase):
    def test_speed_beyond_the_field(self):
        with tempfile.TemporaryDirectory() as tmp:
            with open(os.path.join(tmp, "road.csv"), "w") as f:
                f.write("t,x,y,z\n")
                for i in range(300):                       # 40 m/s along x for 299 s
                    f.write("%d,%d,0,0\n" % (i, 40 * i))
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 20\nspeed = 5\nstatus_interval_s = 0\n"
                        "stop_timeout_s = 1\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n"
                        "[can]\nlog_out = %s/out.log\nlog_time = engine\n"
                        "[object.car]\ninput = replay\nreplay.track = road.csv\noutput = can\n"
                        "profile = road\n" % tmp)
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)
            try:
                warn = [x for x in lines.all if "beyond the SETPOINT frame's" in x]
                self.assertTrue(warn and "object 'car'" in warn[0] and "can.fd = yes" in warn[0],
                                "".join(lines.all))
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                base = M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])   # MBMAP_X_BASE(0)
                deadline = time.monotonic() + WAIT_S
                while True:
                    rr = c.read_input_registers(base + M["MBMAP_X_TX_CLAMPED"], 2, slave=1)
                    self.assertFalse(rr.isError(), rr)
                    n = (rr.registers[0] << 16) | rr.registers[1]
                    if n > 0:
                        break
                    self.assertLess(time.monotonic(), deadline, "tx_clamped stays 0")
                    time.sleep(0.1)
                c.close()
                line = lines.wait_for("sent with a value clipped to its field", WAIT_S)
                self.assertIsNotNone(line, "".join(lines.all))
                self.assertIn("object 'car'", line)
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(WAIT_S)
            status = ct.decode_by_id(os.path.join(tmp, "out.log"), 0x6C0)
            self.assertTrue(status)
            self.assertGreater(sum(sig["ST_Clamped"] == 1 for _, sig in status), 0,
                               "no STATUS frame with ST_Clamped")


if __name__ == "__main__":
    unittest.main(verbosity=2)
