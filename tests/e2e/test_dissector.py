"""test_dissector.py - config/trajd.lua (Wireshark dissector) against canmatrix with config/trajd.dbc.

1. A real run: waypoint frames of the figure-eight track (built by canmatrix,
   classic for object 0 and CAN FD for object 1) replayed by trajd from a
   candump log; trajd's output (SETPOINT, SETPOINT_FD, STATUS) written as a
   candump log.  Both logs are read by python-can and written as one pcap
   (LINKTYPE_CAN_SOCKETCAN, the format of a live capture on can0).
2. To that capture are added, for every frame and every multiplexer value of
   the DBC, one frame canmatrix encodes with random values, so every signal
   occurs; tshark, with the dissector loaded (-X lua_script:), prints every
   trajd.* field named after a signal of the DBC, and each signal must be
   shown at least once (tshark prints an unknown field as empty, so this is
   what catches a signal the dissector lacks).
3. Frame by frame, signal by signal, tshark's values equal canmatrix's
   decoding of the same bytes with config/trajd.dbc (multiplexed signals
   only when selected; a setpoint position 0x80000000 is shown as
   trajd.no_position instead, and STATUS2 page 3's n/a codes (the minimum of
   ST2_Age, ST2_Drift: the run's relative-time objects have no data age) by
   name in trajd.not_available), and trajd.obj is the object of the id.
Every frame type must occur, so the comparison cannot pass empty.
"""
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import can  # noqa: E402
import canmatrix  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
LUA = os.path.join(ROOT, "config", "trajd.lua")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
BASES = {0x680: "TRAJD_WAYPOINT", 0x690: "TRAJD_WAYPOINT_FD", 0x6A0: "TRAJD_SETPOINT",
         0x6B0: "TRAJD_SETPOINT_FD", 0x6C0: "TRAJD_STATUS", 0x6D0: "TRAJD_STATUS2"}
NO_POS = -214748.3648   # 0x80000000 at 0.1 mm
NOT_AVAILABLE = {"ST2_Age": -8388.608, "ST2_Drift": -3276.8}   # the fields' minimum
LINKTYPE_CAN_SOCKETCAN = 227
CANFD_FDF = 0x04


