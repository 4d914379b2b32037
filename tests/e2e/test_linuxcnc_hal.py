"""test_linuxcnc_hal.py - the LinuxCNC recipe of daemon/doc/INTEGRATION.md, run with linuxcnc-uspace's HAL.

A HAL session (halrun, POSIX non-realtime threads of linuxcnc-uspace) runs a
1 ms thread with a `streamer` of three floats; trajd replays a short track at
1 kHz and its stdout goes, as the recipe says, through awk (positions only, no
"nan" rows) into `halstreamer`.  Once the streamer has played every line
(curr-depth 0), its pins hold trajd's last setpoint (its CSV output of the same
run), the track's end point.
Skipped without linuxcnc-uspace (halrun) or without root (rtapi_app runs as
root with RTAPI_UID, a fallback user).
"""
import csv
import os
import shutil
import subprocess
import tempfile
import time
import unittest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
HAL = """loadrt threads name1=t period1=1000000
loadrt streamer depth=8192 cfg=fff
addf streamer.0 t
start
"""


class LinuxCncHal(unittest.TestCase):
    @unittest.skipUnless(os.geteuid() == 0, "not root (rtapi_app needs it)")
    def test_streamer_gets_trajd_setpoints(self):
        # make check installs linuxcnc-uspace (DEPS_TEST): missing is a failure
        self.assertTrue(shutil.which("halrun"), "halrun not found: linuxcnc-uspace not installed (make deps)")
        with tempfile.TemporaryDirectory() as tmp:
            os.chmod(tmp, 0o777)   # rtapi_app runs as the fallback user: its fifo goes here
            env = dict(os.environ, RTAPI_UID="65534", RTAPI_FIFO_PATH=os.path.join(tmp, "fifo"))
            with open(os.path.join(tmp, "track.csv"), "w") as f:
                f.write("t_s,x_m,y_m,z_m\n")
                for i in range(11):
                    f.write("%.6f,%.6f,%.6f,0.000000\n" % (i * 0.1, i * 0.1, (i * 0.1) ** 2 / 4))
            with open(os.path.join(tmp, "t.hal"), "w") as f:
                f.write(HAL)
            with open(os.path.join(tmp, "trajd.conf"), "w") as f:
                f.write("[daemon]\nrate_hz = 1000\nexit_when_done = yes\nstatus_interval_s = 0\n"
                        "[object.a]\ninput = replay\nreplay.track = %s/track.csv\n"
                        "output = stdout, csv\ncsv.path = %s/a.csv\nstdout.header = no\n"
                        % (tmp, tmp))
            subprocess.run(["halrun", "-U"], env=env, capture_output=True)
            hal = subprocess.Popen(["halrun", "-I", "t.hal"], cwd=tmp, env=env,
                                   stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE, text=True)
            try:
                ok = False
                for _ in range(100):   # bounded wait until the HAL session answers
                    if subprocess.run(["halcmd", "show", "pin", "streamer.0.pin.0"], env=env,
                                      capture_output=True, text=True).stdout.count("streamer"):
                        ok = True
                        break
                    time.sleep(0.2)
                self.assertTrue(ok, "HAL session did not start")
                run = ("%s -f -c trajd.conf 2> trajd.err | awk -F, '$4 != \"nan\" "
                       "{ print $4, $5, $6; fflush() }' | halstreamer" % TRAJD)
                r = subprocess.run(["bash", "-o", "pipefail", "-c", run], cwd=tmp, env=env,
                                   capture_output=True, text=True, timeout=60)
                self.assertEqual(r.returncode, 0, r.stderr + open(os.path.join(tmp, "trajd.err")).read())
                for _ in range(300):   # bounded: until the streamer has played every line
                    depth = subprocess.run(["halcmd", "getp", "streamer.0.curr-depth"], env=env,
                                           capture_output=True, text=True).stdout.strip()
                    if depth == "0":
                        break
                    time.sleep(0.1)
                self.assertEqual(depth, "0")
                pins = [subprocess.run(["halcmd", "getp", "streamer.0.pin.%d" % i], env=env,
                                       capture_output=True, text=True).stdout.strip()
                        for i in range(3)]
            finally:
                subprocess.run(["halrun", "-U"], env=env, capture_output=True)
                hal.stdin.close()
                hal.wait(timeout=20)
                hal.stderr.close()
            with open(os.path.join(tmp, "a.csv")) as f:
                rows = [r for r in csv.DictReader(f) if r["x_m"] != "nan"]
            self.assertEqual(rows[-1]["state"], "finished")
            # the pins hold the last line played: trajd's last setpoint, the track's end
            for pin, k in zip(pins, ("x_m", "y_m", "z_m")):
                self.assertAlmostEqual(float(pin), float(rows[-1][k]), delta=1e-6, msg=pins)
            self.assertAlmostEqual(float(pins[0]), 1.0, delta=1e-6)
            self.assertAlmostEqual(float(pins[1]), 0.25, delta=1e-6)


if __name__ == "__main__":
    unittest.main()
