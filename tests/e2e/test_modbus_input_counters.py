"""test_modbus_input_counters.py - what a CAN input lost and resynced, and the time the
object's own limits cost, are on Modbus too (never silent: every refused input and lost
byte is visible on Modbus and CAN status).

The real trajd with Modbus on 127.0.0.1 and two objects:
- 'boat' is fed by a candump log (the CAN log_in transport: the codec and can_port of a
  socket, no kernel CAN) of a real track's waypoint frames, made by canmatrix from
  config/trajd.dbc (tests/helpers/cantools_trajd.py), in which waypoints 40..42 are missing
  (3 lost) and the sender restarts its numbering after waypoint 100 (1 resync);
- 'line' replays a straight line at 3 m/s whose stamps are jittered by +-30 ms (the track
  of test_limits_lag_told.py): the curve through them bends harder than profile auto's
  acceleration limit, and the output loses time to it (limits_lost_s).
Read with pymodbus while trajd runs: boat's object block `lost` is 3 and its diagnostics
block `resyncs` is 1, as trajd's own CAN summary line and the STATUS frames (ST_Lost,
decoded by canmatrix) say, and the reset-counters command written on Modbus
zeroes them on both; line's diagnostics `limits_lost_s` equals the time its exit
line says was lost (to its 0.1 s) and `limits_slowed` is above 0.  Before, `lost` read 0
for an object fed on CAN (only a Modbus-fed object's gaps were counted there), and there
was no register for resyncs or for the time lost to the limits.
Every wait is bounded; trajd is stopped by pid.
"""
import os
import random
import re
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

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
WAIT_S = 60
LOST = (40, 41, 42)  # waypoints whose frames are left out of the log
RESTART_AFTER = 100  # the sender numbers the waypoints after this one from 1 again
FINISHED = 3  # engine_state_t ENGINE_STATE_FINISHED (lib/motion.h)


def jittered(path):
    rnd = random.Random(1)
    with open(path, "w") as f:
        f.write("t,x,y\n")
        for i in range(1000):
            t = 0.1 * i
            j = rnd.uniform(-0.03, 0.03) if i else 0.0
            f.write("%.3f,%.4f,0\n" % (t + j, 3.0 * t))


def faulty_log(tmp):
    """The track as waypoint frames, LOST left out and the numbering restarted."""
    xyz, wp = os.path.join(tmp, "track.csv"), os.path.join(tmp, "wp.log")
    ct.to_xyz(TRACK, xyz, 200)
    ct.write_wplog(xyz, wp, iface="vcan0")
    out = []
    with open(wp) as fh:
        for line in fh.read().splitlines():
            f = line.split()[-1] if not line.startswith("#") else ""
            if f.startswith("680#") and f[4:6] != "04":
                seq = int(f[6:8], 16)
                if seq in LOST:
                    continue
                if seq > RESTART_AFTER:
                    line = line.replace(f, f[:6] + "%02X" % (seq - RESTART_AFTER) + f[8:])
            out.append(line)
    with open(wp, "w") as fh:
        fh.write("\n".join(out) + "\n")


def regs(c, addr, n):
    rr = c.read_input_registers(addr, n, slave=1)
    assert not rr.isError(), rr
    return rr.registers


class InputCounters(unittest.TestCase):
    def test_can_lost_resyncs_and_limits_on_modbus(self):
        with tempfile.TemporaryDirectory() as tmp:
            faulty_log(tmp)
            jittered(os.path.join(tmp, "jit.csv"))
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nspeed = 20\nstatus_interval_s = 0\n"
                        "stop_timeout_s = 1\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\nwrites = yes\n"
                        "[can]\nlog_in = wp.log\nlog_out = sp.log\nlog_ifname = vcan0\n"
                        "log_time = engine\nmax_late_ms = 0\n"
                        "[object.boat]\nid = 0\ninput = can\noutput = can\nwritable = yes\n"
                        "[object.line]\nid = 1\ninput = replay\nreplay.track = jit.csv\n"
                        "output = csv\ncsv.path = line.csv\n")
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S, cwd=tmp)
            try:
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                boat, boat_x = mbsim.obj_base(0), M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])
                line_x = boat_x + M["MBMAP_BLOCK"]
                deadline = time.monotonic() + WAIT_S
                for base in (boat, mbsim.obj_base(1)):  # both at the end of their tracks
                    while regs(c, base + M["MBMAP_O_STATE"], 1)[0] != FINISHED:
                        self.assertLess(time.monotonic(), deadline, "".join(lines.all)[-3000:])
                        time.sleep(0.1)
                while True:
                    lost = mbsim.u32(regs(c, boat + M["MBMAP_O_LOST"], 2), 0)
                    resyncs = mbsim.u32(regs(c, boat_x + M["MBMAP_X_RESYNCS"], 2), 0)
                    if (lost, resyncs) == (len(LOST), 1) or time.monotonic() > deadline:
                        break
                    time.sleep(0.1)
                self.assertEqual((lost, resyncs), (len(LOST), 1), "boat: lost, resyncs on Modbus")
                r = regs(c, line_x + M["MBMAP_X_LIMITS_LOST_S"], 6)
                lost_s, slowed = mbsim.f64(r, 0), mbsim.u32(r, 4)
                self.assertGreater(slowed, 0)
                # the reset-counters command (Modbus) resets what CAN counted too
                w = c.write_register(boat + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_RESET_COUNTERS"],
                                     slave=1)
                self.assertFalse(w.isError(), w)
                deadline = time.monotonic() + WAIT_S
                while mbsim.u32(regs(c, boat + M["MBMAP_O_LOST"], 2), 0) != 0:
                    self.assertLess(time.monotonic(), deadline, "lost not reset")
                    time.sleep(0.1)
                self.assertEqual(mbsim.u32(regs(c, boat_x + M["MBMAP_X_RESYNCS"], 2), 0), 0)
                c.close()
            finally:
                p.send_signal(signal.SIGTERM)
                rc = p.wait(WAIT_S)
            lines.wait_for("\0", WAIT_S)  # the rest, to the end
            err = "".join(lines.all)
            self.assertEqual(rc, 0, err[-3000:])
            m = re.search(r"line finished [^;]*, ([\d.]+) s lost to its speed/acceleration "
                          r"limits", err)
            self.assertIsNotNone(m, err[-3000:])
            self.assertGreater(float(m.group(1)), 1.0)
            self.assertLessEqual(abs(lost_s - float(m.group(1))), 0.051, (lost_s, m.group(1)))
            resync = [x for x in err.splitlines() if "restarted its numbering" in x]
            self.assertEqual(len(resync), 1, err[-3000:])
            st = [int(s["ST_Lost"]) for _, s in ct.decode_by_id(os.path.join(tmp, "sp.log"), 0x6C0)]
            self.assertIn(len(LOST), st)  # STATUS said it, until the reset
            self.assertEqual(st[-1], 0)


if __name__ == "__main__":
    unittest.main(verbosity=2)