def write_pcap(msgs, path):
    """pcap (microseconds) of python-can messages: 8-byte SocketCAN header
    (can_id big-endian, length, FD flags), data padded to 8 or 64 bytes."""
    with open(path, "wb") as f:
        f.write(struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, LINKTYPE_CAN_SOCKETCAN))
        for m in msgs:
            flags = CANFD_FDF | (0x01 if m.bitrate_switch else 0) if m.is_fd else 0
            data = bytes(m.data).ljust(64 if m.is_fd else 8, b"\0")
            rec = struct.pack(">IBBxx", m.arbitration_id, len(m.data), flags) + data
            us = round(m.timestamp * 1e6)
            f.write(struct.pack("<IIII", us // 1000000, us % 1000000, len(rec), len(rec)) + rec)


def synthetic(frames):
    """One message per frame and multiplexer value, encoded by canmatrix from
    random raw values within each signal's range."""
    rng = random.Random(14)
    out, t = [], 1e6
    for base, fr in sorted(frames.items()):
        muxes = sorted({s.mux_val for s in fr.signals if s.mux_val is not None}) or [None]
        for mv in muxes:
            vals = {}
            for s in fr.signals:
                if s.is_multiplexer:
                    vals[s.name] = mv
                elif s.mux_val in (None, mv):
                    hi = (1 << (s.size - 1)) - 1 if s.is_signed else (1 << s.size) - 1
                    vals[s.name] = rng.randint(0, min(hi, 10 ** 6))
            t += 0.001
            out.append(can.Message(timestamp=t, arbitration_id=base, is_extended_id=False,
                                   is_fd=fr.is_fd, data=bytes(fr.encode(vals))))
    return out


class DissectorTest(unittest.TestCase):
    def test_fields_equal_canmatrix(self):
        self.assertTrue(shutil.which("tshark"), "tshark not installed (make deps installs it)")
        db = ct.load_db()
        frames = {b: db.frame_by_id(canmatrix.ArbitrationId(b)) for b in BASES}
        signals = sorted({s.name for fr in frames.values() for s in fr.signals})
        with tempfile.TemporaryDirectory() as d:
            xyz = os.path.join(d, "track.csv")
            ct.to_xyz(TRACK, xyz, 40)
            ct.write_wplog(xyz, os.path.join(d, "wp.log"), also_fd_obj=1)
            with open(os.path.join(d, "t.conf"), "w") as fh:
                fh.write("[daemon]\nrate_hz = 20\nspeed = 30\nexit_when_done = yes\n"
                         "stop_timeout_s = 1\nstatus_interval_s = 0\n"
                         "[can]\nlog_in = wp.log\nlog_out = sp.log\nfd = yes\nmax_late_ms = 0\n"
                         "[object.boat]\nid = 0\ninput = can\noutput = can\n"
                         "[object.fdboat]\nid = 1\ninput = can\noutput = can\ncan.fd = yes\n")
            r = subprocess.run([TRAJD, "-f", "-c", "t.conf"], cwd=d, capture_output=True,
                               text=True, timeout=120)
            self.assertEqual(r.returncode, 0, r.stderr)
            msgs = []
            for log in ("wp.log", "sp.log"):   # python-can reads no comment lines
                with open(os.path.join(d, log)) as fh, open(os.path.join(d, "c.log"), "w") as c:
                    c.writelines(line for line in fh if not line.startswith("#"))
                reader = can.CanutilsLogReader(os.path.join(d, "c.log"))
                msgs += list(reader)
                reader.stop()
            msgs += synthetic(frames)
            pcap = os.path.join(d, "trajd.pcap")
            write_pcap(msgs, pcap)
            cmd = ["tshark", "-n", "-X", "lua_script:" + LUA, "-r", pcap, "-T", "fields",
                   "-E", "separator=\t", "-E", "occurrence=f", "-e", "trajd.obj",
                   "-e", "trajd.no_position", "-e", "trajd.not_available"]
            cmd += [a for s in signals for a in ("-e", "trajd." + s)]
            out = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
            self.assertEqual(out.returncode, 0, out.stderr)
            rows = out.stdout.splitlines()
            self.assertEqual(len(rows), len(msgs))
            seen, shown = {}, set()
            for m, row in zip(msgs, rows):
                shown |= {s for i, s in enumerate(signals) if row.split("\t")[3 + i] != ""}
                cols = row.split("\t")
                base = m.arbitration_id & ~0xF
                if base not in BASES:
                    self.assertEqual(cols[0], "", (hex(m.arbitration_id), row))
                    continue
                seen[base] = seen.get(base, 0) + 1
                self.check_frame(frames[base], m, cols, signals)
            self.assertEqual(set(seen), set(BASES), seen)
            self.assertEqual(set(signals) - shown, set())
            self.assertGreater(getattr(self, "na_seen", 0), 0, "no STATUS2 page 3 with no age")

    def check_frame(self, fr, m, cols, signals):
        where = "%s %s#%s" % (m.timestamp, hex(m.arbitration_id), bytes(m.data).hex())
        self.assertEqual(int(cols[0]), m.arbitration_id & 0xF, where)
        want = {k: float(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}
        got = {s: cols[3 + i] for i, s in enumerate(signals) if cols[3 + i] != ""}
        nopos = [k for k, v in want.items() if v == NO_POS and ("_Pos" in k or
                                                                 k in ("SPFD_X", "SPFD_Y", "SPFD_Z"))]
        for k in nopos:
            del want[k]
        self.assertEqual(cols[1] in ("1", "True"), bool(nopos), where)
        na = sorted(k for k, v in want.items() if NOT_AVAILABLE.get(k) == v)
        for k in na:
            del want[k]
        self.assertEqual(sorted(filter(None, cols[2].split(","))), na, where)
        self.na_seen = getattr(self, "na_seen", 0) + len(na)
        self.assertEqual(set(got), set(want), where)
        for k, v in want.items():
            self.assertAlmostEqual(float(got[k]), v, delta=1e-9 * max(1.0, abs(v)),
                                   msg="%s %s" % (where, k))


if __name__ == "__main__":
    unittest.main()
