#!/usr/bin/python3
"""test_drive_bus_check.py - the bus-log checker of the drive tests
(tests/helpers/drive_bus_check.py) catches each defect issue 23 measured, on
candump logs written here frame by frame (CiA 301 / 402 layouts), and passes
a clean one: a checker that cannot fail would prove nothing.

Each log: 20 Hz, SYNC with counter, one drive (node 1, 10000 counts/m) that
reports statusword + 0x6064 after each SYNC, trajd's RPDO (controlword +
target) after each SYNC; the drive moves at 1 m/s (500 counts per SYNC),
bounds 1.5 m/s and 10 m/s^2.
"""
import os
import struct
import subprocess
import sys
import tempfile
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(REPO, "tests", "helpers", "drive_bus_check.py")
T = 0.05
OE, FAULT, SOD = 0x0237, 0x0218, 0x0250


class Log:
    def __init__(self):
        self.lines = []
        self.t = 100.0
        self.c = 0

    def frame(self, cid, data):
        self.t += 0.001
        self.lines.append("(%.6f) vcan0 %03X#%s" % (self.t, cid, data.hex().upper()))

    def cycle(self, target=None, cw=0x000F, sw=OE, pos=0, skip=0):
        """One cycle: SYNC (counter), trajd's RPDO, then the drive's TPDO."""
        self.t += T
        self.c = (self.c + skip) % 240 + 1
        self.frame(0x080, bytes([self.c]))
        if target is not None:
            self.frame(0x201, struct.pack("<Hi", cw, target))
        self.frame(0x181, struct.pack("<Hi", sw, pos))

    def emcy(self, code):
        self.frame(0x081, struct.pack("<HB5x", code, 1))

    def run(self, *extra):
        with tempfile.NamedTemporaryFile("w", suffix=".log", delete=False) as f:
            f.write("\n".join(self.lines) + "\n")
        try:
            return subprocess.run([sys.executable, CHECK, f.name, "--period-s", str(T),
                                   "--vmax", "1.5", "--amax", "10", "--node", "1:10000"] +
                                  list(extra), capture_output=True, text=True, timeout=60)
        finally:
            os.unlink(f.name)


def moving(log, start, n, pos=None):
    """n cycles at 1 m/s from start (the drive follows one cycle behind)."""
    p = start if pos is None else pos
    for k in range(n):
        tgt = start + 500 * (k + 1)
        log.cycle(tgt, pos=p)
        p = tgt
    return p


class DriveBusCheck(unittest.TestCase):
    def clean(self):
        log = Log()
        log.cycle(None, sw=SOD, pos=12000)      # heard, not enabled: no target yet
        log.cycle(12000, cw=0x0000, sw=SOD, pos=12000)
        log.cycle(12000, cw=0x0000, sw=OE, pos=12000)   # enabled: reported after this SYNC
        log.cycle(12000, pos=12000)             # the first target after it: its 0x6064
        # then a smooth start (accelerating within a*T^2 = 250 counts per SYNC per SYNC)
        p, tgt = 12000, 12000
        for v in (100, 300, 500):
            tgt += v
            log.cycle(tgt, pos=p)
            p = tgt
        return log, moving(log, tgt, 10, p)

    def test_clean_log_passes(self):
        log, _ = self.clean()
        r = log.run()
        self.assertEqual(r.returncode, 0, r.stdout + r.stderr)

    def test_target_while_faulted(self):
        log, p = self.clean()
        log.emcy(0xFF00)
        log.cycle(p + 500, sw=FAULT, pos=p)         # sent before the fault was known: fine
        log.cycle(p + 1000, cw=0, sw=FAULT, pos=p)  # known now: a moving target is a defect
        r = log.run("--allow-emcy", "0xFF00")
        self.assertEqual(r.returncode, 1)
        self.assertIn('"1": 1', r.stdout)

    def test_first_target_after_clear_not_its_position(self):
        log, p = self.clean()
        log.emcy(0xFF00)
        log.cycle(p, sw=FAULT, pos=p)
        log.cycle(p, cw=0, sw=SOD, pos=p)
        log.cycle(p, cw=0, sw=OE, pos=p)
        log.cycle(p + 16639, pos=p)   # trajd's old position, not the drive's
        r = log.run("--allow-emcy", "0xFF00")
        self.assertEqual(r.returncode, 1)
        self.assertIn("first target after enable", r.stdout)

    def test_restart_disables_a_running_drive(self):
        log, p = self.clean()
        log.c = 0                      # a new master: its counter starts at 1 again
        log.cycle(p, cw=0x0000, pos=p)
        r = log.run()
        self.assertEqual(r.returncode, 1)
        self.assertIn("controlword 0x0000 to a drive in Operation Enabled", r.stdout)

    def test_stall_target_n_cycles_ahead(self):
        log, p = self.clean()
        log.cycle(p + 500 * 20, pos=p)   # a 1 s stall: the next SYNC, 20 cycles ahead
        r = log.run()
        self.assertEqual(r.returncode, 1)
        self.assertIn("target step 10000 counts in one SYNC", r.stdout)

    def test_stall_reported_on_request(self):
        log, p = self.clean()
        log.t += 0.95                     # the SYNC comes 1 s late, the target 20 cycles on
        log.cycle(p + 500 * 20, pos=p)
        r = log.run("--stalls", "report")
        self.assertEqual(r.returncode, 0, r.stdout)
        self.assertIn('"stalls": 2', r.stdout)   # the step, and its change
        self.assertIn("trajd stalled 20.1 periods", r.stdout)
        self.assertEqual(log.run().returncode, 1)

    def test_velocity_step(self):
        log, p = self.clean()
        log.cycle(p, pos=p)              # 1 m/s to standing still in one SYNC: 500 counts/T^2
        r = log.run()
        self.assertEqual(r.returncode, 1)
        self.assertIn("step change 500 counts", r.stdout)

    def test_fault_caused_by_trajd(self):
        log, p = self.clean()
        log.emcy(0x8611)                 # following error
        log.cycle(p, sw=FAULT, pos=p)
        r = log.run("--allow-emcy", "0xFF00")
        self.assertEqual(r.returncode, 1)
        self.assertIn("EMCY 0x8611", r.stdout)

    def test_heartbeat_fault_only_after_trajd_is_gone(self):
        log, p = self.clean()
        log.emcy(0x8130)                 # the master's heartbeat lost, after its last SYNC
        self.assertEqual(log.run().returncode, 0)
        log.cycle(p, sw=FAULT, pos=p)    # ... but a SYNC after it: trajd was alive
        self.assertEqual(log.run().returncode, 1)
        # unless the SYNCs had stopped for the consumer time (3 s) before it: a
        # killed trajd, and a new one after
        log2, p = self.clean()
        log2.t += 3.0
        log2.emcy(0x8130)
        log2.frame(0x181, struct.pack("<Hi", FAULT, p))
        log2.c = 0
        log2.cycle(p, cw=0, sw=FAULT, pos=p)
        self.assertEqual(log2.run("--consumer-s", "3").returncode, 0)
        self.assertEqual(log2.run("--consumer-s", "5").returncode, 1)


if __name__ == "__main__":
    unittest.main()
