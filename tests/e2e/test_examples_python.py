"""test_examples_python.py - the shipped Python clients (daemon/doc/examples/) against a real trajd.

1. trajd_modbus_hmi.py (pymodbus) reads a running trajd configured with
   [modbus] word_order = CDAB and two objects (ids 0 and 2): with
   --word-order CDAB, by FC 04 and through the FC 03 mirror, it prints the
   period, both objects, the replayed boat finished at the position of the
   last row of trajd's own CSV; with the wrong order the period is not read.
2. trajd_can_sender.py --log writes a track as a candump log: python-can
   reads it and canmatrix decodes every frame with config/trajd.dbc back to
   the track (to the micrometre / microsecond), ending with FINISH; trajd
   replays that log ([can] log_in), accepts every waypoint and finishes on
   the last one.  (Its paced mode on a live bus is run in the UML guest:
   tests/uml/daemon.sh.)
3. config/PROTOCOL.md's canmatrix snippet ("Feeding trajd from a log"), run
   as written: its frame is the X frame of waypoint 7 at 12.5 m, as the
   frame layout in that document gives it byte by byte.
"""
import csv
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import mbsim  # noqa: E402
import can  # noqa: E402
import canmatrix  # noqa: E402

ROOT = mbsim.ROOT
TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
EX = os.path.join(ROOT, "daemon", "doc", "examples")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
PY = "/usr/bin/python3"


def last_row(path):
    deadline = time.monotonic() + 30
    while True:   # the CSV is buffered: wait (bounded) for a finished row
        with open(path) as f:
            # a row the writer has not finished yet (read mid-write) has no
            # state: not the last one
            rows = [r for r in csv.DictReader(f) if r.get("state")]
        if (rows and rows[-1]["state"] == "finished") or time.monotonic() > deadline:
            return rows[-1]
        time.sleep(0.1)


class HmiReaderTest(unittest.TestCase):
    def test_hmi_reader(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 50\nspeed = 200\nstatus_interval_s = 0\n"
                        "[modbus]\nport = 0\nsystemd_socket = no\nwrites = yes\nword_order = CDAB\n"
                        "[object.boat]\nid = 0\ninput = replay\nreplay.track = %s\n"
                        "output = csv\ncsv.path = %s/boat.csv\n"
                        "[object.fed]\nid = 2\ninput = modbus\noutput = csv\ncsv.path = %s/fed.csv\n"
                        % (TRACK, tmp, tmp))
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            lines = mbsim.Lines(p.stderr)
            try:
                line = lines.wait_for("modbus: TCP on")
                self.assertIsNotNone(line, "".join(lines.all))
                port = line.split(" port ")[1].split(",")[0]
                last = last_row(os.path.join(tmp, "boat.csv"))
                self.assertEqual(last["state"], "finished")
                want = "pos=(%.4f, %.4f, %.4f) m" % tuple(float(last[a + "_m"]) for a in "xyz")
                for extra in ([], ["--fc03"]):
                    out = subprocess.run([PY, os.path.join(EX, "trajd_modbus_hmi.py"), "--port",
                                          port, "--word-order", "cdab"] + extra,
                                         capture_output=True, text=True, timeout=30)
                    self.assertEqual(out.returncode, 0, out.stderr)
                    o = out.stdout
                    self.assertIn("3 object block(s), period 20000 us", o)   # ids 0..2
                    obj0 = re.search(r"^object 0: (\w+) .*$", o, re.M)
                    self.assertIsNotNone(obj0, o)
                    self.assertEqual(obj0.group(1), "finished", o)
                    self.assertIn(want, obj0.group(0))
                    self.assertRegex(o, r"(?m)^object 2: waiting ")
                out = subprocess.run([PY, os.path.join(EX, "trajd_modbus_hmi.py"), "--port", port],
                                     capture_output=True, text=True, timeout=30)
                self.assertNotIn("period 20000 us", out.stdout)
                self.assertRegex(out.stdout, r"period \d+ us")
            finally:
                p.send_signal(signal.SIGTERM)
                p.wait(timeout=mbsim.WAIT_S + 10)
                p.stderr.close()


