"""test_modbus_peers.py - per-client Modbus counters visible to operators
(issue 11: requests, exceptions, evictions and slow drops per peer were only
in the API and in per-event log lines).

trajd (read-only Modbus on 127.0.0.1, request_timeout_ms = 300, peer_log_s =
1) and, all from 127.0.0.1, raw Modbus/TCP clients whose every effect is
known here:
  - a polite client: 5 reads of the daemon block;
  - a client sending 3 requests of a function trajd does not serve (FC 0x11):
    3 exceptions 01;
  - a slow client: one byte of a request, then nothing: closed after the
    request deadline (mb_slow);
  - a client whose MBAP protocol id is 1: closed at once (bad framing).
Wanted, read from the daemon block (registers 48..61) by a raw client:
mb_connections and mb_dropped count them, mb_peers = 1, and the worst
address is 127.0.0.1 (family 4) with exactly 3 exceptions and 2 drops; and
the periodic notice lines name 127.0.0.1 with, summed over the lines, 3
exceptions, 1 slow and 1 dropped.  The old trajd had none of this: the
registers read 0 and no such line existed.

The worst address itself, IPv6 included, is in every object's diagnostics
block (mb_worst_addr0..7 at 62..69: its 8 groups of 16 bits as IPv6 text
writes them, an IPv4 client as ::ffff:a.b.c.d), read by pymodbus: trajd on
::1 with a client on ::1, and trajd on :: (dual stack) with a client on
127.0.0.1 (family 4, not the IPv4-mapped IPv6 form the socket gives).  The
old trajd gave an IPv6 client only in the log (family 6, IPv4 register 0).
"""
import os
import re
import signal
import socket
import struct
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402
from mbsim import M  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
TRACK = os.path.join(mbsim.ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")
WAIT_S = 20
LINE = re.compile(r"modbus: client 127\.0\.0\.1 in the last 1 s: (\d+) connections, (\d+) requests, "
                  r"(\d+) exceptions, (\d+) evicted, (\d+) slow, (\d+) dropped")


def u32(r, i):
    return (r[i] << 16) | r[i + 1]


class PeerCounters(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        conf = os.path.join(self.tmpd.name, "trajd.conf")
        with open(conf, "w") as f:
            f.write("[daemon]\nrate_hz = 50\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                    "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n"
                    "request_timeout_ms = 300\npeer_log_s = 1\n"
                    "[object.boat]\ninput = replay\nreplay.track = %s\noutput = csv\n"
                    "csv.path = boat.csv\n" % TRACK)
        self.p, self.lines, self.port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)

    def tearDown(self):
        if self.p.poll() is None:
            self.p.send_signal(signal.SIGTERM)
            self.p.wait(WAIT_S)
        self.tmpd.cleanup()

    def test_peer_counters(self):
        s = mbsim.connect(self.port)  # polite
        for tid in range(1, 6):
            mbsim.read_input(s, 0, 8, tid)
        s.close()
        s = mbsim.connect(self.port)  # 3 exceptions 01
        for tid in range(1, 4):
            rsp = mbsim.transact(s, struct.pack(">B", 0x11), tid)
            self.assertEqual((rsp[0], rsp[1]), (0x91, 1))
        s.close()
        slow = mbsim.connect(self.port)
        slow.sendall(mbsim.adu(1, struct.pack(">BHH", 4, 0, 8))[:1])
        self.assertTrue(mbsim.closed_within(slow, WAIT_S))
        bad = mbsim.connect(self.port)
        bad.sendall(mbsim.adu(1, struct.pack(">BHH", 4, 0, 8), proto=1))
        self.assertTrue(mbsim.closed_within(bad, WAIT_S))
        slow.close()
        bad.close()
        time.sleep(0.5)  # housekeeping refreshes the summary every 100 ms
        s = mbsim.connect(self.port)  # the reader: connection 5, no exception
        r = mbsim.read_input(s, 0, M["MBMAP_D_GEN_TAIL"] + 2, 1)
        s.close()
        # 4, or 5 if a tick published the snapshot after the reader connected
        self.assertIn(u32(r, M["MBMAP_D_MB_CONNECTIONS"]), (4, 5))
        self.assertEqual(u32(r, M["MBMAP_D_MB_DROPPED"]), 2)
        self.assertEqual(u32(r, M["MBMAP_D_MB_SLOW"]), 1)
        self.assertEqual(r[M["MBMAP_D_MB_PEERS"]], 1)
        self.assertEqual(r[M["MBMAP_D_MB_WORST_FAMILY"]], 4)
        self.assertEqual(u32(r, M["MBMAP_D_MB_WORST_IPV4"]),
                         struct.unpack(">I", socket.inet_aton("127.0.0.1"))[0])
        self.assertEqual(u32(r, M["MBMAP_D_MB_WORST_EXCEPTIONS"]), 3)
        self.assertEqual(u32(r, M["MBMAP_D_MB_WORST_DROPS"]), 2)
        self.assertGreaterEqual(u32(r, M["MBMAP_D_MB_WORST_REQUESTS"]), 8)
        # the notice lines, one per second at most, with the per-interval counts
        time.sleep(2.5)
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(WAIT_S)
        self.lines.wait_for("\0never\0", 2)
        got = [tuple(int(x) for x in m.groups()) for m in map(LINE.search, self.lines.all) if m]
        self.assertGreater(len(got), 0, "".join(self.lines.all))
        tot = [sum(g[k] for g in got) for k in range(6)]
        self.assertEqual(tot[2:], [3, 0, 1, 1], "".join(self.lines.all))


def have_ipv6_loopback():
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@unittest.skipUnless(have_ipv6_loopback(), "no IPv6 loopback (::1)")
class PeerAddress(unittest.TestCase):
    def start(self, address):
        self.tmpd = tempfile.TemporaryDirectory()
        self.addCleanup(self.tmpd.cleanup)
        conf = os.path.join(self.tmpd.name, "trajd.conf")
        with open(conf, "w") as f:
            f.write("[daemon]\nrate_hz = 50\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                    "[modbus]\naddress = %s\nport = 0\nsystemd_socket = no\npeer_log_s = 0\n"
                    "[object.boat]\nid = 3\ninput = replay\nreplay.track = %s\noutput = csv\n"
                    "csv.path = boat.csv\n" % (address, TRACK))
        p, lines, port = mbsim.start_trajd([TRAJD, "-f", "-c", conf], WAIT_S)

        def stop():
            p.send_signal(signal.SIGTERM)
            p.wait(WAIT_S)
            lines.wait_for("\0never\0", 0.5)
        self.addCleanup(stop)
        return port

    def exceptions_from(self, family, host, port, n=3):
        with socket.create_connection((host, port), timeout=WAIT_S) as s:
            self.assertEqual(s.family, family)
            for tid in range(1, n + 1):
                s.sendall(mbsim.adu(tid, struct.pack(">B", 0x11)))
                hdr = mbsim.recv_exact(s, 7)
                self.assertEqual(mbsim.recv_exact(s, struct.unpack(">H", hdr[4:6])[0] - 1),
                                 bytes([0x91, 1]))

    def read(self, host, port):
        """Daemon block and object 3's diagnostics block, by pymodbus."""
        time.sleep(0.5)  # housekeeping refreshes the summary every 100 ms
        c = ModbusTcpClient(host, port=port, timeout=WAIT_S)
        self.assertTrue(c.connect())
        try:
            d = c.read_input_registers(0, M["MBMAP_D_GEN_TAIL"] + 2, slave=1)
            x = c.read_input_registers(M["MBMAP_BLOCK"] * (1 + M["MBMAP_MAX_OBJECTS"] + 3), 100,
                                       slave=1)
        finally:
            c.close()
        self.assertFalse(d.isError(), d)
        self.assertFalse(x.isError(), x)
        return d.registers, x.registers

    # Given trajd on ::1 and a client on ::1 that got 3 exceptions, then the
    # daemon block names an IPv6 worst client and the diagnostics block
    # holds its address, equal to inet_pton's
    def test_ipv6_client(self):
        port = self.start("::1")
        self.exceptions_from(socket.AF_INET6, "::1", port)
        d, x = self.read("::1", port)
        self.assertEqual(d[M["MBMAP_D_MB_WORST_FAMILY"]], 6)
        self.assertEqual(u32(d, M["MBMAP_D_MB_WORST_IPV4"]), 0)
        self.assertEqual(u32(d, M["MBMAP_D_MB_WORST_EXCEPTIONS"]), 3)
        a = M["MBMAP_X_MB_WORST_ADDR"]
        self.assertEqual(x[a:a + 8], list(struct.unpack(">8H", socket.inet_pton(socket.AF_INET6,
                                                                                "::1"))))

    # Given trajd on :: (dual stack: an IPv4 client's socket address is
    # ::ffff:a.b.c.d) and a client on 127.0.0.1, then family 4 and the IPv4
    # register hold 127.0.0.1, and the diagnostics block ::ffff:127.0.0.1
    def test_ipv4_client_on_dual_stack(self):
        port = self.start("::")
        self.exceptions_from(socket.AF_INET, "127.0.0.1", port)
        d, x = self.read("127.0.0.1", port)
        self.assertEqual(d[M["MBMAP_D_MB_WORST_FAMILY"]], 4)
        self.assertEqual(u32(d, M["MBMAP_D_MB_WORST_IPV4"]),
                         struct.unpack(">I", socket.inet_aton("127.0.0.1"))[0])
        a = M["MBMAP_X_MB_WORST_ADDR"]
        self.assertEqual(x[a:a + 8], list(struct.unpack(
            ">8H", socket.inet_pton(socket.AF_INET6, "::ffff:127.0.0.1"))))


if __name__ == "__main__":
    unittest.main()
