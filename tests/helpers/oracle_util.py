"""Pieces the oracle tests share: their checks (check, failures), the engine's segments
evaluated by Horner, and PROJ's east/north/up frame about a point (pyproj: cart +
topocentric), the independent reference for anything geographic."""
import numpy as np
import pyproj

# what check() found wrong: a test script exits 1 if it is not empty
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond:
        failures.append(what)



def evaluate(segs, tq, der=0):
    """The curve of segments (t0, dur, c[3][4]; k(u) = c0 + c1 u + c2 u^2 + c3 u^3) at times
    tq, by Horner; der 0/1/2 in seconds."""
    i = np.clip(np.searchsorted(segs[:, 0], tq, side="right") - 1, 0, len(segs) - 1)
    dur = segs[i, 1][:, None]
    u = ((tq - segs[i, 0]) / segs[i, 1])[:, None]
    c = segs[i, 2:].reshape(-1, 3, 4)
    if der == 0:
        return c[:, :, 0] + u * (c[:, :, 1] + u * (c[:, :, 2] + u * c[:, :, 3]))
    if der == 1:
        return (c[:, :, 1] + u * (2 * c[:, :, 2] + 3 * u * c[:, :, 3])) / dur
    return (2 * c[:, :, 2] + 6 * u * c[:, :, 3]) / dur ** 2


def proj_enu(lat0, lon0, h0):
    """lat, lon (deg), h (m) -> east, north, up (m) about (lat0, lon0, h0) on WGS84."""
    return pyproj.Transformer.from_pipeline(
        "+proj=pipeline +step +proj=axisswap +order=2,1 "
        "+step +proj=unitconvert +xy_in=deg +xy_out=rad "
        "+step +proj=cart +ellps=WGS84 "
        f"+step +proj=topocentric +ellps=WGS84 +lat_0={lat0!r} +lon_0={lon0!r} +h_0={h0!r}")
