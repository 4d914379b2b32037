#!/usr/bin/python3
"""bench_delay.py - the play-out delay D (lib/engine/delay.h), stated and
measured in one run (issue 26 item 5).  Run by tests/bench/bench_delay.sh
(`make bench`); tests/e2e/test_doc_counts.py imports it to recompute the
table lib/engine/DESIGN.md shows ("The delay measured").

Every track is built here, in a temporary directory: no file and no network
outside it.  trajreplay replays each waypoint at its own time on a virtual
clock, so the output is deterministic and the delay at a row is
now - t_s (now_ns on the virtual clock, t_s the track time of the setpoint).

(a) D per configuration, on three regular tracks:
      10 Hz   x = 10 sin(0.05 i), y = 10 cos(0.03 i), t = 0.1 i (600 fixes)
      1 Hz    x = 300 sin(t/60), y = 200 sin(t/97), t = i (3600 fixes)
      200 Hz  the 10 Hz curve at 200 Hz: x = 10 sin(0.5 t), y = 10 cos(0.3 t),
              t = 0.005 i (12000 fixes)
    Per configuration: D and its parts as `trajreplay --summary` states them,
    the steady delay measured (median of now - t_s over the streaming rows
    whose t_s lies in the middle half of the track, and the most any of them
    differs from that median), underruns, and the largest distance from the
    output (every streaming row: rows flagged SCALED lie on the curve at their
    t_s too) to one global solve, scipy's CubicSpline through every waypoint
    with the engine's end conditions (rest: first derivative 0 at both ends),
    as tests/oracle/test_trajreplay.py compares.
(b) The lag over a track with many gaps: the 10 Hz curve cut into 6 pieces
    of 40 s (400 fixes) starting 55 s apart (15 s of silence after each),
    each piece starting 3 m beside the previous piece's end, so that each
    piece is a new trajectory reached by a transfer.  The delay every 5 s of
    now, and per piece the delay at its start (its first streaming row past
    the transfer) and at its end (its last streaming row before the brake to
    rest at its last fix), with the D stated.  trajreplay has no setting of
    [daemon] catchup (-c reads the object's engine settings only), so the
    trace without the lag won back is not shown.
(c) The accuracy/latency frontier (issue 31 item 3) on a bundled track as well: the N2K
    figure-8 at 5 Hz (tests/data/n2k_furuno_figure8_src52.csv), --profile none, its
    reference scipy's CubicSpline through its fixes in east/north metres by pyproj.
"""
import csv
import functools
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.interpolate import CubicSpline

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from oracle_util import proj_enu  # noqa: E402

STREAMING = 1                   # lib/motion.h ENGINE_STATE_STREAMING
SP_TRANSFER, SP_SCALED = 0x08, 0x40
# trajreplay --binary: a 64-byte header, then these records (trajreplay(1))
DTYPE = np.dtype([("now_ns", "<i8"), ("t_s", "<f8"), ("pos_m", "<f8", 3), ("vel_m_s", "<f8", 3),
                  ("acc_m_s2", "<f8", 3), ("state", "<u4"), ("flags", "<u4"), ("cycle", "<u4"),
                  ("track", "<u4"), ("reserved", "<u8")])

TRACKS = ("10 Hz", "1 Hz", "200 Hz")
CONFIGS = ((), ("--max-lookahead", "1"), ("--max-lookahead", "2"), ("--max-lookahead", "3"),
           ("--max-lookahead", "4"), ("--method", "hermite"), ("--method", "hermite-centred"),
           ("--max-lookahead", "6", "--accuracy", "0.1"), ("--max-lookahead", "8", "--accuracy", "3e-3"),
           ("--max-lookahead", "12", "--accuracy", "1e-4"), ("--max-lookahead", "18"),
           ("--delay", "5"),
           ("--max-speed", "10", "--delay", "5"), ("--max-speed", "10", "--delay", "25"))


