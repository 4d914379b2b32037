"""test_modbus_far_waypoint.py - one far-future Modbus waypoint must not block an
object's input (issue 11, case 4), seen from a Modbus client.

trajd with an object fed over Modbus (raw Modbus/TCP frames): 40 good
waypoints (0.1 s apart), then one at t = 1e9 s, then 40 more good ones that
continue the first. Wanted:
  - the far waypoint is refused: exception 03 when it is written, or counted
    in `rejected` once the engine judged it with its neighbours (the engine
    may decide a few waypoints later, ENGINE_EUNCONFIRMED);
  - every later good waypoint is accepted (no exception at all), and the
    object's setpoint time stays on the good track.
The engine before the acceptance policy (lib/engine/accept.h) took the far
waypoint as a new trajectory and answered every later good one with
exception 03 until CLEAR. The far waypoint is refused with its own reason,
unconfirmed (diagnostics block rejected_unconfirmed), and logged with the
client that wrote it.
"""
import os
import struct
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 20


def write_wp(s, seq, t, x, y, z, tid):
    """FC 16 of the whole waypoint block: None if accepted, else the exception code."""
    regs = struct.pack(">Idddd", seq, t, x, y, z)
    n = len(regs) // 2
    pdu = struct.pack(">BHHB", 16, obj_base(0) + M["MBMAP_H_WP"], n, len(regs)) + regs
    rsp = mbsim.transact(s, pdu, tid)
    return None if rsp[0] == 16 else rsp[1]


def good(i):
    t = 0.1 * i
    return (t, 1.0 * t, 0.5 * t, 1.0)


class FarWaypoint(mbsim.FedTrajdCase):
    TRAJD = TRAJD
    WAIT_S = WAIT_S

    def check(self):
        s = mbsim.connect(self.port)
        tid = 0
        for i in range(1, 41):
            tid += 1
            self.assertIsNone(write_wp(s, i, *good(i), tid=tid), "good waypoint %d" % i)
        tid += 1
        far = write_wp(s, 41, 1e9, 40.0, 20.0, 1.0, tid=tid)
        self.assertIn(far, (None, 3))        # refused at once, or judged later
        later = []
        for i in range(42, 82):
            tid += 1
            later.append(write_wp(s, i, *good(i - 1), tid=tid))
        # every good waypoint after the far one is taken
        self.assertEqual(later, [None] * len(later))
        # and the far one is refused (at once, or counted once judged)
        deadline = time.monotonic() + WAIT_S
        while True:
            r = mbsim.read_input(s, obj_base(0), mbsim.BLOCK)
            rejected = mbsim.u32(r, M["MBMAP_O_REJECTED"])
            # (the registers are a snapshot per tick: wait for the one
            # after the last write too)
            if ((far == 3 or rejected >= 1) and mbsim.u32(r, M["MBMAP_O_ACCEPTED"]) >= 79) \
                    or time.monotonic() > deadline:
                break
        self.assertTrue(far == 3 or rejected >= 1, (far, rejected))
        # with its own reason: unconfirmed (the diagnostics block's per-reason
        # counter; issue 11 "rejected with its own reason code"), and nothing else
        x = mbsim.read_input(s, M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"]), mbsim.BLOCK)
        self.assertEqual(mbsim.u32(x, M["MBMAP_X_REJ_UNCONFIRMED"]), 1)
        self.assertEqual(sum(mbsim.u32(x, M["MBMAP_X_REJECTED_BY"] + 2 * k) for k in range(13)), 1)
        # all 80 good ones in but the newest, whose verdict waits for its
        # next neighbour (lib/engine/accept.h, ACCEPT_LAG)
        self.assertGreaterEqual(mbsim.u32(r, M["MBMAP_O_ACCEPTED"]), 79)
        # the setpoint stays on the good track (never near t = 1e9)
        self.assertLess(mbsim.f64(r, M["MBMAP_O_T_S"]), 100.0)
        # and the refusal is logged with the client that wrote it (its own
        # address:port, as this socket sees it) and the waypoint's seq
        me = "modbus %s:%d" % s.getsockname()[:2]
        line = self.lines.wait_for(": rejected (", WAIT_S)
        self.assertIsNotNone(line, "".join(self.lines.all))
        self.assertIn("object 'fed': %s: rejected (" % me, line)
        self.assertIn(" seq 41 t=1000000000.000 s", line)
        s.close()

    def test_far_waypoint_does_not_block(self):
        self.check()


if __name__ == "__main__":
    unittest.main(verbosity=2)
