#!/usr/bin/python3
"""Per-axis limits kept along the path (issue 32 item 1).

The figure-8 x = 20 sin 0.2t, y = 10 sin 0.4t at 10 Hz for 60 s (up to 4 m/s per axis and
0.8, 1.6 m/s^2) with axis_max_speed_m_s = 3,3,3 and axis_max_accel_m_s2 = 0.6,1.2,1:

* every axis within 1 % of its limits, measured by finite differences of the streamed
  positions (not the velocities the engine reports), in trajreplay and in trajd;
* the path within 1 mm of the unlimited run's: each limited row against the unlimited run
  (1 kHz) at the same track time t_s, interpolated;
* slower than the unlimited run (the limits bind), and no underrun or hard stop;
* trajd with the same object: its safety monitor, which holds the per-axis limits on its
  own (lib/safety/safety.h, SAFETY_FAXIS), never trips, with a jerk limit too;
* a jerk limit on a C1 curve (method hermite) is refused by trajreplay and trajd;
* a transfer between two trajectories lasts long enough for every axis: the two pieces of
  a track 15 m apart on x, with a per-axis acceleration limit of 0.05 m/s^2 on x.

* against the time-optimal traversal of the same curve under the same limits (phase plane,
  tests/helpers/topp.py: an offline forward/backward pass, scipy's spline), within the
  issue's 1.25 times: the figure-8, and a rectangle 40 m x 20 m with 2 m corners at 4 m/s
  (3,3 m/s, 1,1 m/s^2), where braking into each corner with a third of the limit took 1.42
  times; the rectangle's peaks within 1 % of the limits too, on the cubic spline and on the
  local C1 Hermite curve, whose acceleration steps at every knot (1.018 m/s^2 on a 1 m/s^2
  axis where a segment's time scaling did not also keep to the next one's room,
  engine_solve.c queue_segment);
* with max_lag_s = 5 the object stops on its path once its lag from the limits passes 5 s:
  in trajreplay the output comes to rest short of the track's end, still on the path, and
  trajreplay exits 8 naming the file line of the first waypoint it stopped short of; in
  trajd the lifecycle logs "lag beyond max_lag_s" and the object is stopped, latched (its
  output holds at rest until the run ends), and trajd exits 75 (the object ended held);
* a track over 100 times faster on an axis than its limit (axis_beyond): the output never
  enters the segment, trajreplay exits 8 naming the segment's end in the file.

tests/bench/bench_axis.py prints the same lengths and peaks.
"""
import csv
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from oracle_util import check, failures  # noqa: E402
from topp import optimal_s, rectangle  # noqa: E402

