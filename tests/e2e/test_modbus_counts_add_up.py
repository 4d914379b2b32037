"""test_modbus_counts_add_up.py - every waypoint written over Modbus is in one counter, across
a clear and a stop/start.

The real trajd with a Modbus-fed object (mbsim.start_fed_trajd), written by pymodbus through
the holding waypoint block (config/PROTOCOL.md), every write acknowledged:
- 60 waypoints at 50 Hz of track (2.5 m/s), the command clear after the 30th, then finish;
- 80 waypoints, the command stop after the 40th, 40 more while the stop is latched, start,
  then finish.
Once the object is finished (nothing left being judged), the object block's accepted +
rejected + duplicates + lost + full and the diagnostics block's unjudged add up to the
waypoints written. Before: one waypoint still being judged at the clear or the stop was in no
counter (or only in dropped, a part of accepted), and the latched ones the start dropped as
past were told on a log line alone (80 written, 72 accounted for).
"""
import os
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

WAIT_S = 30


class CountsAddUp(mbsim.FedTrajdCase):
    TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")

    def setUp(self):
        super().setUp()
        self.c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(self.c.connect())
        self.base = mbsim.obj_base(0)
        self.xb = M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])

    def tearDown(self):
        self.c.close()
        super().tearDown()

    def write(self, seq, t, x):
        rq = mbsim.write_retrying(self.c, self.base + M["MBMAP_H_WP"],
                                  mbsim.wp_regs(seq, t, x, 0.0, 0.0),
                                  time.monotonic() + WAIT_S)
        self.assertFalse(rq.isError(), rq)

    def command(self, code):
        rq = self.c.write_register(self.base + M["MBMAP_H_COMMAND"], code, slave=1)
        self.assertFalse(rq.isError(), rq)

    def finished_counts(self):
        self.command(M["MBMAP_CMD_FINISH"])
        deadline = time.monotonic() + WAIT_S
        while True:
            r = self.c.read_input_registers(self.base, M["MBMAP_BLOCK"], slave=1).registers
            if r[M["MBMAP_O_STATE"]] == 3 and r[M["MBMAP_O_BUFFERED"] + 1] == 0:
                break
            self.assertLess(time.monotonic(), deadline, "never finished")
            time.sleep(0.05)
        x = self.c.read_input_registers(self.xb + M["MBMAP_X_UNJUDGED"], 2, slave=1).registers
        names = ("ACCEPTED", "REJECTED", "DUPLICATES", "LOST", "FULL")
        counts = {n.lower(): mbsim.u32(r, M["MBMAP_O_" + n]) for n in names}
        counts["unjudged"] = mbsim.u32(x, 0)
        return counts

    def test_clear(self):
        for i in range(60):
            if i == 30:
                self.command(M["MBMAP_CMD_CLEAR"])
                time.sleep(0.3)
            self.write(i + 1, 0.02 * i, 0.05 * i)
            time.sleep(0.01)
        counts = self.finished_counts()
        self.assertEqual(sum(counts.values()), 60, counts)

    def test_stop_start(self):
        for i in range(80):
            if i == 40:
                self.command(M["MBMAP_CMD_STOP"])
                time.sleep(0.3)
            self.write(i + 1, 0.02 * i, 0.05 * i)
            time.sleep(0.01)
        self.command(M["MBMAP_CMD_START"])
        time.sleep(0.3)
        counts = self.finished_counts()
        self.assertEqual(sum(counts.values()), 80, counts)


if __name__ == "__main__":
    unittest.main(verbosity=2)
