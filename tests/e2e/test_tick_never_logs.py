"""test_tick_never_logs.py - no log line is made inside the tick (issue 28 item 1).

daemon/core/log.h: "Not for the tick: the tick counts events; a housekeeping
timer logs them."  A line is formatted by its caller and taken under the
log's lock, so a line logged inside the tick would hold the setpoints of
that tick up by its formatting, and by the lock whenever another thread
logs.

Seen from outside with a debugger: trajd runs under gdb with a breakpoint
on log_at, the one function every line goes through, and each hit prints
its backtrace.  While objects start streaming (each start states its
play-out delay D), reach the end of their tracks and the daemon exits, no
backtrace may pass through the tick (core.c's tick(), the clock's
callback on_clock), and the lines the starts owe are all in the log.
"""
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
OBJECTS = 3
WAIT_S = 120


def write_conf(tmp):
    """OBJECTS objects on a line, the last one's track in two pieces 20 s
    apart (a silent end, then a second trajectory 3 m aside, reached by a
    transfer); CSV outputs and the Modbus server's registers (its cycle
    runs in the tick too)."""
    mbsim.line_track(os.path.join(tmp, "track.csv"), 60)
    with open(os.path.join(tmp, "track.csv")) as f:
        rows = f.read().splitlines()
    with open(os.path.join(tmp, "gap.csv"), "w") as f:
        f.write(rows[0] + "\n")
        for r in rows[1:]:
            f.write(r + "\n")
        for r in rows[1:]:
            t, x, y, z = (float(v) for v in r.split(","))
            f.write("%.3f,%.3f,%.3f,%.1f\n" % (t + 26.0, x, y + 3.0, z))
    path = os.path.join(tmp, "trajd.conf")
    with open(path, "w") as f:
        f.write("[daemon]\nrate_hz = 100\nspeed = 10\nstatus_interval_s = 0\n"
                "stop_timeout_s = 1\nexit_when_done = yes\n"
                "[modbus]\naddress = 127.0.0.1\nport = 0\nsystemd_socket = no\n")
        for i in range(OBJECTS):
            f.write("[object.o%d]\nid = %d\ninput = replay\nreplay.track = %s\n"
                    "output = csv\ncsv.path = out%d.csv\n"
                    % (i, i, "gap.csv" if i == OBJECTS - 1 else "track.csv", i))
    return path


def run_under_gdb(tmp, conf):
    """(gdb's stdout, trajd's stderr) of trajd -f -c conf, every log_at hit's
    backtrace printed."""
    cmds = os.path.join(tmp, "gdb.cmds")
    with open(cmds, "w") as f:
        f.write("set pagination off\nset confirm off\nset print thread-events off\n"
                "set breakpoint pending on\nbreak log_at\ncommands\nsilent\n"
                "echo ==== log_at\\n\nbt 16\ncontinue\nend\n"
                "run -f -c %s 2> %s\nquit\n" % (conf, os.path.join(tmp, "stderr.txt")))
    p = subprocess.run(["gdb", "-nx", "-batch", "-x", cmds, TRAJD], cwd=tmp,
                       stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, timeout=WAIT_S)
    with open(os.path.join(tmp, "stderr.txt")) as f:
        return p.stdout, f.read()


class TickNeverLogs(unittest.TestCase):
    def test_no_line_from_the_tick(self):
        with tempfile.TemporaryDirectory() as tmp:
            out, err = run_under_gdb(tmp, write_conf(tmp))
            hits = out.split("==== log_at\n")[1:]
            self.assertGreater(len(hits), OBJECTS, out[-2000:])
            for bt in hits:
                # a frame of its own ("#3  0x... in tick (") or inlined ("#3  tick (")
                self.assertIsNone(re.search(r"^#\d+\s+(0x[0-9a-f]+ in )?(tick|on_clock) \(",
                                            bt, re.M),
                                  "a line logged inside the tick:\n" + bt)
            # the play-out delay of every trajectory's start is in the log, once
            for i in range(OBJECTS):
                for track in (1, 2) if i == OBJECTS - 1 else (1,):
                    lines = re.findall(r"object 'o%d': trajectory %d streams: play-out delay D "
                                       r"[0-9.]+ s" % (i, track), err)
                    self.assertEqual(len(lines), 1, err[-3000:])
            self.assertRegex(err, r"exit: ", err[-2000:])


if __name__ == "__main__":
    unittest.main()
