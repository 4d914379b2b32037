"""Helpers for the CAN tests: a track as waypoint frames, built by canmatrix
from config/trajd.dbc alone (not by our codec), and setpoint logs decoded the
same way.  Also a command line for the guest scenarios:

  cantools_trajd.py xyz IN.csv OUT.csv N         lat/lon track -> xyz CSV (6 decimals), first N rows
  cantools_trajd.py wplog IN_xyz.csv OUT.log [--fd] [--foreign CAPTURE]
                                                  waypoint frames as a candump log stamped at t
  cantools_trajd.py compare SP.log REPLAY.csv [N]  decode setpoints, compare with trajreplay
  cantools_trajd.py uml-check RUN TRACK.csv REF.csv  the UML CAN scenarios' captures (test_can_uml.sh)
  cantools_trajd.py drive-check RUN               the UML drive scenario's capture (test_drive_uml.sh)
  cantools_trajd.py --help                        this text
"""
import csv
import decimal
import logging
import math
import os
import sys

logging.disable(logging.WARNING)
import can  # noqa: E402
import canmatrix  # noqa: E402
import canmatrix.formats  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
DBC = os.path.join(ROOT, "config", "trajd.dbc")

# Setpoint positions are 0.1 mm per bit: trajd rounds, so its value is within
# half a bit of the exact one; trajreplay's exact double rounds the same way
# except within ~1e-12 m of a rounding boundary: allow half a bit plus 1e-9 m.
SP_POS_TOL = 0.5e-4 + 1e-9
SP_VEL_TOL = 0.5e-3 + 1e-9
EARTH_R = 6371000.0
STATES = ["waiting", "streaming", "underrun", "finished"]  # engine_state_name()


def load_db():
    return canmatrix.formats.loadp_flat(DBC)


def to_xyz(src, dst, nmax):
    """Equirectangular local metres about the first point, rounded to um / us.
    (Any smooth mapping will do: the same file feeds both trajreplay and CAN.)"""
    with open(src) as fh:
        rows = list(csv.DictReader(fh))[:nmax]
    lat0, lon0 = float(rows[0]["lat_deg"]), float(rows[0]["lon_deg"])
    with open(dst, "w") as out:
        out.write("t_s,x_m,y_m,z_m\n")
        for r in rows:
            x = math.radians(float(r["lon_deg"]) - lon0) * EARTH_R * math.cos(math.radians(lat0))
            y = math.radians(float(r["lat_deg"]) - lat0) * EARTH_R
            out.write("%.6f,%.6f,%.6f,%.6f\n" % (float(r["t_s"]), x, y, 0.0))


def read_xyz(path):
    with open(path) as fh:
        rd = csv.reader(fh)
        next(rd)
        return [tuple(decimal.Decimal(v) for v in row) for row in rd]


def _raw(fr, name, phys):
    sig = fr.signal_by_name(name)
    return int((phys - sig.offset) / sig.factor)


def waypoint_frames(db, seq, t, x, y, z, fd=False, wp_id=0x680, wpfd_id=0x690):
    """[(id, bytes, is_fd)] for one waypoint, encoded by canmatrix."""
    if fd:
        fr = db.frame_by_id(canmatrix.ArbitrationId(0x690))
        d = {"WPFD_Mux": 5, "WPFD_Seq": seq & 0xFF, "WPFD_Time": _raw(fr, "WPFD_Time", t)}
        for ax, v in zip("XYZ", (x, y, z)):
            d["WPFD_" + ax] = _raw(fr, "WPFD_" + ax, v)
        return [(wpfd_id, bytes(fr.encode(d)), True)]
    fr = db.frame_by_id(canmatrix.ArbitrationId(0x680))
    out = [(wp_id, bytes(fr.encode({"WP_Mux": 0, "WP_Seq": seq & 0xFF,
                                    "WP_Time": _raw(fr, "WP_Time", t)})), False)]
    for k, (ax, v) in enumerate(zip("XYZ", (x, y, z))):
        out.append((wp_id, bytes(fr.encode({"WP_Mux": k + 1, "WP_Seq": seq & 0xFF,
                                            "WP_" + ax: _raw(fr, "WP_" + ax, v)})), False))
    return out


