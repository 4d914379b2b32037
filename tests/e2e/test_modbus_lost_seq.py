"""test_modbus_lost_seq.py - one bogus sequence number does not count as
billions of lost waypoints (issue 11, "Counters mean what they say"), seen
through the running daemon's Modbus server with pymodbus.

A pymodbus client writes whole waypoint blocks (FC 16, lib/proto/mbmap.h
MBMAP_H_WP: u32 seq, f64 t, x, y, z) for one object: seq 1..20 on a
straight line 0.1 s apart, then a waypoint on the same line numbered
0xFFFFFFFF, then 21..40 with 31 left out (the sender lost one). Wanted,
read back with pymodbus over Modbus (the object's block):
  - `lost` (MBMAP_O_LOST) is the one number left out, computed here from
    the numbers sent: steps of 1 lose nothing, 30 -> 32 loses one. Before
    the plausible window (daemon/modbus/modbus_dispatch.c count_seq) the step
    20 -> 0xFFFFFFFF alone added 4 294 967 274 (read in a snapshot taken
    right after it, before the next write: 0 lost wanted there);
  - `seq_jumps` (MBMAP_O_SEQ_JUMPS) counts the one number outside the
    window (read once `last_seq` shows the last number written, after
    FINISH: the block is a snapshot taken each tick);
  - every write is answered without an exception (the bogus number is the
    sender's, the waypoint itself is good).
"""
import os
import sys
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.constants import Endian  # noqa: E402
from pymodbus.payload import BinaryPayloadDecoder  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 20
BOGUS = 0xFFFFFFFF


def feed():
    """(seq, t, x, y, z) in the order written: 1..20, the bogus one, 21..40 without 31."""
    out, i = [], 0
    for seq in list(range(1, 21)) + [BOGUS] + [n for n in range(21, 41) if n != 31]:
        i += 1
        t = 0.1 * i
        out.append((seq, t, 1.0 * t, 0.5 * t, 1.0))
    return out


def expected_lost(seqs):
    """Waypoints lost by the sender: d - 1 for each step forward d between
    consecutive plausible numbers (the bogus one is skipped, not a step)."""
    good = [s for s in seqs if s != BOGUS]
    return sum(b - a - 1 for a, b in zip(good, good[1:]))


