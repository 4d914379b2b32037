"""test_modbus_f32.py - the float32 waypoint block and the health word
(issue 29 item 2), through the running daemon with pymodbus.

1. A PLC without float64 writes waypoints as float32 (lib/proto/mbmap.h
   MBMAP_H_WPF: u32 seq, f32 t, x, y, z, one FC 16 of 10 registers) encoded
   by pymodbus's BinaryPayloadBuilder: 40 waypoints on a circle 0.1 s apart,
   written at once as trajd starts, then nothing.  Every write is taken (busy
   answers retried), the health word (MBMAP_O_HEALTH) reads 0 while the
   object streams, and the writer's silence ends the trajectory
   (lib/engine/silence.h): the object finishes by itself, with no FINISH,
   at rest on the last waypoint as pymodbus sent it: numpy.float32 of its
   coordinates, to 1e-9 m, not their float64 values; those differ by up to
   2^-24 of the coordinate, as PROTOCOL.md states, and no row in underrun.
   (Before: waypoints written before the daemon's first tick never counted
   as arrived, and the object stood in underrun short of its tail for good;
   a batch met on one tick stated a D of its whole span, and the output ran
   short of curve for 0.75 s before the silence ended it.)
2. The health word reads bit 3 (underrun) with state 2 while the output
   runs short of a late writer's data: the same circle, its first interval
   1.6 s, so that the silence that would end the trajectory (6 intervals)
   is longer than the stop on what was written; the writer goes quiet, the
   object brakes to rest in underrun, and a FINISH then ends it (state 3)
   on the last waypoint.
"""
import csv
import math
import os
import sys
import time
import unittest

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 20
N = 40


def waypoints(first_gap_s=0.0):
    return [(i + 1, 0.1 * (i + 1) + (first_gap_s if i else 0.0),
             3.0 * math.cos(0.2 * i) + 100.123456789,
             3.0 * math.sin(0.2 * i) - 7.000001, 0.25) for i in range(N)]


class Float32Block(mbsim.FedTrajdCase):
    TRAJD = TRAJD
    WAIT_S = WAIT_S

    def reg(self, c, off):
        return mbsim.input_reg(c, obj_base(0) + off)

    def wait_state(self, c, state, what):
        mbsim.wait_input(c, obj_base(0) + M["MBMAP_O_STATE"], state, what, WAIT_S)

    def feed(self, c, wps):
        """Write wps as float32 blocks (busy answers retried); returns them as sent."""
        sent = []
        deadline = time.monotonic() + WAIT_S
        for seq, t, x, y, z in wps:
            regs = mbsim.wp_regs(seq, t, x, y, z, f32=True)
            self.assertEqual(len(regs), M["MBMAP_H_WPF_COUNT"])
            rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WPF"], regs, deadline)
            self.assertFalse(rq.isError(), rq)
            sent.append(tuple(float(np.float32(v)) for v in (t, x, y, z)))
        return sent

    def rows_to_end(self):
        end = time.monotonic() + WAIT_S
        while True:
            with open(self.csv) as f:
                rows = [r for r in csv.DictReader(f) if r["state"] != "waiting"]
            if rows and rows[-1]["state"] == "finished" or time.monotonic() > end:
                return rows
            time.sleep(0.1)

    def assert_rests_on(self, rows, sent, f64):
        # every waypoint accepted, and the object rests on the last one as sent in float32
        # (not on its float64 coordinate, 1e-6 m away)
        self.assertEqual(len(rows) and rows[-1]["state"], "finished")
        last = rows[-1]
        for a, v in zip(("x_m", "y_m", "z_m"), sent[-1][1:]):
            self.assertLess(abs(float(last[a]) - v), 1e-9, (a, last[a], v))
        self.assertGreater(abs(float(last["x_m"]) - f64[-1][2]), 1e-7, "float32, not float64")
        drift = max(abs(s[1] - w[2]) for s, w in zip(sent, f64))
        self.assertLessEqual(drift, abs(f64[0][2]) * 2.0 ** -24 * 1.01, "float32 precision as documented")

    def test_float32_waypoints_silent_end(self):
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            sent = self.feed(c, waypoints())
            # streaming well: health 0
            self.wait_state(c, 1, "never streamed")
            self.assertEqual(self.reg(c, M["MBMAP_O_HEALTH"]), 0)
            # the writer goes quiet: its silence ends the trajectory, no FINISH
            self.wait_state(c, 3, "never finished after the writer's silence")
        finally:
            c.close()
        rows = self.rows_to_end()
        self.assert_rests_on(rows, sent, waypoints())
        # the batch's end is no underrun: its D is what the input needs, whichever ticks the
        # writes met, and the silence comes before the output runs short of curve
        self.assertEqual(sum(r["state"] == "underrun" for r in rows), 0)

    def test_health_underrun(self):
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        f64 = waypoints(1.5)
        try:
            sent = self.feed(c, f64)
            self.wait_state(c, 1, "never streamed")
            # the writer goes quiet: the output runs short of data and underruns
            self.wait_state(c, 2, "never underran")
            self.assertTrue(self.reg(c, M["MBMAP_O_HEALTH"]) & M["MBMAP_HEALTH_UNDERRUN"])
            rq = c.write_register(obj_base(0) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"], slave=1)
            self.assertFalse(rq.isError(), rq)
            self.wait_state(c, 3, "never finished")
        finally:
            c.close()
        self.assert_rests_on(self.rows_to_end(), sent, f64)


if __name__ == "__main__":
    unittest.main()
