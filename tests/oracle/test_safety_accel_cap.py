#!/usr/bin/python3
"""test_safety_accel_cap.py - a configured safety_max_accel_m_s2 is kept by the engine, not
only judged by the monitor (engine.h cap_accel_m_s2, daemon/core/cfg.h CFG_SAFETY_SPEED_SHARE).

trajd replays a circle of 20 m radius at 4 m/s (10 Hz, 40 s; 0.8 m/s^2 towards the centre),
reached by a transfer of 8 m from its initial position, for an object whose
safety_max_accel_m_s2 is 1.5: below the time scaling's own 5 m/s^2 and the acceleration
the rest ends of the curve ask.  The engine keeps the bound along the path (the start and
the end ramp, the curve's own acceleration, the transfer), so the monitor never holds it.
Wanted (tests/helpers/cap_circle.py has the common ones):
  - exit 0, no setpoint held by the monitor (ENGINE_SP_FAULT), the run reaches the last
    waypoint at rest, by a transfer first;
  - every row-to-row acceleration (second differences of the positions, as the monitor
    judges them) within the bound;
  - every streamed row on the curve through every waypoint: scipy's CubicSpline with zero
    end velocities (ends = rest) at the row's t_s, within 1e-4 m.
Before, the engine planned the start's ramp at 5 m/s^2 and the monitor held the object on
its first row above 1.5 m/s^2 (a step to rest), until clear: exit 75.
Run with Debian's /usr/bin/python3; BUILD is the build directory.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cap_circle  # noqa: E402
from cap_circle import check  # noqa: E402

BOUND = 1.5


def main():
    p, rows = cap_circle.run("safety_max_accel_m_s2 = %g\ninitial_position = 28,0,0\n" % BOUND)
    now, pos, st = cap_circle.check_common(p, rows)
    flags = np.array([int(r["flags"]) for r in rows])
    check(((flags & 0x08) != 0).any(), "the track is reached by a transfer")
    ok = np.isfinite(pos).all(axis=1)
    step = np.diff(now)
    regular = ok[2:] & ok[1:-1] & ok[:-2] & (np.abs(step[1:] - 0.01) < 1e-9) \
        & (np.abs(step[:-1] - 0.01) < 1e-9)
    acc = np.hypot(*(pos[2:] - 2 * pos[1:-1] + pos[:-2]).T) / 0.01 ** 2
    acc = acc[regular]
    check(acc.max() <= BOUND, "row-to-row acceleration at most %.4f m/s^2, bound %g"
          % (acc.max(), BOUND))


if __name__ == "__main__":
    main()
    sys.exit(1 if cap_circle.FAILED else 0)
