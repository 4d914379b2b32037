#!/usr/bin/python3
"""drive_sim.py - CiA 402 drives in cyclic synchronous position mode, simulated
on vcan0 inside the user-mode-linux guest (tests/uml/drive.sh), or on
python-can's virtual bus (tests/e2e/test_drive_sim.py).

The CANopen side is python-canopen's LocalNode (SDO server, NMT slave with
boot-up and heartbeat) with the object dictionary of tests/uml/cia402_drive.eds;
only the CiA 402 behaviour is written here, from CiA 402-2: the state machine
driven by the controlword written to 0x6040 (table 28: command = controlword
bits under a mask), the statusword bit patterns of table 30, and CSP: the
target 0x607A received by RPDO is applied at the next SYNC.  Like real drives,
a drive here faults (state FAULT, EMCY) on
  - a following error: |target - position| above 0x6065 after its move
    (it moves at most max_step increments per SYNC);
  - a step: two consecutive targets further apart than step_limit increments
    per interpolation period (0x60C2) over the time between their SYNCs;
  - two missed SYNCs in a row (the SYNC counter, CiA 301, jumps by 3 or more
    between two SYNCs of one producer; a counter that starts again at 1 is a
    new producer, a restarted master: its silence is the consumer's to judge);
  - its master's heartbeat not heard within the consumer time of 0x1016:1
    (CiA 301: node-id in bits 16..22, time in ms in bits 0..15; 0 = none),
    watched from the first heartbeat heard on (EMCY 0x8130, "heartbeat");
  - a fault injected by the test (SIGUSR1: node 1; SIGUSR2: every node's quick
    stop, as from a local quick-stop input).
The object dictionary starts at the CiA 301 defaults: no heartbeat (0x1017 =
0), no consumer, no SYNC period (0x1006 = 0) until the master writes them.
A boot-up (the command file, below) resets the node as NMT Reset node does:
every object back to its default, boot-up message, pre-operational, state
Switch on disabled; the position is kept (an absolute encoder).
SIGHUP silences node 2's heartbeat (python-canopen's NmtSlave.stop_heartbeat; its
PDOs go on, as from a drive whose heartbeat producer failed), the next SIGHUP
starts it again at 0x1017's period; each logged as HEARTBEAT_OFF / HEARTBEAT_ON.
Once NMT-started (CiA 301: PDOs only in operational), each drive sends a TPDO
(0x180 + node: statusword u16, position actual value i32) after every SYNC and
on every state change, and keeps 0x6041, 0x6061 and
0x6064 readable by SDO.  An object the EDS does not list is answered by SDO
abort 0x06020000 (python-canopen's SDO server), as by a real drive.

Usage: drive_sim.py OUT NODE:START_INC [NODE:START_INC ...]
Writes OUT/drive_sim.ready once listening, one line per state change to
OUT/sim_events.txt ("<t> <node> <STATE> <why>"), and runs until SIGTERM,
then writes OUT/drive_sim.json (what each drive saw).  Commands besides the
signals: a line "fault N", "quickstop N", "bootup N" or "heartbeat N" (toggle)
written to OUT/sim_cmd (a new file each time: it is read and removed).
"""
import faulthandler
import json
import logging
import os
import signal
import socket
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
EMCY = {"following error": 0x8611, "step": 0x8612, "sync lost": 0x8700, "injected": 0xFF00,
        "heartbeat": 0x8130}
log = logging.getLogger("drive_sim")