class CanSenderTest(unittest.TestCase):
    def test_sender_log(self):
        with tempfile.TemporaryDirectory() as tmp:
            xyz = os.path.join(tmp, "track.csv")
            ct.to_xyz(TRACK, xyz, 80)
            rows = ct.read_xyz(xyz)
            log = os.path.join(tmp, "wp.log")
            out = subprocess.run([PY, os.path.join(EX, "trajd_can_sender.py"), xyz, "--log", log],
                                 capture_output=True, text=True, timeout=30)
            self.assertEqual(out.returncode, 0, out.stderr)
            # canmatrix decodes the frames back to the track
            fr = ct.load_db().frame_by_id(canmatrix.ArbitrationId(0x680))
            got, cmds = {}, []
            reader = can.CanutilsLogReader(log)
            for m in reader:
                self.assertEqual(m.arbitration_id, 0x680)
                d = {k: float(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}
                if d["WP_Mux"] == 4:
                    cmds.append(d["WP_Command"])
                    continue
                key = ("WP_Time", "WP_X", "WP_Y", "WP_Z")[int(d["WP_Mux"])]
                got.setdefault(len(got) if d["WP_Mux"] == 0 else len(got) - 1, {})[key] = d[key]
                self.assertEqual(d["WP_Seq"], len(got) & 0xFF)
            reader.stop()
            self.assertEqual(cmds, [1])   # FINISH, last
            self.assertEqual(len(got), len(rows))
            for i, (t, x, y, z) in enumerate(rows):
                for k, v in zip(("WP_Time", "WP_X", "WP_Y", "WP_Z"), (t, x, y, z)):
                    self.assertAlmostEqual(got[i][k], float(v), delta=0.5e-6, msg=(i, k))
            # trajd replays the log, accepts every waypoint and rests on the last
            conf = os.path.join(tmp, "t.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 50\nspeed = 50\nexit_when_done = yes\n"
                        "status_interval_s = 0\n[can]\nlog_in = %s\nlog_out = %s/out.log\n"
                        "max_late_ms = 0\n[object.boat]\ninput = can\noutput = csv\n"
                        "csv.path = %s/sp.csv\n" % (log, tmp, tmp))
            r = subprocess.run([TRAJD, "-f", "-c", conf], capture_output=True, text=True,
                               timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertRegex(r.stderr, r"waypoints %d accepted, 0 rejected" % len(rows))
            with open(os.path.join(tmp, "sp.csv")) as f:
                last = list(csv.DictReader(f))[-1]
            self.assertEqual(last["state"], "finished")
            for a, v in zip("xyz", rows[-1][1:]):
                self.assertAlmostEqual(float(last[a + "_m"]), float(v), delta=1e-6)


    def test_sender_track_columns(self):
        # Given a track in degrees (the bundled lat/lon CSV), then the sender refuses it in
        # one line naming the columns it needs and why (it died with a Python KeyError
        # traceback); given t,x,y with no z, it sends z = 0.
        with tempfile.TemporaryDirectory() as tmp:
            out = subprocess.run([PY, os.path.join(EX, "trajd_can_sender.py"), TRACK, "--log",
                                  os.path.join(tmp, "wp.log")],
                                 capture_output=True, text=True, timeout=30)
            self.assertEqual(out.returncode, 1, out.stderr)
            self.assertNotIn("Traceback", out.stderr)
            self.assertIn("needs columns t_s (or t), x_m, y_m", out.stderr)
            self.assertIn("a track in degrees", out.stderr)
            xy = os.path.join(tmp, "xy.csv")
            with open(xy, "w") as f:
                f.write("t,x,y\n0,0,0\n0.5,1.25,-2\n")
            log = os.path.join(tmp, "xy.log")
            out = subprocess.run([PY, os.path.join(EX, "trajd_can_sender.py"), xy, "--log", log],
                                 capture_output=True, text=True, timeout=30)
            self.assertEqual(out.returncode, 0, out.stderr)
            fr = ct.load_db().frame_by_id(canmatrix.ArbitrationId(0x680))
            reader = can.CanutilsLogReader(log)
            dec = [{k: float(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}
                   for m in reader]
            reader.stop()
            self.assertEqual([(d["WP_Mux"], d.get("WP_X", d.get("WP_Y", d.get("WP_Z"))))
                              for d in dec if d["WP_Mux"] in (1, 2, 3)],
                             [(1, 0.0), (2, 0.0), (3, 0.0), (1, 1.25), (2, -2.0), (3, 0.0)])


class ProtocolSnippetTest(unittest.TestCase):
    def test_canmatrix_snippet(self):
        text = open(os.path.join(ROOT, "config", "PROTOCOL.md")).read()
        block = text.split("With canmatrix:\n\n", 1)[1].split("\n\n", 1)[0]
        code = "\n".join(line[6:] for line in block.splitlines())
        scope = {}
        cwd = os.getcwd()
        os.chdir(ROOT)   # the snippet names config/trajd.dbc from the repository's root
        try:
            exec(compile(code, "PROTOCOL.md", "exec"), scope)
        finally:
            os.chdir(cwd)
        # mux 1 (X), seq 7, then the position as int48 little-endian in um
        want = bytes([1, 7]) + (12500000).to_bytes(6, "little", signed=True)
        self.assertEqual(scope["data"], want)


if __name__ == "__main__":
    unittest.main()
