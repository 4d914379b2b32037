#!/usr/bin/python3
"""test_drive_sim.py - the CiA 402 drive simulator that tests/uml/drive.sh runs
against trajd (tests/uml/drive_sim.py), checked here against an independent
master: python-canopen's canopen.profiles.p402.BaseNode402 on python-can's
virtual bus, no kernel needed.

- BaseNode402 brings the drive from power-on to Operation Enabled through
  its own transition table (CiA 402-2 figure 13), reading the statusword and
  decoding it with its own bit masks (table 30): the simulator's statusword
  patterns and transitions are what a real master expects;
- boot-up (0x700 + node, 0x00) comes from the node, and a heartbeat only once
  the master set 0x1017 (the CiA 301 default is none);
- the heartbeat consumer 0x1016:1 faults an enabled drive (EMCY 0x8130) when
  the master's heartbeat stops, armed by its first one;
- a boot-up (NMT reset node) puts every object back to its default;
- the SYNC counter: two missed SYNCs fault, a counter starting again at 1 (a
  restarted master) does not;
- an expedited SDO write to an object the drive does not have is refused with
  abort 0x06020000;
- in CSP the drive applies 0x607A at SYNC, and faults (EMCY, FAULT) on a
  target step above its limit, on a following error, and on two missed
  SYNCs; BaseNode402.reset_from_fault brings it back.

Skips when python-canopen (../shared/peers, or TRAJD_PEERS) is absent.
"""
import os
import struct
import sys
import threading
import time
import logging
import unittest

import can

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PEERS = os.environ.get("TRAJD_PEERS", os.path.join(REPO, "..", "shared", "peers"))
HAVE = os.path.isdir(os.path.join(PEERS, "python-canopen", "canopen"))
if HAVE:
    os.environ["TRAJD_PEERS"] = os.path.abspath(PEERS)
    sys.path.insert(0, os.path.join(REPO, "tests", "uml"))
    import drive_sim  # noqa: E402  (it puts python-canopen on the path)
    import canopen  # noqa: E402
    from canopen.profiles.p402 import BaseNode402, State402  # noqa: E402


logging.getLogger("canopen.profiles.p402").setLevel(logging.ERROR)  # "fallback to SDO"


def wait_for(cond, timeout=10.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.005)
    return False


class Recorder(can.Listener if HAVE else object):
    def __init__(self, test):
        self.test = test

    def on_message_received(self, msg):
        with self.test.lock:
            self.test.frames.append((msg.arbitration_id, bytes(msg.data)))


