"""trajd's CAN transport end to end on the host, through the candump-log
transport (the same codec and can_port as on a socket, no kernel needed):

- a real track (figure eight, NMEA 2000 GNSS) is turned into waypoint frames
  by canmatrix from config/trajd.dbc (not by our encoder), written as a
  candump log with comment lines and foreign 29-bit frames from a real
  capture interleaved; trajd replays it and writes its frames as a candump log;
- the setpoints are decoded by python-can + canmatrix and must equal
  trajreplay's output on the same track (within the 0.1 mm field resolution),
  in the classic layout, the FD layout and the CiA 402 RPDO layout;
- faults in the input (gap, duplicate, wrong length, unknown multiplexer) are
  reported in the STATUS frames and the trajectory carries on;
- a sender that restarts its numbering mid-track (its times going on) is
  taken at once (a resync: logged, counted in the exit summary), never
  dropped as out of order;
- a pause of the input mid-track runs the output short: STATUS2 page 7 counts
  the underruns the SETPOINT frames' state shows (issue 26);
- a configuration above the bus-load limit is refused with a clear message,
  and the limit agrees with an independent computation of frame lengths;
- a log with nothing usable for an object (only foreign frames, or every
  waypoint out of range) ends trajd with exit_when_done with an error line
  naming the object and the log and exit 65 (EX_DATAERR), as a replayed
  track does (issue 11 "nothing usable");
- a log_in with no frame at all (empty, only comments and bad lines) or that
  cannot be read (missing, a directory, no permission) is refused by
  --check-config and at start, exit 78, naming the config line and the log
  (and its first bad line), never accepted and then waited on.
"""
import errno
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
TRACK = os.path.join(ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
CAPTURE = os.path.join(ROOT, "tests", "data", "canboat_candumpSample3.log")
NPOINTS = 150          # 30 s of track: enough turns, a short run
RATE_HZ = 100
SPEED = 30             # engine time per wall time: ~1 s per run
RUN_TIMEOUT_S = 30


def conf(d, extra_can="", extra_obj="", output="can"):
    path = os.path.join(d, "t.conf")
    with open(path, "w") as fh:
        fh.write("[daemon]\nrate_hz = %d\nspeed = %d\nexit_when_done = yes\n"
                 "stop_timeout_s = 1\nstatus_interval_s = 0\n"
                 "[can]\nlog_in = wp.log\nlog_out = sp.log\nlog_ifname = vcan0\nlog_time = engine\n"
                 # never drop late cycles here: at speed 30 the wall period is 333 us
                 # and a loaded machine (ASan, other jobs) would drop many (tested in test_can_port)
                 "max_late_ms = 0\n%s"
                 "[object.boat]\ninput = can\noutput = %s\n%s" % (RATE_HZ, SPEED, extra_can, output, extra_obj))
    return path


def run_trajd(path):
    p = subprocess.run([TRAJD, "-f", "-c", path], cwd=os.path.dirname(path),
                       capture_output=True, text=True, timeout=RUN_TIMEOUT_S)
    return p


class CanDaemon(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.d = cls.tmp.name
        cls.xyz = os.path.join(cls.d, "track.csv")
        ct.to_xyz(TRACK, cls.xyz, NPOINTS)
        cls.ref = os.path.join(cls.d, "ref.csv")
        subprocess.run([TRAJREPLAY, "--rate", str(RATE_HZ), "-q", "-o", cls.ref, cls.xyz],
                       check=True, timeout=RUN_TIMEOUT_S)
        cls.refrows = ct.read_replay(cls.ref)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def sub(self, name):
        d = os.path.join(self.d, name)
        os.makedirs(d, exist_ok=True)
        return d

    def reference(self, d):
        """The daemon's own CSV log (now_ns -> row) and, for each of its ticks,
        trajreplay's row at the same TRACK time.  Matching by track time, not
        by tick: when trajd skips a late tick, a waypoint due in it reaches the
        engine one tick later than in trajreplay, which can delay the start of
        streaming by a tick; the curve and the track-time grid are the same."""
        logged = ct.read_replay(os.path.join(d, "sp.csv"))
        by_t = {}
        for _, r in sorted(self.refrows.items()):
            if math.isnan(float(r["x_m"])):
                continue  # no position yet (NO_POSITION): nothing to match a time to
            by_t.setdefault(round(float(r["t_s"]) * 1e9), r)
        ref = {now: by_t[round(float(r["t_s"]) * 1e9)] for now, r in logged.items()
               if round(float(r["t_s"]) * 1e9) in by_t and not math.isnan(float(r["x_m"]))}
        self.assertGreater(len(ref), 0.95 * len(logged))
        for now, e in ref.items():  # the daemon's log against trajreplay (doubles, %.17g)
            for ax in "xyz":
                self.assertLessEqual(abs(float(logged[now][ax + "_m"]) - float(e[ax + "_m"])), 1e-9)
        return logged, ref

    # Given the track as classic waypoint frames with foreign frames and
    # comments, when trajd replays them with SYNC on, then every setpoint
    # equals trajreplay's, each cycle starts with SYNC, and the last STATUS
    # says finished, nothing lost, rejected or malformed.
    def test_classic_matches_trajreplay(self):
        d = self.sub("classic")
        n, nforeign = ct.write_wplog(self.xyz, os.path.join(d, "wp.log"), foreign=CAPTURE)
        self.assertGreater(nforeign, 0)
        # the daemon also logs what it sent, as CSV, from the same tick
        p = run_trajd(conf(d, "sync = yes\n", "csv.path = sp.csv\n", output="can, csv"))
        self.assertEqual(p.returncode, 0, p.stderr)
        log = os.path.join(d, "sp.log")
        # canmatrix decodes the captured frames to the values the daemon logged
        logged = ct.read_replay(os.path.join(d, "sp.csv"))
        rows, _ = ct.decode_setpoints(log)
        # with max_late_ms = 0 every tick goes out on CAN and into the CSV
        self.assertEqual(sorted(rows), sorted(logged))
        for now_ns, r in rows.items():
            e = logged[now_ns]
            for ax in "xyz":
                if math.isnan(float(e[ax + "_m"])):
                    continue  # no position yet (NO_POSITION): the n/a marker on CAN
                self.assertLessEqual(abs(r[ax] - float(e[ax + "_m"])), ct.SP_POS_TOL)
                self.assertLessEqual(abs(r["v" + ax] - float(e["v%s_m_s" % ax])), ct.SP_VEL_TOL)
            self.assertEqual(r["cycle8"], int(e["cycle"]) & 0xFF)
            self.assertEqual(ct.STATES[r["state"]], e["state"])
        _, ref = self.reference(d)
        worst = 0.0
        for now_ns, r in rows.items():
            if now_ns in ref:
                for ax in "xyz":
                    err = abs(r[ax] - float(ref[now_ns][ax + "_m"]))
                    self.assertLessEqual(err, ct.SP_POS_TOL)
                    worst = max(worst, err)
        print("classic: %d setpoints, worst |can - trajreplay| %.3g m" % (len(rows), worst),
              file=sys.stderr)
        rows, others = ct.decode_setpoints(log)
        self.assertEqual(others.get(0x080), len(rows))  # one SYNC per cycle sent
        with open(log) as fh:
            lines = fh.read().splitlines()
        for i, line in enumerate(lines):
            if " 6A0#" in line and line.split()[2][4:6] == "00":  # axis 0 frame of a cycle
                self.assertIn(" 080#", lines[i - 1])
        st = ct.decode_by_id(log, 0x6C0)
        last = st[-1][1]
        self.assertEqual(int(last["ST_State"]), 3)  # finished
        self.assertEqual(int(last["ST_LastSeq"]), n & 0xFF)
        self.assertEqual((last["ST_Lost"], last["ST_Rejected"], last["ST_Malformed"]), (0, 0, 0))

    # Given FD waypoints and an FD object, then the FD setpoints equal
    # trajreplay's too (velocity at 1 um/s), and the cycle counter is whole.
    def test_fd_matches_trajreplay(self):
        d = self.sub("fd")
        ct.write_wplog(self.xyz, os.path.join(d, "wp.log"), fd=True)
        p = run_trajd(conf(d, "fd = yes\n", "can.fd = yes\ncan.brs = yes\ncsv.path = sp.csv\n",
                           output="can, csv"))
        self.assertEqual(p.returncode, 0, p.stderr)
        rows = ct.decode_fd_setpoints(os.path.join(d, "sp.log"))
        logged, ref = self.reference(d)
        self.assertEqual(sorted(rows), sorted(logged))
        prev = -1
        for now_ns, r in sorted(rows.items()):
            for e, tol in ((logged[now_ns], 0.0), (ref.get(now_ns), 1e-9)):
                if e is None:
                    continue
                for ax in "xyz":
                    if math.isnan(float(e[ax + "_m"])):
                        continue  # no position yet (NO_POSITION): the n/a marker on CAN
                    self.assertLessEqual(abs(r[ax] - float(e[ax + "_m"])), ct.SP_POS_TOL + tol)
                    self.assertLessEqual(abs(r["v" + ax] - float(e["v%s_m_s" % ax])), 0.5e-6 + 1e-9)
            self.assertEqual(r["cycle"], int(logged[now_ns]["cycle"]))
            self.assertGreater(r["cycle"], prev)
            prev = r["cycle"]

    # Given the CiA 402 profile (own frames off), then each axis' RPDO holds
    # 0x607A = round(position x counts_per_m) of trajreplay's position.
    def test_cia402_rpdo(self):
        d = self.sub("cia402")
        ct.write_wplog(self.xyz, os.path.join(d, "wp.log"))
        with open(self.xyz) as fh:  # no drive feedback: trajd starts where the track does
            start = fh.read().splitlines()[1].split(",")[1:4]
        p = run_trajd(conf(d, "sync = yes\n", "can.own = no\ncan.cia402 = yes\n"
                                              "can.cia402_feedback = no\n"
                                              "initial_position = %s\n" % ",".join(start) +
                                              "can.cia402_counts_per_m = 1000\ncsv.path = sp.csv\n"
                                              "can.cia402_cob_x = 0x201\ncan.cia402_cob_y = 0x202\n"
                                              "can.cia402_cob_z = 0x203\n",
                           output="can, csv"))
        self.assertEqual(p.returncode, 0, p.stderr)
        # no drive to ask where it stands: the log says where it is taken to be
        self.assertIn("no drive feedback (can.cia402 = targets): the drives are taken to "
                      "stand at initial_position", p.stderr)
        log = os.path.join(d, "sp.log")
        logged, ref = self.reference(d)
        for a, (ax, cob) in enumerate(zip("xyz", (0x201, 0x202, 0x203))):
            frames = ct.decode_by_id(log, cob)
            # no RPDO while there is no position (NO_POSITION: the first
            # waypoints are still being confirmed, lib/engine/accept.h)
            self.assertEqual(len(frames),
                             sum(not math.isnan(float(e["x_m"])) for e in logged.values()))
            for now_ns, sig in frames:
                for e in (logged[now_ns], ref.get(now_ns)):
                    if e is None:
                        continue
                    exp = float(e[ax + "_m"]) * 1000
                    # rounding to the nearest increment: within half an increment
                    # (+1e-6 for a tie decided differently by double rounding)
                    self.assertLessEqual(abs(sig["Target_Position_607A"] - exp), 0.5 + 1e-6)
        rows, others = ct.decode_setpoints(log)
        self.assertEqual(rows, {})  # own frames off
        self.assertGreater(others.get(0x080, 0), 0)
        # STATUS2 page 6 (decoded by canmatrix with the DBC): the track time of that
        # tick's setpoint, as trajd's own CSV has it, to the microsecond
        page6 = [(n, g) for n, g in ct.decode_by_id(log, 0x6D0) if int(g["ST2_Page"]) == 6]
        self.assertGreater(len(page6), 10)
        for now_ns, sig in page6:
            t = float(logged[now_ns]["t_s"])
            self.assertLessEqual(abs(float(sig["ST2_TimeT"]) - t), 0.5e-6 + 1e-6 * 1e-9 * abs(t))

    # Given faults in the input: waypoint 50 missing (gap), 60 sent twice, a
    # short frame and an unknown multiplexer, then STATUS reports 1 lost and 2
    # malformed, the duplicate changes nothing, and the object still finishes.
    def test_faults_reported(self):
        d = self.sub("faults")
        ct.write_faulty_wplog(self.xyz, os.path.join(d, "wp.log"), repeat_60=True)
        p = run_trajd(conf(d))
        self.assertEqual(p.returncode, 0, p.stderr)
        st = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)
        last = st[-1][1]
        self.assertEqual(int(last["ST_Lost"]), 1)
        self.assertEqual(int(last["ST_Malformed"]), 2)
        self.assertEqual(int(last["ST_Rejected"]), 0)
        self.assertEqual(int(last["ST_State"]), 3)
        # the loss was reported at once: some STATUS carries last_err LOST (0x41)
        self.assertIn(0x41, [int(s["ST_LastErr"]) for _, s in st])

    # Given a sender that restarts its numbering mid-track (K-D3: waypoints
    # 81..150 sent as seq 1..70, their times going on), then trajd takes every
    # waypoint: the setpoints are still trajreplay's to the end, nothing is
    # lost or out of order, the restart is logged once at notice level with
    # both numbers and counted in the exit summary, and the last STATUS shows
    # the sender's own number.  (Before, seq 1..70 after 80 were all dropped as
    # out of order: the track ended at waypoint 80.)
    def test_restarted_numbering_resynced(self):
        d = self.sub("restart")
        wp = os.path.join(d, "wp.log")
        n, _ = ct.write_wplog(self.xyz, wp, iface="vcan0")
        with open(wp) as fh:
            lines = fh.read().splitlines()
        for i, line in enumerate(lines):
            f = line.split()[-1] if not line.startswith("#") else ""
            if f.startswith("680#") and f[4:6] != "04" and int(f[6:8], 16) > 80:
                lines[i] = line.replace(f, f[:6] + "%02X" % (int(f[6:8], 16) - 80) + f[8:])
        with open(wp, "w") as fh:
            fh.write("\n".join(lines) + "\n")
        p = run_trajd(conf(d, "", "csv.path = sp.csv\n", output="can, csv"))
        self.assertEqual(p.returncode, 0, p.stderr)
        logged, _ = self.reference(d)  # every setpoint trajreplay's
        end = self.refrows[max(self.refrows)]
        last_row = logged[max(logged)]
        self.assertLessEqual(abs(float(last_row["x_m"]) - float(end["x_m"])), 1e-9)
        last = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)[-1][1]
        self.assertEqual(int(last["ST_State"]), 3)
        self.assertEqual(int(last["ST_LastSeq"]), n - 80)
        self.assertEqual((last["ST_Lost"], last["ST_Rejected"], last["ST_Malformed"]), (0, 0, 0))
        notes = [l for l in p.stderr.splitlines() if "restarted its numbering" in l]
        self.assertEqual(len(notes), 1, p.stderr)
        self.assertIn("object 'boat': sender restarted its numbering: waypoint seq 1 after 80, "
                      "its time later: resynced on id 0x680", notes[0])
        summary = [l for l in p.stderr.splitlines() if "setpoints sent" in l][-1]
        self.assertIn("waypoints %d accepted, 0 rejected" % n, summary)
        self.assertIn(" 0 lost, 0 duplicate frames, 0 out of order, 1 resynced,", summary)

    # Given waypoint 70 of the track moved 500 m east (a position jump no
    # boat makes in 0.2 s), then STATUS counts exactly one rejection,
    # trajd's log names it by its bus, frame id and sequence number, and
    # STATUS2 page 2 counts it under its reason.
    def test_rejection_logged(self):
        d = self.sub("spike")
        xyz = os.path.join(d, "track.csv")
        with open(self.xyz) as fh:
            rows = fh.read().splitlines()
        t, x, y, z = rows[70].split(",")  # the header is line 0: waypoint 70, seq 70
        rows[70] = ",".join((t, "%.6f" % (float(x) + 500.0), y, z))
        with open(xyz, "w") as fh:
            fh.write("\n".join(rows) + "\n")
        ct.write_wplog(xyz, os.path.join(d, "wp.log"), iface="vcan0")
        p = run_trajd(conf(d))
        self.assertEqual(p.returncode, 0, p.stderr)
        last = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)[-1][1]
        self.assertEqual(int(last["ST_Rejected"]), 1)
        lines = [l for l in p.stderr.splitlines() if ": rejected (" in l]
        self.assertEqual(len(lines), 1, p.stderr)
        self.assertIn("object 'boat': can vcan0 id 0x680 seq 70: rejected (", lines[0])
        self.assertIn(" t=%.3f s" % float(t), lines[0])
        # and STATUS2 page 2 counts it under the reason the log gives
        # (canmatrix decodes the page from config/trajd.dbc)
        why = lines[0].split(": rejected (")[1].split(")")[0]
        sig = {"backwards": "ST2_RejBackwards", "same_time": "ST2_RejSameTime",
               "speed": "ST2_RejSpeed", "accel": "ST2_RejAccel",
               "unconfirmed": "ST2_RejUnconfirmed", "stale": "ST2_RejStale"}.get(why, "ST2_RejOther")
        pages = [p2 for _, p2 in ct.decode_by_id(os.path.join(d, "sp.log"), 0x6D0)
                 if int(p2["ST2_Page"]) == 2]
        self.assertGreater(len(pages), 0)
        self.assertEqual(int(pages[-1][sig]), 1, pages[-1])
        self.assertEqual(sum(int(v) for k, v in pages[-1].items() if k.startswith("ST2_Rej")), 1)

    def run_commands(self, name, obj):
        """Object boat (keys obj) with its output on CAN and on a full disk
        (csv.path = /dev/full); the candump input carries the track's waypoint
        frames (and FINISH after the last) with STOP at t = 5 s and CLEAR at
        t = 6 s on its waypoint id, all encoded by canmatrix."""
        d = self.sub(name)
        db = ct.load_db()
        wp = os.path.join(d, "wp.log")
        ct.write_wplog(self.xyz, wp, iface="vcan0")
        with open(wp) as fh:
            lines = fh.read().splitlines()
        lines += ["(%.6f) vcan0 %s" % (t, ct.fmt_frame(*ct.command_frame(db, cmd)))
                  for t, cmd in ((5.0, 2), (6.0, 3))]
        key = lambda l: float(l[1:l.index(")")]) if l.startswith("(") else -1.0
        with open(wp, "w") as fh:
            fh.write("\n".join(sorted(lines, key=key)) + "\n")
        path = os.path.join(d, "t.conf")
        with open(path, "w") as fh:
            fh.write("[daemon]\nrate_hz = %d\nspeed = %d\nexit_when_done = yes\n"
                     "stop_timeout_s = 1\nstatus_interval_s = 0\n"
                     "[can]\nlog_in = wp.log\nlog_out = sp.log\nlog_ifname = vcan0\nmax_late_ms = 0\n"
                     "[object.boat]\noutput = can, csv\ncsv.path = /dev/full\n"
                     # a fixed start slack: the candump input's arrival jitter would
                     # otherwise slow the default one-waypoint slack (start_slack auto)
                     # down once, an underrun state in the states asserted below
                     "start_slack = 8\nmax_lookahead = 25\n%s" % (RATE_HZ, SPEED, obj))
        p = run_trajd(path)
        rows, _ = ct.decode_setpoints(os.path.join(d, "sp.log"))
        end = self.refrows[max(self.refrows)]
        last = rows[max(rows)]
        dist = math.hypot(last["x"] - float(end["x_m"]), last["y"] - float(end["y_m"]))
        states = []  # the engine state in the setpoints, each change
        for k in sorted(rows):
            if not states or states[-1] != rows[k]["state"]:
                states.append(rows[k]["state"])
        return p, d, dist, states

    # Given a CAN input with writable = no, when STOP and CLEAR arrive on its
    # waypoint id amid its waypoints, then neither is obeyed (it runs to the
    # end of its track, where trajreplay ends: FINISH, the end of its own
    # input, is), both are counted in STATUS2 page 1 (decoded by canmatrix
    # from the DBC) and reported in STATUS (0x48), and the log names the
    # object, the command and the id.  Its csv output on a full disk shows in
    # the same page (lines lost, failed writes) and in the exit status.  An
    # object fed by replay with writable = yes obeys the same STOP (state
    # FINISHED mid-track) and CLEAR (WAITING again, then the replay resumes).
    def test_commands_need_writable(self):
        p, d, dist, states = self.run_commands("cmd_ro", "input = can\nwritable = no\n")
        self.assertEqual(states, [0, 1, 3])  # waiting, streaming, finished at the end
        self.assertEqual(p.returncode, 74, p.stderr)  # EX_IOERR: lines lost on /dev/full
        self.assertLess(dist, 2 * ct.SP_POS_TOL)
        st2 = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6D0)
        self.assertGreater(len(st2), 0)
        # the last page 1 (faults): other pages go out in turn after it (page 5, the
        # bus, now that a log file's bus state is published too)
        last = [f for _, f in st2 if int(f["ST2_Page"]) == 1][-1]
        self.assertEqual(int(last["ST2_CmdRefused"]), 2)
        self.assertGreater(int(last["ST2_OutLost"]), 0)
        self.assertGreater(int(last["ST2_OutErrors"]), 0)
        st = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6C0)
        self.assertIn(0x48, [int(s["ST_LastErr"]) for _, s in st])
        self.assertIn("object 'boat'", p.stderr)
        self.assertRegex(p.stderr, r"command frame\(s\) refused, the last (stop|clear) on id 0x680")
        p, d, dist, states = self.run_commands("cmd_rw", "input = replay\nreplay.track = %s\n"
                                               "writable = yes\n" % self.xyz)
        self.assertEqual(p.returncode, 74, p.stderr)
        self.assertIn(3, states[:-1])  # stopped before the end of the track
        self.assertNotIn("command frame(s) refused", p.stderr)
        st2 = ct.decode_by_id(os.path.join(d, "sp.log"), 0x6D0)
        page1 = [f for _, f in st2 if int(f["ST2_Page"]) == 1]   # the faults page, last sent
        self.assertEqual(int(page1[-1]["ST2_CmdRefused"]), 0)

    # Given the track's waypoint frames with the second half of the log sent
    # 1 s late (a pause of the input mid-track, the stamps unchanged), then
    # the output runs short: each entry into underrun is on the bus in the
    # SETPOINT frames' state (canmatrix), and STATUS2 page 7 (issues 26, 32)
    # counts them all, with the delay D grown (once at least) to match.
    def test_underruns_on_status2(self):
        d = self.sub("pause")
        wp = os.path.join(d, "wp.log")
        ct.write_wplog(self.xyz, wp, iface="vcan0")
        with open(wp) as fh:
            lines = fh.read().splitlines()
        stamp = lambda l: float(l[1:l.index(")")])
        stamps = [stamp(l) for l in lines if l.startswith("(")]
        mid = (stamps[0] + stamps[-1]) / 2
        with open(wp, "w") as fh:
            fh.writelines("(%.6f)%s\n" % (stamp(l) + 1.0, l[l.index(")") + 1:])
                          if l.startswith("(") and stamp(l) > mid else l + "\n" for l in lines)
        p = run_trajd(conf(d))
        self.assertEqual(p.returncode, 0, p.stderr[-800:])
        rows, _ = ct.decode_setpoints(os.path.join(d, "sp.log"))
        states = [rows[k]["state"] for k in sorted(rows)]
        entered = sum(1 for a, b in zip(states, states[1:]) if b == 2 and a != 2)
        self.assertGreater(entered, 0)  # the pause did run the output short
        page7 = [f for _, f in ct.decode_by_id(os.path.join(d, "sp.log"), 0x6D0)
                 if int(f["ST2_Page"]) == 7]
        self.assertGreater(len(page7), 0)
        self.assertEqual(int(page7[-1]["ST2_Underruns"]), entered)
        self.assertGreater(int(page7[-1]["ST2_DelayGrown"]), 0)
        self.assertEqual((int(page7[-1]["ST2_AxisBeyond"]), int(page7[-1]["ST2_AxisLagStops"])),
                         (0, 0))

    # Given 4 objects at 1 kHz with own frames and CiA 402 RPDOs at 500 kbit/s,
    # then --check-config refuses with the computed load, which agrees with
    # frame lengths computed here from Davis et al. 2007 (eq. 2).
    def test_busload_refused(self):
        d = self.sub("load")
        def bits(n):  # worst-case classic 11-bit frame, with IFS
            return 8 * n + 47 + (34 + 8 * n - 1) // 4
        objs = "".join("[object.o%d]\nid = %d\ninput = can\noutput = can\ncan.cia402 = yes\n"
                       "can.cia402_feedback = no\ninitial_position = 0,0,0\n"
                       "can.cia402_cob_x = 0x%x\ncan.cia402_cob_y = 0x%x\ncan.cia402_cob_z = 0x%x\n"
                       % (i, i, 0x201 + 3 * i, 0x202 + 3 * i, 0x203 + 3 * i) for i in range(4))
        path = os.path.join(d, "load.conf")
        with open(path, "w") as fh:
            fh.write("[daemon]\nrate_hz = 1000\n[can]\ninterface = vcan0\nsync = yes\n"
                     "bitrate = 500000\nwaypoint_hz = 10\nstatus_period_ms = 100\n" + objs)
        # per object: STATUS and STATUS2 at 10 Hz, 10 waypoints/s of 4 frames
        per_s = 1000 * (bits(0) + 4 * (3 * bits(8) + 3 * bits(4))) + 4 * (2 * 10 * bits(8) + 10 * 4 * bits(8))
        expect = per_s / 500000 * 100
        p = subprocess.run([TRAJD, "--check-config", path], capture_output=True, text=True, timeout=10)
        self.assertNotEqual(p.returncode, 0)
        msg = p.stdout + p.stderr
        self.assertIn("CAN bus load %.1f %%" % expect, msg)
        self.assertIn("max_load_percent = 70", msg)
        # and one object at 100 Hz, classic, is well below: accepted
        with open(path, "w") as fh:
            fh.write("[daemon]\nrate_hz = 100\n[can]\ninterface = vcan0\n"
                     "[object.o0]\ninput = can\noutput = can\n")
        p = subprocess.run([TRAJD, "--check-config", path], capture_output=True, text=True, timeout=10)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)

    # Given a kernel without CAN (this host), when trajd is told to use a
    # SocketCAN interface, then it refuses to start with the reason, instead
    # of running in a DOWN state that could never come up.
    def test_no_can_in_kernel(self):
        import socket
        try:
            socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
            self.skipTest("this kernel has CAN (covered by test_can_uml.sh)")
        except OSError:
            pass
        d = self.sub("nocan")
        path = os.path.join(d, "s.conf")
        with open(path, "w") as fh:
            fh.write("[daemon]\nrate_hz = 100\n[can]\ninterface = vcan0\n"
                     "[object.o0]\ninput = can\noutput = can\n")
        p = subprocess.run([TRAJD, "-f", "-c", path], capture_output=True, text=True, timeout=10)
        self.assertNotEqual(p.returncode, 0)
        self.assertIn("cannot open a CAN socket", p.stderr)

    # Given a candump log_in of the track without the FINISH frame at its
    # end, when trajd replays it with exit_when_done, then the log's end ends
    # the object's input as a replayed track's does: it runs to the last
    # waypoint (the track's own, from the CSV), comes to rest there
    # (finished, velocity 0) and trajd exits 0 (it stayed in underrun for
    # ever: issue 23)
    def test_log_in_without_finish_ends_its_input(self):
        d = self.sub("nofinish")
        ct.write_wplog(self.xyz, os.path.join(d, "wp.log"))
        with open(os.path.join(d, "wp.log")) as fh:
            lines = fh.read().splitlines(True)
        with open(os.path.join(d, "wp.log"), "w") as fh:
            fh.writelines(lines[:-1])  # the FINISH command frame, the last line
        self.assertNotEqual(lines[-1], lines[-2])
        p = run_trajd(conf(d, "", "csv.path = sp.csv\n", output="csv"))
        self.assertEqual(p.returncode, 0, p.stderr[-800:])
        last = ct.read_replay(os.path.join(d, "sp.csv"))
        last = last[max(last)]
        t, x, y, z = ct.read_xyz(self.xyz)[-1]
        self.assertEqual(last["state"], "finished", last)
        for ax, want in zip("xyz", (x, y, z)):
            self.assertAlmostEqual(float(last[ax + "_m"]), float(want), delta=1e-3)
            self.assertEqual(float(last["v%s_m_s" % ax]), 0.0)


