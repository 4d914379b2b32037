"""test_dropped_and_delay_told.py - the waypoints a stop or clear drops are counted, and a
relative-time object's play-out delay D is shown where its status is read.

The real trajd replays a 60 s line (10 Hz, relative time) with Modbus on 127.0.0.1 and its
control socket in a temporary directory. While it streams:
- trajctl status (the control socket's JSON) gives delay_s equal to the D trajd logged when
  the trajectory started ("play-out delay D 2.377 s = ..."), and the Modbus diagnostics
  block's delay_s the same; they were null and absent (Modbus register 44, the daemon's
  clock_delay, read 10 s for it);
- trajctl clear drops the track buffered ahead: the JSON's dropped and the diagnostics
  block's dropped then agree and are above 0, and the exit line says how many. Before, no
  counter held them (probe: 600 waypoints written, 599 accounted for after a clear).
Every wait is bounded; trajd is stopped by pid.
"""
import json
import os
import re
import signal
import socket
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 30


def ctl(path, line):
    """One request on trajd's control socket (config/PROTOCOL.md "Control socket"): its
    JSON replies up to the status's "end", or the one reply of a command."""
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(WAIT_S)
    s.connect(path)
    f = s.makefile("r")
    json.loads(f.readline())  # the hello
    s.sendall(line.encode() + b"\n")
    out = []
    while True:
        m = json.loads(f.readline())
        out.append(m)
        if not line.startswith("status") or m.get("reply") == "end":
            break
    f.close()
    s.close()
    return out


def obj_status(sock):
    for r in ctl(sock, "status"):
        if r.get("object") == "a":
            return r
    raise AssertionError("no status of 'a'")


class DroppedAndDelayTold(unittest.TestCase):
    def test_clear_counts_dropped_and_d_shown(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "line.csv"), 600)
            sock = os.path.join(tmp, "ctl.sock")
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\ncontrol_socket = %s\n"
                        "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n"
                        "[object.a]\nid = 0\nwritable = yes\ninput = replay\n"
                        "replay.track = line.csv\noutput = csv\ncsv.path = a.csv\n" % sock)
            p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S, cwd=tmp)
            try:
                line = lines.wait_for("trajectory 1 streams: play-out delay D ", WAIT_S)
                self.assertIsNotNone(line, "".join(lines.all))
                d_logged = float(re.search(r"play-out delay D ([\d.]+) s", line).group(1))
                time.sleep(1.0)
                st = obj_status(sock)
                self.assertIsNotNone(st["delay_s"], st)
                self.assertAlmostEqual(st["delay_s"], d_logged, delta=0.0005)
                c = ModbusTcpClient("127.0.0.1", port=port, timeout=WAIT_S)
                self.assertTrue(c.connect())
                xb = M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"])
                rr = c.read_input_registers(xb + M["MBMAP_X_DELAY_S"], 4, slave=1)
                self.assertFalse(rr.isError(), rr)
                self.assertAlmostEqual(mbsim.f64(rr.registers, 0), d_logged, delta=0.0005)
                self.assertEqual(st["dropped"], 0)
                r = ctl(sock, "clear a")
                self.assertEqual(r[0].get("reply"), "ok", r)
                deadline = time.monotonic() + WAIT_S
                while True:  # at rest: what it dropped is counted
                    st = obj_status(sock)
                    rr = c.read_input_registers(xb + M["MBMAP_X_DROPPED"], 2, slave=1)
                    mb = mbsim.u32(rr.registers, 0)
                    if st["dropped"] > 0 and mb == st["dropped"]:
                        break
                    self.assertLess(time.monotonic(), deadline, (st, mb))
                    time.sleep(0.05)
                dropped = st["dropped"]
                self.assertGreater(dropped, 10)  # D's worth of waypoints, at least
                c.close()
            finally:
                p.send_signal(signal.SIGTERM)
                rc = p.wait(WAIT_S)
            lines.wait_for("\0", WAIT_S)
            err = "".join(lines.all)
            self.assertEqual(rc, 0, err[-3000:])
            self.assertRegex(err, r"; a [^;]*, (\d+) waypoints dropped by a stop, clear or reload")


if __name__ == "__main__":
    unittest.main(verbosity=2)
