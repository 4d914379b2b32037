#!/usr/bin/python3
"""drive_bus_check.py - the verdict on CiA 402 drives driven by trajd, from the
bus log alone (a candump -L file, read with python-can's CanutilsLogReader).
Shares no code with trajd: the statusword patterns are CiA 402-2 table 30,
the frames CiA 301 (SYNC 0x080, EMCY 0x080 + node, TPDO1 0x180 + node with
statusword u16 + position actual value 0x6064 i32, RPDO1 0x200 + node with
[controlword u16] + target 0x607A i32), as the drives are configured in
README.md ("Wiring a CiA 402 drive").

Rules, per drive (node); "known" means reported by a TPDO logged before the
last SYNC preceding the RPDO (trajd reads the bus at the start of each cycle,
then sends SYNC and the RPDOs: a TPDO after that SYNC cannot be known yet).
A SYNC counter starting again at 1 marks a new master (trajd restarted): it
knows nothing, so its first target to each drive is a "first" one (rule 2).
  1. a drive known not to be in Operation Enabled gets no target, or its own
     0x6064 (+-tol counts): never a moving one;
  2. the first target after a drive is known to have entered Operation
     Enabled equals its 0x6064 (+-tol);
  3. a drive known to be in Operation Enabled gets controlword 0x000F only
     (never Disable voltage, Shutdown, Quick stop: trajd restarted while it
     runs must adopt it);
  4. between two consecutive SYNCs, the targets of a drive in Operation
     Enabled move by at most v*T*counts_per_m + tol, and change their step by
     at most a*T^2*counts_per_m + 2 tol (v, a: the object's configured safety
     limits, T: the period); a SYNC missing (trajd stalled) does not widen
     the bound: the drive applies one target per SYNC;
  5. no drive fault caused by trajd: every EMCY code is one the test injected
     (--allow-emcy), or 0x8130 (heartbeat consumer: the master is gone) after
     the last SYNC of the log, or with --consumer-s S after S seconds without
     SYNC (trajd killed, never while it runs).
Exits 0 if no rule is broken, 1 else; prints a JSON summary (and the first
violations).

Usage: drive_bus_check.py LOG --period-s T --vmax V --amax A --node N:CPM ...
       [--tol 1] [--allow-emcy 0xFF00,...] [--stalls fail|report] [--json OUT]
"""
import argparse
import json
import struct
import sys

import can

SYNC = 0x080
OE = "operation enabled"


def state_of(sw):
    """CiA 402-2 table 30."""
    if sw & 0x4F == 0x00:
        return "not ready"
    if sw & 0x4F == 0x40:
        return "switch on disabled"
    if sw & 0x6F == 0x21:
        return "ready"
    if sw & 0x6F == 0x23:
        return "switched on"
    if sw & 0x6F == 0x27:
        return OE
    if sw & 0x6F == 0x07:
        return "quick stop"
    if sw & 0x4F == 0x0F:
        return "fault reaction"
    if sw & 0x4F == 0x08:
        return "fault"
    return "unknown"


class Drive:
    def __init__(self, node, cpm):
        self.node = node
        self.cpm = abs(cpm)
        self.hist = []             # (SYNC count when reported, state, 0x6064)
        self.was_oe = False        # known in Operation Enabled at the previous RPDO
        self.seq = []              # (SYNC count, target) sent in Operation Enabled
        self.st = {"rpdo": 0, "tpdo": 0, "enables": 0, "first_targets": [], "max_step": 0,
                   "max_step2": 0, "states": []}

    def tpdo(self, sw, pos, sync_index, t):
        self.st["tpdo"] += 1
        s = state_of(sw)
        if not self.hist or self.hist[-1][1] != s:
            self.st["states"].append([round(t, 4), s])
        self.hist.append((sync_index, s, pos))
        del self.hist[:-64]

    def known(self, sync_index):
        """(state, 0x6064) trajd can know when it sent SYNC number sync_index."""
        for k, s, pos in reversed(self.hist):
            if k < sync_index:
                return s, pos
        return None, None


