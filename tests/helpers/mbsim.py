"""mbsim.py - helpers for the Modbus tests: start/stop the server harness
(test_modbus_server --serve) or trajd, raw Modbus/TCP frames, the synthetic snapshot
check, and the load generator.  Register numbers are read from lib/proto/mbmap.h
(the single source), never retyped here.

Everything waits for an event with a bounded timeout; nothing sleeps and hopes.
"""
import os
import re
import select
import signal
import socket
import struct
import subprocess
import tempfile
import threading
import time
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
WAIT_S = 5.0   # bound on every wait for a line, a socket, an answer


def mbmap_constants():
    """#define MBMAP_* numbers from lib/proto/mbmap.h (simple integer ones only)."""
    out = {}
    with open(os.path.join(ROOT, "lib", "proto", "mbmap.h")) as f:
        for line in f:
            m = re.match(r"#define (MBMAP_\w+) (0x[0-9a-fA-F]+|\d+)u?\b", line)
            if m:
                out[m.group(1)] = int(m.group(2), 0)
    return out


M = mbmap_constants()
BLOCK = M["MBMAP_BLOCK"]


def obj_base(k):
    return BLOCK * (1 + k)


class Server:
    """The harness (default) or any command that prints 'PORT <n>' when ready."""

    def __init__(self, args=(), cmd=None):
        self.cmd = cmd or [os.path.join(BUILD, "tests", "test_modbus_server"), "--serve"]
        self.p = subprocess.Popen(self.cmd + list(args), stdin=subprocess.PIPE,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        line = self._line(WAIT_S)
        m = re.match(r"PORT (-?\d+)", line or "")
        if not m:
            self.p.kill()
            raise RuntimeError("server did not start: %r %s" % (line, self.p.stderr.read()))
        self.port = int(m.group(1))
        self.wait_published()

    def wait_published(self):
        """Wait (bounded) for the first snapshot: generation 0 means no tick
        has been published yet and every value still reads 0, so a check of
        tick values against it would race the server's first tick."""
        s = connect(self.port)
        try:
            deadline = time.monotonic() + WAIT_S
            while u32(read_input(s, M["MBMAP_D_GEN"], 2), 0) == 0:
                if time.monotonic() > deadline:
                    raise RuntimeError("no snapshot published within %.0f s" % WAIT_S)
        finally:
            s.close()

    def _line(self, timeout):
        r, _, _ = select.select([self.p.stdout], [], [], timeout)
        return self.p.stdout.readline() if r else None

    def alive(self):
        return self.p.poll() is None

    def stop(self):
        """Close stdin (the harness stops on EOF), wait, return the STATS dict."""
        self.p.stdin.close()
        self.p.wait(timeout=WAIT_S)
        out, err = self.p.stdout.read(), self.p.stderr.read()
        stats = {}
        for line in out.splitlines():
            if line.startswith("STATS "):
                stats = {k: int(v) for k, v in (kv.split("=") for kv in line.split()[1:])}
        if self.p.returncode != 0:
            raise RuntimeError("server exited %d: %s" % (self.p.returncode, err))
        return stats


class Lines:
    """Lines of a text stream, read by a thread, waited for with a bound
    (select() on a buffered text pipe would miss lines already buffered)."""

    def __init__(self, stream):
        import queue
        self.q = queue.Queue()
        self.all = []
        self.t = threading.Thread(target=self._run, args=(stream,), daemon=True)
        self.t.start()

    def _run(self, stream):
        for line in stream:
            self.q.put(line)
        self.q.put(None)

    def wait_for(self, text, timeout=WAIT_S):
        """The first line containing text, or None at EOF or after timeout s."""
        import queue
        end = time.monotonic() + timeout
        while True:
            try:
                line = self.q.get(timeout=max(0.0, end - time.monotonic()))
            except queue.Empty:
                return None
            if line is None:
                return None
            self.all.append(line)
            if text in line:
                return line


def port_of(line):
    """The TCP port in trajd's "modbus: TCP on ... port N, ..." line."""
    return int(line.split(" port ")[1].split(",")[0])


def start_fed_trajd(trajd, tmpdir, csv_path, timeout=WAIT_S):
    """trajd at 100 Hz with one object 'fed' (input = modbus, csv to csv_path)
    and a writable Modbus server on an ephemeral port of 127.0.0.1, its config
    in tmpdir; as start_trajd."""
    conf = os.path.join(tmpdir, "trajd.conf")
    with open(conf, "w") as f:
        f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                "[modbus]\naddress = 127.0.0.1\nport = 0\nwrites = yes\nsystemd_socket = no\n"
                "[object.fed]\ninput = modbus\noutput = csv\ncsv.path = %s\n" % csv_path)
    return start_trajd([trajd, "-f", "-c", conf], timeout)


