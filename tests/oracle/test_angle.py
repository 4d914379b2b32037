"""test_angle.py - lib/util/angle (through build/libtrajd.so) against scipy.

The heading axis is interpolated by the monotone cubic Hermite that
scipy.interpolate.PchipInterpolator computes; unwrapping against numpy.unwrap
(period 360).  Random headings on random (non-uniform) times, with turns
across +-180 in both directions.
"""
import ctypes
import os
import random
import sys

import numpy as np
from scipy.interpolate import PchipInterpolator

lib = ctypes.CDLL(os.path.join(os.environ.get("BUILD", "build"), "libtrajd.so"))
D = ctypes.c_double
P = ctypes.POINTER(D)
lib.angle_pchip_eval.restype = D
lib.angle_pchip_eval.argtypes = [P, P, ctypes.c_size_t, D, ctypes.POINTER(ctypes.c_size_t)]
lib.angle_unwrap_deg.argtypes = [P, ctypes.c_size_t]
lib.angle_wrap_deg.restype = D
lib.angle_wrap_deg.argtypes = [D]
TOL = 1e-9  # degrees


def main():
    rnd = random.Random(20261125)
    worst = 0.0
    for case in range(40):
        n = rnd.randint(2, 40)
        t = np.cumsum([rnd.uniform(0.05, 2.0) for _ in range(n)])
        # a heading that turns by up to 60 degrees per sample, written wrapped
        u = np.cumsum([rnd.uniform(-60, 60) for _ in range(n)]) + rnd.uniform(-180, 180)
        wrapped = [lib.angle_wrap_deg(float(v)) for v in u]
        assert all(-180 < w <= 180 for w in wrapped)
        a = (D * n)(*wrapped)
        lib.angle_unwrap_deg(a, n)
        ref_unwrapped = np.unwrap(np.array(wrapped), period=360.0)
        assert np.allclose(list(a), ref_unwrapped, atol=1e-9), (list(a), ref_unwrapped)
        tt = (D * n)(*t)
        f = PchipInterpolator(t, ref_unwrapped)
        hint = ctypes.c_size_t(0)
        xs = np.linspace(t[0] - 1, t[-1] + 1, 400)
        for x in xs:
            got = lib.angle_pchip_eval(tt, a, n, float(x), ctypes.byref(hint))
            want = float(f(min(max(x, t[0]), t[-1])))
            worst = max(worst, abs(got - want))
            assert abs(got - want) < TOL, (case, x, got, want)
    # a turn across 180 never passes near 0 once wrapped
    t = (D * 4)(0, 1, 2, 3)
    a = (D * 4)(170, 179, -179, -170)
    lib.angle_unwrap_deg(a, 4)
    hint = ctypes.c_size_t(0)
    for x in np.linspace(0, 3, 301):
        w = lib.angle_wrap_deg(lib.angle_pchip_eval(t, a, 4, float(x), ctypes.byref(hint)))
        assert abs(w) >= 170 - 1e-9, (x, w)
    print("test_angle.py: 40 random headings, worst difference to scipy PchipInterpolator %.3g deg"
          % worst)
    return 0


if __name__ == "__main__":
    sys.exit(main())
