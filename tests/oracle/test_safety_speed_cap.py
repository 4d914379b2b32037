#!/usr/bin/python3
"""test_safety_speed_cap.py - a configured safety_max_speed_m_s is kept by the engine, not
only judged by the monitor (engine.h cap_speed_m_s, daemon/core/cfg.h CFG_SAFETY_SPEED_SHARE).

trajd replays a circle of 20 m radius at 4 m/s (10 Hz, 40 s) for an object whose
safety_max_speed_m_s is 3: the time scaling plays the circle slower (the waypoints are
kept and passed exactly, their timing yields), so the monitor never holds it.  Wanted:
  - exit 0, no setpoint held by the monitor (ENGINE_SP_FAULT), the run reaches the last
    waypoint at rest;
  - every row-to-row speed (finite differences, as the monitor judges them) within the bound;
  - every streamed row on the curve through every waypoint: scipy's CubicSpline with zero
    end velocities (ends = rest) at the row's t_s, within 1e-4 m;
  - the output took longer than the track (4/3 of it at least, less the rest ends).
(tests/helpers/cap_circle.py has the common ones.)
Before, the engine planned the circle at 4 m/s and the monitor held the object on the first
row above 3 m/s (a step to rest), until clear: exit 75.
Run with Debian's /usr/bin/python3; BUILD is the build directory.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cap_circle  # noqa: E402
from cap_circle import check  # noqa: E402

BOUND = 3.0


def main():
    t, _, _ = cap_circle.circle()
    p, rows = cap_circle.run("safety_max_speed_m_s = %g\n" % BOUND)
    now, pos, st = cap_circle.check_common(p, rows)
    ok = np.isfinite(pos).all(axis=1)
    step = np.diff(now)
    fd = np.hypot(*np.diff(pos, axis=0).T) / np.where(step > 0, step, np.inf)
    fd = fd[ok[1:] & ok[:-1] & (np.abs(step - 0.01) < 1e-9)]
    check(fd.max() <= BOUND, "row-to-row speed at most %.4f m/s, bound %g" % (fd.max(), BOUND))
    moving = now[st]
    check(moving[-1] - moving[0] > (4.0 / BOUND) * 0.95 * (t[-1] - 2.0),
          "played in %.1f s, the track lasts %.1f s" % (moving[-1] - moving[0], t[-1]))


if __name__ == "__main__":
    main()
    sys.exit(1 if cap_circle.FAILED else 0)
