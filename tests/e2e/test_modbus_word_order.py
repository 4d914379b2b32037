"""test_modbus_word_order.py - [modbus] word_order and the FC 03 mirror in the running daemon.

For each word order (ABCD, CDAB, BADC, DCBA), trajd replays a boat to its end
and is fed waypoints over Modbus:
1. pymodbus's decoder, given that order (byteorder/wordorder), reads the
   daemon's output period (u32), the boat's final position (f32) and track
   time (f64) as the last row of trajd's CSV; the ABCD decoder does not
   (except for ABCD), so the option really reorders.
2. The same values come through the FC 03 mirror (holding register
   MBMAP_MIRROR_BASE + a = input register a), read by pymodbus and by mbpoll
   (`-t 4:float`: -B for ABCD, no -B for CDAB, mbpoll's only two orders).
3. pymodbus's payload builder writes waypoints in that order; trajd accepts
   them, and after the finish command the object rests on the last one.
4. A write into the mirror is exception 02; an unknown order is refused by
   trajd --check-config with file:line.
"""
import csv
import os
import signal
import struct
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.constants import Endian  # noqa: E402
from pymodbus.payload import BinaryPayloadBuilder, BinaryPayloadDecoder  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRACK = os.path.join(mbsim.ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
MIRROR = int(subprocess.run(["sed", "-n", r"s/^#define MBMAP_MIRROR_BASE \([0-9]*\).*/\1/p",
                             os.path.join(mbsim.ROOT, "lib", "proto", "mbmap.h")],
                            capture_output=True, text=True).stdout)
# byteorder (within a word), wordorder (of the words) per order name
ORDERS = {"ABCD": (Endian.Big, Endian.Big), "CDAB": (Endian.Big, Endian.Little),
          "BADC": (Endian.Little, Endian.Big), "DCBA": (Endian.Little, Endian.Little)}
WAYPOINTS = [(1, 0.0, 0.0, 0.0, 0.0), (2, 1.0, 0.5, 0.25, 0.0), (3, 2.0, 1.0, 0.5, 0.125),
             (4, 3.0, 1.5, 0.75, 0.25), (5, 4.0, 2.0, 1.0, 0.375)]


def f32(x):
    return struct.unpack(">f", struct.pack(">f", x))[0]


def mbpoll(port, *args):
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(port), "-a", "1", "-0", "-1"]
                         + list(args) + ["127.0.0.1"], capture_output=True, text=True,
                         timeout=mbsim.WAIT_S)
    return [line.split("\t")[1] for line in out.stdout.splitlines()
            if line.startswith("[") and "\t" in line], out.stdout + out.stderr