class FedTrajdCase(unittest.TestCase):
    """Each test with its own start_fed_trajd (self.p, self.lines, self.port;
    its csv at self.csv), stopped by SIGTERM after it.  TRAJD: the binary;
    WAIT_S: the bound on starting and stopping it."""
    TRAJD = None
    WAIT_S = WAIT_S

    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.csv = os.path.join(self.tmpd.name, "fed.csv")
        self.p, self.lines, self.port = start_fed_trajd(self.TRAJD, self.tmpd.name, self.csv,
                                                        self.WAIT_S)

    def tearDown(self):
        self.p.send_signal(signal.SIGTERM)
        self.p.wait(self.WAIT_S)
        self.lines.wait_for("\0", 1)
        self.p.stderr.close()
        self.tmpd.cleanup()


def start_trajd(argv, timeout=WAIT_S, **popen_kw):
    """Start trajd (argv: its command line) and wait up to timeout s for its
    Modbus port.  Returns (process, Lines of its stderr, port); kills it and
    raises RuntimeError with its log when it never reports the port."""
    p = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                         stderr=subprocess.PIPE, text=True, **popen_kw)
    lines = Lines(p.stderr)
    line = lines.wait_for("modbus: TCP on", timeout)
    if line is None:
        p.kill()
        raise RuntimeError("trajd did not start: %s" % "".join(lines.all))
    return p, lines, port_of(line)


def line_track(path, n=3000, dt_s=0.1):
    """A straight line at 2.06 m/s (x 2 m/s, y 0.5 m/s, z = 1), n fixes dt_s apart,
    as CSV t,x,y,z: the track of the daemon tests that need one."""
    with open(path, "w") as f:
        f.write("t,x,y,z\n")
        for i in range(n):
            f.write("%.3f,%.3f,%.3f,1.0\n" % (i * dt_s, 2.0 * i * dt_s, 0.5 * i * dt_s))


# ---- pymodbus clients ----------------------------------------------------------

def wp_regs(seq, t, x, y, z, f32=False):
    """A waypoint block as pymodbus's BinaryPayloadBuilder encodes it (words and
    bytes big-endian): u32 seq, then t, x, y, z as float64 (MBMAP_H_WP) or, f32,
    float32 (MBMAP_H_WPF)."""
    from pymodbus.constants import Endian
    from pymodbus.payload import BinaryPayloadBuilder
    b = BinaryPayloadBuilder(byteorder=Endian.Big, wordorder=Endian.Big)
    b.add_32bit_uint(seq)
    for v in (t, x, y, z):
        (b.add_32bit_float if f32 else b.add_64bit_float)(v)
    return b.to_registers()


def input_reg(c, addr):
    """Input register addr (FC 04, one register) by pymodbus client c; an exception
    answer is an AssertionError."""
    rr = c.read_input_registers(addr, 1, slave=1)
    assert not rr.isError(), rr
    return rr.registers[0]


def wait_input(c, addr, value, what, timeout=WAIT_S, poll_s=0.02):
    """Read input register addr by pymodbus client c every poll_s until it reads
    value, for at most timeout s (then AssertionError what)."""
    deadline = time.monotonic() + timeout
    while input_reg(c, addr) != value:
        assert time.monotonic() < deadline, what
        time.sleep(poll_s)


def write_retrying(c, addr, regs, deadline):
    """FC 16 of regs at addr by pymodbus client c, again 10 ms later while trajd
    answers busy (exception 06: the object's buffer is full), until the
    monotonic deadline (then AssertionError "feed too slow"); returns the last
    answer."""
    while True:
        assert time.monotonic() < deadline, "feed too slow"
        rq = c.write_registers(addr, regs, slave=1)
        if not (rq.isError() and rq.exception_code == 6):
            return rq
        time.sleep(0.01)


# ---- raw Modbus/TCP ----------------------------------------------------------

