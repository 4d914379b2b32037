#!/usr/bin/python3
"""test_reload_cells.py - what a reload does to each object, mid-motion
(issue 23, the reload and end-of-input cells; issue 28 item 2, the reload
mechanism).  The real trajd binary, its setpoints read from its stdout pipe,
its log from stderr, systemd's notify protocol from a socket this test binds
(tests/e2e/test_daemon.py's Daemon).  Continuity is judged against the
object's own configured limits (max_speed_m_s x the periods elapsed), never
against trajd's numbers.  Every wait is for an event, bounded.
"""
import math
import os
import signal
import socket
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import test_daemon as td  # noqa: E402

PERIOD_NS = 10_000_000       # rate_hz = 100
VMAX = 4.0                   # the object's max_speed_m_s (the track moves at 2 m/s)
SCALED = 0x40
NO_POS_M = -214748.3648      # CAN SETPOINT position 0x80000000: no position
CAN = "[can]\nlog_out = sp.log\nlog_time = wall\nmax_load_percent = 0\n"


def conf(objs, daemon="", extra=""):
    return ("[daemon]\nrate_hz = 100\nstatus_interval_s = 1\nstop_timeout_s = 10\n%s%s" % (daemon, extra)
            + "".join(objs))


def obj(name, oid, output="stdout", more=""):
    return ("[object.%s]\nid = %d\ninput = replay\nreplay.track = circle.csv\noutput = %s\n"
            "max_speed_m_s = %g\nscale_accel_m_s2 = 1\n%s" % (name, oid, output, VMAX, more))


def pos(row):
    return [float(x) for x in row[3:6]]


def vel(row):
    return [float(x) for x in row[6:9]]


