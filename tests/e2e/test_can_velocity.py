#!/usr/bin/python3
"""test_can_velocity.py - the source's velocity over CAN into trajd's local method (issue 31).

A helix sampled at 1 Hz with its exact velocity is encoded by canmatrix from config/trajd.dbc
(not by our encoder) as a candump log: object 0 on classic frames, each waypoint's VELOCITY
frame (WAYPOINT mux 6) first, object 1 as CAN FD frames with mux 7. trajd replays the log
([can] log_in) with `method = hermite` and writes each object's setpoints to CSV. Every
streamed row must lie on scipy's CubicHermiteSpline of the velocities as the frames carry
them (1 cm/s per bit: the test quantizes them itself), far closer than to the Hermite of
velocities estimated from the positions, which the same objects stream when the frames
carry none (object 2, classic frames without VELOCITY)."""
import csv
import os
import subprocess
import sys
import tempfile
import unittest
from decimal import Decimal

import numpy as np
from scipy.interpolate import CubicHermiteSpline

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import canmatrix  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))
TRAJD = os.path.join(BUILD, "bin", "trajd")
N = 40
W = 0.15


def helix():
    t = np.arange(N, dtype=float)
    pos = np.stack([30 * np.cos(W * t), 30 * np.sin(W * t), 0.5 * t], axis=1)
    vel = np.stack([-30 * W * np.sin(W * t), 30 * W * np.cos(W * t), 0.5 + 0 * t], axis=1)
    return t, np.round(pos, 6), vel


def raw(fr, name, phys):
    """The nearest code of phys for signal name (canmatrix's factor and offset)."""
    sig = fr.signal_by_name(name)
    return int(round((float(phys) - float(sig.offset)) / float(sig.factor)))


def frames(db, seq, t, p, v, obj, fd):
    """canmatrix-encoded frames of one waypoint: FD mux 7, or VELOCITY first then TIME..Z."""
    if fd:
        fr = db.frame_by_id(canmatrix.ArbitrationId(0x690))
        d = {"WPFD_Mux": 7, "WPFD_Seq": seq & 0xFF, "WPFD_Time": raw(fr, "WPFD_Time", t)}
        for a, ax in enumerate("XYZ"):
            d["WPFD_" + ax] = raw(fr, "WPFD_" + ax, p[a])
            d["WPFD_V" + ax] = raw(fr, "WPFD_V" + ax, v[a])
        return [(0x690 + obj, bytes(fr.encode(d)), True)]
    out = []
    if v is not None:
        fr = db.frame_by_id(canmatrix.ArbitrationId(0x680))
        d = {"WP_Mux": 6, "WP_Seq": seq & 0xFF}
        for a, ax in enumerate("XYZ"):
            d["WP_V" + ax] = raw(fr, "WP_V" + ax, v[a])
        out.append((0x680 + obj, bytes(fr.encode(d)), False))
    dec = [Decimal("%.6f" % x) for x in (t, *p)]
    return out + [(i + obj, b, f) for i, b, f in ct.waypoint_frames(db, seq, *dec)]


def rows(path):
    with open(path) as fh:
        r = [x for x in csv.DictReader(fh) if x["state"] == "streaming"
             and not int(x["flags"]) & 0x08]  # not a transfer (ENGINE_SP_TRANSFER)
    return (np.array([float(x["t_s"]) for x in r]),
            np.array([[float(x[k]) for k in ("x_m", "y_m", "z_m")] for x in r]))


class CanVelocity(unittest.TestCase):
    def test_velocity_frames_shape_the_curve(self):
        db = ct.load_db()
        t, pos, vel = helix()
        qvel = np.round(vel * 100) / 100  # 1 cm/s per bit, as sent
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "wp.log"), "w") as fh:
                for i in range(N):
                    for obj, fd, v in ((0, False, vel[i]), (1, True, vel[i]), (2, False, None)):
                        for can_id, data, is_fd in frames(db, i + 1, t[i], pos[i], v, obj, fd):
                            fh.write("(%.6f) can0 %s\n" % (t[i], ct.fmt_frame(can_id, data, is_fd)))
                for obj in range(3):
                    fh.write("(%.6f) can0 %s\n" % (t[-1], ct.fmt_frame(
                        *ct.command_frame(db, 1, 0x680 + obj))))
            conf = os.path.join(d, "t.conf")
            with open(conf, "w") as fh:
                fh.write("[daemon]\nrate_hz = 50\nspeed = 20\nexit_when_done = yes\n"
                         "stop_timeout_s = 1\nstatus_interval_s = 0\n"
                         "[can]\nlog_in = wp.log\nlog_ifname = vcan0\nmax_late_ms = 0\nfd = yes\n"
                         + "".join("[object.o%d]\nid = %d\ninput = can\noutput = csv\n"
                                   "csv.path = o%d.csv\nmethod = hermite\nends = natural\n"
                                   "profile = none\n%s" % (k, k, k, "can.fd = yes\n" if k == 1 else "")
                                   for k in range(3)))
            p = subprocess.run([TRAJD, "-f", "-c", conf], cwd=d, capture_output=True, text=True,
                               timeout=60)
            self.assertEqual(p.returncode, 0, p.stderr[-2000:])
            given = CubicHermiteSpline(t, pos, qvel)
            est = {}
            for obj in range(3):
                ts, got = rows(os.path.join(d, "o%d.csv" % obj))
                self.assertGreater(len(ts), 1000, obj)
                err = np.abs(got - given(ts)).max()
                est[obj] = err
                if obj < 2:  # a CSV row has 9 significant digits or so: 1e-6 m is far above
                    self.assertLess(err, 1e-5, "object %d: %.2e m off the Hermite of its "
                                    "velocities" % (obj, err))
            print("off the Hermite of the given velocities, m: %s" % est)
            # without VELOCITY frames the curve is the estimated one: far from the given
            self.assertGreater(est[2], 1e3 * max(est[0], est[1], 1e-7))


if __name__ == "__main__":
    unittest.main(verbosity=2)