def command_frame(db, cmd, wp_id=0x680):
    fr = db.frame_by_id(canmatrix.ArbitrationId(0x680))
    return (wp_id, bytes(fr.encode({"WP_Mux": 4, "WP_Seq": 0, "WP_Command": cmd})), False)


def fmt_frame(can_id, data, is_fd):
    return "%03X%s%s" % (can_id, "##0" if is_fd else "#", data.hex().upper())


def write_wplog(xyz, out, fd=False, foreign=None, iface="can0", time_scale=1.0, also_fd_obj=None):
    """Waypoint frames of track xyz as a candump -l log stamped at each t (plus
    a FINISH command after the last), with comment lines on top and, if
    foreign is a capture, its first frames interleaved (not our ids).
    time_scale: stamps are t / time_scale (canplayer replays wall time, trajd
    runs at speed = time_scale); the frames still carry t.
    also_fd_obj: object number n whose FD waypoint frames (0x690+n) carry the
    same track too, interleaved."""
    db = load_db()
    rows = read_xyz(xyz)
    foreign_lines = []
    if foreign:
        with open(foreign) as fh:
            foreign_lines = [l.split()[-1] for l in fh if l.strip() and not l.startswith("#")][:50]
    with open(out, "w") as fh:
        fh.write("# waypoints of %s as trajd CAN frames (canmatrix from config/trajd.dbc)\n" % xyz)
        fh.write("#\n")
        for i, (t, x, y, z) in enumerate(rows):
            frames = waypoint_frames(db, i + 1, t, x, y, z, fd)
            if also_fd_obj is not None:
                frames += waypoint_frames(db, i + 1, t, x, y, z, True, wpfd_id=0x690 + also_fd_obj)
            for can_id, data, is_fd in frames:
                fh.write("(%.6f) %s %s\n" % (float(t) / time_scale, iface, fmt_frame(can_id, data, is_fd)))
            if i < len(foreign_lines):
                fh.write("(%.6f) %s %s\n" % (float(t) / time_scale, iface, foreign_lines[i]))
        fh.write("(%.6f) %s %s\n" % (float(rows[-1][0]) / time_scale, iface,
                                      fmt_frame(*command_frame(db, 1))))
        if also_fd_obj is not None:
            fh.write("(%.6f) %s %s\n" % (float(rows[-1][0]) / time_scale, iface,
                                          fmt_frame(*command_frame(db, 1, 0x680 + also_fd_obj))))
    return len(rows), min(len(rows), len(foreign_lines))


def write_faulty_wplog(xyz, out, repeat_60=False):
    """write_wplog with faults: waypoint 50 missing (1 lost), a frame of wrong
    length and one of an unknown multiplexer after waypoint 60 (2 malformed),
    and with repeat_60 waypoint 60's frames sent again (a duplicate)."""
    write_wplog(xyz, out)
    with open(out) as fh:
        lines = fh.read().splitlines()
    res = []
    for line in lines:
        f = line.split()[-1] if not line.startswith("#") else ""
        if f.startswith("680#") and int(f[6:8], 16) == 50 and f[4:6] != "04":
            continue  # waypoint 50 lost
        res.append(line)
        if f.startswith("680#") and int(f[6:8], 16) == 60 and f[4:6] == "03":
            ts = line.split()[0]
            if repeat_60:
                res += [l for l in lines if l.startswith(ts) and "680#" in l]  # 60 again
            res.append("%s vcan0 680#0011" % ts)            # wrong length
            res.append("%s vcan0 680#0911000000000000" % ts)  # unknown mux
    with open(out, "w") as fh:
        fh.write("\n".join(res) + "\n")


