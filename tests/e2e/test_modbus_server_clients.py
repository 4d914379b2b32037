"""test_modbus_server_clients.py - the Modbus server (harness loop, tests/unit/test_modbus_server.c
--serve) against an independent client (pymodbus 3, Debian) and against raw,
hand-built ADUs: every unserved function code, out-of-range addresses and
counts, malformed frames, silent clients, 200 connections at once, and a short
load of 50 clients while 4 objects tick at 1 kHz (no torn read).
"""
import os
import socket
import struct
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.constants import Endian  # noqa: E402
from pymodbus.payload import BinaryPayloadBuilder, BinaryPayloadDecoder  # noqa: E402

SERVED = {3, 4, 6, 16}
LOAD_SECONDS = float(os.environ.get("MB_LOAD_SECONDS", "3"))


def decoder(regs):
    # The documented word order: big-endian bytes, most significant word first.
    return BinaryPayloadDecoder.fromRegisters(regs, byteorder=Endian.Big, wordorder=Endian.Big)


class PymodbusTest(unittest.TestCase):
    def setUp(self):
        self.srv = mbsim.Server(["--objects", "2", "--writes", "1", "--capacity", "1000"])
        self.c = ModbusTcpClient("127.0.0.1", port=self.srv.port, timeout=mbsim.WAIT_S)
        self.assertTrue(self.c.connect())

    def tearDown(self):
        self.c.close()
        self.srv.stop()

    def test_floats_and_blocks(self):
        # Given the harness ticking, when pymodbus reads whole object blocks,
        # then its own float decoder (Endian.Big/Big) gives the synthetic
        # values of one tick: head/tail generation, cycle, t, x, y, z agree.
        for i in range(100):
            k = i % 2
            rr = self.c.read_input_registers(obj_base(k), mbsim.BLOCK, slave=1)
            self.assertFalse(rr.isError(), rr)
            r = rr.registers
            self.assertIsNone(mbsim.check_synthetic_block(r, k))
            d = decoder(r)
            gen = d.decode_32bit_uint()
            d.skip_bytes(2 * (M["MBMAP_O_T_S"] - 2))
            t = d.decode_64bit_float()
            x, y, z = d.decode_32bit_float(), d.decode_32bit_float(), d.decode_32bit_float()
            self.assertEqual(t, gen * 0.001)
            self.assertEqual((x, y, z), (gen + 1000.0 * k, gen + 1000.0 * k + 0.25,
                                         gen + 1000.0 * k + 0.5))

    def test_waypoints_and_commands(self):
        # Given writes enabled, when pymodbus writes waypoint blocks built with
        # its own payload builder (u32 + 4 x f64, Endian.Big), then the engine
        # side sees them (accepted, last_seq); a backwards time and an unknown
        # command are refused with exception 03 and counted.
        def wp(seq, t, x):
            b = BinaryPayloadBuilder(byteorder=Endian.Big, wordorder=Endian.Big)
            b.add_32bit_uint(seq)
            for v in (t, x, 2 * x, -x):
                b.add_64bit_float(v)
            return b.to_registers()
        base = obj_base(1)
        for i in range(1, 21):
            rq = self.c.write_registers(base + M["MBMAP_H_WP"], wp(i, i * 0.5, i * 1.5), slave=1)
            self.assertFalse(rq.isError(), rq)
        rq = self.c.write_registers(base + M["MBMAP_H_WP"], wp(21, 1.0, 0.0), slave=1)
        self.assertTrue(rq.isError())
        self.assertEqual(rq.exception_code, 3)
        rq = self.c.write_register(base + M["MBMAP_H_COMMAND"], 77, slave=1)
        self.assertEqual(rq.exception_code, 3)
        rq = self.c.write_register(base + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_STOP"], slave=1)
        self.assertFalse(rq.isError(), rq)
        # The snapshot shows it from the next tick on: wait for two generations.
        g0 = mbsim.u32(self.c.read_input_registers(M["MBMAP_D_GEN"], 2, slave=1).registers, 0)
        for _ in range(10000):
            r = self.c.read_input_registers(base, mbsim.BLOCK, slave=1).registers
            if mbsim.u32(r, 0) >= g0 + 2:
                break
        self.assertEqual(mbsim.u32(r, M["MBMAP_O_ACCEPTED"]), 20)
        self.assertEqual(mbsim.u32(r, M["MBMAP_O_LAST_SEQ"]), 20)
        self.assertEqual(mbsim.u32(r, M["MBMAP_O_MB_REJECTED"]), 2)
        self.assertEqual(r[M["MBMAP_O_STATE"]], 3)   # the fake engine: stop -> finished


class RawTest(unittest.TestCase):
    def setUp(self):
        self.srv = mbsim.Server(["--objects", "2", "--writes", "1", "--max-clients", "64",
                                 "--idle-ms", "60000"])

    def tearDown(self):
        self.assertTrue(self.srv.alive())
        stats = self.srv.stop()
        self.assertGreater(stats["requests"], 0)

    def assert_alive(self):
        s = mbsim.connect(self.srv.port)
        r = mbsim.read_input(s, 0, 3)
        self.assertEqual(r[0], M["MBMAP_MAGIC"])
        s.close()

    def test_every_unserved_function(self):
        # Given one connection, when each function code 0..127 other than 3,
        # 4, 6, 16 is sent (with a plausible 4-byte body), then each is
        # answered with exception 01 on the same connection.
        s = mbsim.connect(self.srv.port)
        for fc in range(128):
            if fc in SERVED:
                continue
            rsp = mbsim.transact(s, bytes([fc, 0, 0, 0, 1]), tid=fc)
            self.assertEqual(rsp, bytes([fc | 0x80, 1]), "fc %d" % fc)
        s.close()
        # Codes 128..255 are the exception range, not functions: no answer
        # can be formed (fc + 0x80 overflows), the connection is dropped.
        for fc in (0x80, 0x83, 0xff):
            s = mbsim.connect(self.srv.port)
            s.sendall(mbsim.adu(1, bytes([fc, 0, 0, 0, 1])))
            self.assertTrue(mbsim.closed_within(s, mbsim.WAIT_S), fc)
            s.close()

    def test_addresses_and_counts(self):
        # Given 2 objects (registers 0..299), when reads and writes go past the
        # end or use counts outside the spec, then 02 and 03 come back.
        s = mbsim.connect(self.srv.port)
        end = mbsim.BLOCK * 3
        cases = [
            (struct.pack(">BHH", 4, end - 1, 2), 2),
            (struct.pack(">BHH", 3, end, 1), 2),
            (struct.pack(">BHH", 4, 65535, 125), 2),
            (struct.pack(">BHH", 4, 0, 0), 3),
            (struct.pack(">BHH", 4, 0, 126), 3),
            (struct.pack(">BHH", 3, 0, 2000), 3),
            (struct.pack(">BHH", 6, end, 1), 2),
            (struct.pack(">BHH", 6, 5, 1), 2),                 # daemon block is read-only
            (struct.pack(">BHHB", 16, 100, 2, 4) + b"\0" * 4, 2),  # not a field
            (struct.pack(">BHHB", 16, 100, 124, 246) + b"\0" * 246, 3),  # > 123 registers
            (struct.pack(">BHHB", 16, 100, 0, 0), 3),
            (struct.pack(">BHHB", 16, 100, 1, 3) + b"\0" * 3, 3),  # byte count lies
            (struct.pack(">BHH", 4, 0, 1) + b"\0", 3),          # trailing byte
            (bytes([4, 0]), 3),                                 # truncated
        ]
        for i, (pdu, code) in enumerate(cases):
            rsp = mbsim.transact(s, pdu, tid=i)
            self.assertEqual(rsp, bytes([pdu[0] | 0x80, code]), "case %d %r" % (i, pdu))
        s.close()

    def test_malformed_adus(self):
        # Given raw byte streams that are not Modbus/TCP, when sent, then the
        # connection is closed (no resynchronisation is possible) and the
        # server still answers others.
        bad = [
            mbsim.adu(1, b"\x04\x00\x00\x00\x01", proto=1),
            mbsim.adu(1, b"\x04", length=0),
            mbsim.adu(1, b"\x04", length=1),
            mbsim.adu(1, b"\x04" * 300, length=300),
            bytes(range(64)) + b"\xff" * 7,          # protocol id 0x0203
        ]
        for raw in bad:
            s = mbsim.connect(self.srv.port)
            s.sendall(raw)
            self.assertTrue(mbsim.closed_within(s, mbsim.WAIT_S), raw[:16])
            s.close()
        # A request split byte by byte is still one request.
        s = mbsim.connect(self.srv.port)
        for b in mbsim.adu(9, struct.pack(">BHH", 4, 0, 1)):
            s.send(bytes([b]))
        hdr = mbsim.recv_exact(s, 7)
        self.assertEqual(struct.unpack(">H", hdr[:2])[0], 9)
        s.close()
        # Two pipelined requests in one segment: two answers, in order.
        s = mbsim.connect(self.srv.port)
        s.sendall(mbsim.adu(1, struct.pack(">BHH", 4, 0, 1)) + mbsim.adu(2, struct.pack(">BHH", 4, 1, 1)))
        a, b = mbsim.recv_exact(s, 11), mbsim.recv_exact(s, 11)
        self.assertEqual((a[:2], b[:2]), (b"\0\1", b"\0\2"))
        s.close()
        self.assert_alive()

    def test_random_garbage_connections(self):
        # Given 100 connections sending random bytes (fixed seed), then the
        # server survives and answers a proper client.
        import random
        rnd = random.Random(1234)
        for _ in range(100):
            s = mbsim.connect(self.srv.port)
            try:
                s.sendall(bytes(rnd.getrandbits(8) for _ in range(rnd.randint(1, 600))))
            except OSError:
                pass
            s.close()
        self.assert_alive()

    def test_silent_and_many_connections(self):
        # Given 30 clients that connect and say nothing, and then 200
        # connections opened at once (max 64 clients), then a new client is
        # still answered at once, and nothing crashes.
        silent = [mbsim.connect(self.srv.port) for _ in range(30)]
        self.assert_alive()
        many = []
        for _ in range(200):
            try:
                many.append(socket.create_connection(("127.0.0.1", self.srv.port), timeout=mbsim.WAIT_S))
            except OSError:
                pass
        for s in many:
            s.close()
        for s in silent:
            s.close()
        self.assert_alive()
        # Partial request then silence: the half request never blocks others.
        s = mbsim.connect(self.srv.port)
        s.sendall(mbsim.adu(1, struct.pack(">BHH", 4, 0, 1))[:9])
        self.assert_alive()
        s.close()


class ShortLoadTest(unittest.TestCase):
    def test_no_torn_reads_under_load(self):
        # Given 4 objects ticking at 1 kHz and 50 clients reading whole blocks
        # back to back for LOAD_SECONDS, then no block mixes two ticks, every
        # client was answered, and the server is alive.  Rates are printed.
        srv = mbsim.Server(["--objects", "4", "--max-clients", "64"])
        n, torn, counts, errors = mbsim.load(srv.port, 50, LOAD_SECONDS, 4)
        stats = srv.stop()
        print("load: %d requests in %.0f s = %.0f req/s; lateness p99 %d us max %d us; missed %d"
              % (n, LOAD_SECONDS, n / LOAD_SECONDS, stats["late_p99_us"], stats["late_max_us"],
                 stats["missed"]))
        self.assertEqual(errors, [])
        self.assertEqual(torn, [])
        self.assertTrue(all(c > 0 for c in counts), counts)


if __name__ == "__main__":
    unittest.main(verbosity=2)
