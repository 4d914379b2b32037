#!/usr/bin/python3
"""test_cia402.py - lib/proto/cia402.{h,c} against python-canopen, a CANopen
stack no one on this project wrote (../shared/peers/python-canopen; skipped
with a message when absent):

- every statusword 0..0xFFFF maps to the state canopen.profiles.p402's
  SW_MASK table gives, and the controlword we send from each state is the one
  its TRANSITIONTABLE lists for the next step towards OPERATION ENABLED;
- an expedited SDO download we encode is executed by canopen's LocalNode (a
  real SDO server, on python-can's virtual bus), its replies (done, abort)
  decode as what they are, and every abort code it knows has a text here.
"""
import ctypes
import os
import sys
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
sys.path.insert(0, os.path.join(ROOT, "tests", "helpers"))
import canproto_ctypes as cp  # noqa: E402

# ../shared/peers next to the checkout (TRAJD_PEERS overrides, e.g. from a git worktree)
PEER = os.path.join(os.environ.get("TRAJD_PEERS", os.path.join(ROOT, "..", "shared", "peers")),
                    "python-canopen")
if not os.path.isdir(os.path.join(PEER, "canopen")):
    print("SKIP: test_cia402.py: %s is absent (python-canopen is the independent reference; "
          "set TRAJD_PEERS to the folder holding it)" % os.path.normpath(PEER))
    sys.exit(77)  # skipped (tests/run.sh): ../shared is not part of a user's checkout
sys.path.insert(0, PEER)
import can  # noqa: E402
import canopen  # noqa: E402
from canopen.profiles.p402 import State402  # noqa: E402
from canopen.sdo.exceptions import SdoAbortedError  # noqa: E402

LIB = cp.load()
P = ctypes.POINTER
LIB.cia402_state.argtypes = [ctypes.c_uint16]
LIB.cia402_state_name.restype = ctypes.c_char_p
LIB.cia402_controlword_towards_enabled.argtypes = [ctypes.c_int, ctypes.c_int]
LIB.cia402_controlword_towards_enabled.restype = ctypes.c_uint16
LIB.cia402_encode_sdo_download.argtypes = [ctypes.c_uint8, ctypes.c_uint16, ctypes.c_uint8,
                                           ctypes.c_uint32, ctypes.c_uint, P(cp.Frame)]
LIB.cia402_encode_heartbeat.argtypes = [ctypes.c_uint8, P(cp.Frame)]
LIB.cia402_sdo_abort_text.argtypes = [ctypes.c_uint32]
LIB.cia402_sdo_abort_text.restype = ctypes.c_char_p


class SdoReply(ctypes.Structure):
    _fields_ = [("kind", ctypes.c_int), ("index", ctypes.c_uint16), ("sub", ctypes.c_uint8),
                ("value", ctypes.c_uint32), ("abort_code", ctypes.c_uint32)]


LIB.cia402_decode_sdo_reply.argtypes = [ctypes.c_uint8, P(cp.Frame), P(SdoReply)]
DOWNLOAD_OK, ABORT = 1, 2
NAMES = {0: "NOT READY TO SWITCH ON", 1: "SWITCH ON DISABLED", 2: "READY TO SWITCH ON",
         3: "SWITCHED ON", 4: "OPERATION ENABLED", 5: "QUICK STOP ACTIVE",
         6: "FAULT REACTION ACTIVE", 7: "FAULT", 8: None}
# the way to OPERATION ENABLED, one transition at a time (CiA 402-2 figure 13)
NEXT = {"SWITCH ON DISABLED": "READY TO SWITCH ON", "READY TO SWITCH ON": "SWITCHED ON",
        "SWITCHED ON": "OPERATION ENABLED", "QUICK STOP ACTIVE": "SWITCH ON DISABLED"}


def p402_state(sw):
    for name, (mask, val) in State402.SW_MASK.items():
        if sw & mask == val:
            return name
    return None