class LostSeq(mbsim.FedTrajdCase):
    TRAJD = TRAJD
    WAIT_S = WAIT_S

    def u32(self, c, reg, base=None):
        rr = c.read_input_registers(obj_base(0) + reg if base is None else reg, 2, slave=1)
        self.assertFalse(rr.isError(), rr)
        d = BinaryPayloadDecoder.fromRegisters(rr.registers, byteorder=Endian.Big,
                                               wordorder=Endian.Big)
        return d.decode_32bit_uint()

    def test_bogus_seq_is_not_lost(self):
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            wps = feed()
            deadline = time.monotonic() + WAIT_S
            for seq, t, x, y, z in wps:
                rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WP"],
                                          mbsim.wp_regs(seq, t, x, y, z), deadline)
                self.assertFalse(rq.isError(), "seq %#x: %s" % (seq, rq))
                if seq == BOGUS:
                    # a snapshot taken after it: lost counted nothing (the
                    # old count read 0xFFFFFFFF - 20 - 1 here)
                    g = self.u32(c, M["MBMAP_D_GEN"], base=0)
                    while self.u32(c, M["MBMAP_D_GEN"], base=0) < g + 2:
                        self.assertLess(time.monotonic(), deadline, "no new snapshot")
                        time.sleep(0.005)
                    self.assertEqual(self.u32(c, M["MBMAP_O_LOST"]), 0)
            # end of input, so the engine judges the last waypoint too; the
            # block is a snapshot taken each tick: wait for one that holds it
            rq = c.write_register(obj_base(0) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"],
                                  slave=1)
            self.assertFalse(rq.isError(), rq)
            while self.u32(c, M["MBMAP_O_LAST_SEQ"]) != wps[-1][0]:
                self.assertLess(time.monotonic(), deadline, "last_seq never came")
                time.sleep(0.01)
            want = expected_lost([w[0] for w in wps])
            self.assertEqual(want, 1)
            self.assertEqual(self.u32(c, M["MBMAP_O_LOST"]), want)
            self.assertEqual(self.u32(c, M["MBMAP_O_SEQ_JUMPS"]), 1)
            self.assertEqual(self.u32(c, M["MBMAP_O_LAST_SEQ"]), wps[-1][0])
        finally:
            c.close()

    def test_repeat_is_no_jump(self):
        # Given seq 1..10, seq 5 written twice (a client retrying after a reply it
        # lost), then the repeat is a duplicate (the engine's), neither lost nor
        # a jump: seq_jumps stays 0 (it counted 1, as for a bogus number).
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            deadline = time.monotonic() + WAIT_S
            for seq in [1, 2, 3, 4, 5, 5, 6, 7, 8, 9, 10]:
                rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WP"],
                                          mbsim.wp_regs(seq, 0.1 * seq, 0.1 * seq, 0.0, 1.0),
                                          deadline)
                self.assertFalse(rq.isError(), "seq %d: %s" % (seq, rq))
            rq = c.write_register(obj_base(0) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"],
                                  slave=1)
            self.assertFalse(rq.isError(), rq)
            while self.u32(c, M["MBMAP_O_LAST_SEQ"]) != 10:
                self.assertLess(time.monotonic(), deadline, "last_seq never came")
                time.sleep(0.01)
            self.assertEqual(self.u32(c, M["MBMAP_O_LOST"]), 0)
            self.assertEqual(self.u32(c, M["MBMAP_O_SEQ_JUMPS"]), 0)
            self.assertEqual(self.u32(c, M["MBMAP_O_DUPLICATES"]), 1)
        finally:
            c.close()

    def test_refused_waypoint_is_not_lost(self):
        # Given seq 1..10 with seq 6 out of range (x = 2e7 m), seq 3 with x NaN and
        # seq 8 with t infinite (each exception 03, counted in mb_rejected), then
        # `lost` is 0: each came, and was refused, not lost (seq 6 was counted twice,
        # in rejected and in lost; seq 3 and 8 in lost and nowhere else, unlogged).
        # The non-finite ones are refused by the engine as any other source's:
        # logged with the peer and their seq (and counted in rejected_not_finite).
        bad = {3: (0.3, float("nan")), 6: (0.6, 2e7), 8: (float("inf"), 0.8)}
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            deadline = time.monotonic() + WAIT_S
            for seq in range(1, 11):
                t, x = bad.get(seq, (0.1 * seq, 0.1 * seq))
                rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WP"],
                                          mbsim.wp_regs(seq, t, x, 0.05 * seq, 1.0), deadline)
                self.assertEqual(rq.isError(), seq in bad, "seq %d: %s" % (seq, rq))
                if seq in bad:
                    self.assertEqual(rq.exception_code, 3, rq)
            rq = c.write_register(obj_base(0) + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"],
                                  slave=1)
            self.assertFalse(rq.isError(), rq)
            while self.u32(c, M["MBMAP_O_LAST_SEQ"]) != 10:
                self.assertLess(time.monotonic(), deadline, "last_seq never came")
                time.sleep(0.01)
            self.assertEqual(self.u32(c, M["MBMAP_O_LOST"]), 0)
            self.assertEqual(self.u32(c, M["MBMAP_O_SEQ_JUMPS"]), 0)
            for seq in (3, 8):
                line = self.lines.wait_for("rejected (not_finite) seq %d " % seq, WAIT_S)
                self.assertIsNotNone(line, "seq %d not logged" % seq)
                self.assertIn("modbus 127.0.0.1:", line)
        finally:
            c.close()

    def test_dropped_client_logged(self):
        # Given a client whose MBAP header has protocol id 7 (no frame boundary
        # to trust: the server closes it), then a line says so at once, with the
        # client and why.  Before, it was only in the peer summary every 60 s,
        # which an exit or a reload dropped: a shorter run never told it.
        s = mbsim.connect(self.port)
        s.sendall(bytes([0, 1, 0, 7, 0, 6, 1, 3, 0, 0, 0, 1]))
        s.settimeout(WAIT_S)
        self.assertEqual(s.recv(100), b"")  # closed by the server
        s.close()
        line = self.lines.wait_for("modbus: closed", 5)
        self.assertIsNotNone(line, "".join(self.lines.all))
        self.assertIn("127.0.0.1:", line)
        self.assertIn("protocol id 7", line)

    def test_counters_kept_over_a_reload(self):
        # Given seq 1, 2, 4..7 (3 lost) and 8 out of range (exception 03, mb_rejected),
        # when trajd is reloaded with its file unchanged ("carried over without
        # interruption") and the sender goes on at 20..22, then the object keeps its
        # Modbus counters and its numbering: lost 1 + 11 (9..19 never came) = 12,
        # mb_rejected 1.  Before, the reload zeroed them all and restarted the
        # numbering: lost 0, mb_rejected 0.
        import signal
        c = ModbusTcpClient("127.0.0.1", port=self.port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        deadline = time.monotonic() + WAIT_S
        for seq in (1, 2, 4, 5, 6, 7, 8):
            x = 2e7 if seq == 8 else 0.1 * seq
            rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WP"],
                                      mbsim.wp_regs(seq, 0.1 * seq, x, 0.0, 0.0), deadline)
            self.assertEqual(rq.isError(), seq == 8, "seq %d: %s" % (seq, rq))
        c.close()
        self.p.send_signal(signal.SIGHUP)
        line = self.lines.wait_for("modbus: TCP on", WAIT_S)  # the server reopened
        self.assertIsNotNone(line)
        self.assertIsNotNone(self.lines.wait_for("1 carried over without interruption", WAIT_S))
        c = ModbusTcpClient("127.0.0.1", port=mbsim.port_of(line), timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            for seq in (20, 21, 22):
                rq = mbsim.write_retrying(c, obj_base(0) + M["MBMAP_H_WP"],
                                          mbsim.wp_regs(seq, 0.1 * seq, 0.1 * seq, 0.0, 0.0),
                                          deadline)
                self.assertFalse(rq.isError(), "seq %d: %s" % (seq, rq))
            g = self.u32(c, M["MBMAP_D_GEN"], base=0)
            while self.u32(c, M["MBMAP_D_GEN"], base=0) < g + 2:
                self.assertLess(time.monotonic(), deadline, "no new snapshot")
                time.sleep(0.005)
            self.assertEqual(self.u32(c, M["MBMAP_O_LOST"]), 12)
            self.assertEqual(self.u32(c, M["MBMAP_O_MB_REJECTED"]), 1)
            self.assertEqual(self.u32(c, M["MBMAP_O_SEQ_JUMPS"]), 0)
        finally:
            c.close()


if __name__ == "__main__":
    unittest.main(verbosity=2)