class Drive:
    # 4 m/s at 20 Hz, 10000 increments per metre (tests/uml/drive.sh)
    def __init__(self, net, node_id, start_inc, events=None, max_step=2000, step_limit=5000,
                 eds=EDS):
        self.id = node_id
        self.net = net
        self.node = canopen.LocalNode(node_id, eds)
        net.add_node(self.node)
        self.node.add_write_callback(self.on_write)
        self.node.add_read_callback(self.on_read)
        net.subscribe(0x200 + node_id, self.on_rpdo)
        self.lock = threading.RLock()
        self.events = events
        self.pos = start_inc
        self.target = None       # last target received (applied at the next SYNC)
        self.last_applied = None
        self.max_step = max_step
        self.step_limit = step_limit
        self.last_cw = 0
        self.in_flight = 0       # SYNCs left in which a target may predate a change
        self.last_counter = None
        self.last_sync_ts = None
        self.master_hb = None    # bus time (s, epoch) of the master's last heartbeat (armed)
        self.subscribed = set()
        self.log = {"node": node_id, "start_inc": start_inc, "states": [], "faults": [],
                    "syncs": 0, "rpdo": 0, "rpdo_not_enabled": 0, "rpdo_before_enabled": 0,
                    "rpdo_not_enabled_off": 0,
                    "max_target_step": 0, "max_sync_gap": 0, "targets": [], "cw": [],
                    "max_lag_s": 0.0,
                    "sdo": []}
        self.t0 = time.monotonic()
        self.state = "NOT READY TO SWITCH ON"
        # power-on: CiA 301 boot-up (0x700 + node, 0x00), then pre-operational with
        # the heartbeat of 0x1017 (python-canopen's NMT slave sends both)
        self.node.nmt.send_command(0x81)
        self.node.nmt.send_command(0x80)
        self.enter("NOT READY TO SWITCH ON", "power on")
        self.enter("SWITCH ON DISABLED", "self test done")  # transition 1, by itself

    def now(self):
        return round(time.monotonic() - self.t0, 4)

    def consumer(self):
        """(master node, consumer time in s) of 0x1016:1, or (0, 0)."""
        v = self.node.sdo[0x1016][1].raw
        return (v >> 16) & 0x7F, (v & 0xFFFF) / 1000.0

    def lag(self, ts):
        """The frame's bus time (its receive stamp, s since the epoch) and how
        far behind the bus this simulator reads (its log's max_lag_s): a slow
        guest must not make the drive judge its consumer late."""
        now = time.time()
        if ts is None:
            return now
        self.log["max_lag_s"] = max(self.log["max_lag_s"], round(now - ts, 3))
        return ts

    def on_master_heartbeat(self, cob, data, ts):
        with self.lock:
            t = self.lag(ts)
            if (cob & 0x7F) == self.consumer()[0] and self.consumer()[1] > 0:
                if self.master_hb is None:
                    self.note("CONSUMER_ARMED", "first master heartbeat")
                self.master_hb = t

    def check_consumer(self):
        with self.lock:
            node, tmo = self.consumer()
            if not tmo or self.master_hb is None or time.time() - self.master_hb <= tmo:
                return
            self.master_hb = None    # once, until the master is heard again
            self.note("MASTER_LOST", "no heartbeat from node %d for %g s" % (node, tmo))
            if self.state in ("FAULT", "FAULT REACTION ACTIVE", "NOT READY TO SWITCH ON",
                              "SWITCH ON DISABLED"):
                return
            self.fault("heartbeat")

    def bootup(self, why="reset node"):
        """NMT Reset node, as by a power glitch or a local reset: defaults, boot-up."""
        with self.lock:
            self.node.nmt.stop_heartbeat()
            self.node.data_store.clear()      # every object back to its default
            self.target = None
            self.last_applied = None
            self.last_counter = None
            self.master_hb = None
            self.last_cw = 0
            self.note("BOOTUP", why)
            self.node.nmt.send_command(0x81)  # boot-up message
            self.node.nmt.send_command(0x80)  # pre-operational (heartbeat of 0x1017: none)
            self.enter("NOT READY TO SWITCH ON", why)
            self.enter("SWITCH ON DISABLED", "self test done")

    def statusword(self):
        return SW[self.state] | REMOTE

    def toggle_heartbeat(self):
        nmt = self.node.nmt
        self.hb_off = not getattr(self, "hb_off", False)
        if self.hb_off:
            nmt.stop_heartbeat()
        else:
            nmt.start_heartbeat(self.node.sdo[0x1017].raw)
        self.note("HEARTBEAT_OFF" if self.hb_off else "HEARTBEAT_ON", "test")

    def note(self, what, why):
        if self.events:
            with open(self.events, "a") as f:
                f.write("%.4f %d %s %s\n" % (self.now(), self.id, what, why.replace(" ", "_")))

    def enter(self, state, why=""):
        if self.state == "OPERATION ENABLED":
            self.in_flight = 2    # SYNCs until a target must follow the change
        self.state = state
        self.log["states"].append([self.now(), state, why])
        self.note(state.replace(" ", "_"), why)
        self.send_tpdo()

    def send_tpdo(self):
        if self.node.nmt.state != "OPERATIONAL":
            return    # CiA 301: PDOs only in NMT operational (after NMT start)
        self.net.send_message(0x180 + self.id, struct.pack("<Hi", self.statusword(), int(self.pos)))

    def fault(self, why):
        with self.lock:
            if self.state in ("FAULT", "FAULT REACTION ACTIVE"):
                return
            log.warning("node %d: fault: %s", self.id, why)
            self.log["faults"].append([self.now(), why])
            self.enter("FAULT REACTION ACTIVE", why)
            self.net.send_message(0x80 + self.id, struct.pack("<HB5x", EMCY[why], 0x01))
            self.enter("FAULT", why)

    def quick_stop(self, why):
        with self.lock:
            if self.state == "OPERATION ENABLED":
                self.enter("QUICK STOP ACTIVE", why)

    def on_read(self, index, subindex, od):
        with self.lock:
            if index == 0x6041:
                return self.statusword()
            if index == 0x6064:
                return int(self.pos)
            if index == 0x6061:
                return self.node.sdo[0x6060].raw
        return None

    # controlword (CiA 402-2 table 28; the transitions of figure 13)
    def on_write(self, index, subindex, od, data):
        self.log["sdo"].append([self.now(), index, subindex, int.from_bytes(data, "little")])
        if index == 0x1016:
            master = (int.from_bytes(data, "little") >> 16) & 0x7F
            if master and master not in self.subscribed:
                self.subscribed.add(master)
                self.net.subscribe(0x700 + master, self.on_master_heartbeat)
            self.master_hb = None    # watched again from its next heartbeat
            return
        if index != 0x6040:
            return
        self.controlword(int.from_bytes(data, "little"))

    def controlword(self, cw):
        with self.lock:
            if cw == self.last_cw and self.log["cw"]:
                return    # unchanged (an RPDO repeats it every cycle)
            self.log["cw"].append([self.now(), cw, self.state])
            rising_reset = cw & 0x80 and not self.last_cw & 0x80
            self.last_cw = cw
            s = self.state
            if s == "FAULT":
                if rising_reset:
                    self.enter("SWITCH ON DISABLED", "fault reset")        # 15
                return
            if s in ("NOT READY TO SWITCH ON", "FAULT REACTION ACTIVE"):
                return                                                      # not commandable
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
            raw = bytes(data)
            self.target = struct.unpack("<i", raw[-4:])[0]
            if self.state != "OPERATION ENABLED":
                self.log["rpdo_not_enabled"] += 1
                # a target for a drive not enabled: only its own position is harmless
                # (but for the ones the master sent before it could know: it reads
                # the bus at the start of its cycle, and a change handled here just
                # after a SYNC may have reached the bus before it: two SYNCs' grace)
                if not self.in_flight:
                    self.log["rpdo_not_enabled_off"] = max(self.log["rpdo_not_enabled_off"],
                                                           abs(self.target - int(self.pos)))
                if not any(st == "OPERATION ENABLED" for _, st, _ in self.log["states"]):
                    self.log["rpdo_before_enabled"] += 1
            if len(raw) == 6:    # controlword, then target (trajd's can.cia402_controlword)
                cw = struct.unpack("<H", raw[:2])[0]
                self.log.setdefault("rpdo_cw", []).append([cw, self.state])
                self.controlword(cw)    # a mapped controlword acts as if written by SDO

    def period(self):
        # the interpolation period trajd wrote to 0x60C2 (value x 10^index s)
        return self.node.sdo[0x60C2][1].raw * 10.0 ** self.node.sdo[0x60C2][2].raw

    def on_sync(self, counter, ts=None):
        with self.lock:
            self.log["syncs"] += 1
            self.lag(ts)
            self.in_flight = max(0, self.in_flight - 1)
            # time since the last SYNC as the bus saw it (a master that missed a
            # deadline sends the next SYNC and target later, and further ahead)
            dt = None if ts is None or self.last_sync_ts is None else ts - self.last_sync_ts
            self.last_sync_ts = ts
            if self.last_counter is not None and counter and counter != 1:
                gap = (counter - self.last_counter) % SYNC_OVERFLOW
                self.log["max_sync_gap"] = max(self.log["max_sync_gap"], gap)
                if gap >= 3 and self.state == "OPERATION ENABLED":
                    log.warning("node %d: SYNC counter %d after %d", self.id, counter,
                                self.last_counter)
                    self.fault("sync lost")
            self.last_counter = counter
            if self.state == "OPERATION ENABLED" and self.target is not None:
                t = self.target
                if self.last_applied is None:
                    # the first target after Enable operation: how far from where it stands
                    self.log.setdefault("enable_offsets", []).append(abs(t - self.pos))
                    self.note("FIRST_TARGET", "after enable")
                else:
                    step = abs(t - self.last_applied)
                    self.log["max_target_step"] = max(self.log["max_target_step"], step)
                    # step_limit increments per interpolation period, over the
                    # time the SYNCs say passed (never less than one period)
                    cycles = 1.0 if dt is None else max(1.0, dt / self.period())
                    if step > self.step_limit * cycles:
                        log.warning("node %d: target step %d", self.id, step)
                        self.fault("step")
                        return
                self.last_applied = t
                self.log["targets"].append(t)
                d = max(-self.max_step, min(self.max_step, t - self.pos))
                self.pos += d
                if abs(t - self.pos) > self.node.sdo[0x6065].raw:
                    self.fault("following error")
                    return
            self.send_tpdo()