class ReloadCells(unittest.TestCase):
    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        td.xyz_track(os.path.join(self.tmp, "circle.csv"), 3000, 0.1)  # 2 m/s for 300 s
        self.conf = os.path.join(self.tmp, "trajd.conf")

    def tearDown(self):
        self.tmpd.cleanup()

    def assert_continuous(self, b, a, what):
        """Row a follows row b (same object) with no step: k periods on in
        engine time, the position within VMAX x k T of b's."""
        dt_ns = int(a[1]) - int(b[1])
        self.assertGreater(dt_ns, 0, what)
        self.assertEqual(dt_ns % PERIOD_NS, 0, what)
        k = dt_ns // PERIOD_NS
        step = math.dist(pos(a), pos(b))
        self.assertLessEqual(step, VMAX * k * PERIOD_NS * 1e-9 + 1e-6,
                             "%s: step %.4f m in %d periods\n%s\n%s" % (what, step, k, b, a))
        return k

    def failed_reload(self, d, text, why):
        """SIGHUP with text as the config, which cannot open: refused with
        why, and boat's stream goes on where it was (same trajectory, track
        time k periods on, no step)."""
        before = d.line(lambda l: l.startswith("boat,") and ",streaming," in l and
                        not int(l.split(",")[13]) & SCALED)
        td.write(self.conf, text)
        d.p.send_signal(signal.SIGHUP)
        f, _ = d.msg(lambda f: f.get("READY") == "1")
        self.assertIn("reload refused", f.get("STATUS", ""))
        self.assertIn(why, f.get("STATUS", ""))
        d.err_line(lambda l: "reload refused (cannot open)" in l and why in l)
        while True:  # the old stdout transport reopens: a header, then the rows go on
            l = d.line()
            if l.startswith("object,"):
                break
            if l.startswith("boat,"):
                before = l
        after = d.line(lambda l: l.startswith("boat,"))
        b, a = before.split(","), after.split(",")
        k = self.assert_continuous(b, a, "at the failed reload")
        self.assertEqual(a[12], "streaming", a)
        self.assertEqual(a[15], b[15], "a new trajectory: %s / %s" % (b, a))
        # progress kept: track time a period on (a restart would begin at 0;
        # a stall of k periods during the reload is no step: assert_track_step)
        td.assert_track_step(self, b, a, k, PERIOD_NS)
        # and from there on, every row continues the last
        prev = a
        for _ in range(20):
            cur = d.line(lambda l: l.startswith("boat,")).split(",")
            self.assert_continuous(prev, cur, "after the failed reload")
            prev = cur

    def run_failed_reload(self, make_bad, why):
        """boat writes stdout and CAN (log_out, wall-clock stamps); a reload
        with make_bad() fails with why.  Then the CAN log, read by python-can
        and decoded by canmatrix from config/trajd.dbc, has no step anywhere
        (it had a 36 m one: issue 23)."""
        td.write(self.conf, conf([obj("boat", 0, "stdout, can")], extra=CAN))
        d = td.Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", td.START_TIMEOUT_S)
            self.failed_reload(d, make_bad(), why)
            # counted where the status is shown
            d.msg(lambda f: "reloads 1 (1 failed)" in f.get("STATUS", ""), 5)
            d.p.send_signal(signal.SIGTERM)
            d.lines_until_eof(timeout=20)
            self.assertEqual(d.wait(20), 0, d.stderr())
        finally:
            d.close()
        import cantools_trajd as ct
        rows, _ = ct.decode_setpoints(os.path.join(self.tmp, "sp.log"))
        moving = [(t, r) for t, r in rows.items()  # in file order
                  if all(a in r for a in "xyz") and r["x"] > NO_POS_M + 1]
        self.assertGreater(len(moving), 100)
        for (t0, a), (t1, b) in zip(moving, moving[1:]):
            step = math.dist([a[x] for x in "xyz"], [b[x] for x in "xyz"])
            self.assertLessEqual(step, VMAX * (t1 - t0) * 1e-9 + 2 * ct.SP_POS_TOL,
                                 "CAN step at %d ns: %r -> %r" % (t1, a, b))

    def test_failed_reload_bad_csv_path(self):
        # Given boat streaming at 2 m/s, when SIGHUP with a config whose CSV
        # output lies in a directory that does not exist, then the reload is
        # refused with the reason, and boat goes on untouched.
        self.run_failed_reload(lambda: conf([obj("boat", 0, "stdout, can, csv",
                                                 "csv.path = no/such/dir/x.csv\n")], extra=CAN),
                               "no/such/dir")

    def test_failed_reload_busy_modbus_port(self):
        # The same with a Modbus port another process listens on.
        busy = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            busy.bind(("0.0.0.0", 0))
            busy.listen(1)
            port = busy.getsockname()[1]
            self.run_failed_reload(lambda: conf([obj("boat", 0, "stdout, can")],
                                                extra=CAN + "[modbus]\nport = %d\n"
                                                "systemd_socket = no\n" % port), "modbus")
        finally:
            busy.close()

    def start_two(self):
        td.write(self.conf, conf([obj("boat", 0), obj("gone", 1)]))
        d = td.Daemon(self.tmp, self.conf)
        d.msg(lambda f: f.get("READY") == "1", td.START_TIMEOUT_S)
        d.line(lambda l: l.startswith("gone,") and ",streaming," in l and
               not int(l.split(",")[13]) & SCALED)
        return d

    def test_removed_object_brakes_to_rest(self):
        # Given boat and gone streaming at 2 m/s, when SIGHUP with gone
        # removed, then the log says gone brakes to rest from its speed,
        # gone's rows slow down within its limits (no step, velocity changing
        # by at most scale_accel_m_s2 + the track's v^2/r per period) and the
        # last one is at rest; boat goes on.  SIGHUPs sent while gone brakes
        # are coalesced into one more reload.  gone's replay, refused
        # meanwhile, is said for what it is (not "trajd is stopping", which it
        # said before) and counted once gone is gone (the count was lost).
        d = self.start_two()
        try:
            td.write(self.conf, conf([obj("boat", 0)]))
            d.p.send_signal(signal.SIGHUP)
            l = d.err_line(lambda l: "object 'gone' removed: braking to rest from" in l)
            v0 = float(l.split("braking to rest from ")[1].split()[0])
            self.assertAlmostEqual(v0, 2.0, delta=0.1)
            for _ in range(3):  # while gone brakes (2 s): coalesced
                d.p.send_signal(signal.SIGHUP)
                d.err_line(lambda l: "coalesced" in l)
            d.err_line(lambda l: l.find("reloaded: 1 object(s)") >= 0)
            d.err_line(lambda l: l.find("reloaded: 1 object(s)") >= 0)  # the coalesced one
            rows = []  # every stdout line from here on
            for want in ("object,", "object,", "boat,"):
                d.line(lambda l: rows.append(l) or l.startswith(want))
            d.p.send_signal(signal.SIGTERM)
            rows += d.lines_until_eof(timeout=20)
            self.assertEqual(d.wait(20), 0, d.stderr())
        finally:
            d.close()
        err = d.stderr()
        self.assertEqual(err.count("SIGHUP: reloading"), 2, err)
        self.assertIn("object 'gone': waypoint from ", err)
        self.assertIn("refused: a reload removes the object", err)
        self.assertNotIn("trajd is stopping", err.split("SIGTERM")[0])
        self.assertRegex(err, r"object 'gone' removed: [1-9]\d* waypoint\(s\) refused while it "
                              r"braked to rest")
        gone = [r for r in (l.split(",") for l in rows) if r[0] == "gone"]
        self.assertNotIn("gone", [r[0] for r in (l.split(",") for l in rows[-5:])])
        amax = 1.0 + 2.0 ** 2 / 50.0  # scale_accel_m_s2 + the circle's v^2/r
        for b, a in zip(gone, gone[1:]):
            k = self.assert_continuous(b, a, "gone braking")
            dv = math.dist(vel(a), vel(b))
            self.assertLessEqual(dv, amax * k * PERIOD_NS * 1e-9 + 1e-6, "%s\n%s" % (b, a))
        self.assertEqual(vel(gone[-1]), [0.0, 0.0, 0.0], gone[-1])
        self.assertEqual(gone[-1][12], "finished", gone[-1])

    def test_removal_in_a_failed_reload(self):
        # Given boat and gone streaming, when SIGHUP with gone removed and a
        # CSV output that cannot open, then gone brakes to rest (the removal
        # comes first), the reload fails, and gone, still in the running
        # configuration, takes its input again and leaves its rest by a
        # transfer: every row of it continuous within its limits.
        d = self.start_two()
        try:
            td.write(self.conf, conf([obj("boat", 0, "stdout, csv",
                                          "csv.path = no/such/dir/x.csv\n")]))
            d.p.send_signal(signal.SIGHUP)
            d.err_line(lambda l: "object 'gone' removed: braking to rest" in l)
            d.err_line(lambda l: "reload refused (cannot open)" in l)
            rows = []
            d.line(lambda l: rows.append(l) or (l.startswith("gone,") and ",streaming," in l and
                                                 rows and any(",finished," in r for r in rows)),
                   30)
            d.p.send_signal(signal.SIGTERM)
            rows += d.lines_until_eof(timeout=20)
            self.assertEqual(d.wait(20), 0, d.stderr())
        finally:
            d.close()
        gone = [r for r in (l.split(",") for l in rows) if r[0] == "gone"]
        states = [r[12] for r in gone]
        rest = states.index("finished")
        self.assertIn("streaming", states[rest:])
        self.assertEqual(vel(gone[rest]), [0.0, 0.0, 0.0])
        for b, a in zip(gone, gone[1:]):
            self.assert_continuous(b, a, "gone braked, then resumed")

    def test_sigterm_while_a_removed_object_brakes(self):
        # Given a reload waiting for a removed object to rest, when SIGTERM,
        # then the pending reload is dropped and trajd exits 0.
        d = self.start_two()
        try:
            td.write(self.conf, conf([obj("boat", 0)]))
            d.p.send_signal(signal.SIGHUP)
            d.err_line(lambda l: "object 'gone' removed: braking" in l)
            d.p.send_signal(signal.SIGTERM)
            d.err_line(lambda l: "the pending reload is dropped" in l)
            d.lines_until_eof(timeout=20)
            self.assertEqual(d.wait(20), 0, d.stderr())
        finally:
            d.close()


    def test_fifo_track_in_a_reload_is_refused_and_sigterm_works(self):
        # Given trajd running, when SIGHUP with a config whose track is a FIFO
        # (no writer), then the reload is refused at check time with the
        # reason (it blocked in open() for good, and SIGTERM was then never
        # read); boat goes on, and SIGTERM ends trajd with 0.
        fifo = os.path.join(self.tmp, "pipe.csv")
        os.mkfifo(fifo)
        td.write(self.conf, conf([obj("boat", 0)]))
        d = td.Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", td.START_TIMEOUT_S)
            td.write(self.conf, conf([obj("boat", 0), obj("piped", 1).replace("circle.csv",
                                                                                "pipe.csv")]))
            d.p.send_signal(signal.SIGHUP)
            d.err_line(lambda l: "reload refused" in l and "pipe.csv: not a regular file: a FIFO"
                       in l)
            d.line(lambda l: l.startswith("boat,"))
            d.p.send_signal(signal.SIGTERM)
            d.lines_until_eof(timeout=20)
            self.assertEqual(d.wait(20), 0, d.stderr())
        finally:
            d.close()


    def reload_log(self, d):
        """SIGHUP; the log lines of that reload, up to 'reloaded:'."""
        d.p.send_signal(signal.SIGHUP)
        seen = []
        d.err_line(lambda l: seen.append(l) or "reloaded:" in l or "reload refused" in l, 60)
        return seen

    def test_unchanged_track_is_not_parsed_again(self):
        # Given boat on circle.csv and big on a 1e6-waypoint track, when SIGHUP
        # with a config whose objects are unchanged, then neither track is
        # parsed again (the log says so) and both are carried over; when
        # circle.csv is rewritten and SIGHUP, then only circle.csv is parsed
        # again and boat is a changed object (not carried over).
        with open(os.path.join(self.tmp, "big.csv"), "w") as f:
            f.write("t,x,y,z\n")
            f.writelines("%d,%d,0,0\n" % (i, i) for i in range(1000000))
        objs = [obj("boat", 0), obj("big", 1, "csv", "csv.path = big.out\n").replace(
            "circle.csv", "big.csv")]
        td.write(self.conf, conf(objs))
        d = td.Daemon(self.tmp, self.conf)
        try:
            d.msg(lambda f: f.get("READY") == "1", td.START_TIMEOUT_S * 3)
            td.write(self.conf, conf(objs).replace("status_interval_s = 1", "status_interval_s = 2"))
            log = "\n".join(self.reload_log(d))
            for name, n in (("circle.csv", 3000), ("big.csv", 1000000)):
                self.assertIn("%s unchanged (%d waypoints): not parsed again" % (name, n), log)
            self.assertIn("reloaded: 2 object(s), 2 carried over", log)
            td.xyz_track(os.path.join(self.tmp, "circle.csv"), 3000, 0.1, radius_m=60.0)
            log = "\n".join(self.reload_log(d))
            self.assertNotIn("circle.csv unchanged", log)
            self.assertIn("big.csv unchanged (1000000 waypoints): not parsed again", log)
            self.assertIn("reloaded: 2 object(s), 1 carried over", log)
            d.p.send_signal(signal.SIGTERM)
            d.lines_until_eof(timeout=30)
            self.assertEqual(d.wait(30), 0, d.stderr())
        finally:
            d.close()


