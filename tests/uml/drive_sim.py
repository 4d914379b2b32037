#!/usr/bin/python3
"""drive_sim.py - CiA 402 drives in cyclic synchronous position mode, simulated
on vcan0 inside the user-mode-linux guest (tests/uml/drive.sh).

The CANopen side is python-canopen's LocalNode (SDO server, NMT slave) with
the object dictionary of tests/uml/cia402_drive.eds; only the CiA 402
behaviour is written here, from CiA 402-2: the state machine driven by the
controlword written to 0x6040 (table 28: command = controlword bits under a
mask), the statusword bit patterns of table 30, and CSP: the target 0x607A
received by RPDO is applied at the next SYNC.  Like real drives, a drive here
faults (state FAULT, EMCY) on
  - a following error: |target - position| above 0x6065 after its move
    (it moves at most max_step increments per SYNC);
  - a step: two consecutive targets further apart than step_limit increments;
  - two missed SYNCs in a row (the SYNC counter, CiA 301, jumps by 3 or more);
  - a fault injected by the test (the file <out>/inject_fault appears).
Each drive sends a TPDO (0x180 + node: statusword u16, position actual value
i32) after every SYNC and on every state change.

Usage: drive_sim.py OUT NODE:START_INC [NODE:START_INC ...]
Runs until SIGTERM, then writes OUT/drive_sim.json (what each drive saw).
"""
import json
import os
import signal
import struct
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PEERS = os.environ.get("TRAJD_PEERS", os.path.join(HERE, "..", "..", "..", "shared", "peers"))
sys.path.insert(0, os.path.join(PEERS, "python-canopen"))
import canopen  # noqa: E402

EDS = os.path.join(HERE, "cia402_drive.eds")
SW = {"NOT READY TO SWITCH ON": 0x0000, "SWITCH ON DISABLED": 0x0040,
      "READY TO SWITCH ON": 0x0021, "SWITCHED ON": 0x0023, "OPERATION ENABLED": 0x0027,
      "QUICK STOP ACTIVE": 0x0007, "FAULT REACTION ACTIVE": 0x000F, "FAULT": 0x0008}
REMOTE = 0x0200          # statusword bit 9: controlled over the network
SYNC_OVERFLOW = 240      # the SYNC counter runs 1..240 (trajd: can.sync_overflow = 240)
EMCY = {"following error": 0x8611, "step": 0x8612, "sync lost": 0x8700, "injected": 0xFF00}