class StateMachine(unittest.TestCase):
    def test_every_statusword(self):
        for sw in range(0x10000):
            self.assertEqual(NAMES[LIB.cia402_state(sw)], p402_state(sw), hex(sw))

    def test_controlword_is_the_transition(self):
        for s, name in NAMES.items():
            if name in NEXT:
                cw = LIB.cia402_controlword_towards_enabled(s, 0)
                self.assertEqual(cw, State402.TRANSITIONTABLE[(name, NEXT[name])], name)
        enabled = [k for k, v in NAMES.items() if v == "OPERATION ENABLED"][0]
        self.assertEqual(LIB.cia402_controlword_towards_enabled(enabled, 0),
                         State402.CW_OPERATION_ENABLED)
        fault = [k for k, v in NAMES.items() if v == "FAULT"][0]
        # fault reset: bit 7 (the reset acts on its rising edge)
        self.assertEqual(LIB.cia402_controlword_towards_enabled(fault, 1) & 0x80, 0x80)
        self.assertEqual(LIB.cia402_controlword_towards_enabled(fault, 0) & 0x80, 0)


class Sdo(unittest.TestCase):
    def setUp(self):
        self.bus_node = can.Bus(interface="virtual", channel="cia402", receive_own_messages=False)
        self.bus_us = can.Bus(interface="virtual", channel="cia402", receive_own_messages=False)
        self.net = canopen.Network(self.bus_node)
        self.net.connect()
        self.node = canopen.LocalNode(5, os.path.join(PEER, "eds", "sample.eds"))
        self.net.add_node(self.node)

    def tearDown(self):
        self.net.disconnect()
        self.bus_us.shutdown()

    def roundtrip(self, index, sub, value, size):
        f = cp.Frame()
        self.assertEqual(LIB.cia402_encode_sdo_download(5, index, sub, value, size, ctypes.byref(f)), 0)
        self.bus_us.send(can.Message(arbitration_id=f.id, data=f.payload(), is_extended_id=False))
        m = self.bus_us.recv(5.0)
        while m is not None and m.arbitration_id != 0x585:
            m = self.bus_us.recv(5.0)  # (what else the node sends: not ours to judge here)
        self.assertIsNotNone(m, "the SDO server did not answer")
        g = cp.Frame(id=m.arbitration_id, len=len(m.data))
        for i, b in enumerate(m.data):
            g.data[i] = b
        r = SdoReply()
        self.assertEqual(LIB.cia402_decode_sdo_reply(5, ctypes.byref(g), ctypes.byref(r)), 0)
        return r

    def test_download_done_and_stored(self):
        # the producer heartbeat time 0x1017 (u16) = 100 ms
        r = self.roundtrip(0x1017, 0, 100, 2)
        self.assertEqual((r.kind, r.index, r.sub), (DOWNLOAD_OK, 0x1017, 0))
        self.assertEqual(self.node.sdo[0x1017].raw, 100)

    def test_abort_reported(self):
        # sample.eds has no 0x6060 (modes of operation): the server aborts
        r = self.roundtrip(0x6060, 0, 8, 1)
        self.assertEqual((r.kind, r.index), (ABORT, 0x6060))
        self.assertIn(r.abort_code, SdoAbortedError.CODES)
        self.assertNotEqual(LIB.cia402_sdo_abort_text(r.abort_code), b"unknown abort code")

    def test_every_abort_code_has_a_text(self):
        for code in SdoAbortedError.CODES:
            self.assertNotEqual(LIB.cia402_sdo_abort_text(code), b"unknown abort code", hex(code))


class Heartbeat(unittest.TestCase):
    # Given trajd's heartbeat as NMT master (node 127), when canopen's heartbeat
    # consumer of that node hears the frame, then it reads the node as OPERATIONAL.
    def test_master_heartbeat_is_operational(self):
        f = cp.Frame()
        LIB.cia402_encode_heartbeat(127, ctypes.byref(f))
        network = canopen.Network()
        node = canopen.RemoteNode(127, canopen.ObjectDictionary())
        network.add_node(node)
        network.notify(f.id, bytearray(f.payload()), 0.0)
        self.assertEqual(node.nmt.state, "OPERATIONAL")


if __name__ == "__main__":
    unittest.main(verbosity=2)