@unittest.skipUnless(HAVE, "python-canopen not found at %s (set TRAJD_PEERS)" % PEERS)
class DriveSim(unittest.TestCase):
    def setUp(self):
        chan = "drive_sim_%d_%s" % (os.getpid(), self.id())
        self.frames = []
        self.lock = threading.Lock()
        self.master = canopen.Network()
        self.master.connect(interface="virtual", channel=chan, receive_own_messages=False)
        self.master.notifier.add_listener(Recorder(self))  # every frame, in order
        self.simnet = canopen.Network()
        self.simnet.connect(interface="virtual", channel=chan)
        self.drive = drive_sim.Drive(self.simnet, 5, 1000)
        drive_sim.attach_sync(self.simnet, [self.drive])
        self.node = BaseNode402(5, drive_sim.EDS)
        self.master.add_node(self.node)
        self.node.sdo.RESPONSE_TIMEOUT = 2.0
        self.counter = 0

    def tearDown(self):
        self.master.disconnect()
        self.simnet.disconnect()

    def ids(self):
        with self.lock:
            return [i for i, _ in self.frames]

    def sync(self, skip=0):
        self.counter = (self.counter + skip) % 240 + 1
        answers = lambda: sum(1 for i in self.ids() if i in (0x185, 0x085))  # noqa: E731
        n = answers()
        self.master.send_message(0x080, bytes([self.counter]))
        # the drive answers every SYNC with its TPDO (or an EMCY first); the
        # heartbeat (0x705) may come in between
        self.assertTrue(wait_for(lambda: answers() > n))

    def target(self, inc):
        self.master.send_message(0x205, struct.pack("<i", inc))

    def enable(self):
        # interpolation period 1 s: every SYNC of these tests comes within one period,
        # so a step is judged per one period (the drive allows more after a longer gap)
        self.node.sdo[0x60C2][1].raw = 1
        self.node.sdo[0x60C2][2].raw = 0
        self.node.nmt.send_command(0x01)  # NMT start: PDOs from now on
        self.assertTrue(wait_for(lambda: self.drive.node.nmt.state == "OPERATIONAL"))
        self.node.state = "OPERATION ENABLED"
        self.assertEqual(self.node.state, "OPERATION ENABLED")

    def test_bring_up_by_base_node_402(self):
        # the simulator's own power-on: boot-up; no heartbeat at the CiA 301
        # default (0x1017 = 0) until the master sets one
        self.assertTrue(wait_for(lambda: 0x705 in self.ids()))
        with self.lock:
            hb = [d for i, d in self.frames if i == 0x705]
        self.assertEqual(hb[0], b"\x00")
        self.assertEqual(self.node.sdo[0x1017].raw, 0)
        time.sleep(0.2)
        self.assertEqual(self.ids().count(0x705), 1)
        self.node.sdo[0x1017].raw = 20
        self.assertTrue(wait_for(lambda: self.ids().count(0x705) >= 3))
        with self.lock:
            self.assertEqual([d for i, d in self.frames if i == 0x705][-1], b"\x7f")
        self.node.nmt.send_command(0x01)  # NMT start
        self.assertTrue(wait_for(lambda: self.drive.node.nmt.state == "OPERATIONAL"))
        self.assertEqual(self.node.state, "SWITCH ON DISABLED")
        self.node.sdo[0x6060].raw = 8
        self.node.sdo[0x60C2][1].raw = 10
        self.node.sdo[0x60C2][2].raw = -3
        self.assertEqual(self.node.op_mode, "CYCLIC SYNCHRONOUS POSITION")
        self.enable()
        states = [s for _, s, _ in self.drive.log["states"]]
        self.assertEqual(states, ["NOT READY TO SWITCH ON", "SWITCH ON DISABLED", "READY TO SWITCH ON",
                                  "SWITCHED ON", "OPERATION ENABLED"])
        self.assertEqual([cw for _, cw, _ in self.drive.log["cw"]], [0x06, 0x07, 0x0F])
        # every state's statusword decodes to that state with BaseNode402's masks
        for name, sw in drive_sim.SW.items():
            matches = [s for s, (mask, bits) in State402.SW_MASK.items()
                       if (sw | drive_sim.REMOTE) & mask == bits]
            self.assertEqual(matches, [name])

    def test_sdo_abort_for_a_missing_object(self):
        with self.assertRaises(canopen.SdoAbortedError) as e:
            self.node.sdo.download(0x6071, 0, b"\x01\x00")
        self.assertEqual(e.exception.code, 0x06020000)

    def test_csp_follows_target_at_sync(self):
        self.enable()
        self.target(1500)
        self.assertEqual(self.drive.pos, 1000)  # not before the SYNC
        self.sync()
        self.assertEqual(self.drive.pos, 1500)
        self.assertEqual(self.node.sdo[0x6064].raw, 1500)
        self.target(3400)
        self.sync()
        self.assertEqual(self.drive.pos, 3400)
        self.assertEqual(self.drive.state, "OPERATION ENABLED")

    def test_fault_on_step_and_reset(self):
        self.enable()
        self.target(1000)
        self.sync()
        self.target(1000 + self.drive.step_limit + 1)
        self.sync()
        self.assertTrue(wait_for(lambda: self.drive.state == "FAULT"))
        self.assertEqual(self.node.state, "FAULT")
        with self.lock:
            emcy = [d for i, d in self.frames if i == 0x085]
        self.assertEqual(struct.unpack("<H", emcy[0][:2])[0], drive_sim.EMCY["step"])
        # BaseNode402 writes Disable voltage, waits its timeout (the drive stays in
        # FAULT), then Fault reset (0x80, the rising edge) and the usual sequence:
        # the order trajd follows (lib/proto/cia402.h)
        self.node.TIMEOUT_RESET_FAULT = 0.3
        self.node.reset_from_fault()
        cws = [cw for _, cw, _ in self.drive.log["cw"]]
        self.assertEqual(cws[cws.index(0x0F) + 1:], [0x00, 0x80, 0x06, 0x07, 0x0F])
        self.assertEqual(self.node.state, "OPERATION ENABLED")

    def test_fault_on_following_error(self):
        self.enable()
        self.target(1000)
        self.sync()
        # within the step limit, but the drive moves at most max_step per SYNC:
        # it falls behind, and beyond 0x6065 it faults
        t = 1000
        for _ in range(8):
            t += self.drive.step_limit
            self.target(t)
            self.sync()
            if wait_for(lambda: self.drive.state == "FAULT", 0.2):
                break
        self.assertEqual([w for _, w in self.drive.log["faults"]], ["following error"])

    def test_consumer_faults_when_the_master_stops(self):
        self.enable()
        self.node.sdo[0x1016][1].raw = (127 << 16) | 150   # node 127, 150 ms
        time.sleep(0.4)
        self.assertEqual(self.drive.state, "OPERATION ENABLED")   # not armed: none heard yet
        for _ in range(5):                                        # the master's heartbeat
            self.master.send_message(0x77F, b"\x05")
            self.drive.check_consumer()
            time.sleep(0.05)
        self.assertEqual(self.drive.state, "OPERATION ENABLED")
        time.sleep(0.2)                                           # then silence
        self.drive.check_consumer()
        self.assertTrue(wait_for(lambda: self.drive.state == "FAULT"))
        self.assertEqual([w for _, w in self.drive.log["faults"]], ["heartbeat"])
        self.assertTrue(wait_for(lambda: 0x085 in self.ids()))
        with self.lock:
            emcy = [d for i, d in self.frames if i == 0x085]
        self.assertEqual(struct.unpack("<H", emcy[0][:2])[0], 0x8130)

    def test_bootup_resets_the_node(self):
        self.enable()
        self.node.sdo[0x1017].raw = 20
        self.node.sdo[0x6060].raw = 8
        self.target(1400)
        self.sync()
        n = self.ids().count(0x705)
        self.drive.bootup()
        self.assertEqual(self.drive.state, "SWITCH ON DISABLED")
        self.assertEqual(self.drive.node.nmt.state, "PRE-OPERATIONAL")
        self.assertEqual(self.node.sdo[0x6060].raw, 0)   # defaults again
        self.assertEqual(self.node.sdo[0x1017].raw, 0)
        self.assertEqual(self.node.sdo[0x6064].raw, 1400)  # the position is kept
        with self.lock:
            self.assertEqual([d for i, d in self.frames if i == 0x705][n], b"\x00")

    def test_sync_counter_restart_is_a_new_master(self):
        self.enable()
        self.sync()
        self.sync()
        self.counter = 0    # a restarted master counts from 1 again
        self.sync()
        self.assertEqual(self.drive.state, "OPERATION ENABLED")

    def test_fault_after_two_missed_syncs(self):
        self.enable()
        self.sync()
        self.sync(skip=1)   # one missed SYNC: tolerated
        self.assertEqual(self.drive.state, "OPERATION ENABLED")
        self.sync(skip=2)   # two missed in a row: fault
        self.assertTrue(wait_for(lambda: self.drive.state == "FAULT"))
        self.assertEqual([w for _, w in self.drive.log["faults"]], ["sync lost"])


if __name__ == "__main__":
    if not HAVE:  # skipped (tests/run.sh): ../shared is not part of a user's checkout
        print("SKIP: python-canopen not found at %s (set TRAJD_PEERS)" % PEERS)
        sys.exit(77)
    unittest.main()