def attach_sync(net, drives):
    def on_sync(cob, data, ts):
        c = data[0] if len(data) else 0
        for d in drives:
            d.on_sync(c, ts)
    net.subscribe(0x080, on_sync)


def main():
    out = sys.argv[1]
    logging.basicConfig(level=logging.WARNING, stream=sys.stderr,
                        format="%(relativeCreated)d %(name)s %(levelname)s %(message)s")
    specs = [(int(n), int(s)) for n, s in (a.split(":") for a in sys.argv[2:])]
    # only what a drive listens to: NMT, SYNC, EMCY/SYNC range, its RPDO and SDO
    filters = [{"can_id": 0x000, "can_mask": 0x7FF}, {"can_id": 0x080, "can_mask": 0x7FF},
               {"can_id": 0x700, "can_mask": 0x780}]    # heartbeats: the master's
    for n, _ in specs:
        filters += [{"can_id": 0x200 + n, "can_mask": 0x7FF}, {"can_id": 0x600 + n, "can_mask": 0x7FF}]
    net = canopen.Network()
    net.connect(interface="socketcan", channel="vcan0", can_filters=filters)
    # a slow guest must not lose SYNCs in the socket: room for seconds of traffic
    # (SO_RCVBUFFORCE: root in the guest, past net.core.rmem_max's 208 KiB,
    # which SO_RCVBUF alone is capped at)
    try:
        net.bus.socket.setsockopt(socket.SOL_SOCKET, 33, 4 << 20)   # SO_RCVBUFFORCE
    except OSError:
        net.bus.socket.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    events = os.path.join(out, "sim_events.txt")
    drives = [Drive(net, n, s, events) for n, s in specs]
    attach_sync(net, drives)
    done = threading.Event()
    def on_term(*a):
        done.set()
        # a shutdown that hangs says where (every thread's stack on stderr), and ends
        faulthandler.dump_traceback_later(10, exit=True)
    signal.signal(signal.SIGTERM, on_term)
    signal.signal(signal.SIGUSR1, lambda *a: drives[0].fault("injected"))
    signal.signal(signal.SIGUSR2, lambda *a: [d.quick_stop("local quick stop") for d in drives])
    signal.signal(signal.SIGHUP, lambda *a: drives[1].toggle_heartbeat())
    with open(os.path.join(out, "drive_sim.ready"), "w") as f:
        f.write("ready\n")
    cmd = os.path.join(out, "sim_cmd")
    by_node = {d.id: d for d in drives}
    actions = {"fault": lambda d: d.fault("injected"),
               "quickstop": lambda d: d.quick_stop("local quick stop"),
               "bootup": lambda d: d.bootup(), "heartbeat": lambda d: d.toggle_heartbeat()}
    while not done.wait(0.02):
        for d in drives:
            d.check_consumer()
        if os.path.exists(cmd):
            with open(cmd) as f:
                lines = f.read().split("\n")
            os.unlink(cmd)
            for line in lines:
                w = line.split()
                if len(w) == 2 and w[0] in actions and int(w[1]) in by_node:
                    actions[w[0]](by_node[int(w[1])])
    for d in drives:
        d.log["final_inc"] = d.pos
        d.log["final_state"] = d.state
        d.log["sdo_6060"] = d.node.sdo[0x6060].raw
        d.log["sdo_60c2"] = [d.node.sdo[0x60C2][1].raw, d.node.sdo[0x60C2][2].raw]
    tmp = os.path.join(out, "drive_sim.json.tmp")
    with open(tmp, "w") as f:
        json.dump([d.log for d in drives], f)
    os.rename(tmp, os.path.join(out, "drive_sim.json"))
    net.disconnect()


if __name__ == "__main__":
    main()
