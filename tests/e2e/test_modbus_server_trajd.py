"""test_modbus_server_trajd.py - Modbus in the running daemon, with independent clients.

1. mbpoll reads trajd's registers (magic, objects, period; a replayed boat's
   position/velocity/acceleration as floats with -B) and the floats are a row
   of trajd's own CSV output rounded to float32; mbpoll writes a command
   (clear) and the state register follows.
2. pymodbus feeds a whole real track (the NMEA 2000 figure eight, converted
   to x,y,z) through the waypoint block, pacing itself on exception 06, then
   writes finish (end of input); the setpoints trajd streams for that object (CSV output) are
   those of `trajreplay` on the same x,y,z file (row for row by track time,
   bit for bit), and every block read over Modbus during the feed is one of
   trajreplay's rows rounded to float32 (no torn read).
3. Configuration errors: input = modbus without writes is refused by
   trajd --check-config with file:line.
"""
import bisect
import csv
import math
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M, obj_base  # noqa: E402

from pymodbus.client import ModbusTcpClient  # noqa: E402
from pymodbus.constants import Endian  # noqa: E402
from pymodbus.payload import BinaryPayloadBuilder  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(mbsim.BUILD, "bin", "trajreplay")
TRACK = os.path.join(mbsim.ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
FEED_RATE_HZ = 10      # output rate for the feed test
FINE_RATE_HZ = 1000    # the reference curve between the feed test's rows
FEED_SPEED = 50        # engine time per wall time: the 357 s track streams in ~7 s
FEED_WAIT_S = 60       # bound on the whole feed + stream
# D of the fed object and of its references: 0.24 s of wall time at FEED_SPEED that
# the feed may fall behind before the output slows (D the input needs, 2.7 s, is
# 54 ms there: a feed held up that long at the start left 14 rows identical)
FEED_DELAY_S = 12
FEED_MAX_SPEED = 30    # m/s: a stop reserve short enough for that D (the profile's is 400)
FEED_SETTINGS = ["--delay", str(FEED_DELAY_S), "--max-speed", str(FEED_MAX_SPEED)]


def f32(x):
    return struct.unpack(">f", struct.pack(">f", x))[0]


# Setpoint flag "time-scaled" (lib/motion.h, ENGINE_SP_SCALED).
with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "lib",
                       "motion.h")) as _f:
    SCALED = int(re.search(r"#define ENGINE_SP_SCALED\s+(0x[0-9a-fA-F]+)", _f.read()).group(1), 16)

class Trajd:
    """trajd -f on a config; port from its log line; stopped by pid (SIGTERM)."""

    def __init__(self, conf_text, tmp):
        self.conf = os.path.join(tmp, "trajd.conf")
        with open(self.conf, "w") as f:
            f.write(conf_text)
        self.p, self.lines, self.port = mbsim.start_trajd([TRAJD, "-f", "-c", self.conf])

    def stop(self):
        self.p.send_signal(signal.SIGTERM)
        rc = self.p.wait(timeout=mbsim.WAIT_S + 10)
        self.lines.wait_for("\0", 0.5)    # collect what is left for messages
        self.log = self.lines.all
        return rc


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def mbpoll(port, *args, write=()):
    out = subprocess.run(["mbpoll", "-m", "tcp", "-p", str(port), "-a", "1", "-0", "-1"]
                         + list(args) + ["127.0.0.1"] + [str(w) for w in write],
                         capture_output=True, text=True,
                         timeout=mbsim.WAIT_S)
    vals = [line.split("\t")[1] for line in out.stdout.splitlines()
            if line.startswith("[") and "\t" in line]
    return out.returncode, vals, out.stdout + out.stderr


