"""Helpers for the CAN tests: a track as waypoint frames, built by canmatrix
from config/trajd.dbc alone (not by our codec), and setpoint logs decoded the
same way.  Also a command line for the guest scenarios:

  cantools_trajd.py xyz IN.csv OUT.csv N         lat/lon track -> xyz CSV (6 decimals), first N rows
  cantools_trajd.py wplog IN_xyz.csv OUT.log [--fd] [--foreign CAPTURE]
                                                  waypoint frames as a candump log stamped at t
  cantools_trajd.py compare SP.log REPLAY.csv     decode setpoints, compare with trajreplay
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

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
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


def write_wplog(xyz, out, fd=False, foreign=None, iface="can0"):
    """Waypoint frames of track xyz as a candump -l log stamped at each t (plus
    a FINISH command after the last), with comment lines on top and, if
    foreign is a capture, its first frames interleaved (not our ids)."""
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
            for can_id, data, is_fd in waypoint_frames(db, i + 1, t, x, y, z, fd):
                fh.write("(%.6f) %s %s\n" % (t, iface, fmt_frame(can_id, data, is_fd)))
            if i < len(foreign_lines):
                fh.write("(%.6f) %s %s\n" % (t, iface, foreign_lines[i]))
        fh.write("(%.6f) %s %s\n" % (rows[-1][0], iface, fmt_frame(*command_frame(db, 1))))
    return len(rows), min(len(rows), len(foreign_lines))


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
            "cycle": int(d["SPFD_Cycle"])}
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


if __name__ == "__main__":
    cmd = sys.argv[1]
    if cmd == "xyz":
        to_xyz(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    elif cmd == "wplog":
        fd = "--fd" in sys.argv
        foreign = sys.argv[sys.argv.index("--foreign") + 1] if "--foreign" in sys.argv else None
        iface = sys.argv[sys.argv.index("--iface") + 1] if "--iface" in sys.argv else "can0"
        print(write_wplog(sys.argv[2], sys.argv[3], fd, foreign, iface))
    elif cmd == "compare":
        n, worst = compare(sys.argv[2], sys.argv[3], int(sys.argv[4]) if len(sys.argv) > 4 else 100)
        print("compared %d setpoints, worst |can - trajreplay| = %.3g m" % (n, worst))
    else:
        sys.exit("unknown command " + cmd)
