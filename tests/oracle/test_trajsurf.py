#!/usr/bin/python3
"""trajsurf end to end: grid CSV in, sampled surface CSV and SVG out.

The samples are checked against scipy: the interpolating bicubic B-spline
with natural borders is the tensor product of natural cubic splines on
uniform knots (CubicSpline(bc_type='natural') along rows, then columns).
"""
import errno
import os
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

import numpy as np
from scipy.interpolate import CubicSpline

BUILD = os.environ.get("BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
TRAJSURF = os.path.join(BUILD, "bin", "trajsurf")
# Samples by forward differences over <= 8 steps per cell, values O(10):
# rounding ~1e-14; the reference is another O(n) spline solver.
TOL = 1e-10


def run(*args):
    return subprocess.run([TRAJSURF, *args], capture_output=True, text=True, timeout=60)


def reference(g, steps):
    """Natural tensor spline of grid g (M x N x 3) sampled like trajsurf."""
    M, N, _ = g.shape
    u = np.arange((M - 1) * steps + 1) / steps
    v = np.arange((N - 1) * steps + 1) / steps
    along_u = CubicSpline(np.arange(M), g, axis=0, bc_type="natural")(u)     # U x N x 3
    return CubicSpline(np.arange(N), along_u, axis=1, bc_type="natural")(v)  # U x V x 3


class TestTrajsurf(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.d = self.dir.name

    def tearDown(self):
        self.dir.cleanup()

    def test_indexed_grid_matches_scipy_and_svg(self):
        # Given an i,j,x,y,z grid (rows shuffled) of a warped 7 x 5 sheet,
        # when trajsurf samples it with 6 steps per cell, then every sample
        # equals scipy's natural tensor spline, grid points are reproduced
        # exactly, and the SVG is well-formed with one polygon per cell.
        rng = np.random.default_rng(1)
        M, N, steps = 7, 5, 6
        g = np.zeros((M, N, 3))
        for i in range(M):
            for j in range(N):
                x, y = i * 1.5 + 0.2 * j, j * 1.1 - 0.1 * i
                g[i, j] = (x, y, np.sin(x) * np.cos(0.5 * y) + rng.normal(0, 0.1))
        rows = [(i, j, *g[i, j]) for i in range(M) for j in range(N)]
        rng.shuffle(rows)
        src = os.path.join(self.d, "grid.csv")
        with open(src, "w") as f:
            f.write("i,j,x,y,z\n")
            for r in rows:
                f.write("%d,%d,%.17g,%.17g,%.17g\n" % r)
        out, svg = os.path.join(self.d, "s.csv"), os.path.join(self.d, "s.svg")
        r = run("-n", str(steps), "-o", out, "-s", svg, src)
        self.assertEqual(r.returncode, 0, r.stderr)
        data = np.loadtxt(out, delimiter=",", skiprows=1)
        U, V = (M - 1) * steps + 1, (N - 1) * steps + 1
        self.assertEqual(data.shape, (U * V, 5))
        xyz = data[:, 2:].reshape(U, V, 3)
        np.testing.assert_allclose(xyz, reference(g, steps), atol=TOL, rtol=0)
        np.testing.assert_array_equal(xyz[::steps, ::steps], g)
        np.testing.assert_allclose(data[:, 0].reshape(U, V)[:, 0], np.arange(U) / steps)
        root = ET.parse(svg).getroot()
        ns = "{http://www.w3.org/2000/svg}"
        self.assertEqual(len(root.findall(f".//{ns}polygon")), (U - 1) * (V - 1))
        self.assertEqual(len(root.findall(f".//{ns}circle")), M * N)

    def test_height_matrix(self):
        # Given a plain matrix of heights with -x/-y spacings, then x, y are
        # column*dx, row*dy at the grid points and the heights interpolate.
        z = np.array([[0, 1, 0, 2], [1, 3, 1, 0], [0, 1, 4, 1]], float)
        src = os.path.join(self.d, "h.csv")
        np.savetxt(src, z, delimiter=",")
        r = run("-n", "2", "-x", "0.5", "-y", "2", src)
        self.assertEqual(r.returncode, 0, r.stderr)
        data = np.loadtxt(r.stdout.splitlines(), delimiter=",", skiprows=1)
        xyz = data[:, 2:].reshape(5, 7, 3)
        g = np.dstack([np.tile(np.arange(4) * 0.5, (3, 1)), np.tile(np.arange(3)[:, None] * 2.0, (1, 4)), z])
        np.testing.assert_allclose(xyz, reference(g, 2), atol=TOL, rtol=0)

    def test_long_rows(self):
        # Given a height matrix of 4000 columns written by repr (a row is
        # about 76 kB, longer than the 64 KiB the reader once took in one
        # piece: it read the tail as a row of its own and refused the file),
        # then every row is read whole: with -n 1 the output is the grid,
        # x = column, y = row, z = the heights, bit for bit.
        rng = np.random.default_rng(11)
        z = rng.uniform(-1000, 1000, (2, 4000))
        src = os.path.join(self.d, "wide.csv")
        with open(src, "w") as f:
            for row in z:
                f.write(",".join(repr(float(v)) for v in row) + "\n")
        self.assertGreater(os.path.getsize(src), 2 * 65536)
        r = run("-n", "1", src)
        self.assertEqual(r.returncode, 0, r.stderr[-300:])
        data = np.loadtxt(r.stdout.splitlines(), delimiter=",", skiprows=1)
        xyz = data[:, 2:].reshape(2, 4000, 3)
        np.testing.assert_array_equal(xyz[:, :, 2], z)
        np.testing.assert_array_equal(xyz[:, :, 0], np.tile(np.arange(4000.0), (2, 1)))

    def test_bad_input(self):
        # Given ragged, non-numeric or incomplete grids, then exit 1 with a
        # message naming the file (and line); bad options exit 2.
        cases = {"ragged.csv": "1,2,3\n4,5\n", "text.csv": "1,2\nx,y\n",
                 "hole.csv": "i,j,x,y,z\n0,0,0,0,0\n1,1,1,1,1\n0,1,0,1,0\n",
                 "tiny.csv": "1,2,3\n", "nul.csv": "1,2\n3,4\n5\x00,6\n"}
        for name, text in cases.items():
            p = os.path.join(self.d, name)
            with open(p, "w") as f:
                f.write(text)
            r = run(p)
            self.assertEqual(r.returncode, 1, name)
            self.assertIn(name, r.stderr)
        self.assertIn("nul.csv:3: NUL byte", run(os.path.join(self.d, "nul.csv")).stderr)
        self.assertEqual(run("-n", "0", "x").returncode, 2)
        self.assertEqual(run().returncode, 2)
        # the file's line of the point at fault, and what is wrong with it (it said
        # "row 4" for line 5, and "expected i,j,x,y,z" of a NaN height)
        for name, text, want in (
                ("frac.csv", "i,j,x,y,z\n0,0,0,0,0\n0,1,0,1,0\n1,0,1,0,0\n1.7,1,1,1,1\n",
                 "frac.csv:5: bad grid index (1.7, 1)"),
                ("twice.csv", "i,j,x,y,z\n0,0,0,0,0\n0,1,0,1,0\n\n1,0,1,0,0\n0,1,0,1,0\n",
                 "twice.csv:6: grid point (0, 1) given twice"),
                ("nan.csv", "i,j,x,y,z\n0,0,0,0,0\n0,1,0,1,nan\n",
                 "nan.csv:3: expected i,j,x,y,z, five finite numbers"),
                ("spaces.csv", "1 2 3\n4 5 6\n",
                 "spaces.csv:1: expected finite numbers separated by commas")):
            p = os.path.join(self.d, name)
            with open(p, "w") as f:
                f.write(text)
            r = run(p)
            self.assertEqual(r.returncode, 1, name)
            self.assertIn(want, r.stderr)
        # a spacing of 0 (or below) collapses the grid: a bad option
        m = os.path.join(self.d, "m.csv")
        with open(m, "w") as f:
            f.write("1,2\n3,4\n")
        for opt in ("-x", "-y"):
            self.assertEqual(run(opt, "0", m).returncode, 2, opt)
            self.assertEqual(run(opt, "-1", m).returncode, 2, opt)

    def test_output_failure(self):
        # Given a full disk (/dev/full) for the samples on stdout, -o or the
        # -s picture, then exit 3 (an output failed) with a message naming
        # it and ENOSPC (stdout on /dev/full exited 0 without a word; -o and
        # -s exited 1, the status of bad input).
        grid = os.path.join(self.d, "g.csv")
        with open(grid, "w") as f:
            f.write("1,2,3\n4,5,6\n7,8,9\n")
        enospc = os.strerror(errno.ENOSPC)
        with open("/dev/full", "w") as full:
            r = subprocess.run([TRAJSURF, "-n", "64", grid], stdout=full, stderr=subprocess.PIPE,
                               text=True, timeout=60)
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("stdout: " + enospc, r.stderr)
        for args, name in ((["-o", "/dev/full"], "/dev/full"),
                           (["-o", os.devnull, "-s", "/dev/full"], "/dev/full")):
            r = run("-n", "64", *args, grid)
            self.assertEqual(r.returncode, 3, r.stderr)
            self.assertIn(name + ": " + enospc, r.stderr)
        r = run("-n", "64", "-o", os.devnull, grid)
        self.assertEqual(r.returncode, 0, r.stderr)


if __name__ == "__main__":
    unittest.main(verbosity=2)