class CanLogNothingUsable(unittest.TestCase):
    # Given a candump log_in holding nothing usable for the object, when
    # trajd replays it with exit_when_done, then it exits 65 (EX_DATAERR,
    # as for a replayed track with no usable waypoint) with an error line
    # naming the object and the log, never 0 as if it had done its work
    def run_log(self, d, body):
        with open(os.path.join(d, "wp.log"), "w") as fh:
            fh.write(body)
        return run_trajd(conf(d, output="csv", extra_obj="csv.path = sp.csv\n"))

    def test_nothing_usable(self):
        with tempfile.TemporaryDirectory() as d:
            far = os.path.join(d, "far.csv")
            with open(far, "w") as fh:  # x = 1e8 m: encodable, above max_abs_m (1e7)
                fh.write("t,x,y,z\n" + "".join("%d,1e8,0,0\n" % i for i in range(20)))
            ct.write_wplog(far, os.path.join(d, "far.log"))
            with open(os.path.join(d, "far.log")) as fh:
                far_log = fh.read()
            with open(CAPTURE) as fh:
                foreign = "".join(l for l in fh if l.strip() and not l.startswith("#"))
            cases = {  # a log with no frame at all: CanLogInRefused
                "foreign": foreign,
                "range": far_log,
            }
            for name, body in cases.items():
                p = self.run_log(d, body)
                self.assertEqual(p.returncode, 65, "%s: %s" % (name, p.stderr[-800:]))
                self.assertRegex(p.stderr, r"<3>can: object 'boat': log_in \S*wp.log ended with no "
                                 r"usable waypoint for it \(0 accepted, \d+ rejected, \d+ malformed"
                                 r" frames, \d+ bad lines[^\n]*\); trajd will exit with status 65", name)
                self.assertIn("<3>a replayed track or candump log ended 1 time(s) with no usable "
                              "waypoint for an object", p.stderr)
            # a log made for another object's id (waypoints on 0x681, this object's 0x680):
            # the line names both (it said "0 accepted" alone; only the status said how
            # many frames were for no object)
            shifted = os.path.join(d, "shifted.csv")
            with open(shifted, "w") as fh:
                fh.write("t,x,y,z\n" + "".join("%d,%d,0,0\n" % (i, i) for i in range(20)))
            ct.write_wplog(shifted, os.path.join(d, "shifted.log"))
            with open(os.path.join(d, "shifted.log")) as fh:
                body = fh.read().replace(" can0 680#", " can0 681#")
            self.assertIn(" can0 681#", body)
            p = self.run_log(d, body)
            self.assertEqual(p.returncode, 65, p.stderr[-800:])
            self.assertRegex(p.stderr, r"ended with no usable waypoint for it \(0 accepted, .*; "
                             r"\d+ frames on ids no object uses, the first on 0x681, while its "
                             r"waypoints come on 0x680")
            # one usable waypoint among them: exit 0
            good = cases["range"].replace("#010100407A10F35A", "#0101000000000000", 1)  # x 1e8 -> 0
            self.assertNotEqual(good, cases["range"])
            p = self.run_log(d, good)
            self.assertEqual(p.returncode, 0, p.stderr[-800:])
            self.assertNotIn("no usable waypoint", p.stderr)

    # Given an NMEA 2000 candump log with no position in it (foreign frames,
    # or trajd's own waypoint frames), when trajreplay reads it, then a
    # message saying what the log held and what replays it instead, exit 1
    # (it said "no waypoints" alone)
    def test_trajreplay_nothing_usable(self):
        with tempfile.TemporaryDirectory() as d:
            log = os.path.join(d, "x.log")
            with open(log, "w") as fh:
                fh.write("(0.100000) can0 123#00\n(0.200000) can0 124#0011\n")
            p = subprocess.run([TRAJREPLAY, "-q", "--format", "n2k", log], capture_output=True,
                               text=True, timeout=RUN_TIMEOUT_S)
            self.assertEqual(p.returncode, 1, p.stderr)
            self.assertIn("trajreplay: %s: no waypoints: no NMEA 2000 position with a usable fix "
                          "(PGN 129029 or 129025) among its 2 frames (0 positions without one, 0 "
                          "bad lines); a log of trajd's own WAYPOINT frames is replayed by trajd "
                          "([can] log_in)" % log, p.stderr)
            self.assertEqual(p.stdout, "")
            # trajd's own waypoint log given to trajreplay: the same hint
            xyz = os.path.join(d, "t.csv")
            with open(xyz, "w") as fh:
                fh.write("t,x,y,z\n" + "".join("%d,%d,0,0\n" % (i, i) for i in range(10)))
            ct.write_wplog(xyz, log)
            p = subprocess.run([TRAJREPLAY, "-q", log], capture_output=True, text=True,
                               timeout=RUN_TIMEOUT_S)
            self.assertEqual(p.returncode, 1, p.stderr)
            self.assertIn("among its 41 frames", p.stderr)
            self.assertIn("is replayed by trajd ([can] log_in)", p.stderr)