class MbpollTrajdTest(unittest.TestCase):
    def test_mbpoll_reads_and_commands(self):
        with tempfile.TemporaryDirectory() as tmp:
            d = Trajd("""
[daemon]
rate_hz = 100
speed = 10
status_interval_s = 0
[modbus]
port = 0
writes = yes
systemd_socket = no
[object.boat]
input = replay
replay.track = %s
output = csv
csv.path = %s/boat.csv
writable = yes
""" % (TRACK, tmp), tmp)
            try:
                # Given trajd replaying the boat, when mbpoll reads the daemon
                # block, then magic, version, 1 object and a 10000 us period.
                rc, v, out = mbpoll(d.port, "-r", "0", "-c", "3", "-t", "3")
                self.assertEqual(v, ["29764", "1", "1"], out)
                rc, v, out = mbpoll(d.port, "-r", str(M["MBMAP_D_PERIOD_US"]), "-t", "3:int", "-B")
                self.assertEqual(v, ["10000"], out)
                # Wait (bounded) until the boat streams, by its state register.
                base = obj_base(0)
                for _ in range(200):
                    rc, v, out = mbpoll(d.port, "-r", str(base + M["MBMAP_O_STATE"]), "-t", "3")
                    if v == ["1"]:
                        break
                self.assertEqual(v, ["1"], out)
                # When mbpoll reads x,y,z,vx,vy,vz,ax,ay,az in one request with -B,
                # then they are one row of trajd's CSV rounded to float32.
                rc, v, out = mbpoll(d.port, "-r", str(base + M["MBMAP_O_POS"]), "-c", "9",
                                    "-t", "3:float", "-B")
                self.assertEqual(len(v), 9, out)
                got = [float(x) for x in v]
                # Feed override: mbpoll writes 50 % to holding register 101;
                # the override register reads 50 and the rate (f32) ramps to
                # 0.5 along the path (bounded wait), then back to 100 %.
                rc, _, out = mbpoll(d.port, "-r", str(base + M["MBMAP_H_OVERRIDE"]), "-t", "4",
                                    write=[50])
                self.assertEqual(rc, 0, out)
                for _ in range(200):
                    rc, v, out = mbpoll(d.port, "-r", str(base + M["MBMAP_O_RATE"]), "-t",
                                        "3:float", "-B")
                    if v and abs(float(v[0]) - 0.5) < 1e-6:
                        break
                self.assertEqual(v, ["0.5"], out)
                rc, v, out = mbpoll(d.port, "-r", str(base + M["MBMAP_O_OVERRIDE"]), "-t", "3")
                self.assertEqual(v, ["50"], out)
                rc, _, out = mbpoll(d.port, "-r", str(base + M["MBMAP_H_OVERRIDE"]), "-t", "4",
                                    write=[201])
                self.assertNotEqual(rc, 0, out)     # above 200 %: exception 03
                rc, _, out = mbpoll(d.port, "-r", str(base + M["MBMAP_H_OVERRIDE"]), "-t", "4",
                                    write=[100])
                self.assertEqual(rc, 0, out)
                # Clear it (mbpoll writes holding register 100 = 3), and the
                # state register shows waiting once the boat has braked to
                # rest along its path (a controlled stop: bounded wait).  The
                # replay goes on, so the boat may set off again to its live
                # track (a transfer that leads: lib/engine/transfer.h) within
                # a few waypoints, 20 ms at speed 10: a poll may miss the rest,
                # which the CSV then shows (below).
                rc, _, out = mbpoll(d.port, "-r", str(base + M["MBMAP_H_COMMAND"]), "-t", "4",
                                    write=[M["MBMAP_CMD_CLEAR"]])
                self.assertEqual(rc, 0, out)
                for _ in range(200):
                    rc, v, out = mbpoll(d.port, "-r", str(base + M["MBMAP_O_STATE"]), "-t", "3")
                    if v == ["0"]:
                        break
                polled_rest = v == ["0"]
            finally:
                self.assertEqual(d.stop(), 0, "".join(d.log))
            rows = read_csv(os.path.join(tmp, "boat.csv"))
            cols = ["x_m", "y_m", "z_m", "vx_m_s", "vy_m_s", "vz_m_s", "ax_m_s2", "ay_m_s2", "az_m_s2"]
            # mbpoll prints floats with 6 significant digits (%g): the match
            # is within that printing, relative 5e-6 (and 1e-30 absolute).
            def close(a, b):
                return abs(a - b) <= 5e-6 * max(abs(a), abs(b)) + 1e-30
            match = [r for r in rows if all(close(f32(float(r[c])), g) for c, g in zip(cols, got))]
            self.assertTrue(match, "mbpoll floats %s are no CSV row" % got)
            # the clear's rest: after streaming, a waiting row at rest (never
            # before the clear: the track runs on)
            first = next(i for i, r in enumerate(rows) if r["state"] == "streaming")
            rest = [r for r in rows[first:] if r["state"] == "waiting"
                    and all(float(r[c]) == 0.0 for c in cols[3:6])]
            self.assertTrue(polled_rest or rest, "no rest after the clear")


