"""test_geo.py - lib/util/geo (through build/libtrajd.so) against pyproj (PROJ 9).

PROJ's pipeline cart + topocentric is an independent implementation of the
same WGS84 geodetic -> ECEF -> ENU route.  Points: random within 200 km of
several origins (polar, equatorial, both hemispheres, the date line, the
real tracks' first points), heights from -500 m to 9 km.
"""
import ctypes
import math
import os
import random
import sys

import pyproj

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
from oracle_util import proj_enu  # noqa: E402

# Both sides compute exact formulas in double precision on ~6.4e6 m ECEF
# values (ulp ~1e-9 m); PROJ's topocentric step differs only in operation
# order.  1e-6 m leaves a factor 1000 above rounding and 1000 below the
# millimetre the loader promises.
TOL_M = 1e-6

lib = ctypes.CDLL(os.path.join(os.environ.get("BUILD", "build"), "libtrajd.so"))
Frame = ctypes.c_double * 10          # geo_enu_t: 10 doubles
Vec3 = ctypes.c_double * 3
lib.geo_enu_init.argtypes = [ctypes.c_double] * 3 + [ctypes.POINTER(Frame)]
lib.geo_to_enu.argtypes = [ctypes.POINTER(Frame)] + [ctypes.c_double] * 3 + [ctypes.POINTER(Vec3)]
lib.geo_to_ecef.argtypes = [ctypes.c_double] * 3 + [ctypes.POINTER(Vec3)]
D = ctypes.c_double
lib.geo_from_enu.argtypes = [ctypes.POINTER(Frame), ctypes.POINTER(Vec3)] + [ctypes.POINTER(D)] * 3
lib.geo_from_ecef.argtypes = [ctypes.POINTER(Vec3)] + [ctypes.POINTER(D)] * 3
# The inverse (ENU/ECEF -> geodetic): 1e-9 degree is 0.1 mm on the ground.
TOL_DEG = 1e-9


def main():
    rnd = random.Random(20260521)
    origins = [(45.273245, 13.715185, 271.0), (45.772175035, 14.357659249, 542.320923),
               (34.4059417, 133.5412196, 0.0), (0.0, 0.0, 0.0), (-33.9, 18.4, 12.0),
               (89.9, 45.0, 2800.0), (-77.85, 166.67, 10.0), (10.0, 179.99, 5.0)]
    ecef = pyproj.Transformer.from_crs("EPSG:4979", "EPSG:4978", always_xy=True)
    worst = 0.0
    count = 0
    inv_count = [0]
    for lat0, lon0, h0 in origins:
        # Given an origin, when random nearby points are converted by both,
        # then east/north/up agree to TOL_M.
        frame = Frame()
        assert lib.geo_enu_init(lat0, lon0, h0, ctypes.byref(frame)) == 0
        tr = proj_enu(lat0, lon0, h0)
        for _ in range(300):
            lat = max(-90.0, min(90.0, lat0 + rnd.uniform(-1.8, 1.8)))
            lon = lon0 + rnd.uniform(-1.8, 1.8)
            h = rnd.uniform(-500.0, 9000.0)
            out = Vec3()
            assert lib.geo_to_enu(ctypes.byref(frame), lat, lon, h, ctypes.byref(out)) == 0
            e, n, u = tr.transform(lat, lon, h)
            err = max(abs(out[0] - e), abs(out[1] - n), abs(out[2] - u))
            worst = max(worst, err)
            count += 1
            assert err < TOL_M, (lat0, lon0, lat, lon, h, tuple(out), (e, n, u))
            # and back: pyproj's inverse of its own east/north/up against geo_from_enu
            la, lo, hh = D(), D(), D()
            assert lib.geo_from_enu(ctypes.byref(frame), ctypes.byref(Vec3(e, n, u)), ctypes.byref(la),
                                    ctypes.byref(lo), ctypes.byref(hh)) == 0
            rlat, rlon, rh = tr.transform(e, n, u, direction="INVERSE")
            # longitude as a distance on the ground (meaningless at a pole)
            dlon = ((lo.value - rlon + 180.0) % 360.0 - 180.0) * math.cos(math.radians(rlat))
            assert abs(la.value - rlat) < TOL_DEG and abs(dlon) < TOL_DEG and abs(hh.value - rh) < TOL_M, \
                (lat0, lon0, (e, n, u), (la.value, lo.value, hh.value), (rlat, rlon, rh))
            inv_count[0] += 1
        # And ECEF itself against EPSG:4979 -> EPSG:4978.
        for _ in range(50):
            lat, lon, h = rnd.uniform(-90, 90), rnd.uniform(-180, 180), rnd.uniform(-500, 9000)
            out = Vec3()
            assert lib.geo_to_ecef(lat, lon, h, ctypes.byref(out)) == 0
            x, y, z = ecef.transform(lon, lat, h)
            err = max(abs(out[0] - x), abs(out[1] - y), abs(out[2] - z))
            worst = max(worst, err)
            assert err < TOL_M, (lat, lon, h, tuple(out), (x, y, z))
            la, lo, hh = D(), D(), D()
            assert lib.geo_from_ecef(ctypes.byref(Vec3(x, y, z)), ctypes.byref(la), ctypes.byref(lo),
                                     ctypes.byref(hh)) == 0
            rlon, rlat, rh = ecef.transform(x, y, z, direction="INVERSE")
            assert abs(la.value - rlat) < TOL_DEG and abs(lo.value - rlon) < TOL_DEG and \
                abs(hh.value - rh) < TOL_M, ((x, y, z), (la.value, lo.value, hh.value), (rlat, rlon, rh))
    # Given bad input, then a negative error and no exception.
    out = Vec3()
    assert lib.geo_to_ecef(float("nan"), 0.0, 0.0, ctypes.byref(out)) < 0
    assert lib.geo_to_ecef(91.0, 0.0, 0.0, ctypes.byref(out)) < 0
    print(f"test_geo.py: {count} ENU points + ECEF points, worst difference to pyproj {worst:.3g} m; "
          f"{inv_count[0]} ENU -> lat/lon/alt inverses within {TOL_DEG:g} deg, {TOL_M:g} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