def connect(port):
    s = socket.create_connection(("127.0.0.1", port), timeout=WAIT_S)
    s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return s


def adu(tid, pdu, unit=1, proto=0, length=None):
    if length is None:
        length = len(pdu) + 1
    return struct.pack(">HHHB", tid, proto, length, unit) + pdu


def recv_exact(s, n):
    buf = b""
    while len(buf) < n:
        chunk = s.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("closed after %d of %d bytes" % (len(buf), n))
        buf += chunk
    return buf


def transact(s, pdu, tid=1, unit=1):
    """Send one request, return the response PDU (tid checked)."""
    s.sendall(adu(tid, pdu, unit))
    hdr = recv_exact(s, 7)
    rtid, proto, length, _ = struct.unpack(">HHHB", hdr)
    assert rtid == tid and proto == 0, (rtid, proto)
    return recv_exact(s, length - 1)


def read_input(s, addr, count, tid=1):
    pdu = transact(s, struct.pack(">BHH", 4, addr, count), tid)
    if pdu[0] != 4 or pdu[1] != 2 * count:
        raise IOError("exception %r" % pdu)
    return list(struct.unpack(">%dH" % count, pdu[2:]))


def closed_within(s, timeout):
    """True if the peer closed s (EOF or reset) within timeout seconds."""
    s.settimeout(timeout)
    try:
        return s.recv(300) == b""
    except socket.timeout:
        return False
    except OSError:
        return True


# ---- values --------------------------------------------------------------------

def u32(r, i):
    return (r[i] << 16) | r[i + 1]


def f32(r, i):
    return struct.unpack(">f", struct.pack(">HH", r[i], r[i + 1]))[0]


def f64(r, i):
    return struct.unpack(">d", struct.pack(">HHHH", *r[i:i + 4]))[0]


def f32_round(x):
    return struct.unpack(">f", struct.pack(">f", x))[0]


def check_synthetic_block(r, k):
    """A whole object block of the harness: one tick, or the reason it is not.
    See tests/unit/test_modbus_server.c for the synthetic values."""
    g = u32(r, M["MBMAP_O_GEN"])
    if u32(r, M["MBMAP_O_GEN_TAIL"]) != g:
        return "generation head %d tail %d" % (g, u32(r, M["MBMAP_O_GEN_TAIL"]))
    c = u32(r, M["MBMAP_O_CYCLE"])
    if c != g:
        return "cycle %d in generation %d" % (c, g)
    if f64(r, M["MBMAP_O_T_S"]) != c * 0.001:
        return "t %r at cycle %d" % (f64(r, M["MBMAP_O_T_S"]), c)
    for a in range(3):
        if f32(r, M["MBMAP_O_POS"] + 2 * a) != f32_round(c + 1000.0 * k + 0.25 * a):
            return "pos[%d] %r at cycle %d" % (a, f32(r, M["MBMAP_O_POS"] + 2 * a), c)
        if f32(r, M["MBMAP_O_VEL"] + 2 * a) != f32_round(-(c + a)):
            return "vel[%d] at cycle %d" % (a, c)
        if f32(r, M["MBMAP_O_ACC"] + 2 * a) != f32_round(2.0 * c + k):
            return "acc[%d] at cycle %d" % (a, c)
    return None


# ---- load ------------------------------------------------------------------------

def load(port, clients, seconds, objects, check=check_synthetic_block):
    """clients threads, each reading whole object blocks back to back for
    seconds.  Returns (requests, torn list, per-client answered counts, errors)."""
    stop_at = time.monotonic() + seconds
    counts = [0] * clients
    torn = []
    errors = []
    start = threading.Barrier(clients)

    def worker(i):
        try:
            s = connect(port)
            start.wait(WAIT_S)
            tid = 0
            while time.monotonic() < stop_at:
                k = (i + tid) % objects
                tid = (tid + 1) & 0xffff
                r = read_input(s, obj_base(k), BLOCK, tid)
                why = check(r, k)
                if why:
                    torn.append(why)
                counts[i] += 1
            s.close()
        except Exception as e:  # noqa: BLE001 - reported, the test fails on it
            errors.append("client %d: %r" % (i, e))

    th = [threading.Thread(target=worker, args=(i,)) for i in range(clients)]
    for t in th:
        t.start()
    for t in th:
        t.join(seconds + 2 * WAIT_S)
    return sum(counts), torn, counts, errors