# A bundled track (issue 31 item 3: "on the bundled tracks and a synthetic one"): the
# N2K capture of a boat's figure-8 at 5 Hz (tests/data/ATTRIBUTION.md), as recorded, with its
# 0.5 s hole and a fix 24 ms after the one before.  Replayed with --profile none, so that
# every fix is in the curve as in the reference: scipy's spline through its waypoints in
# east/north metres about the first fix, by pyproj (PROJ's cart + topocentric), as
# tests/oracle/test_trajreplay.py converts them.
BUNDLED = {"figure-8 5 Hz": "n2k_furuno_figure8_src52.csv"}
DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")


@functools.lru_cache(maxsize=None)
def bundled(name):
    """(t, x, y, path) of a bundled track: east/north by pyproj (oracle_util.proj_enu), read
    once for all the configurations measured on it."""
    path = os.path.join(DATA, BUNDLED[name])
    with open(path) as f:
        r = list(csv.DictReader(f))
    t = np.array([float(x["t_s"]) for x in r])
    lat = np.array([float(x["lat_deg"]) for x in r])
    lon = np.array([float(x["lon_deg"]) for x in r])
    e, n, _ = proj_enu(lat[0], lon[0], 0.0).transform(lat, lon, np.zeros_like(lat))
    return t, e, n, path


def track(name):
    """(t, x, y) of a track of (a)."""
    if name in BUNDLED:
        return bundled(name)[:3]
    if name == "10 Hz":
        i = np.arange(600)
        return 0.1 * i, 10 * np.sin(0.05 * i), 10 * np.cos(0.03 * i)
    if name == "1 Hz":
        t = np.arange(3600.0)
        return t, 300 * np.sin(t / 60), 200 * np.sin(t / 97)
    if name == "200 Hz":
        t = 0.005 * np.arange(12000)
        return t, 10 * np.sin(0.5 * t), 10 * np.cos(0.3 * t)
    raise KeyError(name)


def gap_track():
    """(t, x, y) of (b): 6 pieces of 40 s, 55 s apart, each 3 m beside the last one's end."""
    i = np.arange(400)
    px, py = 10 * np.sin(0.05 * i), 10 * np.cos(0.03 * i)
    tt, xx, yy = [], [], []
    ox = oy = 0.0
    for k in range(6):
        tt.append(55.0 * k + 0.1 * i)
        xx.append(px + ox)
        yy.append(py + oy)
        ox += px[-1] - px[0] + 3.0
        oy += py[-1] - py[0]
    return np.concatenate(tt), np.concatenate(xx), np.concatenate(yy)


def write_track(path, t, x, y):
    with open(path, "w") as f:
        f.write("t,x,y\n")
        f.write("".join("%r,%r,%r\n" % (float(a), float(b), float(c)) for a, b, c in zip(t, x, y)))


def replay(exe, path, opts, tmp):
    """(exit code, summary dict, records, stderr) of trajreplay -q --summary --binary."""
    out = os.path.join(tmp, "out.bin")
    p = subprocess.run([exe, "-q", "--summary", "--binary", "-o", out] + list(opts) + [path],
                       capture_output=True, text=True, timeout=600)
    s = {}
    for line in p.stderr.splitlines():
        if line.startswith("summary: "):
            k, v = line[len("summary: "):].split(" ", 1)
            s[k] = float(v) if k != "method" else v.strip()
    rows = np.fromfile(out, dtype=DTYPE, offset=64) if p.returncode == 0 else None
    return p.returncode, s, rows, p.stderr


def refusal(stderr):
    """trajreplay's reason, without its prefix."""
    line = next((l for l in stderr.splitlines() if not l.startswith("summary: ")), stderr.strip())
    return line.replace("trajreplay: invalid engine configuration: ", "")