class FeedTest(unittest.TestCase):
    def test_pymodbus_feed_matches_trajreplay(self):
        with tempfile.TemporaryDirectory() as tmp:
            # The track as x,y,z (a local flat projection; any one will do as
            # long as trajreplay and the feed read the same numbers).
            xyz = os.path.join(tmp, "track.csv")
            wps = []
            with open(TRACK) as f, open(xyz, "w") as o:
                o.write("t,x,y,z\n")
                rd = csv.DictReader(f)
                lat0 = lon0 = None
                for r in rd:
                    lat, lon = float(r["lat_deg"]), float(r["lon_deg"])
                    if lat0 is None:
                        lat0, lon0 = lat, lon
                    x = (lon - lon0) * 111320.0 * math.cos(math.radians(lat0))
                    y = (lat - lat0) * 110540.0
                    line = "%.17g,%.17g,%.17g,0\n" % (float(r["t_s"]), x, y)
                    o.write(line)
                    wps.append(tuple(float(v) for v in line.split(",")))
            ref_path = os.path.join(tmp, "ref.csv")
            p = subprocess.run([TRAJREPLAY, "--rate", str(FEED_RATE_HZ)] + FEED_SETTINGS +
                               ["-q", "--summary", "-o", ref_path, xyz], check=True, timeout=60,
                               capture_output=True, text=True)
            # the waypoints trajreplay refuses: the engine judges each with
            # its neighbours, so a refusal may come after the write was
            # answered (lib/engine/accept.h); the register counts them all
            ref_rejected = int(re.search(r"summary: rejected (\d+)", p.stderr).group(1))
            # the reference's rows on the curve's own timing: a time-scaled row
            # (ENGINE_SP_SCALED: trajreplay's own replay slowed down where the
            # track's timing needed more than the start slack) moves at rate * k'
            ref = {r["t_s"]: r for r in read_csv(ref_path)
                   if r["state"] in ("1", "streaming") and not int(r["flags"]) & SCALED}
            self.assertGreater(len(ref), 1000)

            d = Trajd("""
[daemon]
rate_hz = %d
speed = %d
status_interval_s = 0
[modbus]
port = 0
writes = yes
systemd_socket = no
[object.fed]
input = modbus
; a small buffer, so the feed meets flow control (exception 06) and must pace itself
capacity = 100
; D longer than the input needs: the feed may fall that far behind before the output slows
delay_s = %g
max_speed_m_s = %g
output = csv
csv.path = %s/fed.csv
""" % (FEED_RATE_HZ, FEED_SPEED, FEED_DELAY_S, FEED_MAX_SPEED, tmp), tmp)
            reads = []
            try:
                c = ModbusTcpClient("127.0.0.1", port=d.port, timeout=mbsim.WAIT_S)
                self.assertTrue(c.connect())
                base = obj_base(0)
                busy, refused = set(), 0
                deadline = time.monotonic() + FEED_WAIT_S
                for i, (t, x, y, z) in enumerate(wps):
                    b = BinaryPayloadBuilder(byteorder=Endian.Big, wordorder=Endian.Big)
                    b.add_32bit_uint(i + 1)
                    for v in (t, x, y, z):
                        b.add_64bit_float(v)
                    regs = b.to_registers()
                    while True:
                        self.assertLess(time.monotonic(), deadline, "feed too slow")
                        rq = c.write_registers(base + M["MBMAP_H_WP"], regs, slave=1)
                        if not rq.isError():
                            break
                        if rq.exception_code == 6:       # buffer full: wait a tick, retry
                            busy.add(i)
                            rr = c.read_input_registers(base, mbsim.BLOCK, slave=1)
                            reads.append(rr.registers)
                            continue
                        self.assertEqual(rq.exception_code, 3, rq)
                        refused += 1                    # the engine refused it, as in trajreplay
                        break
                    if i % 10 == 0:
                        reads.append(c.read_input_registers(base, mbsim.BLOCK, slave=1).registers)
                rq = c.write_register(base + M["MBMAP_H_COMMAND"], M["MBMAP_CMD_FINISH"], slave=1)
                self.assertFalse(rq.isError(), rq)
                # Wait (bounded) for the object to finish, reading blocks meanwhile
                # (one per new generation is enough: keep the first of each).
                last_gen = None
                while time.monotonic() < deadline:
                    r = c.read_input_registers(base, mbsim.BLOCK, slave=1).registers
                    if mbsim.u32(r, 0) != last_gen:
                        reads.append(r)
                        last_gen = mbsim.u32(r, 0)
                    if r[M["MBMAP_O_STATE"]] == 3:
                        break
                self.assertEqual(r[M["MBMAP_O_STATE"]], 3, "not finished")
                # Counters mean what they say (issue 11): rejected is the bad
                # data (exception 03 when refused at once, or judged later
                # with its neighbours: as many as trajreplay refuses), the
                # buffer-full refusals (exception 06) are flow control,
                # counted in full.
                self.assertEqual(mbsim.u32(r, M["MBMAP_O_REJECTED"]), ref_rejected)
                self.assertLessEqual(refused, ref_rejected)
                # (each waypoint once, however often it was offered again)
                self.assertEqual(mbsim.u32(r, M["MBMAP_O_FULL"]), len(busy))
                c.close()
            finally:
                self.assertEqual(d.stop(), 0, "".join(d.log))
            # the exit status line says the same: rejected excludes the
            # buffer-full refusals, which have their own count (issue 11)
            ex = [ln for ln in d.log if "exit: " in ln]
            self.assertEqual(len(ex), 1, "".join(d.log))
            m = re.search(r"; fed \w+ t=[-\d.]+ s, wp \d+ ok (\d+) rejected (\d+) full,", ex[0])
            self.assertIsNotNone(m, ex[0])
            self.assertEqual((int(m.group(1)), int(m.group(2))), (ref_rejected, len(busy)), ex[0])
            print("fed %d waypoints, %d waypoints refused busy, %d refused, %d Modbus block reads"
                  % (len(wps), len(busy), refused, len(reads)))
            self.assertGreater(len(busy), 0)     # flow control was exercised

            # Then every streaming row trajd wrote is trajreplay's row at the
            # same track time, bit for bit (same engine, same pushes) -- or,
            # where the feed fell behind (a loaded machine) and the time
            # scaling slowed the output down (lib/engine/TIMESCALE.md), which
            # shifts the grid of track times afterwards: a point of the same
            # curve at its own track time (cubic Hermite between the two rows
            # around it of trajreplay's replay at FINE_RATE_HZ: exact within a
            # segment, within jerk jump * (1 ms)^3 across one).
            fed = [r for r in read_csv(os.path.join(tmp, "fed.csv")) if r["state"] in ("1", "streaming")]
            cols = ["x_m", "y_m", "z_m", "vx_m_s", "vy_m_s", "vz_m_s", "ax_m_s2", "ay_m_s2", "az_m_s2"]
            fine_path = os.path.join(tmp, "fine.csv")
            subprocess.run([TRAJREPLAY, "--rate", str(FINE_RATE_HZ)] + FEED_SETTINGS +
                           ["-q", "-o", fine_path, xyz],
                           check=True, timeout=60, capture_output=True, text=True)
            fine = {r["t_s"]: r for r in read_csv(fine_path)
                    if r["state"] in ("1", "streaming") and not int(r["flags"]) & SCALED}
            t_ref = sorted(float(t) for t in fine)
            by_t = {float(k): v for k, v in fine.items()}

            def on_curve(t):
                """x, y, z of the reference curve at track time t."""
                i = bisect.bisect_right(t_ref, t) - 1
                if i < 0 or i + 1 >= len(t_ref):
                    return None
                t0, t1 = t_ref[i], t_ref[i + 1]
                if t1 - t0 > 1.001 / FINE_RATE_HZ:
                    return None  # across reference rows left out (time-scaled)
                a, b = by_t[t0], by_t[t1]
                h, u = t1 - t0, (t - t0) / (t1 - t0)
                h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
                h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
                return [h00 * float(a[p]) + h10 * h * float(a[v]) + h01 * float(b[p])
                        + h11 * h * float(b[v])
                        for p, v in (("x_m", "vx_m_s"), ("y_m", "vy_m_s"), ("z_m", "vz_m_s"))]

            exact = off = 0
            for r in fed:
                if r["t_s"] in ref and not int(r["flags"]) & SCALED:
                    diff = [c for c in cols if float(r[c]) != float(ref[r["t_s"]][c])]
                    self.assertEqual(diff, [], r["t_s"])
                    exact += 1
                    continue
                want = on_curve(float(r["t_s"]))
                if want is None:
                    continue
                err = max(abs(float(r[c]) - w) for c, w in zip(("x_m", "y_m", "z_m"), want))
                self.assertLess(err, 1e-6, r["t_s"])
                off += 1
            print("fed rows: %d identical to trajreplay's, %d on the curve after a slow-down"
                  % (exact, off))
            self.assertGreater(exact, 100)
            # Rows may be missing where ticks were skipped (a loaded machine, or
            # ASan), so coverage is asked loosely: a good share of the rows,
            # spread from the start to the end of the track.
            self.assertGreater(len(fed), len(ref) // 3, (len(fed), len(ref)))
            t_fed = sorted(float(r["t_s"]) for r in fed)
            self.assertLess(t_fed[0] - t_ref[0], 0.1 * (t_ref[-1] - t_ref[0]))
            self.assertLess(t_ref[-1] - t_fed[-1], 0.1 * (t_ref[-1] - t_ref[0]))

            # And every Modbus read while streaming is one tick of trajd's
            # output: t as f64, x,y,z,vx.. in f32 -- trajreplay's row at that
            # t, or (after a slow-down) a point of the curve at t.
            torn = checked = 0
            for r in reads:
                if r[M["MBMAP_O_STATE"]] != 1:
                    continue
                self.assertEqual(mbsim.u32(r, M["MBMAP_O_GEN"]), mbsim.u32(r, M["MBMAP_O_GEN_TAIL"]))
                t = mbsim.f64(r, M["MBMAP_O_T_S"])
                got = [mbsim.f32(r, M["MBMAP_O_POS"] + 2 * i) for i in range(9)]
                row = by_t.get(t)
                if row is not None and not r[M["MBMAP_O_FLAGS"]] & SCALED:
                    torn += got != [f32(float(row[c])) for c in cols]
                else:
                    want = on_curve(t)
                    if want is None:
                        continue
                    # float32 of coordinates of a few hundred metres: 1e-4 m
                    torn += max(abs(g - w) for g, w in zip(got[:3], want)) > 1e-4
                checked += 1
            self.assertGreater(checked, 10)
            self.assertEqual(torn, 0)


class SocketActivationTest(unittest.TestCase):
    def test_systemd_socket(self):
        # Given systemd-socket-activate holding a listening socket on a free
        # port (as trajd.socket does for 502) and [modbus] port = 0, when a
        # client connects, then trajd is started with the socket (LISTEN_FDS),
        # says so, and answers on that port rather than binding its own.
        probe = socket.socket()
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
        probe.close()
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "sa.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\n[modbus]\nport = 0\n"
                        "[object.boat]\ninput = replay\nreplay.track = %s\noutput = stdout\n" % TRACK)
            p = subprocess.Popen(["systemd-socket-activate", "-l", "127.0.0.1:%d" % port,
                                  TRAJD, "-f", "-c", conf], stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE, text=True)
            try:
                lines = mbsim.Lines(p.stderr)
                # Wait (bounded) until it listens, by its own log line.
                self.assertIsNotNone(lines.wait_for("Listening on"), "did not listen")
                s = mbsim.connect(port)
                r = mbsim.read_input(s, 0, 3)
                self.assertEqual(r[0], M["MBMAP_MAGIC"])
                s.close()
                log = lines.wait_for("modbus: TCP")
                self.assertIsNotNone(log, "no modbus log line: %s" % lines.all)
                self.assertIn("systemd socket, port %d" % port, log)
            finally:
                p.send_signal(signal.SIGTERM)
                self.assertEqual(p.wait(timeout=mbsim.WAIT_S + 10), 0)


