#!/usr/bin/python3
"""test_modbus_velocity.py - the waypoint-with-velocity block (issue 31, lib/proto/mbmap.h
MBMAP_H_WPV: u32 seq, f64 t, x, y, z, vx, vy, vz, one FC 16 of 30 registers) through the
running daemon, written by pymodbus's BinaryPayloadBuilder.

A helix 0.2 s apart with its exact velocity goes to an object with `method = hermite`, then
FINISH. Every streamed row lies on scipy's CubicHermiteSpline of the velocities as written
(to 1e-9 m), and far from the Hermite of velocities estimated from the positions (what the
float64 block without velocity gives; a write of it to a second object checks that too).
ArrivalVerdict: with max_lookahead = 1 each written waypoint is accepted as it is written.
"""
import csv
import os
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np
from scipy.interpolate import CubicHermiteSpline

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.constants import Endian  # noqa: E402
from pymodbus.payload import BinaryPayloadBuilder  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 30
N = 40
DT = 0.2
W = 0.6
# trajd.conf before the objects: Modbus writes on an ephemeral port
CONF_HEAD = ("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
             "[modbus]\naddress = 127.0.0.1\nport = 0\nwrites = yes\nsystemd_socket = no\n")


def helix():
    t = DT * np.arange(1, N + 1)
    pos = np.stack([5 * np.cos(W * t), 5 * np.sin(W * t), 0.3 * t], axis=1)
    vel = np.stack([-5 * W * np.sin(W * t), 5 * W * np.cos(W * t), 0.3 + 0 * t], axis=1)
    return t, pos, vel


def streamed(path):
    with open(path) as f:
        rows = [r for r in csv.DictReader(f)]
    st = [r for r in rows if r["state"] == "streaming" and not int(r["flags"]) & 0x08]  # ENGINE_SP_TRANSFER
    return (rows[-1]["state"] if rows else "", np.array([float(r["t_s"]) for r in st]),
            np.array([[float(r[k]) for k in ("x_m", "y_m", "z_m")] for r in st]))


class VelocityBlock(unittest.TestCase):
    def test_velocity_block_shapes_the_curve(self):
        t, pos, vel = helix()
        with tempfile.TemporaryDirectory() as d:
            conf = os.path.join(d, "trajd.conf")
            with open(conf, "w") as f:
                f.write(CONF_HEAD)
                for k in range(2):
                    f.write("[object.o%d]\nid = %d\ninput = modbus\noutput = csv\n"
                            "csv.path = %s\nmethod = hermite\nends = natural\nprofile = none\n"
                            % (k, k, os.path.join(d, "o%d.csv" % k)))
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)
            try:
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                deadline = time.monotonic() + WAIT_S
                for i in range(N):
                    for k, block, count in ((0, "MBMAP_H_WPV", "MBMAP_H_WPV_COUNT"),
                                            (1, "MBMAP_H_WP", "MBMAP_H_WP_COUNT")):
                        b = BinaryPayloadBuilder(byteorder=Endian.Big, wordorder=Endian.Big)
                        b.add_32bit_uint(i + 1)
                        for v in (t[i], *pos[i], *(vel[i] if k == 0 else ())):
                            b.add_64bit_float(float(v))
                        regs = b.to_registers()
                        self.assertEqual(len(regs), M[count])
                        while True:
                            self.assertLess(time.monotonic(), deadline, "feed too slow")
                            rq = c.write_registers(obj_base(k) + M[block], regs, slave=1)
                            if not rq.isError():
                                break
                            self.assertEqual(rq.exception_code, 6, rq)  # busy: retry
                            time.sleep(0.01)
                for k in range(2):
                    rq = c.write_register(obj_base(k) + M["MBMAP_H_COMMAND"],
                                          M["MBMAP_CMD_FINISH"], slave=1)
                    self.assertFalse(rq.isError(), rq)
                c.close()
                end = time.monotonic() + WAIT_S
                while time.monotonic() < end:
                    done = [streamed(os.path.join(d, "o%d.csv" % k))[0] == "finished"
                            for k in range(2)]
                    if all(done):
                        break
                    time.sleep(0.1)
            finally:
                p.terminate()
                p.wait(WAIT_S)
                p.stderr.close()
            given = CubicHermiteSpline(t, pos, vel)
            off = []
            for k in range(2):
                state, ts, got = streamed(os.path.join(d, "o%d.csv" % k))
                self.assertEqual(state, "finished", k)
                self.assertGreater(len(ts), 300, k)
                off.append(np.abs(got - given(ts)).max())
            self.assertLess(off[0], 1e-9, "the block's velocities shape the curve: %.2e m" % off[0])
            self.assertGreater(off[1], 1e4 * max(off[0], 1e-12),
                               "without them the curve differs (%.2e m)" % off[1])


class ArrivalVerdict(unittest.TestCase):
    """max_lookahead = 1 through the daemon (issue 31, lib/engine/accept.h at_arrival): the
    helix written with its velocities, one waypoint at a time, to an object with
    max_lookahead 1 and to one with 2.  After each write (and a few ticks) the accepted
    count the object's Modbus block shows includes the waypoint just written with 1, and
    lags by one with 2 (its next neighbour confirms it); past the first trajectory's
    confirmation, for every write."""

    def test_kept_as_written(self):
        t, pos, vel = helix()
        with tempfile.TemporaryDirectory() as d:
            conf = os.path.join(d, "trajd.conf")
            with open(conf, "w") as f:
                f.write(CONF_HEAD)
                for k, ml in enumerate((1, 2)):
                    f.write("[object.o%d]\nid = %d\ninput = modbus\noutput = csv\n"
                            "csv.path = %s\nmax_lookahead = %d\n"
                            % (k, k, os.path.join(d, "o%d.csv" % k), ml))
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)
            seen = {0: [], 1: []}
            try:
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                for i in range(N):
                    b = BinaryPayloadBuilder(byteorder=Endian.Big, wordorder=Endian.Big)
                    b.add_32bit_uint(i + 1)
                    for v in (t[i], *pos[i], *vel[i]):
                        b.add_64bit_float(float(v))
                    regs = b.to_registers()
                    for k in range(2):
                        rq = c.write_registers(obj_base(k) + M["MBMAP_H_WPV"], regs, slave=1)
                        self.assertFalse(rq.isError(), rq)
                    time.sleep(0.05)  # a few ticks: the blocks show the verdicts
                    for k in range(2):
                        r = c.read_input_registers(obj_base(k), mbsim.BLOCK, slave=1).registers
                        seen[k].append(mbsim.u32(r, M["MBMAP_O_ACCEPTED"]))
                c.close()
            finally:
                p.terminate()
                p.wait(WAIT_S)
                p.stderr.close()
        late = [(i, seen[0][i], seen[1][i]) for i in range(10, N)
                if seen[0][i] != i + 1 or seen[1][i] != i]
        self.assertEqual(late, [], "writes whose count was not (i + 1, i): (i, ml 1, ml 2)")


if __name__ == "__main__":
    unittest.main()