def measure(exe, name, opts, tmp):
    """A row of (a): dict with 'refused' (the reason) or D, its parts and what was measured."""
    if name in BUNDLED:
        t, x, y, path = bundled(name)
        opts = tuple(opts) + ("--profile", "none")
    else:
        t, x, y = track(name)
        path = os.path.join(tmp, name.replace(" ", "") + ".csv")
        if not os.path.exists(path):
            write_track(path, t, x, y)
    rc, s, rows, err = replay(exe, path, opts, tmp)
    if rc != 0:
        return {"refused": refusal(err), "exit": rc}
    now = rows["now_ns"] * 1e-9
    st = rows["state"] == STREAMING
    span = t[-1] - t[0]
    mid = st & (rows["t_s"] >= t[0] + 0.25 * span) & (rows["t_s"] <= t[0] + 0.75 * span)
    d = now[mid] - rows["t_s"][mid]
    med = float(np.median(d))
    cs = CubicSpline(t, np.c_[x, y], bc_type=((1, [0, 0]), (1, [0, 0])))
    on = st & ((rows["flags"] & SP_TRANSFER) == 0)
    err_m = float(np.max(np.hypot(*(rows["pos_m"][on, :2] - cs(rows["t_s"][on])).T)))
    return {"D": s["delay_s"], "lookahead": s["delay_lookahead_s"], "slack": s["delay_slack_s"],
            "stop": s["delay_stop_s"], "interval": s["delay_interval_s"], "speed": s["delay_speed_m_s"],
            "steady": med, "spread": float(np.max(np.abs(d - med))), "rows": int(mid.sum()),
            "underruns": int(s["underruns"]), "catchups": int(s["catchups"]), "err_m": err_m,
            "method": s.get("method", "?")}


def opts_text(opts):
    return " ".join(opts) if opts else "defaults"


# The accuracy/latency frontier the top-level README shows (issue 31): the 10 Hz track and
# the bundled figure-8, from the local methods (each of them: the C2 ones max_lookahead
# picks, the C1 ones by name) to the default lookahead
FRONTIER = (("--max-lookahead", "1"), ("--max-lookahead", "2"), ("--max-lookahead", "3"),
            ("--max-lookahead", "4"), ("--method", "hermite"), ("--method", "hermite-centred"),
            ("--max-lookahead", "6", "--accuracy", "0.1"), ("--max-lookahead", "8", "--accuracy", "3e-3"),
            ("--max-lookahead", "12", "--accuracy", "1e-4"), ())
FRONTIER_TRACKS = ("10 Hz", "figure-8 5 Hz")


def table_a(exe, tmp, tracks=TRACKS, configs=CONFIGS):
    """The lines of table (a), markdown, then the notes: each refusal's message once."""
    lines = ["| track | configuration | method | D s | lookahead + slack + stop s | steady delay s "
             "(max off) | underruns | max error m |", "|---|---|---|---|---|---|---|---|"]
    why = []
    for name in tracks:
        for opts in configs:
            m = measure(exe, name, opts, tmp)
            cfg = "`%s`" % opts_text(opts)
            if "refused" in m:
                if m["refused"] not in why:
                    why.append(m["refused"])
                lines.append("| %s | %s | | refused (%d) | | | | |" % (name, cfg, why.index(m["refused"]) + 1))
                continue
            lines.append("| %s | %s | %s | %.3f | %.3f + %.3f + %.3f | %.3f (%.3f) | %d | %.1e |" % (
                name, cfg, m["method"], m["D"], m["lookahead"], m["slack"], m["stop"], m["steady"], m["spread"],
                m["underruns"], m["err_m"]))
    return lines + [""] + ["(%d) %s" % (k + 1, w) for k, w in enumerate(why)]