def limit_memory():
    """The child may not read a 1 GiB file into memory (the old code did);
    not under AddressSanitizer, whose shadow memory needs the address space."""
    import resource
    with open(td.TRAJD, "rb") as f:
        if b"__asan_init" in f.read():
            return
    resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))


class CheckTime(unittest.TestCase):
    """A FIFO, a device or a file above the size cap named as a replay.track
    or a [can] log_in is refused by --check-config with the reason, before
    anything is read (issue 28 item 2)."""

    def setUp(self):
        self.tmpd = tempfile.TemporaryDirectory()
        self.tmp = self.tmpd.name
        self.conf = os.path.join(self.tmp, "trajd.conf")

    def tearDown(self):
        self.tmpd.cleanup()

    def refused(self, text, why):
        td.write(self.conf, text)
        r = subprocess.run([td.TRAJD, "--check-config", self.conf], capture_output=True,
                           text=True, timeout=30, preexec_fn=limit_memory)
        self.assertEqual(r.returncode, 78, r.stdout + r.stderr)
        self.assertIn(why, r.stderr)

    def track_conf(self, path):
        return "[object.boat]\ninput = replay\nreplay.track = %s\noutput = stdout\n" % path

    def log_in_conf(self, path):
        return ("[can]\nlog_in = %s\nlog_out = out.log\n"
                "[object.boat]\ninput = can\noutput = can\n" % path)

    def test_fifo(self):
        fifo = os.path.join(self.tmp, "pipe")
        os.mkfifo(fifo)
        self.refused(self.track_conf(fifo), "%s: not a regular file: a FIFO" % fifo)
        self.refused(self.log_in_conf(fifo), "log_in %s: not a regular file: a FIFO" % fifo)

    def test_device(self):
        self.refused(self.track_conf("/dev/zero"), "/dev/zero: not a regular file: a character "
                                                   "device")
        self.refused(self.log_in_conf("/dev/zero"), "log_in /dev/zero: not a regular file: a "
                                                    "character device")

    def test_size_cap(self):
        # a sparse file one byte above 1 GiB (TRACK_FILE_MAX_BYTES,
        # CAN_LOGFILE_MAX_BYTES): refused from its size, nothing read
        big = os.path.join(self.tmp, "big.csv")
        with open(big, "w") as f:
            f.truncate((1 << 30) + 1)
        self.refused(self.track_conf(big), "%s: larger than %d bytes" % (big, 1 << 30))
        self.refused(self.log_in_conf(big), "log_in %s: larger than %d bytes" % (big, 1 << 30))


if __name__ == "__main__":
    unittest.main()