class CanLogInRefused(unittest.TestCase):
    # Given a [can] log_in (line 8 of the config) that holds no CAN frame or
    # cannot be read, when trajd --check-config reads the config, then it
    # exits 78 (EX_CONFIG) with "<conf>:8: [can]: log_in <path>: <why>", the
    # why naming the first bad line where there is one; trajd -f refuses to
    # start with the same line (with or without exit_when_done), within a
    # bound: it accepted the config, then exited 65 at the end of an empty
    # replay, or only at start ("read error") for a directory
    LOG_IN_LINE = 8

    def refused(self, d, why, user=None):
        path = conf(d, output="csv", extra_obj="csv.path = sp.csv\n")
        msg = "%s:%d: [can]: log_in %s: %s" % (path, self.LOG_IN_LINE, os.path.join(d, "wp.log"),
                                               why)
        kw = {"user": user} if user is not None else {}
        trajd = TRAJD
        if user is not None:
            # the user may not reach the checkout (under a directory only root
            # may enter, e.g. mktemp -d): run a copy from d, which it can
            trajd = os.path.join(d, "trajd")
            shutil.copy(TRAJD, trajd)
            os.chmod(trajd, 0o755)
        p = subprocess.run([trajd, "--check-config", path], capture_output=True, text=True,
                           timeout=RUN_TIMEOUT_S, **kw)
        self.assertEqual(p.returncode, 78, p.stdout + p.stderr)
        self.assertIn(msg, p.stderr)
        for when_done in ("yes", "no"):
            with open(path) as fh:
                text = fh.read().replace("exit_when_done = yes", "exit_when_done = " + when_done)
            with open(path, "w") as fh:
                fh.write(text)
            p = subprocess.run([trajd, "-f", "-c", path], capture_output=True, text=True,
                               timeout=RUN_TIMEOUT_S, **kw)
            self.assertEqual(p.returncode, 78, when_done + ": " + p.stderr[-800:])
            self.assertIn(msg, p.stderr)
            self.assertFalse(os.path.exists(os.path.join(d, "sp.csv")), "it ran")

    def test_empty(self):
        with tempfile.TemporaryDirectory() as d:
            open(os.path.join(d, "wp.log"), "w").close()
            self.refused(d, "empty: no CAN frame in it")

    def test_no_frame_line(self):
        # 4 lines: 1 comment, 1 blank, 2 bad (lines 3 and 4)
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "wp.log"), "w") as fh:
                fh.write("# only comments\n\nnot a frame\n(1.0) can0 zz#\n")
            self.refused(d, "no CAN frame in it (4 lines: 2 comments or blank, 2 bad, the "
                            "first bad at line 3: not a candump frame)")

    def test_missing(self):
        with tempfile.TemporaryDirectory() as d:
            self.refused(d, os.strerror(errno.ENOENT))

    def test_directory(self):
        with tempfile.TemporaryDirectory() as d:
            os.mkdir(os.path.join(d, "wp.log"))
            self.refused(d, os.strerror(errno.EISDIR))

    def test_unreadable(self):
        # root reads a mode-000 file: then trajd runs as nobody (65534)
        with tempfile.TemporaryDirectory() as d:
            log = os.path.join(d, "wp.log")
            with open(log, "w") as fh:
                fh.write("(1.000000) vcan0 123#00\n")
            os.chmod(log, 0)
            user = None
            if os.geteuid() == 0:
                os.chmod(d, 0o777)
                user = 65534
            self.refused(d, os.strerror(errno.EACCES), user=user)


if __name__ == "__main__":
    unittest.main()