class Drive:
    # 4 m/s at 20 Hz, 10000 increments per metre (tests/uml/drive.sh)
    def __init__(self, net, node_id, start_inc, out, max_step=2000, step_limit=2000):
        self.id = node_id
        self.net = net
        self.node = canopen.LocalNode(node_id, EDS)
        net.add_node(self.node)
        self.node.add_write_callback(self.on_write)
        net.subscribe(0x200 + node_id, self.on_rpdo)
        self.lock = threading.Lock()
        self.state = "SWITCH ON DISABLED"  # NOT READY passes on by itself (transition 1)
        self.pos = start_inc
        self.target = None       # last target received (applied at the next SYNC)
        self.last_applied = None
        self.max_step = max_step
        self.step_limit = step_limit
        self.window = 5000       # 0x6065 default (EDS)
        self.last_cw = 0
        self.last_counter = None
        self.out = out
        self.log = {"node": node_id, "start_inc": start_inc, "states": [], "faults": [],
                    "syncs": 0, "rpdo": 0, "rpdo_not_enabled": 0, "rpdo_before_enabled": 0, "max_target_step": 0,
                    "max_sync_gap": 0, "targets": [], "cw": []}
        self.t0 = time.monotonic()
        self.enter(self.state)

    def now(self):
        return round(time.monotonic() - self.t0, 4)

    def statusword(self):
        return SW[self.state] | REMOTE

    def enter(self, state, why=""):
        self.state = state
        self.log["states"].append([self.now(), state, why])
        self.send_tpdo()

    def send_tpdo(self):
        self.net.send_message(0x180 + self.id, struct.pack("<Hi", self.statusword(), int(self.pos)))

    def fault(self, why):
        if self.state in ("FAULT", "FAULT REACTION ACTIVE"):
            return
        self.log["faults"].append([self.now(), why])
        self.enter("FAULT REACTION ACTIVE", why)
        self.net.send_message(0x80 + self.id, struct.pack("<HB5x", EMCY[why], 0x01))
        self.enter("FAULT", why)

    # controlword (CiA 402-2 table 28; the transitions of figure 13)
    def on_write(self, index, subindex, od, data):
        if index != 0x6040:
            return
        cw = int.from_bytes(data, "little")
        with self.lock:
            self.log["cw"].append([self.now(), cw])
            rising_reset = cw & 0x80 and not self.last_cw & 0x80
            self.last_cw = cw
            s = self.state
            if s == "FAULT":
                if rising_reset:
                    self.enter("SWITCH ON DISABLED", "fault reset")        # 15
                return
            if cw & 0x82 == 0x00:                                           # disable voltage
                if s in ("READY TO SWITCH ON", "SWITCHED ON", "OPERATION ENABLED",
                         "QUICK STOP ACTIVE"):
                    self.enter("SWITCH ON DISABLED", "disable voltage")     # 7, 9, 10, 12
            elif cw & 0x86 == 0x02:                                         # quick stop
                if s == "OPERATION ENABLED":
                    self.enter("QUICK STOP ACTIVE", "quick stop")           # 11
                elif s in ("READY TO SWITCH ON", "SWITCHED ON"):
                    self.enter("SWITCH ON DISABLED", "quick stop")          # 7, 10
            elif cw & 0x87 == 0x06:                                         # shutdown
                if s in ("SWITCH ON DISABLED", "SWITCHED ON", "OPERATION ENABLED"):
                    self.enter("READY TO SWITCH ON", "shutdown")            # 2, 6, 8
            elif cw & 0x8F == 0x07:                                         # switch on
                if s in ("READY TO SWITCH ON", "OPERATION ENABLED"):
                    self.enter("SWITCHED ON", "switch on")                  # 3, 5
            elif cw & 0x8F == 0x0F:                                         # enable operation
                if s in ("SWITCHED ON", "QUICK STOP ACTIVE"):
                    # CSP: the drive holds where it is until a target comes
                    self.target = None
                    self.last_applied = None
                    self.enter("OPERATION ENABLED", "enable operation")     # 4, 16

    def on_rpdo(self, cob, data, ts):
        with self.lock:
            self.log["rpdo"] += 1
            if self.state != "OPERATION ENABLED":
                self.log["rpdo_not_enabled"] += 1
                if not any(st == "OPERATION ENABLED" for _, st, _ in self.log["states"]):
                    self.log["rpdo_before_enabled"] += 1
            raw = bytes(data)
            self.target = struct.unpack("<i", raw[-4:])[0]  # 607A last (with or without 6040)

    def on_sync(self, counter):
        with self.lock:
            self.log["syncs"] += 1
            if self.last_counter is not None and counter:
                gap = (counter - self.last_counter) % SYNC_OVERFLOW
                self.log["max_sync_gap"] = max(self.log["max_sync_gap"], gap)
                if gap >= 3 and self.state == "OPERATION ENABLED":
                    self.fault("sync lost")
            self.last_counter = counter
            if os.path.exists(os.path.join(self.out, "inject_fault_%d" % self.id)):
                os.unlink(os.path.join(self.out, "inject_fault_%d" % self.id))
                self.fault("injected")
            if self.state == "OPERATION ENABLED" and self.target is not None:
                t = self.target
                if self.last_applied is not None:
                    step = abs(t - self.last_applied)
                    self.log["max_target_step"] = max(self.log["max_target_step"], step)
                    if step > self.step_limit:
                        self.fault("step")
                        return
                self.last_applied = t
                self.log["targets"].append(t)
                d = max(-self.max_step, min(self.max_step, t - self.pos))
                self.pos += d
                if abs(t - self.pos) > self.window:
                    self.fault("following error")
                    return
            self.send_tpdo()


def main():
    out = sys.argv[1]
    net = canopen.Network()
    net.connect(interface="socketcan", channel="vcan0")
    drives = []
    for spec in sys.argv[2:]:
        node, start = spec.split(":")
        drives.append(Drive(net, int(node), int(start), out))

    def on_sync(cob, data, ts):
        c = data[0] if len(data) else 0
        for d in drives:
            d.on_sync(c)
    net.subscribe(0x080, on_sync)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *a: done.set())
    with open(os.path.join(out, "drive_sim.ready"), "w") as f:
        f.write("ready\n")
    while not done.wait(0.05):
        pass
    for d in drives:
        d.log["final_inc"] = d.pos
        d.log["final_state"] = d.state
        d.log["sdo_6060"] = d.node.sdo[0x6060].raw
        d.log["sdo_60c2"] = [d.node.sdo[0x60C2][1].raw, d.node.sdo[0x60C2][2].raw]
    with open(os.path.join(out, "drive_sim.json"), "w") as f:
        json.dump([d.log for d in drives], f)
    net.disconnect()


if __name__ == "__main__":
    main()
