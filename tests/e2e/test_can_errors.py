"""test_can_errors.py - the CAN bus state from SocketCAN error frames, end to end on the host.

trajd reads a candump log (`[can] log_in`) holding error frames as the kernel
delivers them (can_id with CAN_ERR_FLAG, DLC 8), built here from the
constants of linux/can/error.h (not from trajd's headers): a controller going
error-warning, error-passive (with CAN_ERR_CNT error counters), bus-off,
restarted, then a protocol error, an RX overflow and warning again.  Then:
- the Modbus daemon block (read by pymodbus) gives can_state = warning and
  the counters the sequence implies (entries into each state, restarts, bus
  errors, overflows, the last TX/RX error counters);
- trajd logs each state change in order, with the interface;
- its CAN output (log_out) carries the state in STATUS2 page 5 (decoded by
  canmatrix with config/trajd.dbc): bus-off while it lasted, at the end
  warning with the counters;
- frames are spaced wider than the daemon's 100 ms housekeeping, so every
  state is published once.
Real kernel error frames on vcan0 are injected in the UML guest
(tests/uml/canerr.sh, run by test_can_uml.sh).
"""
import os
import re
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
import cantools_trajd as ct  # noqa: E402
import can  # noqa: E402
import canmatrix  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")


def kernel_constants():
    with open("/usr/include/linux/can/error.h") as f:
        text = f.read()
    k = {m.group(1): int(m.group(2), 16) for m in
         re.finditer(r"#define (CAN_ERR_\w+)\s+0x([0-9A-Fa-f]+)", text)}
    with open("/usr/include/linux/can.h") as f:
        k["CAN_ERR_FLAG"] = int(re.search(r"#define CAN_ERR_FLAG\s+0x([0-9A-Fa-f]+)",
                                          f.read()).group(1), 16)
    return k


K = kernel_constants()


def err_frame(cls, crtl=0, tx=0, rx=0, prot=0):
    data = [0, crtl, prot, 0, 0, 0, tx, rx]
    return "%08X#%s" % (K["CAN_ERR_FLAG"] | cls, "".join("%02X" % b for b in data))


# (frame, state after it or None if unchanged)
SEQUENCE = [
    (err_frame(K["CAN_ERR_CRTL"], K["CAN_ERR_CRTL_RX_WARNING"]), "error-warning"),
    (err_frame(K["CAN_ERR_CRTL"] | K["CAN_ERR_CNT"], K["CAN_ERR_CRTL_TX_PASSIVE"], 128, 5),
     "error-passive"),
    (err_frame(K["CAN_ERR_BUSOFF"]), "bus-off"),
    (err_frame(K["CAN_ERR_RESTARTED"]), "error-active"),
    (err_frame(K["CAN_ERR_PROT"] | K["CAN_ERR_BUSERROR"], prot=K["CAN_ERR_PROT_BIT"]), None),
    (err_frame(K["CAN_ERR_CRTL"], K["CAN_ERR_CRTL_RX_OVERFLOW"]), None),
    (err_frame(K["CAN_ERR_CRTL"] | K["CAN_ERR_CNT"], K["CAN_ERR_CRTL_TX_WARNING"], 100, 3),
     "error-warning"),
]
GAP_S = 0.3   # between frames (log time = wall time at speed 1), > 100 ms housekeeping


def u32(regs, off):
    return regs[off] << 16 | regs[off + 1]


class CanErrorsTest(unittest.TestCase):
    def test_error_frames_to_state_and_counters(self):
        with tempfile.TemporaryDirectory() as tmp:
            with open(os.path.join(tmp, "err.log"), "w") as f:
                for i, (fr, _) in enumerate(SEQUENCE):
                    f.write("(%.6f) can0 %s\n" % (1 + i * GAP_S, fr))
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 50\nstatus_interval_s = 0\n"
                        "[modbus]\nport = 0\nsystemd_socket = no\n"
                        "[can]\nlog_in = %s/err.log\nlog_out = %s/out.log\n"
                        "[object.boat]\ninput = can\noutput = can\n"
                        % (tmp, tmp))
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                line = lines.wait_for("modbus: TCP on")
                self.assertIsNotNone(line, "".join(lines.all))
                port = mbsim.port_of(line)
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=mbsim.WAIT_S)
                self.assertTrue(c.connect())
                deadline = time.monotonic() + 30
                while True:   # until every frame is counted (bounded)
                    rr = c.read_input_registers(0, 100, slave=1)
                    self.assertFalse(rr.isError(), rr)
                    r = rr.registers
                    if u32(r, M["MBMAP_D_CAN_ERR_FRAMES"]) >= len(SEQUENCE):
                        break
                    self.assertLess(time.monotonic(), deadline, r)
                    time.sleep(0.1)
                time.sleep(0.3)   # one more housekeeping: the state is published
                r = c.read_input_registers(0, 100, slave=1).registers
                c.close()
                self.assertEqual(r[M["MBMAP_D_CAN_STATE"]], M["MBMAP_CAN_WARNING"])
                want = {"MBMAP_D_CAN_ERR_FRAMES": 7, "MBMAP_D_CAN_WARNINGS": 2,
                        "MBMAP_D_CAN_PASSIVES": 1, "MBMAP_D_CAN_BUS_OFFS": 1,
                        "MBMAP_D_CAN_RESTARTS": 1, "MBMAP_D_CAN_BUS_ERRORS": 1,
                        "MBMAP_D_CAN_OVERFLOWS": 1}
                self.assertEqual({k: u32(r, M[k]) for k in want}, want)
                self.assertEqual((r[M["MBMAP_D_CAN_TX_ERR"]], r[M["MBMAP_D_CAN_RX_ERR"]]),
                                 (100, 3))
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(timeout=mbsim.WAIT_S + 10)
                lines.wait_for("\0", 0.5)
                p.stderr.close()
            # STATUS2 page 5 in trajd's CAN log, decoded by canmatrix with config/trajd.dbc
            db = ct.load_db()
            fr = db.frame_by_id(canmatrix.ArbitrationId(0x6D0))
            pages = []
            reader = can.CanutilsLogReader(os.path.join(tmp, "out.log"))
            for m in reader:
                if m.arbitration_id == 0x6D0:
                    d = {k: int(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}
                    if d["ST2_Page"] == 5:
                        pages.append(d)
            reader.stop()
            self.assertTrue(pages, "no STATUS2 page 5")
            self.assertEqual(pages[-1], {"ST2_Page": 5, "ST2_BusState": 2, "ST2_TxErr": 100,
                                         "ST2_RxErr": 3, "ST2_BusOffs": 1, "ST2_ErrFrames": 7})
            self.assertIn(4, [d["ST2_BusState"] for d in pages])   # bus-off was sent too
            logged = [m.group(1) for m in (re.search(r"controller (\S+) \(error frames", x)
                                           for x in lines.all) if m]
            self.assertEqual(logged, [s for _, s in SEQUENCE if s], "".join(lines.all))


if __name__ == "__main__":
    unittest.main()