def check(path, period_s, vmax, amax, nodes, tol=1, allow_emcy=(), stalls="fail", consumer_s=None):
    drives = {n: Drive(n, cpm) for n, cpm in nodes.items()}
    bad = []
    sync_index = 0
    last_sync_t = None
    counter = None
    sync_dt = 0.0
    emcys = []
    frames = masters = 0

    stalled = []
    stall_until = -1   # the SYNCs whose steps follow from trajd's last stall

    def violate(t, node, rule, text):
        v = {"t": round(t, 4), "node": node, "rule": rule, "what": text}
        if rule == 4 and sync_dt > 1.5 * period_s:   # say why, if trajd stalled
            v["what"] += " after %.0f ms without SYNC (trajd stalled %.1f periods)" % (
                sync_dt * 1e3, sync_dt / period_s)
        elif rule == 4 and sync_index <= stall_until:
            v["what"] += " (the SYNC after trajd's stall)"
        if rule == 4 and sync_index <= stall_until and stalls == "report":
            stalled.append(v)
            return
        bad.append(v)

    for msg in can.CanutilsLogReader(path):
        frames += 1
        cid, data, t = msg.arbitration_id, bytes(msg.data), msg.timestamp
        if msg.is_error_frame or msg.is_extended_id:
            continue
        if cid == SYNC:
            sync_index += 1
            sync_dt = t - last_sync_t if last_sync_t is not None else 0.0
            last_sync_t = t
            if sync_dt > 1.5 * period_s:
                stall_until = sync_index + 1
            c = data[0] if data else None
            if c == 1 and counter is not None and counter != 240:
                masters += 1    # the counter starts again: a new master (trajd restarted)
                for d in drives.values():
                    d.was_oe = False
                    d.seq = []
            counter = c
            continue
        node = cid & 0x7F
        fn = cid & 0x780
        d = drives.get(node)
        if d is None:
            continue
        if fn == 0x180 and len(data) >= 6:
            sw, pos = struct.unpack_from("<Hi", data)
            d.tpdo(sw, pos, sync_index, t)
        elif fn == 0x080 and len(data) == 8:
            code = struct.unpack_from("<H", data)[0]
            silent = last_sync_t is None or (consumer_s is not None and
                                             t - last_sync_t >= 0.9 * consumer_s)
            if code:
                emcys.append((t, node, code, silent))
        elif fn == 0x200 and len(data) in (4, 6):
            d.st["rpdo"] += 1
            cw = struct.unpack_from("<H", data)[0] if len(data) == 6 else None
            target = struct.unpack_from("<i", data, len(data) - 4)[0]
            known, pos = d.known(sync_index)
            if known is None:
                violate(t, node, 1, "target %d before the drive was heard" % target)
                continue
            if known != OE:
                d.was_oe = False
                d.seq = []
                if abs(target - pos) > tol:
                    violate(t, node, 1, "target %d while the drive is in %s at 0x6064 = %d"
                            % (target, known, pos))
                continue
            if cw is not None and cw != 0x000F:
                violate(t, node, 3, "controlword 0x%04X to a drive in Operation Enabled" % cw)
            if not d.was_oe:
                d.was_oe = True
                d.st["enables"] += 1
                d.st["first_targets"].append(target - pos)
                if abs(target - pos) > tol:
                    violate(t, node, 2, "first target after enable %d, its 0x6064 %d (%+d)"
                            % (target, pos, target - pos))
            if d.seq and d.seq[-1][0] == sync_index:
                d.seq[-1] = (sync_index, target)    # two in one cycle: the later counts
            else:
                d.seq.append((sync_index, target))
            d.seq = d.seq[-3:]
            step_max = vmax * period_s * d.cpm + tol
            step2_max = amax * period_s ** 2 * d.cpm + 2 * tol
            if len(d.seq) >= 2 and d.seq[-1][0] - d.seq[-2][0] == 1:
                step = abs(d.seq[-1][1] - d.seq[-2][1])
                d.st["max_step"] = max(d.st["max_step"], step)
                if step > step_max:
                    violate(t, node, 4, "target step %d counts in one SYNC (%.3f m/s, bound %.3f)"
                            % (step, step / d.cpm / period_s, vmax))
            if len(d.seq) == 3 and d.seq[2][0] - d.seq[0][0] == 2:
                s2 = abs(d.seq[2][1] - 2 * d.seq[1][1] + d.seq[0][1])
                d.st["max_step2"] = max(d.st["max_step2"], s2)
                if s2 > step2_max:
                    violate(t, node, 4, "step change %d counts in one SYNC (%.2f m/s^2, bound %.2f)"
                            % (s2, s2 / d.cpm / period_s ** 2, amax))
    for t, node, code, silent in emcys:
        if code in allow_emcy:
            continue
        if code == 0x8130 and (silent or (last_sync_t is not None and t > last_sync_t)):
            continue
        violate(t, node, 5, "drive fault: EMCY 0x%04X" % code)
    return {"frames": frames, "syncs": sync_index, "masters": masters + (sync_index > 0),
            "violations": len(bad),
            "by_rule": {r: sum(1 for b in bad if b["rule"] == r) for r in range(1, 6)},
            "first": bad[:20], "stalls": len(stalled), "stalls_first": stalled[:5], "emcy": [[round(t, 4), n, "0x%04X" % c] for t, n, c, _ in emcys],
            "drives": {n: d.st for n, d in drives.items()}}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log")
    ap.add_argument("--period-s", type=float, required=True)
    ap.add_argument("--vmax", type=float, required=True)
    ap.add_argument("--amax", type=float, required=True)
    ap.add_argument("--node", action="append", required=True, help="NODE:COUNTS_PER_M")
    ap.add_argument("--tol", type=int, default=1)
    ap.add_argument("--allow-emcy", default="")
    ap.add_argument("--stalls", choices=("fail", "report"), default="fail",
                    help="report: rule 4 at a SYNC late by > 1.5 periods and the next one is "
                         "listed, not failed")
    ap.add_argument("--consumer-s", type=float,
                    help="the drives' heartbeat consumer time: 0x8130 after that long without SYNC")
    ap.add_argument("--json")
    a = ap.parse_args()
    nodes = {int(n, 0): float(c) for n, c in (x.split(":") for x in a.node)}
    allow = tuple(int(x, 0) for x in a.allow_emcy.split(",") if x)
    s = check(a.log, a.period_s, a.vmax, a.amax, nodes, a.tol, allow, a.stalls, a.consumer_s)
    text = json.dumps(s, indent=1)
    if a.json:
        with open(a.json, "w") as f:
            f.write(text)
    short = {k: v for k, v in s.items() if k != "drives"}
    short["drives"] = {n: {k: v for k, v in st.items() if k != "states"}
                       for n, st in s["drives"].items()}
    print(json.dumps(short))
    return 1 if s["violations"] else 0


if __name__ == "__main__":
    sys.exit(main())
