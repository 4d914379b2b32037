#!/usr/bin/env python3
"""trajd_modbus_hmi.py - read trajd's status over Modbus TCP, as an HMI would.

Needs python3-pymodbus (Debian).  Prints the daemon block and, per object,
its state, track time, position, velocity and counters; once, or every
--interval seconds.  The register map is config/PROTOCOL.md "Modbus"
(installed as trajd.conf(5) / share/doc/trajd); addresses are 0-based.

  trajd_modbus_hmi.py [--host 127.0.0.1] [--port 1502] [--unit 1]
                      [--word-order ABCD|CDAB|BADC|DCBA] [--fc03] [--interval S]

--word-order must match [modbus] word_order of the daemon; --fc03 reads the
holding-register mirror (holding 20000 + a = input a) for devices that only
do function 03.  Exit status: 0, or 1 if trajd did not answer or is not trajd.
"""
import argparse
import sys
import time

from pymodbus.client import ModbusTcpClient
from pymodbus.constants import Endian
from pymodbus.payload import BinaryPayloadDecoder

MAGIC = 0x7444          # input register 0
MIRROR = 20000          # FC 03 mirror of the input registers
BLOCK = 100             # object k at 100 * (k + 1)
STATES = {0: "waiting", 1: "streaming", 2: "underrun", 3: "finished"}
CAN_STATES = {0: "-", 1: "error-active", 2: "error-warning", 3: "error-passive", 4: "bus-off",
              5: "down"}
# byteorder (within a word), wordorder, per [modbus] word_order
ORDERS = {"ABCD": (Endian.Big, Endian.Big), "CDAB": (Endian.Big, Endian.Little),
          "BADC": (Endian.Little, Endian.Big), "DCBA": (Endian.Little, Endian.Little)}


class Block:
    """Registers of one block, decoded in the daemon's word order."""

    def __init__(self, regs, order):
        self.regs, (self.bo, self.wo) = regs, ORDERS[order]

    def dec(self, off, n):
        return BinaryPayloadDecoder.fromRegisters(self.regs[off:off + n], byteorder=self.bo,
                                                  wordorder=self.wo)

    def u16(self, off):
        return self.regs[off]

    def u32(self, off):
        return self.dec(off, 2).decode_32bit_uint()

    def f32(self, off):
        return self.dec(off, 2).decode_32bit_float()

    def f64(self, off):
        return self.dec(off, 4).decode_64bit_float()


def read_block(c, base, args):
    """One whole block in one request: every value from the same tick."""
    if args.fc03:
        rr = c.read_holding_registers(MIRROR + base, BLOCK, slave=args.unit)
    else:
        rr = c.read_input_registers(base, BLOCK, slave=args.unit)
    if rr.isError():
        raise IOError("Modbus read at %d: %s" % (base, rr))
    return Block(rr.registers, args.word_order)


def show(c, args):
    d = read_block(c, 0, args)
    if d.u16(0) != MAGIC:
        raise IOError("register 0 is 0x%04X, not trajd's 0x%04X" % (d.u16(0), MAGIC))
    n = d.u16(2)
    print("trajd map v%d: %d object block(s), period %d us, uptime %d s, lateness p99 %d us, "
          "CAN %s, Modbus requests %d" % (d.u16(1), n, d.u32(8), d.u32(6), d.u32(12),
                                          CAN_STATES.get(d.u16(18), d.u16(18)), d.u32(20)))
    # Object k's block sits at 100 * (k + 1), k = its [object] id (register 2
    # counts the blocks); blocks of unused ids read as zeros (generation 0).
    for k in range(n):
        o = read_block(c, BLOCK * (k + 1), args)
        if o.u32(0) == 0:
            continue
        print("object %d: %s t=%.6f s pos=(%.4f, %.4f, %.4f) m vel=(%.3f, %.3f, %.3f) m/s "
              "buffered %d free %d accepted %d rejected %d lost %d underruns %d"
              % (k, STATES.get(o.u16(2), o.u16(2)), o.f64(18), o.f32(22), o.f32(24),
                 o.f32(26), o.f32(28), o.f32(30), o.f32(32), o.u32(8), o.u32(10),
                 o.u32(40), o.u32(42), o.u32(44), o.u32(46)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=1502)
    ap.add_argument("--unit", type=int, default=1)
    ap.add_argument("--word-order", default="ABCD", type=str.upper, choices=sorted(ORDERS))
    ap.add_argument("--fc03", action="store_true", help="read the holding-register mirror")
    ap.add_argument("--interval", type=float, default=0, help="repeat every S seconds")
    args = ap.parse_args()
    c = ModbusTcpClient(args.host, port=args.port, timeout=3)
    if not c.connect():
        print("cannot connect to %s:%d" % (args.host, args.port), file=sys.stderr)
        return 1
    try:
        while True:
            show(c, args)
            if args.interval <= 0:
                return 0
            time.sleep(args.interval)
    except (IOError, KeyboardInterrupt) as e:
        if isinstance(e, KeyboardInterrupt):
            return 0
        print(e, file=sys.stderr)
        return 1
    finally:
        c.close()


if __name__ == "__main__":
    sys.exit(main())