def decode_fd_setpoints(log, sp_id=0x6B0):
    """{now_ns: {"x":.., "vx":.., "state":.., "cycle":..}} from SETPOINT_FD frames."""
    db = load_db()
    fr = db.frame_by_id(canmatrix.ArbitrationId(0x6B0))
    rows = {}
    for m in can.CanutilsLogReader(log):
        if m.arbitration_id != sp_id:
            continue
        assert m.is_fd and len(m.data) == 32
        d = {k: float(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}
        rows[round(m.timestamp * 1e6) * 1000] = {
            "x": d["SPFD_X"], "y": d["SPFD_Y"], "z": d["SPFD_Z"], "vx": d["SPFD_VX"],
            "vy": d["SPFD_VY"], "vz": d["SPFD_VZ"], "state": int(d["SPFD_State"]),
            "cycle": int(d["SPFD_Cycle"]), "flags": int(d["SPFD_Flags"])}
    return rows


def decode_by_id(log, can_id):
    """[(now_ns, {signal: value})] of every frame with can_id, decoded by canmatrix."""
    db = load_db()
    fr = db.frame_by_id(canmatrix.ArbitrationId(can_id))
    out = []
    for m in can.CanutilsLogReader(log):
        if m.arbitration_id == can_id:
            out.append((round(m.timestamp * 1e6) * 1000,
                        {k: float(v.phys_value) for k, v in fr.decode(bytes(m.data)).items()}))
    return out


def decode_setpoints(log, sp_id=0x6A0):
    """{now_ns: {"x": .., "vx": .., ..., "state": .., "cycle8": ..}} from a
    candump log of classic SETPOINT frames (python-can reads the log,
    canmatrix decodes).  Also returns the other frames' ids counted."""
    db = load_db()
    fr = db.frame_by_id(canmatrix.ArbitrationId(0x6A0))
    rows, others = {}, {}
    for m in can.CanutilsLogReader(log):
        if m.arbitration_id != sp_id:
            others[m.arbitration_id] = others.get(m.arbitration_id, 0) + 1
            continue
        d = {k: v.phys_value for k, v in fr.decode(bytes(m.data)).items()}
        now_ns = round(m.timestamp * 1e6) * 1000
        r = rows.setdefault(now_ns, {})
        ax = "xyz"[int(d["SP_Axis"])]
        r[ax] = float(d["SP_%s_Pos" % ax.upper()])
        r["v" + ax] = float(d["SP_%s_Vel" % ax.upper()])
        r["state"] = int(d["SP_State"])
        r["cycle8"] = int(d["SP_Cycle"])
    return rows, others


def read_replay(path):
    with open(path) as fh:
        return {int(r["now_ns"]): r for r in csv.DictReader(fh)}


def quant(v, lsb, lo, hi):
    return max(lo, min(hi, round(v / lsb))) * lsb


def compare(sp_log, replay_csv, min_rows=100):
    """Every setpoint in the CAN log equals trajreplay's for the same tick,
    within the field resolution; returns (rows compared, worst error m)."""
    rows, _ = decode_setpoints(sp_log)
    ref = read_replay(replay_csv)
    worst = 0.0
    n = 0
    last = max(ref)
    prev_cycle = None
    for now_ns, r in sorted(rows.items()):
        # trajreplay stops at FINISHED; the daemon rests there until it exits
        assert now_ns in ref or now_ns > last, "tick %d not in trajreplay output" % now_ns
        e = ref[min(now_ns, last)]
        for ax in "xyz":
            exp = quant(float(e[ax + "_m"]), 1e-4, -2**31, 2**31 - 1)
            err = abs(r[ax] - exp)
            worst = max(worst, abs(r[ax] - float(e[ax + "_m"])))
            assert abs(r[ax] - float(e[ax + "_m"])) <= SP_POS_TOL, (now_ns, ax, r[ax], e[ax + "_m"], err)
            v = float(e["v%s_m_s" % ax])
            assert abs(r["v" + ax] - max(-32.768, min(32.767, v))) <= SP_VEL_TOL, (now_ns, ax, r["v" + ax], v)
        assert STATES[r["state"]] == e["state"], (now_ns, r["state"], e["state"])
        # cycle: the engine counts ticks answered; the daemon may skip late
        # ticks (trajreplay never does), so only its increase is checked
        assert prev_cycle is None or (r["cycle8"] - prev_cycle) & 0xFF >= 1, (now_ns, r["cycle8"])
        prev_cycle = r["cycle8"]
        n += 1
    assert n >= min_rows, "only %d setpoints compared" % n
    return n, worst


def _log_frames(path):
    return list(can.CanutilsLogReader(path))


def uml_check(run, xyz, ref1k):
    """Checks on the guest's captures (tests/uml/daemon.sh)."""
    import numpy as np
    db = load_db()
    sp = db.frame_by_id(canmatrix.ArbitrationId(0x6A0))
    rp = db.frame_by_id(canmatrix.ArbitrationId(0x201))
    msgs = _log_frames(os.path.join(run, "cap.log"))
    # cycles: SYNC, then 3 setpoint frames, then 3 RPDOs (in this order)
    cycles, cur = [], None
    finished_at = None
    for m in msgs:
        i = m.arbitration_id
        if i == 0x080:
            cur = {"t": m.timestamp}
            cycles.append(cur)
        elif i == 0x6A0 and cur is not None:
            d = {k: v for k, v in sp.decode(bytes(m.data)).items()}
            ax = int(d["SP_Axis"].raw_value)
            cur["xyz"[ax]] = float(d["SP_%s_Pos" % "XYZ"[ax]].phys_value)
            cur["raw" + "xyz"[ax]] = d["SP_%s_Pos" % "XYZ"[ax]].raw_value
            cur["state"] = int(d["SP_State"].raw_value)
        elif i in (0x201, 0x202, 0x203) and cur is not None:
            cur["rpdo%d" % (i - 0x201)] = rp.decode(bytes(m.data))["Target_Position_607A"].raw_value
        elif i == 0x6C0 and finished_at is None and m.data[0] == 3:
            finished_at = m.timestamp
    assert finished_at is not None
    # The drives report nothing (can.cia402_feedback = no): initial_position (the
    # track's start) is where they stand from the first cycle, never a waypoint.
    # A cycle without a position would carry the int32 n/a marker (0x80000000)
    # in trajd's own frames, and no RPDO (a drive would follow it)
    nopos = [c for c in cycles if all(c.get("raw" + ax) == -2**31 for ax in "xyz")]
    assert not nopos, nopos[:2]
    for c in nopos:
        assert not any(k in c for k in ("rpdo0", "rpdo1", "rpdo2")), c
        assert c["state"] == 0, c
    cycles = [c for c in cycles if not any(c.get("raw" + ax) == -2**31 for ax in "xyz")]
    whole = [c for c in cycles if all(k in c for k in ("x", "y", "z", "rpdo0", "rpdo1", "rpdo2"))]
    # The guest is slow: candump may lose frames (its receive queue), and trajd
    # drops a cycle when its socket buffer is full (counted in STATUS): most
    # cycles must still be whole.
    # (a late cycle sends its SYNC and RPDOs but not the own frames: those are
    # not whole cycles, and not counted against)
    own = [c for c in cycles if "x" in c]
    assert len(whole) >= 0.5 * len(own), (len(whole), len(own), len(cycles))
    # CiA 402 RPDO = the same position in 1e-4 m increments (+-1 at a rounding tie)
    for c in whole:
        for a, ax in enumerate("xyz"):
            assert abs(c["rpdo%d" % a] - c["raw" + ax]) <= 1, c
    # every streamed setpoint lies on trajreplay's curve (sampled at 1 kHz)
    with open(ref1k) as fh:
        ref = [(float(r["x_m"]), float(r["y_m"])) for r in csv.DictReader(fh)]
    R = np.array(ref)
    A, B = R[:-1], R[1:]
    AB = B - A
    L2 = np.maximum((AB ** 2).sum(1), 1e-30)
    worst = 0.0
    pts = [(c["x"], c["y"]) for c in cycles if "x" in c and "y" in c and c["t"] <= finished_at]
    for (px, py) in pts:
        P = np.array([px, py])
        tt = np.clip(((P - A) * AB).sum(1) / L2, 0, 1)
        dist = np.sqrt((((A + AB * tt[:, None]) - P) ** 2).sum(1)).min()
        worst = max(worst, dist)
    # tolerance: 0.1 mm field (half a bit per axis: 0.071 mm) + 1e-5 m for the
    # forward-difference stepper at 100 Hz vs 1 kHz (engine bound is far smaller)
    assert worst <= 0.71e-4 + 1e-5, worst
    # the last setpoint before FINISHED is the last waypoint
    last_wp = read_xyz(xyz)[-1]
    fin = [c for c in whole if c["t"] >= finished_at][:1]
    assert fin and abs(fin[0]["x"] - float(last_wp[1])) <= 0.5e-4 + 1e-9 and \
        abs(fin[0]["y"] - float(last_wp[2])) <= 0.5e-4 + 1e-9, (fin, last_wp)
    # object 1 streams the same track as FD frames (0x691 in, 0x6B1 out)
    fdrows = decode_fd_setpoints(os.path.join(run, "cap.log"), sp_id=0x6B1)
    # no position yet: the n/a marker with flags bit 4 (ENGINE_SP_NO_POSITION)
    for r in fdrows.values():
        assert (r["x"] == -2**31 * 1e-4) == bool(r["flags"] & 0x10), r
    # every positioned row, not only those before object 0 finished: its waypoints
    # come from another sender in the guest, which a busy host may delay by seconds
    fd_pts = [(r["x"], r["y"]) for t, r in sorted(fdrows.items()) if not r["flags"] & 0x10]
    assert len(fd_pts) > 0.5 * len(pts), (len(fd_pts), len(pts))
    fd_worst = 0.0
    for (px, py) in fd_pts:
        P = np.array([px, py])
        tt = np.clip(((P - A) * AB).sum(1) / L2, 0, 1)
        fd_worst = max(fd_worst, np.sqrt((((A + AB * tt[:, None]) - P) ** 2).sum(1)).min())
    assert fd_worst <= 0.71e-4 + 1e-5, fd_worst
    # down/up: the outage is the largest gap between cycles; right after it,
    # cycles come at the normal pace (no burst of stale ones)
    ts = [c["t"] for c in cycles]
    gaps = [(ts[i + 1] - ts[i], i) for i in range(len(ts) - 1)]
    g, gi = max(gaps)
    assert g >= 0.25, g   # the 0.3 s outage
    after = [t for t in ts[gi + 1:] if t - ts[gi + 1] < 0.010]
    # 10 ms at 1 kHz wall = 10 cycles; guest timing is loose, a burst would be far more
    assert len(after) <= 15, len(after)
    # the kernel holds exactly our receive filters for trajd: the waypoint ids
    # of object 0 (classic) and object 1 (classic and FD)
    with open(os.path.join(run, "rcvlist_sff.txt")) as fh:
        sff = fh.read()
    ids = sorted({int(w, 16) for line in sff.splitlines() for w in line.split()[1:2]
                  if line.strip().startswith("vcan0") and len(w) == 3})
    assert ids == [0x680, 0x681, 0x691], (ids, sff)
    # throughput of the last phase
    fast = _log_frames(os.path.join(run, "cap5.log"))
    span = fast[-1].timestamp - fast[0].timestamp if len(fast) > 1 else 0
    fps = len(fast) / span if span > 0 else 0
    with open(os.path.join(run, "fast.txt")) as fh:
        tx0, tx1, t0, t1 = (float(v) for v in fh.read().split())
    return {"kernel_tx_fps": (tx1 - tx0) / (t1 - t0), "cycles": len(cycles),
            "fd_on_curve_worst_m": fd_worst, "on_curve_worst_m": worst, "outage_s": g,
            "cycles_10ms_after_up": len(after), "whole_cycles": len(whole),
            "fast_frames": len(fast), "fast_fps": fps}


def drive_check(run):
    """Checks on the drive scenario (tests/uml/drive.sh): what the simulated
    CiA 402 drives saw (drive_sim.json), what was on the bus (dcap.log, with
    STATUS2 decoded by canmatrix from the DBC) and what trajd logged
    (drive.err); the controlwords are judged by python-canopen's CiA 402
    master tables (canopen.profiles.p402.State402), not by trajd's."""
    import json
    import re
    sys.path.insert(0, os.path.join(os.environ["TRAJD_PEERS"], "python-canopen"))
    from canopen.profiles.p402 import State402
    with open(os.path.join(run, "drive_sim.json")) as fh:
        d1, d2, d3 = json.load(fh)
    with open(os.path.join(run, "drive.conf")) as fh:
        conf = fh.read()
    with open(os.path.join(run, "drive.err")) as fh:
        log = fh.read()
    rate = float(re.search(r"^rate_hz = (\S+)", conf, re.M).group(1))
    sdo = re.search(r"^can.cia402_sdo = (.*)$", conf, re.M).group(1).split(";")[0]
    want = []
    for item in sdo.split(","):
        m = re.match(r"\s*0x([0-9A-Fa-f]+):(\d+)=(-?(?:0x[0-9A-Fa-f]+|\d+))/(\d)", item)
        want.append([int(m.group(1), 16), int(m.group(2)), int(m.group(3), 0) % (1 << (8 * int(m.group(4))))])
    names = lambda d: [s for _, s, _ in d["states"]]  # noqa: E731
    enabled_path = ["NOT READY TO SWITCH ON", "SWITCH ON DISABLED", "READY TO SWITCH ON",
                    "SWITCHED ON", "OPERATION ENABLED"]
    for d in (d1, d2):
        # power-on: the configuration list written in order by expedited SDO, then the
        # controlword sequence; the interpolation period written is trajd's period
        # (a request unanswered for 500 ms on a slow guest is sent again: the same write twice)
        writes = [w[1:] for w in d["sdo"]]
        writes = [w for k, w in enumerate(writes) if k == 0 or w != writes[k - 1]]
        assert writes[:len(want)] == want, (writes[:4], want)
        assert d["sdo_6060"] == 8, d["sdo_6060"]
        assert abs(d["sdo_60c2"][0] * 10.0 ** d["sdo_60c2"][1] - 1 / rate) < 1e-9, d["sdo_60c2"]
        st = names(d)
        assert st[:5] == enabled_path, st
        # nothing a drive would follow while not enabled: its own 0x6064 as target
        assert d["rpdo_not_enabled_off"] <= 1, d["rpdo_not_enabled_off"]
        # every controlword trajd wrote is the master's command for the drive's state
        # (python-canopen's table: towards Operation Enabled, the fault reset on a
        # rising edge of bit 7 after Disable voltage, Disable voltage to hold)
        for t, cw, state in d["cw"]:
            if cw == State402.CW_DISABLE_VOLTAGE:
                assert state in ("OPERATION ENABLED", "QUICK STOP ACTIVE", "FAULT",
                                 "SWITCH ON DISABLED"), (t, cw, state)
            else:
                nxt = State402.next_state_indirect(state)
                assert State402.TRANSITIONTABLE[(state, nxt)] == cw, (t, cw, state)
        # SYNC every cycle although every cycle was late: the SYNC counter never
        # skipped (a drive faults on two missed SYNCs)
        assert d["max_sync_gap"] == 1 and d["syncs"] > 100, (d["max_sync_gap"], d["syncs"])
        # the RPDO's controlword to an enabled drive: Enable operation, never another
        assert d["rpdo_cw"] and all(cw == 0x0F for cw, st in d["rpdo_cw"]
                                    if st == "OPERATION ENABLED"), d["rpdo_cw"][:5]
    # the only fault is the injected one: no step, no following error, no SYNC loss
    assert [w for _, w in d1["faults"]] == ["injected"], d1["faults"]
    assert d2["faults"] == [], d2["faults"]
    # node 3: its list names 0x6071, which it lacks: abort reported, never enabled
    assert names(d3) == enabled_path[:2], names(d3)
    idx = [w[1] for w in d3["sdo"]]
    idx = [w for k, w in enumerate(idx) if k == 0 or w != idx[k - 1]]
    assert idx == [0x6060, 0x6040] and d3["cw"][0][1] == 0, d3["sdo"]
    assert "refused SDO write of 0x6071: abort 0x06020000 (object does not exist" in log
    # node 1 started 2 m (20000 increments) away from the track: its first target
    # is where it stood; node 2 (inverted): the track's y from 0 to 3 m is 0 .. -30000
    assert abs(d1["targets"][0] - 20000) <= 1, d1["targets"][:3]
    assert 0 in d1["targets"] and -30000 in d2["targets"]
    assert all(t <= 0 for t in d2["targets"]) and min(d2["targets"]) == -30000
    # each time a drive was enabled (power-on, node 1 after its fault, both after the
    # quick stop) trajd's first target was where the drive stood: no step on enable
    for d, n in ((d1, 3), (d2, 2)):
        assert len(d["enable_offsets"]) == n and max(d["enable_offsets"]) <= 1, d["enable_offsets"]
    # and it read node 2's increments back through the inversion: +3 m at the end
    starts = re.findall(r"starting from \((\S+), (\S+), (\S+)\)", log)
    assert len(starts) == 3 and starts[0][:2] == ("2.0000", "-0.0000"), starts
    assert all(y == "3.0000" for _, y, _ in starts[1:]), starts
    # every cycle was late (max_late_ms = 0.001): trajd's median lateness above it
    late = re.search(r"late p50/p99/p99.9/max (\d+)/", log)
    assert late and int(late.group(1)) > 1, late
    msgs = _log_frames(os.path.join(run, "dcap.log"))
    # on the bus: SYNC counter 1..240 without a gap; targets within the transfer's
    # bound of speed (1.5 x 2 m / 1 s) over the time between them (+ one period: a
    # tick that woke late, then one on time)
    sync = [m.data[0] for m in msgs if m.arbitration_id == 0x080]
    assert all((b - a) % 240 == 1 for a, b in zip(sync, sync[1:])), "SYNC counter gap"
    worst = 0.0
    for cob in (0x201, 0x202):
        rp = [(m.timestamp, int.from_bytes(m.data[2:6], "little", signed=True))
              for m in msgs if m.arbitration_id == cob]
        for (ta, a), (tb, b) in zip(rp, rp[1:]):
            worst = max(worst, abs(b - a) / (10000 * 3.0 * (tb - ta + 1 / rate)))
    # (1.5: margin for the capture's timestamp jitter in a loaded guest; the old 2 m step
    # in one cycle is 20000 / (30000 x 0.1) = 6.7)
    assert worst <= 1.5, worst
    # drive fault: after node 1's FAULT statusword, trajd sent node 1 only its own
    # position as target (beyond one cycle in flight) until it was enabled again
    i = next(k for k, m in enumerate(msgs) if m.arbitration_id == 0x181 and m.data[0] & 0x4F == 0x08)
    j = next(k for k, m in enumerate(msgs[i:], i) if m.arbitration_id == 0x181 and m.data[0] & 0x6F == 0x27)
    at = int.from_bytes(msgs[i].data[2:6], "little", signed=True)
    after = [int.from_bytes(m.data[2:6], "little", signed=True) for m in msgs[i:j]
             if m.arbitration_id == 0x201]
    assert all(abs(t - at) <= 1 for t in after[1:]), (at, after[:5])
    assert "a drive left Operation Enabled (x: fault" in log
    # ... and reported it: STATUS error 0x47, STATUS2 page 4 (decoded from the DBC):
    # node 1 in fault, object held, EMCY code of the simulator's injected fault
    st = [m for m in msgs[i:j] if m.arbitration_id == 0x6C0]
    assert any(m.data[7] == 0x47 for m in st), [bytes(m.data).hex() for m in st[:3]]
    db = load_db()
    s2 = db.frame_by_id(canmatrix.ArbitrationId(0x6D0))
    pages = [s2.decode(bytes(m.data)) for m in msgs[i:j] if m.arbitration_id == 0x6D0 and m.data[0] == 4]
    val = lambda sig: getattr(sig.raw_value, "real", sig.raw_value)  # noqa: E731
    held = [p for p in pages if val(p["ST2_Held"]) == 1 and val(p["ST2_StateX"]) == 7]
    assert held and val(held[-1]["ST2_Emcy"]) == 0xFF00, pages[:2]
    assert (val(held[-1]["ST2_Statusword"]) & 0x4F) == 0x08
    # ... and on Modbus (mbpoll in the guest, after the fault): object 0's drive_states
    # (x in fault, y disabled by trajd or still enabled, z none, held), statusword,
    # NMT state, EMCY; the daemon's EMCY count, last SDO abort (node 3's) and count
    def regs(name):
        with open(os.path.join(run, name)) as fh:
            return [int(m, 16) for m in re.findall(r"^\[\d+\]:\s+(0x[0-9A-Fa-f]+)", fh.read(), re.M)]
    states, sw, nmt, emcy = regs("mb_obj.txt")
    assert states & 0xF == 7 and (states >> 8) & 0xF == 15 and states & 0x8000, hex(states)
    assert sw & 0x4F == 0x08 and nmt == 5 and emcy == 0xFF00, (hex(sw), nmt, hex(emcy))
    dm = regs("mb_daemon.txt")
    assert (dm[0] << 16 | dm[1]) >= 1 and (dm[2] << 16 | dm[3]) == 0x06020000 and dm[4] >= 1, dm
    # quick stop: trajd answered with Disable voltage (transition 12), not Enable
    for d in (d1, d2):
        k = [n for n, (_, cw, state) in enumerate(d["cw"]) if state == "QUICK STOP ACTIVE"]
        assert k and d["cw"][k[0]][1] == 0, d["cw"]
        assert names(d)[-3:] == ["READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED"]
    # node 2's heartbeat stopped: object 0 held (override in force 0 %, drive_states
    # bit 14 heartbeat lost; the drives stay enabled), the daemon's count; after the clear the
    # operator's 50 % is in force (drive.sh waited for it), the loss no longer shown
    override, _, _, _, states = regs("mb_hb.txt")
    assert override == 0 and states & 0x4000, (override, hex(states))
    assert regs("mb_hb_daemon.txt")[0] >= 1
    override, _, _, _, states = regs("mb_hb_after.txt")
    assert override == 50 and not states & 0xC000, (override, hex(states))
    # ... and on CAN: STATUS2 page 4 flagged the lost heartbeat, page 1 counted the
    # refused CAN override
    p4 = [s2.decode(bytes(m.data)) for m in msgs if m.arbitration_id == 0x6D0 and m.data[0] == 4]
    assert any(val(p["ST2_HbLost"]) == 1 for p in p4), "no STATUS2 page 4 with HbLost"
    assert val(p4[-1]["ST2_HbLost"]) == 0, p4[-1]
    p1 = [s2.decode(bytes(m.data)) for m in msgs if m.arbitration_id == 0x6D0 and m.data[0] == 1]
    assert p1 and val(p1[-1]["ST2_CmdRefused"]) >= 1, p1[-1:]
    # heartbeat consumer: the nodes' NMT state (operational after NMT start) in STATUS2
    ok = [p for p in (s2.decode(bytes(m.data)) for m in msgs if m.arbitration_id == 0x6D0 and m.data[0] == 4)
          if val(p["ST2_StateX"]) == 4]
    assert ok and all(val(p["ST2_Nmt"]) == 5 for p in ok[-3:]), ok[-1:]
    return {"syncs_seen_by_drive1": d1["syncs"], "max_sync_gap": max(d1["max_sync_gap"], d2["max_sync_gap"]),
            "max_target_step_inc": max(d1["max_target_step"], d2["max_target_step"]),
            "worst_step_over_bound": round(worst, 3), "targets_after_fault": len(after),
            "late_p50_us": int(late.group(1))}


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        sys.exit(0 if len(sys.argv) >= 2 else 2)
    cmd = sys.argv[1]
    if cmd == "xyz":
        to_xyz(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    elif cmd == "wplog":
        fd = "--fd" in sys.argv
        foreign = sys.argv[sys.argv.index("--foreign") + 1] if "--foreign" in sys.argv else None
        iface = sys.argv[sys.argv.index("--iface") + 1] if "--iface" in sys.argv else "can0"
        scale = float(sys.argv[sys.argv.index("--time-scale") + 1]) if "--time-scale" in sys.argv else 1.0
        also = int(sys.argv[sys.argv.index("--also-fd-obj") + 1]) if "--also-fd-obj" in sys.argv else None
        print(write_wplog(sys.argv[2], sys.argv[3], fd, foreign, iface, scale, also))
    elif cmd == "uml-check":
        r = uml_check(sys.argv[2], sys.argv[3], sys.argv[4])
        print("uml: " + ", ".join("%s %s" % (k, ("%.3g" % v) if isinstance(v, float) else v)
                                  for k, v in r.items()))
    elif cmd == "drive-check":
        r = drive_check(sys.argv[2])
        print("uml drive: " + ", ".join("%s %s" % kv for kv in r.items()))
    elif cmd == "compare":
        n, worst = compare(sys.argv[2], sys.argv[3], int(sys.argv[4]) if len(sys.argv) > 4 else 100)
        print("compared %d setpoints, worst |can - trajreplay| = %.3g m" % (n, worst))
    else:
        sys.exit("unknown command " + cmd)
