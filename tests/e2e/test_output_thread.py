"""test_output_thread.py - the tick never writes file output itself (issue 28 item 1).

Seen from outside, by the kernel's own accounts:
1. Under strace -f, every write(2) to the csv file and to stdout comes from a
   thread other than the one that runs the clock (trajd's main thread, the
   one that reads the clock's timerfd), and the output is whole: one line per
   tick, the header first.  The same for the CAN output's candump log
   ([can] log_out), whose every line python-can reads back.
2. A stderr nobody reads (a pipe of 4 KiB, F_SETPIPE_SZ, full after a few
   status lines) does not stop the clock: the csv file keeps growing by one
   line per tick while the pipe is full (the loop wrote its log lines itself
   and blocked in write(2) until someone read); once the pipe is read again,
   the lines queued meanwhile come out whole and in order.
3. With [realtime] fifo_priority (as root), the main thread runs SCHED_FIFO
   and the writer thread ("trajd-out") SCHED_OTHER (field 41 of
   /proc/PID/task/TID/stat, proc(5)), so the writer never takes the tick's CPU
   from it.
"""
import os
import re
import fcntl
import signal
import subprocess
import sys
import tempfile
import time
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

TRAJD = os.path.join(mbsim.BUILD, "bin", "trajd")
WAIT_S = 60
SCHED_OTHER, SCHED_FIFO = 0, 1


def write_conf(tmp, n, rt="", done=True, can=False):
    mbsim.line_track(os.path.join(tmp, "track.csv"), n)
    path = os.path.join(tmp, "trajd.conf")
    with open(path, "w") as f:
        f.write("[daemon]\nrate_hz = 100\nspeed = 10\nstatus_interval_s = 0\nstop_timeout_s = 1\n"
                "exit_when_done = %s\n" % ("yes" if done else "no") + rt +
                ("[can]\nlog_out = can.log\nmax_load_percent = 0\n" if can else "") +
                "[object.a]\ninput = replay\nreplay.track = track.csv\noutput = csv stdout%s\n"
                "csv.path = out.csv\n" % (" can" if can else ""))
    return path