class WordOrderTest(unittest.TestCase):
    def run_order(self, order, tmp):
        conf = os.path.join(tmp, "trajd.conf")
        with open(conf, "w") as f:
            f.write("""[daemon]
rate_hz = 50
speed = 200
status_interval_s = 0
[modbus]
port = 0
writes = yes
systemd_socket = no
word_order = %s
[object.boat]
id = 0
input = replay
replay.track = %s
output = csv
csv.path = %s/boat.csv
[object.fed]
id = 1
input = modbus
output = csv
csv.path = %s/fed.csv
""" % (order, TRACK, tmp, tmp))
        p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = mbsim.Lines(p.stderr)
        try:
            line = lines.wait_for("modbus: TCP on")
            self.assertIsNotNone(line, "".join(lines.all))
            port = mbsim.port_of(line)
            self.check(order, port, tmp)
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(timeout=mbsim.WAIT_S + 10)
            p.stderr.close()

    def read(self, c, fc, addr, count):
        rr = (c.read_input_registers if fc == 4 else c.read_holding_registers)(addr, count, slave=1)
        self.assertFalse(rr.isError(), rr)
        return rr.registers

    def wait_state(self, c, k, state):
        mbsim.wait_input(c, obj_base(k) + M["MBMAP_O_STATE"], state,
                         "object %d never reached state %d" % (k, state), 30, 0.05)

    def check(self, order, port, tmp):
        bo, wo = ORDERS[order]
        c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
        self.assertTrue(c.connect())
        try:
            self.wait_state(c, 0, 3)   # the boat's replay is finished: its values rest
            deadline = time.monotonic() + 30   # the CSV is buffered: wait for a finished row
            while True:
                with open(os.path.join(tmp, "boat.csv")) as f:
                    last = list(csv.DictReader(f))[-1]
                if last["state"] == "finished" or time.monotonic() > deadline:
                    break
                time.sleep(0.1)
            base = obj_base(0)
            for fc, off in ((4, 0), (3, MIRROR)):
                regs = self.read(c, fc, off + base + M["MBMAP_O_T_S"], 10)
                dec = BinaryPayloadDecoder.fromRegisters(regs, byteorder=bo, wordorder=wo)
                t = dec.decode_64bit_float()
                xyz = [dec.decode_32bit_float() for _ in range(3)]
                self.assertEqual(t, float(last["t_s"]), (order, fc))
                self.assertEqual(xyz, [f32(float(last[a + "_m"])) for a in "xyz"], (order, fc))
                per = self.read(c, fc, off + M["MBMAP_D_PERIOD_US"], 2)
                self.assertEqual(BinaryPayloadDecoder.fromRegisters(
                    per, byteorder=bo, wordorder=wo).decode_32bit_uint(), 20000, (order, fc))
                abcd = BinaryPayloadDecoder.fromRegisters(
                    per, byteorder=Endian.Big, wordorder=Endian.Big).decode_32bit_uint()
                self.assertEqual(abcd == 20000, order == "ABCD", (order, fc, abcd))
            if order in ("ABCD", "CDAB"):
                flags = ["-B"] if order == "ABCD" else []
                v, out = mbpoll(port, "-r", str(MIRROR + base + M["MBMAP_O_POS"]), "-c", "3",
                                "-t", "4:float", *flags)
                self.assertEqual(len(v), 3, out)
                for got, a in zip(v, "xyz"):   # mbpoll prints 6 significant digits
                    self.assertAlmostEqual(float(got), float(last[a + "_m"]),
                                           delta=1e-5 * max(1, abs(float(last[a + "_m"]))))
                v, out = mbpoll(port, "-r", str(MIRROR + M["MBMAP_D_PERIOD_US"]), "-t", "4:int",
                                *flags)
                self.assertEqual(v, ["20000"], out)
            self.feed(c, bo, wo, order)
            rr = c.write_register(MIRROR + 100, 1, slave=1)
            self.assertTrue(rr.isError())
            self.assertEqual(rr.exception_code, 2)
        finally:
            c.close()

    def feed(self, c, bo, wo, order):
        fed = obj_base(1)
        for seq, t, x, y, z in WAYPOINTS:
            b = BinaryPayloadBuilder(byteorder=bo, wordorder=wo)
            b.add_32bit_uint(seq)
            for v in (t, x, y, z):
                b.add_64bit_float(v)
            rr = c.write_registers(fed + M["MBMAP_H_WP"], b.to_registers(), slave=1)
            self.assertFalse(rr.isError(), (order, seq, rr))
        rr = c.write_register(fed + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"], slave=1)
        self.assertFalse(rr.isError(), rr)
        self.wait_state(c, 1, 3)
        regs = self.read(c, 4, fed + M["MBMAP_O_POS"], 6)
        dec = BinaryPayloadDecoder.fromRegisters(regs, byteorder=bo, wordorder=wo)
        self.assertEqual([dec.decode_32bit_float() for _ in range(3)],
                         [f32(v) for v in WAYPOINTS[-1][2:]], order)
        regs = self.read(c, 4, fed + M["MBMAP_O_ACCEPTED"], 2)
        self.assertEqual(BinaryPayloadDecoder.fromRegisters(
            regs, byteorder=bo, wordorder=wo).decode_32bit_uint(), len(WAYPOINTS), order)

    def test_orders(self):
        for order in ORDERS:
            with self.subTest(order=order), tempfile.TemporaryDirectory() as tmp:
                self.run_order(order, tmp)

    def test_bad_order_refused(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "bad.conf")
            with open(conf, "w") as f:
                f.write("[modbus]\nport = 0\nword_order = ABDC\n\n[object.a]\ninput = replay\n"
                        "replay.track = %s\noutput = stdout\n" % TRACK)
            out = subprocess.run([TRAJD, "--check-config", conf], capture_output=True, text=True,
                                 timeout=mbsim.WAIT_S)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("bad.conf:3", out.stdout + out.stderr)


if __name__ == "__main__":
    unittest.main()