BUILD = os.environ.get("BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
TRAJREPLAY = os.path.join(BUILD, "bin", "trajreplay")
TRAJD = os.path.join(BUILD, "bin", "trajd")
VLIM = (3.0, 3.0, 3.0)
ALIM = (0.6, 1.2, 1.0)
# Finite differences of 100 Hz positions against the analytic peaks: the engine's own
# margin is below 0.1 % (measured); 1 % is the issue's.
TOL = 1.01


# the goal against the time-optimal traversal
GOAL = 1.25
# per-axis jerk limits, and how much longer than the speed and acceleration limits'
# time-optimal traversal a run with them may take (the figure-8 at 2 m/s^3: 1.37 times on the
# cubic spline, 2.23 on the local C2 Hermite, whose curve's own jerk is larger; 22 when it
# crawled)
JLIM = (2.0, 2.0, 2.0)
JERK_GOAL = 2.5


def write(path, t, x, y):
    with open(path, "w") as f:
        f.write("t,x,y,z\n")
        for a, b, c in zip(t, x, y):
            f.write("%r,%r,%r,0\n" % (a, b, c))


def figure8(path):
    t = np.arange(0, 60.0001, 0.1)
    write(path, t, 20 * np.sin(0.2 * t), 10 * np.sin(0.4 * t))


def rows(path):
    with open(path) as f:
        r = [x for x in csv.DictReader(f) if x["state"] in ("streaming", "finished")]
    now = np.array([int(x["now_ns"]) * 1e-9 for x in r])
    t = np.array([float(x["t_s"]) for x in r])
    p = np.array([[float(x[k]) for k in ("x_m", "y_m", "z_m")] for x in r])
    flags = np.array([int(x["flags"]) for x in r])
    return now, t, p, flags


def peaks(now, p):
    dt = np.diff(now)
    v = np.diff(p, axis=0) / dt[:, None]
    a = np.diff(v, axis=0) / (0.5 * (dt[1:] + dt[:-1]))[:, None]
    return np.abs(v).max(axis=0), np.abs(a).max(axis=0)


def jerks(now, p):
    """Peak |jerk| per axis: third finite differences of the positions, over the runs of
    four rows a period apart (trajd does not write the rows of ticks it missed at a speed
    above 1, and across such a gap the differences are no jerk)."""
    dt = np.diff(now)
    per = np.median(dt)
    j = (p[3:] - 3 * p[2:-1] + 3 * p[1:-2] - p[:-3]) / per ** 3
    even = np.all(np.abs(np.stack([dt[:-2], dt[1:-1], dt[2:]]) - per) <= 1e-6 * per, axis=0)
    return np.abs(j[even]).max(axis=0)


def replay(src, out, *opts, code=0, err=None):
    """The --summary counters of a run, which must exit with code; err: a list given
    the stderr lines that are not summary lines."""
    p = subprocess.run([TRAJREPLAY, "-q", "--summary", "--profile", "machine", "-o", out]
                       + list(opts) + [src], capture_output=True, text=True, timeout=300)
    assert p.returncode == code, (p.returncode, p.stderr)
    if err is not None:
        err += [l for l in p.stderr.splitlines() if not l.startswith("summary: ")]
    return {l.split()[1]: l.split()[2] for l in p.stderr.splitlines()
            if l.startswith("summary: ")}


def stop_line(err, src):
    """From trajreplay's 'src:LINE: error: the output stopped on its path at t = T s'
    line: (LINE, T), or None."""
    for l in err:
        m = re.match(re.escape(src) + r":(\d+): error: the output stopped on its path at "
                     r"t = ([-\d.]+) s", l)
        if m:
            return int(m.group(1)), float(m.group(2))
    return None


def first_line_after(src, t):
    """The file line (1-based, the header is line 1) of the first waypoint after t."""
    with open(src) as f:
        for n, l in enumerate(f, 1):
            if n > 1 and float(l.split(",")[0]) > t:
                return n
    return None


def main():
    lim = ["--axis-max-speed", "3,3,3", "--axis-max-accel", "0.6,1.2,1"]
    with tempfile.TemporaryDirectory() as d:
        src = os.path.join(d, "f8.csv")
        figure8(src)
        s = replay(src, os.path.join(d, "lim.csv"), "--rate", "100", *lim)
        replay(src, os.path.join(d, "free.csv"), "--rate", "1000")
        now, t, p, flags = rows(os.path.join(d, "lim.csv"))
        fnow, ft, fp, fflags = rows(os.path.join(d, "free.csv"))
        v, a = peaks(now, p)
        for k, ax in enumerate("xy"):
            check(v[k] <= TOL * VLIM[k], "trajreplay: peak |v%s| %.4f m/s, limit %g" % (
                ax, v[k], VLIM[k]))
            check(a[k] <= TOL * ALIM[k], "trajreplay: peak |a%s| %.4f m/s^2, limit %g" % (
                ax, a[k], ALIM[k]))
        on = (flags & 0x08) == 0  # not ENGINE_SP_TRANSFER
        m = on & (t >= ft[0]) & (t <= ft[-1])
        ref = np.stack([np.interp(t[m], ft, fp[:, k]) for k in range(3)], axis=1)
        dev = np.abs(p[m] - ref).max()
        check(m.sum() > 5000 and dev <= 1e-3, "path within 1 mm of the unlimited run at the "
              "same track time: %.2e m over %d rows" % (dev, m.sum()))
        check(now[-1] - now[0] > 1.2 * (fnow[-1] - fnow[0]),
              "slower than unlimited: %.1f s against %.1f s" % (now[-1] - now[0],
                                                                fnow[-1] - fnow[0]))
        check(s.get("underruns") == "0" and s.get("hard_stops") == "0",
              "no underrun, no hard stop (%s, %s)" % (s.get("underruns"), s.get("hard_stops")))
        t8 = np.arange(0, 60.0001, 0.1)
        opt = optimal_s(t8, 20 * np.sin(0.2 * t8), 10 * np.sin(0.4 * t8), VLIM[:2], ALIM[:2])
        run = now[on][-1] - now[on][0]
        check(run <= GOAL * opt, "figure-8: %.1f s against the time-optimal %.1f s (%.2f, goal "
              "%.2f)" % (run, opt, run / opt, GOAL))
        lost = float(s.get("axis_lost_s", "nan"))
        check(lost > 0.5 * ((now[-1] - now[0]) - (fnow[-1] - fnow[0])),
              "the time lost to the per-axis limits reported: axis_lost_s %.1f s" % lost)

        # per-axis jerk limits (2 m/s^3) too: every axis within them by third finite
        # differences, and no crawl: the speed and acceleration limits' time-optimal
        # traversal, which the jerk limit can only lengthen, at most JERK_GOAL times over.
        # On the local C2 Hermite curve (three pieces per interval, whose limits alternate)
        # the reserve for the rises of every limit to the queue's end was held against the
        # next capped piece: the output crawled at rate 0.02 (1714 s against 110 s)
        for method in ("cubic", "hermite-c2"):
            sj = replay(src, os.path.join(d, "jerk.csv"), "--rate", "100", "--method", method,
                        *lim, "--axis-max-jerk", "%g,%g,%g" % JLIM)
            jnow, _, jp, jfl = rows(os.path.join(d, "jerk.csv"))
            jv, ja = peaks(jnow, jp)
            jj = jerks(jnow, jp)
            check(all(jv[k] <= TOL * VLIM[k] and ja[k] <= TOL * ALIM[k] and
                      jj[k] <= TOL * JLIM[k] for k in range(2)) and
                  sj.get("hard_stops") == "0",
                  "figure-8, %s, jerk limit %g: peaks |v| %s, |a| %s, |j| %s" % (
                      method, JLIM[0], np.round(jv[:2], 4), np.round(ja[:2], 4),
                      np.round(jj[:2], 4)))
            jon = (jfl & 0x08) == 0
            jrun = jnow[jon][-1] - jnow[jon][0]
            check(jrun <= JERK_GOAL * opt, "figure-8, %s, jerk limit %g: %.1f s against the "
                  "time-optimal %.1f s without it (%.2f, at most %g)" % (
                      method, JLIM[0], jrun, opt, jrun / opt, JERK_GOAL))

        # on a C1 curve (method hermite: its acceleration steps at every waypoint) no time
        # scaling holds a jerk limit, and the safety monitor, which holds it, would trip at
        # every waypoint: trajreplay (exit 2) and trajd --check-config (exit 78, EX_CONFIG)
        # refuse it with the reason; a C2 curve is accepted
        for method, refused in (("hermite", True), ("cubic", False)):
            errj = []
            replay(src, os.path.join(d, "c1.csv"), "--rate", "100", "--method", method,
                   *lim, "--axis-max-jerk", "2,2,2", err=errj, code=2 if refused else 0)
            conf = os.path.join(d, "c1.conf")
            with open(conf, "w") as f:
                f.write("[daemon]\nrate_hz = 100\n[object.a]\ninput = replay\n"
                        "replay.track = %s\noutput = csv\ncsv.path = %s\nmethod = %s\n"
                        "axis_max_jerk_m_s3 = 2,2,2\n" % (src, os.path.join(d, "c1d.csv"), method))
            pc = subprocess.run([TRAJD, "--check-config", conf], capture_output=True, text=True,
                                timeout=60)
            said = [l for l in errj + pc.stderr.splitlines()
                    if "cannot be held on a C1 curve" in l]
            check(pc.returncode == (78 if refused else 0) and len(said) == (2 if refused else 0),
                  "method %s with axis_max_jerk_m_s3: %s (trajd --check-config exit %d)" % (
                      method, said if said else "accepted", pc.returncode))

        # the rectangle: its corners braked into with what the straights leave of the limits
        rt, rx, ry = rectangle()
        rsrc = os.path.join(d, "rect.csv")
        write(rsrc, rt, rx, ry)
        ropt = optimal_s(rt, rx, ry, (3.0, 3.0), (1.0, 1.0))
        for method in ("cubic", "hermite"):
            rs = replay(rsrc, os.path.join(d, "rect_out.csv"), "--rate", "100", "--method", method,
                        "--axis-max-speed", "3,3,0", "--axis-max-accel", "1,1,0")
            rnow, _, rp, rfl = rows(os.path.join(d, "rect_out.csv"))
            rv, ra = peaks(rnow, rp)
            check(all(rv[k] <= TOL * 3.0 and ra[k] <= TOL * 1.0 for k in range(2)) and
                  rs.get("hard_stops") == "0",
                  "rectangle, %s: peaks |v| %s of 3, |a| %s of 1 m/s^2" % (
                      method, np.round(rv[:2], 4), np.round(ra[:2], 4)))
            if method == "cubic":  # the curve the optimum is worked out on
                ron = (rfl & 0x08) == 0
                run = rnow[ron][-1] - rnow[ron][0]
                check(run <= GOAL * ropt, "rectangle: %.1f s against the time-optimal %.1f s "
                      "(%.2f, goal %.2f)" % (run, ropt, run / ropt, GOAL))

        # trajd with the same object: the monitor holds the limits too, and never trips
        conf = os.path.join(d, "t.conf")
        with open(conf, "w") as f:
            f.write("[daemon]\nrate_hz = 100\nspeed = 20\nexit_when_done = yes\n"
                    "status_interval_s = 0\nstop_timeout_s = 1\n"
                    "[object.f8]\ninput = replay\nreplay.track = %s\noutput = csv\n"
                    "csv.path = %s\nprofile = machine\naxis_max_speed_m_s = 3,3,3\n"
                    "axis_max_accel_m_s2 = 0.6,1.2,1\n" % (src, os.path.join(d, "trajd.csv")))
        p2 = subprocess.run([TRAJD, "-f", "-c", conf], cwd=d, capture_output=True, text=True,
                            timeout=120)
        now2, _, pos2, flags2 = rows(os.path.join(d, "trajd.csv"))
        v2, a2 = peaks(now2, pos2)
        check(p2.returncode == 0 and not (flags2 & 0x20).any(),  # ENGINE_SP_FAULT
              "trajd: exit %d, no setpoint held by the safety monitor" % p2.returncode)
        check(all(v2[k] <= TOL * VLIM[k] and a2[k] <= TOL * ALIM[k] for k in range(2)),
              "trajd: peaks |v| %s, |a| %s within the limits" % (np.round(v2[:2], 4),
                                                                   np.round(a2[:2], 4)))
        # and with a jerk limit, which the monitor holds as well (third differences,
        # SAFETY_AXIS_MARGIN above): never tripped on the C2 curve
        confj = os.path.join(d, "tj.conf")
        with open(confj, "w") as f:
            f.write(open(conf).read().replace("trajd.csv", "trajdj.csv") +
                    "axis_max_jerk_m_s3 = %g,%g,%g\n" % JLIM)
        pj = subprocess.run([TRAJD, "-f", "-c", confj], cwd=d, capture_output=True, text=True,
                            timeout=120)
        nowj, _, posj, flagsj = rows(os.path.join(d, "trajdj.csv"))
        jvj, jaj = peaks(nowj, posj)
        jjj = jerks(nowj, posj)
        check(pj.returncode == 0 and not (flagsj & 0x20).any() and
              all(jvj[k] <= TOL * VLIM[k] and jaj[k] <= TOL * ALIM[k] and
                  jjj[k] <= TOL * JLIM[k] for k in range(2)),
              "trajd with axis_max_jerk_m_s3 = %g: exit %d, no setpoint held by the safety "
              "monitor, peaks |v| %s, |a| %s, |j| %s" % (
                  JLIM[0], pj.returncode, np.round(jvj[:2], 4), np.round(jaj[:2], 4),
                  np.round(jjj[:2], 4)))

        # max_lag_s: the object stops on its path; trajreplay exits 8 and names the
        # first waypoint of the file it stopped short of
        err5 = []
        s5 = replay(src, os.path.join(d, "lag.csv"), "--rate", "100", "--max-lag", "5", *lim,
                    code=8, err=err5)
        now5, t5, p5, fl5 = rows(os.path.join(d, "lag.csv"))
        # the trajectory it stopped in (trajreplay has no lifecycle to buffer what comes
        # after: the rest of the track starts trajectories of its own)
        first = np.cumsum((fl5 & 0x02) != 0) <= 1  # up to the second ENGINE_SP_NEW_TRACK
        stop_t = t5[first][-1]
        t5, p5, fl5 = t5[first], p5[first], fl5[first]
        m5 = ((fl5 & 0x08) == 0) & (t5 >= ft[0]) & (t5 <= ft[-1])
        ref5 = np.stack([np.interp(t5[m5], ft, fp[:, k]) for k in range(3)], axis=1)
        check(int(s5.get("axis_lag_stops", "0")) >= 1 and stop_t < 59.0 and
              np.abs(p5[m5] - ref5).max() <= 1e-3,
              "trajreplay --max-lag 5: %s stop(s), at rest at t_s %.1f of 60 s, on the path "
              "(%.1e m)" % (s5.get("axis_lag_stops"), stop_t, np.abs(p5[m5] - ref5).max()))
        where = stop_line(err5, src)
        check(where is not None and where[1] <= stop_t and
              where[0] == first_line_after(src, where[1]),
              "trajreplay --max-lag 5: exit 8, stopped at t = %s s (at rest at %.1f s), short of "
              "the file's line %s (the first waypoint after it: %s)" % (
                  where and where[1], stop_t, where and where[0],
                  where and first_line_after(src, where[1])))
        conf5 = os.path.join(d, "t5.conf")
        with open(conf5, "w") as f:
            f.write(open(conf).read().replace("trajd.csv", "trajd5.csv") + "max_lag_s = 5\n")
        p6 = subprocess.run([TRAJD, "-f", "-c", conf5], cwd=d, capture_output=True, text=True,
                            timeout=120)
        with open(os.path.join(d, "trajd5.csv")) as f:
            last = list(csv.DictReader(f))[-1]
        check("'lag beyond max_lag_s'" in p6.stderr and float(last["t_s"]) < 59.0 and
              float(last["vx_m_s"]) == 0.0 and float(last["vy_m_s"]) == 0.0,
              "trajd max_lag_s = 5: the lifecycle's lag event logged, the object at rest at "
              "t_s %s (exit %d)" % (last["t_s"], p6.returncode))
        check(p6.returncode == 75 and "object 'f8' ended held: stopped on its path by the "
              "per-axis limits" in p6.stderr,
              "trajd max_lag_s = 5: exit 75 (EX_TEMPFAIL, the object ended held), got %d" %
              p6.returncode)

        # a track over 100 times faster on x than its limit from the first segment
        # (2 m/s against 0.01): the output never enters it, trajreplay exits 8 naming
        # the end of that segment, the file's second waypoint (line 3)
        fast = os.path.join(d, "fast.csv")
        with open(fast, "w") as f:
            f.write("t,x,y,z\n" + "".join("%d,%d,0,0\n" % (i, 2 * i) for i in range(41)))
        errb = []
        sb = replay(fast, os.path.join(d, "fast_out.csv"), "--rate", "10", "--axis-max-speed",
                    "0.01,0,0", code=8, err=errb)
        _, _, pb, flb = rows(os.path.join(d, "fast_out.csv"))
        pb = pb[np.cumsum((flb & 0x02) != 0) <= 1]  # its first trajectory, as above
        where = stop_line(errb, fast)
        check(int(sb.get("axis_beyond", "0")) >= 1 and where == (3, 0.0) and len(pb) and
              np.abs(pb[:, 0]).max() == 0.0,
              "trajreplay --axis-max-speed 0.01: exit 8, axis_beyond %s, stopped at %s "
              "(line 3, t = 0 s), x never left 0 in its trajectory (max |x| %g)" % (
                  sb.get("axis_beyond"), where, np.abs(pb[:, 0]).max() if len(pb) else -1))

        # a transfer: two pieces 15 m apart on x after a gap
        tr = os.path.join(d, "gap.csv")
        with open(tr, "w") as f:
            f.write("t,x,y,z\n")
            for i in range(50):
                f.write("%r,0,%r,0\n" % (0.1 * i, 0.01 * i))
            for i in range(50):
                f.write("%r,15,%r,0\n" % (200 + 0.1 * i, 0.01 * i))
        # the transfer's own limits would take it in 3 s (peak 10 m/s^2); the axis's in 42 s
        replay(tr, os.path.join(d, "gap_out.csv"), "--rate", "100", "--axis-max-accel",
               "0.05,0,0", "--transfer-speed", "10", "--transfer-accel", "10")
        replay(tr, os.path.join(d, "gap_free.csv"), "--rate", "100", "--transfer-speed", "10",
               "--transfer-accel", "10")
        pk = []
        for name in ("gap_out.csv", "gap_free.csv"):
            now3, _, p3, fl3 = rows(os.path.join(d, name))
            x = (fl3 & 0x08) != 0  # the transfer's rows (ENGINE_SP_TRANSFER)
            pk.append((peaks(now3[x], p3[x])[1][0], x.sum()))
        check(pk[0][1] > 100 and pk[0][0] <= TOL * 0.05 and pk[1][0] > 2 * 0.05,
              "transfer of 15 m on x: peak |ax| %.4f m/s^2 within 0.05 (%d rows; %.3f without "
              "the axis limit)" % (pk[0][0], pk[0][1], pk[1][0]))
    print("%d failure(s)" % len(failures))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