def lag_trace(exe, tmp):
    """(summary, [(now, state, piece, delay or None)] every 5 s, per piece a dict) of (b).
    The D of a piece is the one stated when its output started: the summary's delay_s of
    the track replayed up to that piece's end (engine_delay: the last start's)."""
    t, x, y = gap_track()
    path = os.path.join(tmp, "gaps.csv")
    write_track(path, t, x, y)
    rc, s, rows, err = replay(exe, path, (), tmp)
    if rc != 0:
        raise SystemExit("gap track: exit %d: %s" % (rc, err))
    now = rows["now_ns"] * 1e-9
    delay = now - rows["t_s"]
    st = rows["state"] == STREAMING
    names = ["waiting", "streaming", "underrun", "finished"]
    trace = []
    for k in range(0, len(rows), 500):   # 100 Hz: every 5 s
        on = st[k] and not rows["flags"][k] & SP_TRANSFER
        trace.append((now[k], "transfer" if st[k] and not on else names[rows["state"][k]],
                      int(rows["track"][k]), delay[k] if on else None))
    pieces = []
    for p in range(1, 7):
        on = np.flatnonzero(st & (rows["track"] == p) & ((rows["flags"] & SP_TRANSFER) == 0))
        free = on[(rows["flags"][on] & SP_SCALED) == 0]   # rate 1: past the ramp, before the brake
        part = os.path.join(tmp, "part.csv")
        write_track(part, t[:400 * p], x[:400 * p], y[:400 * p])
        d = replay(exe, part, (), tmp)[1]["delay_s"] if p < 6 else s["delay_s"]
        pieces.append({"D": d, "out_s": now[on[0]], "first": delay[on[0]], "start": delay[free[0]],
                       "end": delay[free[-1]]})
    return s, trace, pieces


def main(exe):
    with tempfile.TemporaryDirectory() as tmp:
        print("(a) The play-out delay D per configuration: D as `trajreplay --summary` states it,")
        print("its parts, the steady delay measured (median of now - t_s, streaming rows, middle")
        print("half of the track; in brackets the most a row is off it), underruns, and the largest")
        print("distance of a streamed row from scipy's CubicSpline through every waypoint (rest ends).")
        print()
        print("\n".join(table_a(exe, tmp)))
        print()
        s, trace, pieces = lag_trace(exe, tmp)
        print("(b) The lag over a track with gaps: the 10 Hz curve in 6 pieces of 40 s, 55 s apart,")
        print("each 3 m beside the previous piece's end (a transfer); the lag beyond D won back at")
        print("up to 5 %% (catchup.h).  D stated at the end: %.3f s (lookahead %.3f + slack %.3f +"
              % (s["delay_s"], s["delay_lookahead_s"], s["delay_slack_s"]))
        print("stop %.3f); underruns %d, catchups %d, silent ends %d, trajectories %d."
              % (s["delay_stop_s"], s["underruns"], s["catchups"], s["silent_ends"], s["tracks"]))
        print()
        print("| now s | state | piece | delay s |")
        print("|---|---|---|---|")
        for now, state, piece, d in trace:
            print("| %.0f | %s | %d | %s |" % (now, state, piece, "" if d is None else "%.3f" % d))
        print()
        print("| piece | output starts, now s | D s | delay at its first row | after the ramp | "
              "at its end (before the brake) | lag won back | lag left |")
        print("|---|---|---|---|---|---|---|---|")
        for k, p in enumerate(pieces):
            print("| %d | %.2f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |" % (
                k + 1, p["out_s"], p["D"], p["first"], p["start"], p["end"], p["start"] - p["end"],
                p["end"] - p["D"]))
        print()
        print("trajreplay offers no [daemon] catchup setting: the trace without the catch-up is not shown.")
        print()
        print("(c) The accuracy/latency frontier on a bundled track (the top-level README shows it")
        print("with the 10 Hz rows of (a)): the N2K figure-8 at 5 Hz as recorded, --profile none,")
        print("against scipy's CubicSpline through its waypoints in east/north metres by pyproj.")
        print()
        print("\n".join(l for l in table_a(exe, tmp, FRONTIER_TRACKS[1:], FRONTIER) if l))


if __name__ == "__main__":
    main(sys.argv[1])