def strace_run(test, tmp, conf):
    """trajd under strace -f: (its exit line's match, stdout, {fd: writer
    tids}, the clock readers' tids, the main tid, {path suffix: fd})."""
    trace = os.path.join(tmp, "trace.txt")
    p = subprocess.run(["strace", "-f", "-qq", "-o", trace,
                        "-e", "trace=openat,write,timerfd_create,read,close",
                        TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                       timeout=WAIT_S)
    test.assertEqual(p.returncode, 0, p.stderr)
    with open(trace) as f:
        writers, clock_readers, main, fds = parse_trace(f)
    return p, writers, clock_readers, main, fds


def joined_calls(lines):
    """[(tid, call)] of strace -f lines, each call whole: a call another
    thread interrupted is printed in two parts ("read(9,  <unfinished ...>",
    later "<... read resumed>..., 8) = 8" on the same thread), joined here."""
    calls, open_part = [], {}
    for ln in lines:
        if not ln[:1].isdigit():
            continue
        tid, call = ln.split(None, 1)
        call = call.rstrip("\n")
        if call.endswith("<unfinished ...>"):
            open_part[tid] = call[:-len("<unfinished ...>")]
            continue
        m = re.match(r"<\.\.\. \w+ resumed>\s?(.*)", call)
        if m:
            if tid not in open_part:
                continue   # its first part came before the trace began
            call = open_part.pop(tid) + m.group(1)
        calls.append((tid, call))
    return calls


def parse_trace(lines):
    """({fd: writer tids}, the clock readers' tids, the main tid, {path
    suffix: fd}) of an strace -f trace of trajd."""
    calls = joined_calls(lines)
    main = int(calls[0][0])   # the first line is trajd's execve's thread
    # fd numbers are reused: a write counts for a file only while its fd is open
    fds, writers, clock_readers, timer_fds, open_now = {}, {}, set(), set(), {1: 1}
    for pid, call in calls:
        pid = int(pid)
        m = re.match(r'openat\(AT_FDCWD, "[^"]*/?(out\.csv|can\.log)", O_WRONLY.*\)\s+= (\d+)',
                     call)
        if m:
            fds[m.group(1)] = int(m.group(2))
            open_now[int(m.group(2))] = int(m.group(2))
        m = re.match(r"timerfd_create\(.*\)\s+= (\d+)", call)
        if m:
            timer_fds.add(int(m.group(1)))
        # "close(5 <unfinished ...>" too (strace -f splits calls that
        # another thread interrupts), and an fd number taken again by any
        # other call (an eventfd of a worker) is no timer any more
        m = re.match(r"close\((\d+)", call)
        if m:
            timer_fds.discard(int(m.group(1)))
            open_now.pop(int(m.group(1)), None)
        # (a file opened, a track read on a worker: openat too)
        m = re.match(r"(eventfd2?|signalfd4?|epoll_create1?|socket|accept4?|pipe2?|dup[23]?|openat)"
                     r"\(.*\)\s+= (\d+)", call)
        if m:
            timer_fds.discard(int(m.group(2)))
        m = re.match(r"read\((\d+), .*, 8\)\s+= 8", call)
        if m and int(m.group(1)) in timer_fds:
            clock_readers.add(pid)
        m = re.match(r"write\((\d+), ", call)
        if m and int(m.group(1)) in open_now:
            writers.setdefault(int(m.group(1)), set()).add(pid)
    return writers, clock_readers, main, fds


def task_stat(pid, tid):
    with open("/proc/%d/task/%d/stat" % (pid, tid)) as f:
        rest = f.read().rsplit(")", 1)[1].split()
    return rest  # rest[0] is field 3 (state)


class OutputThreadTest(unittest.TestCase):
    def test_trace_parser_joins_split_calls(self):
        # Given a trace (strace -f's form) where another thread's write split
        # the clock's timerfd_create and its reads, as under load
        trace = ["100   openat(AT_FDCWD, \"/etc/ld.so.cache\", O_RDONLY|O_CLOEXEC) = 3\n",
                 "100   timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC|TFD_NONBLOCK <unfinished ...>\n",
                 "101   write(2, \"<6>started\"..., 11 <unfinished ...>\n",
                 "100   <... timerfd_create resumed>) = 9\n",
                 "101   <... write resumed>)              = 11\n",
                 "100   read(9,  <unfinished ...>\n",
                 "102   read(8, \"\\1\\0\\0\\0\\0\\0\\0\\0\", 8) = 8\n",
                 "100   <... read resumed>\"\\1\\0\\0\\0\\0\\0\\0\\0\", 8) = 8\n"]
        # then the main thread is the one clock reader (the eventfd 8 of a
        # writer is no clock); the first parts alone name neither
        writers, clock_readers, main, fds = parse_trace(trace)
        self.assertEqual(main, 100)
        self.assertEqual(clock_readers, {100})

    def test_writes_off_the_clock_thread(self):
        with tempfile.TemporaryDirectory() as tmp:
            p, writers, clock_readers, main, fds = strace_run(self, tmp, write_conf(tmp, 60))
            csv_fd = fds.get("out.csv")
            self.assertIsNotNone(csv_fd)
            # Given the clock read by the main thread only, then neither the
            # csv file nor stdout is ever written by it.
            self.assertEqual(clock_readers, {main})
            self.assertIn(csv_fd, writers)
            self.assertIn(1, writers)
            self.assertNotIn(main, writers[csv_fd])
            self.assertNotIn(main, writers[1])
            # And the output is whole: the header, then one line per tick.
            with open(os.path.join(tmp, "out.csv")) as f:
                rows = f.read().splitlines()
            m = re.search(r"ticks (\d+), missed (\d+)", p.stderr)
            self.assertIsNotNone(m, p.stderr)
            self.assertTrue(rows[0].startswith("object,"))
            self.assertEqual(len(rows) - 1, int(m.group(1)))
            self.assertEqual(p.stdout.splitlines(), rows)

    def test_can_log_out_off_the_clock_thread(self):
        import can   # python-can (Debian python3-can), an independent reader
        with tempfile.TemporaryDirectory() as tmp:
            p, writers, clock_readers, main, fds = strace_run(self, tmp,
                                                              write_conf(tmp, 60, can=True))
            log_fd = fds.get("can.log")
            self.assertIsNotNone(log_fd)
            self.assertEqual(clock_readers, {main})
            self.assertIn(log_fd, writers)
            self.assertNotIn(main, writers[log_fd])
            with open(os.path.join(tmp, "can.log")) as f:
                lines = f.read().splitlines()
            msgs = list(can.CanutilsLogReader(os.path.join(tmp, "can.log")))
            self.assertGreater(len(msgs), 100)
            self.assertEqual(len(msgs), len(lines))
            # (nothing was lost: strace_run saw exit status 0, not 74)

    def test_unread_stderr_does_not_stop_the_clock(self):
        with tempfile.TemporaryDirectory() as tmp:
            mbsim.line_track(os.path.join(tmp, "track.csv"), 3000)
            conf = os.path.join(tmp, "trajd.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\nstatus_interval_s = 1\nstop_timeout_s = 0\n"
                        "[object.a]\nid = 0\ninput = replay\nreplay.track = track.csv\n"
                        "output = csv\ncsv.path = a.csv\n")
                for i in range(1, 41):   # a long status line: ~3 KB a second
                    f.write("[object.o%02d]\nid = %d\ninput = replay\nreplay.track = track.csv\n"
                            "output = stdout\n" % (i, i))
            r, w = os.pipe()
            fcntl.fcntl(w, fcntl.F_SETPIPE_SZ, 4096)
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=w)
            os.close(w)
            out = []
            try:
                def rows():
                    try:
                        with open(os.path.join(tmp, "a.csv")) as f:
                            return sum(1 for _ in f)
                    except FileNotFoundError:
                        return 0
                # Given stderr unread for 4 s (the pipe is full within 2) ...
                time.sleep(4)
                n0, t0 = rows(), time.monotonic()
                time.sleep(3)
                n1, t1 = rows(), time.monotonic()
                # ... then the clock ran on: at least half the ticks of those 3 s
                # were written (a blocked loop writes none).
                self.assertGreater(n1 - n0, 0.5 * 100 * (t1 - t0), (n0, n1))
            finally:
                p.send_signal(signal.SIGTERM)
                with os.fdopen(r, "r", errors="replace") as f:
                    out = f.read()   # until trajd exits (EOF)
                rc = p.wait(WAIT_S)
            self.assertEqual(rc, 0, out[-2000:])
            # The lines queued while nobody read came out after, whole and in order
            # (fewer than the queue holds: none dropped).
            ups = [int(u) for u in re.findall(r"^<6>status: up (\d+) s", out, re.M)]
            self.assertGreaterEqual(len(ups), 5, out[-2000:])
            self.assertEqual(ups, list(range(ups[0], ups[0] + len(ups))))
            self.assertNotIn("log lines dropped", out)
            self.assertIn("<6>exit:", out)

    @unittest.skipUnless(os.geteuid() == 0, "SCHED_FIFO needs root")
    def test_writer_thread_sched_other(self):
        with tempfile.TemporaryDirectory() as tmp:
            conf = write_conf(tmp, 60, rt="[realtime]\nfifo_priority = 10\n", done=False)
            p, lines = None, None
            p = subprocess.Popen([TRAJD, "-f", "-c", conf], cwd=tmp, stdin=subprocess.DEVNULL,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            try:
                lines = mbsim.Lines(p.stderr)
                self.assertIsNotNone(lines.wait_for("started:", WAIT_S), "".join(lines.all))
                policy = {}
                for _ in range(50):   # the writer starts with the outputs, just before
                    for tid in map(int, os.listdir("/proc/%d/task" % p.pid)):
                        with open("/proc/%d/task/%d/comm" % (p.pid, tid)) as f:
                            policy[f.read().strip(), tid == p.pid] = int(task_stat(p.pid, tid)[38])
                    if any(k[0] == "trajd-out" for k in policy):
                        break
                    time.sleep(0.1)
            finally:
                p.send_signal(signal.SIGTERM)
                rc = p.wait(WAIT_S)
                if lines:
                    lines.wait_for("\0", 1)
                p.stderr.close()
            self.assertEqual(rc, 0)
            mains = [v for k, v in policy.items() if k[1]]
            outs = [v for k, v in policy.items() if k[0] == "trajd-out"]
            self.assertEqual(mains, [SCHED_FIFO], policy)
            self.assertEqual(outs, [SCHED_OTHER], policy)


if __name__ == "__main__":
    unittest.main()
