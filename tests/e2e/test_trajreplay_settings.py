#!/usr/bin/python3
"""test_trajreplay_settings.py - trajreplay's engine settings, its config
mode (-c trajd.conf --object NAME) and the bounds on what it writes.

The engine settings come from one table (lib/engine/engine_settings.c):
every setting is an option, and a trajd config's object gives the same
output as the same settings given as options.  (tests/e2e/test_daemon.py
checks trajreplay -c against trajd itself, row by row.)
"""
import os
import subprocess
import sys
import tempfile
import unittest

BUILD = os.environ.get("BUILD", os.path.abspath("build"))
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(REPO, "tests", "data")
FIGURE8 = os.path.join(DATA, "n2k_furuno_figure8_src52.csv")
VISNJAN = os.path.join(DATA, "gpxgo_visnjan.csv")


def write(path, text):
    with open(path, "w") as f:
        f.write(text)


def run(args, timeout=120):
    return subprocess.run([TRAJREPLAY, "-q"] + args, capture_output=True, text=True,
                          errors="replace", timeout=timeout)


def first_lines(src, dst, n):
    with open(src) as f:
        write(dst, "".join(f.readlines()[:n]))


class TestConfigMode(unittest.TestCase):
    # every engine key set away from its default (a valid combination)
    ENGINE_KEYS = {
        "method": ("smooth", "--method"), "param": ("uniform", "--param"),
        "ends": ("clamped", "--ends"), "start_vel_m_s": ("0.5,-0.25,0", "--start-vel"),
        "end_vel_m_s": ("0,0.125,0", "--end-vel"), "fragment": ("20", "--fragment"),
        "overlap": ("10", "--overlap"), "accuracy": ("1e-4", "--accuracy"),
        "max_lookahead": ("24", "--max-lookahead"), "capacity": ("999", "--capacity"),
        "max_gap_s": ("8", "--max-gap"), "max_abs_m": ("5e5", "--max-abs"),
        "profile": ("road", "--profile"), "max_speed_m_s": ("3", "--max-speed"),
        # 0.05: under the default profile (auto) turns are free and 0.5 m/s^2
        # of speed change does not bite on this walk
        "max_accel_m_s2": ("0.05", "--max-accel"), "confirm": ("1", "--confirm"),
        "transfer_speed_m_s": ("0.5", "--transfer-speed"),
        "transfer_accel_m_s2": ("0.2", "--transfer-accel"),
        "max_segment_s": ("30", "--max-segment"), "start_slack": ("3", "--start-slack"),
        "smooth_window": ("20", "--smooth-window"), "smooth_ctrl": ("5", "--smooth-ctrl"),
        "scale_accel_m_s2": ("2", "--scale-accel"), "scale_jerk_m_s3": ("20", "--scale-jerk"),
    }

    def setUp(self):
        self.tmpdir = tempfile.TemporaryDirectory()
        self.tmp = self.tmpdir.name
        self.track = os.path.join(self.tmp, "walk.csv")
        first_lines(VISNJAN, self.track, 60)
        self.conf = os.path.join(self.tmp, "t.conf")
        keys = "".join("%s = %s\n" % (k, v) for k, (v, _) in self.ENGINE_KEYS.items())
        write(self.conf, "[daemon]\nrate_hz = 40\n"
                         "[object.a]\nid = 0\ninput = replay\nreplay.track = walk.csv\noutput = stdout\n"
                         + keys +
                         "[object.b]\nid = 1\ninput = replay\nreplay.track = walk.csv\noutput = stdout\n")

    def tearDown(self):
        self.tmpdir.cleanup()

    def out(self, args, name):
        path = os.path.join(self.tmp, name + ".csv")
        p = run(["-o", path] + args)
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(path) as f:
            return f.read()

    def test_every_key_is_an_option(self):
        # Given object a with every engine key set, then trajreplay -c gives
        # byte for byte what the same settings given as options give
        opts = []
        for v, opt in self.ENGINE_KEYS.values():
            opts += [opt, v]
        by_conf = self.out(["-c", self.conf, "--object", "a"], "conf")
        by_opts = self.out(["--rate", "40", "--object", "a"] + opts + [self.track], "opts")
        self.assertTrue(by_conf == by_opts, "-c object a differs from the same options")
        # and not the defaults' output (the settings were applied)
        default = self.out(["--rate", "40", "--object", "a", self.track], "default")
        self.assertTrue(by_conf != default, "-c object a gives the defaults' output")
        # and object b (no engine key) is the defaults' output at the config's rate
        self.assertTrue(self.out(["-c", self.conf, "--object", "b"], "b")
                        == default.replace("\na,", "\nb,"), "-c object b: not the defaults")

    def test_each_option_changes_the_output(self):
        # Given one setting at a time away from its default, then the output
        # differs from the default one (each option reaches the engine),
        # except those with no effect alone on this track (max_abs_m,
        # max_segment_s; smooth_* without method smooth; the end velocities
        # without ends clamped, and ends clamped with zero velocities, which
        # is rest), which must at least be accepted.
        default = self.out(["--rate", "20", self.track], "d")
        no_effect = {"max_abs_m", "max_segment_s", "smooth_window", "smooth_ctrl", "ends",
                     "end_vel_m_s", "start_vel_m_s", "capacity",
                     # the time scaling acts only when it is needed (underrun,
                     # stop, override): a clean replay is the same
                     "scale_accel_m_s2", "scale_jerk_m_s3",
                     # a clean walk: every profile keeps every fix; no transfer
                     "profile", "transfer_speed_m_s", "transfer_accel_m_s2"}
        for key, (v, opt) in self.ENGINE_KEYS.items():
            extra = [opt, v]
            if key == "fragment":
                extra += ["--overlap", "10"]
            got = self.out(["--rate", "20"] + extra + [self.track], key)
            if key not in no_effect:
                self.assertTrue(got != default, key + ": no effect on the output")
        # and those have an effect where they apply
        for extra, base in ((["--ends", "clamped", "--start-vel", "1,0,0"], []),
                            (["--ends", "clamped", "--end-vel", "0,1,0"], []),
                            (["--method", "smooth", "--smooth-window", "20"], ["--method", "smooth"]),
                            (["--method", "smooth", "--smooth-ctrl", "5"], ["--method", "smooth"])):
            a = self.out(["--rate", "20"] + extra + [self.track], "a")
            b = self.out(["--rate", "20"] + base + [self.track], "b")
            self.assertTrue(a != b, " ".join(extra) + ": no effect on the output")
        # capacity is flow control: a replay offering 400 waypoints 1 ms apart
        # at 20 Hz fills a small buffer (waypoints offered again, none lost)
        fast = os.path.join(self.tmp, "fast.csv")
        write(fast, "t,x,y,z\n" + "".join("%g,%g,0,0\n" % (i * 1e-3, i * 1e-3) for i in range(400)))
        for cap, full in (("72", True), ("4096", False)):
            p = run(["--summary", "--rate", "20", "--capacity", cap, "-o", os.devnull, fast])
            self.assertEqual(p.returncode, 0, p.stderr)
            self.assertIn("summary: accepted 400\n", p.stderr)
            self.assertEqual("summary: full_retries 0\n" not in p.stderr, full, p.stderr)

    def test_options_override_the_config(self):
        # Given -c with object a and --fragment/--overlap on the command line,
        # then the command line wins over the file
        opts = []
        for key, (v, opt) in self.ENGINE_KEYS.items():
            opts += [opt, "8" if key == "overlap" else "16" if key == "fragment" else v]
        over = self.out(["-c", self.conf, "--object", "a", "--fragment", "16", "--overlap", "8"],
                        "over")
        ref = self.out(["--rate", "40", "--object", "a"] + opts + [self.track], "ref")
        self.assertTrue(over == ref, "command-line options did not override the config")

    def test_config_errors(self):
        # no such object, several objects and none chosen, a bad config, a
        # bad value of an engine option: usage errors (2), with the reason
        p = run(["-c", self.conf, "--object", "zz"])
        self.assertEqual(p.returncode, 2)
        self.assertIn("no such object", p.stderr)
        self.assertIn("a, b", p.stderr)
        p = run(["-c", self.conf])
        self.assertEqual(p.returncode, 2)
        self.assertIn("--object", p.stderr)
        bad = os.path.join(self.tmp, "bad.conf")
        write(bad, "[object.a]\ninput = replay\nreplay.track = walk.csv\noutput = stdout\n"
                   "fragment = 2\n")
        p = run(["-c", bad])
        self.assertEqual(p.returncode, 2)
        self.assertIn("bad.conf:5:", p.stderr)
        for opt, val in (("--capacity", "0"), ("--start-slack", "-1"), ("--max-abs", "x"),
                         ("--method", "spline"), ("--end-vel", "1,2")):
            p = run([opt, val, self.track])
            self.assertEqual(p.returncode, 2, (opt, p.stderr))
            self.assertIn(opt + ": expected", p.stderr)

    def test_single_object_needs_no_name(self):
        # Given a config with one object, then -c alone replays it, under its name
        one = os.path.join(self.tmp, "one.conf")
        write(one, "[object.boat]\ninput = replay\nreplay.track = walk.csv\noutput = stdout\n")
        got = self.out(["-c", one], "one")
        self.assertTrue(got.splitlines()[1].startswith("boat,"))
        self.assertTrue(got == self.out(["--object", "boat", self.track], "ref"))

    def test_config_replay_keys(self):
        # Given an object whose replay.skip_bad = yes, on a track with a bad
        # line, then trajreplay -c skips and counts it, as trajd does (it
        # failed on the bad line: the key was not read), and gives what
        # --skip-bad gives
        with open(self.track) as f:
            lines = f.read().splitlines(True)
        bad = os.path.join(self.tmp, "badline.csv")
        write(bad, "".join(lines[:20]) + "1,2\n" + "".join(lines[20:]))
        conf = os.path.join(self.tmp, "skip.conf")
        write(conf, "[object.boat]\ninput = replay\nreplay.track = badline.csv\n"
                    "replay.skip_bad = yes\noutput = stdout\n")
        p = run(["--summary", "-c", conf, "-o", os.path.join(self.tmp, "skip.csv")])
        self.assertEqual(p.returncode, 0, p.stderr)
        ref = run(["--summary", "--skip-bad", "--object", "boat", "-o",
                   os.path.join(self.tmp, "skipref.csv"), bad])
        self.assertEqual(ref.returncode, 0, ref.stderr)
        with open(os.path.join(self.tmp, "skip.csv")) as f, \
                open(os.path.join(self.tmp, "skipref.csv")) as g:
            self.assertTrue(f.read() == g.read(), "-c with replay.skip_bad differs from --skip-bad")


if __name__ == "__main__":
    unittest.main(verbosity=2)