class RtuTrajdTest(unittest.TestCase):
    def test_rtu_from_config(self):
        # Given a socat pty pair and trajd with rtu_device on one end at
        # 19200 8E1 unit 5 (from [modbus]), when mbpoll -m rtu with those
        # settings reads the daemon block on the other end, then it is
        # answered; with unit 6 it is not.
        socat = subprocess.Popen(["socat", "-d", "-d", "pty,raw,echo=0", "pty,raw,echo=0"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        try:
            lines = mbsim.Lines(socat.stderr)
            ttys = []
            for _ in range(2):
                line = lines.wait_for("PTY is ")
                self.assertIsNotNone(line, "socat did not open a pty pair")
                ttys.append(line.split("PTY is ")[1].strip())
            with tempfile.TemporaryDirectory() as tmp:
                d = Trajd("""
[daemon]
rate_hz = 100
status_interval_s = 0
[modbus]
port = 0
systemd_socket = no
rtu_device = %s
rtu_baud = 19200
rtu_parity = even
unit_id = 5
[object.boat]
input = replay
replay.track = %s
output = stdout
""" % (ttys[0], TRACK), tmp)
                try:
                    rtu = ["mbpoll", "-m", "rtu", "-b", "19200", "-P", "even", "-0", "-1",
                           "-r", "0", "-c", "3", "-t", "3"]
                    out = subprocess.run(rtu + ["-a", "5", "-o", "1", ttys[1]], capture_output=True,
                                         text=True, timeout=mbsim.WAIT_S)
                    vals = [x.split("\t")[1] for x in out.stdout.splitlines() if x.startswith("[")]
                    self.assertEqual(vals, ["29764", "1", "1"], out.stdout + out.stderr)
                    out = subprocess.run(rtu + ["-a", "6", "-o", "0.3", ttys[1]], capture_output=True,
                                         text=True, timeout=mbsim.WAIT_S)
                    self.assertNotEqual(out.returncode, 0, out.stdout)
                finally:
                    self.assertEqual(d.stop(), 0, "".join(d.log))
                # the line as the serial notation writes it: data bits, parity, stop bits
                # (it read "19200 E81")
                self.assertIn("modbus: RTU on %s 19200 8E1 unit 5" % ttys[0], "".join(d.log))
        finally:
            socat.terminate()
            socat.wait(timeout=mbsim.WAIT_S)


class ConfigTest(unittest.TestCase):
    def test_input_modbus_needs_writes(self):
        # Given an object with input = modbus and writes off, when checked,
        # then trajd refuses the file and names the object's line.
        with tempfile.TemporaryDirectory() as tmp:
            conf = os.path.join(tmp, "bad.conf")
            with open(conf, "w") as f:
                f.write("[modbus]\nport = 1502\n\n[object.fed]\ninput = modbus\noutput = stdout\n")
            out = subprocess.run([TRAJD, "--check-config", conf], capture_output=True, text=True,
                                 timeout=mbsim.WAIT_S)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("bad.conf:4", out.stdout + out.stderr)
            self.assertIn("writes", out.stdout + out.stderr)
            with open(conf, "w") as f:
                f.write("[modbus]\nallow = 10.0.0.0/40\n\n[object.a]\ninput = replay\n"
                        "replay.track = %s\noutput = stdout\n" % TRACK)
            out = subprocess.run([TRAJD, "--check-config", conf], capture_output=True, text=True,
                                 timeout=mbsim.WAIT_S)
            self.assertNotEqual(out.returncode, 0)
            self.assertIn("bad.conf:2", out.stdout + out.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
