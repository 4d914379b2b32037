"""test_doc_counts.py - the counts in daemon/README.md's trajreplay table and
lib/spline/README.md's cubic-vs-smooth table are those of a run (issue 14: no
stale numbers).

The table under "**Measured.**" in daemon/README.md's trajreplay part gives,
per bundled track, what `trajreplay --summary -o FILE TRACK` (default
settings) reports: waypoints read, accepted, gaps, setpoints, and the CSV's
size in bytes.  Each row is replayed here and compared exactly.
"""
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import replay_summary  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
BUILD = os.environ.get("BUILD", os.path.join(ROOT, "build"))


def table_rows():
    """[(track, {column: int})] of the table whose header starts '| track | read |'."""
    with open(os.path.join(ROOT, "daemon", "README.md"), encoding="utf-8") as f:
        lines = f.read().split("\n")
    start = next(i for i, l in enumerate(lines) if l.startswith("| track | read |"))
    head = [c.strip() for c in lines[start].strip("|").split("|")]
    rows = []
    for l in lines[start + 2:]:
        if not l.startswith("|"):
            break
        cells = [c.strip() for c in l.strip("|").split("|")]
        track = cells[0].strip("`")
        rows.append((track, {h: int(re.sub(r"[ ,]", "", c)) for h, c in zip(head[1:], cells[1:])}))
    return rows


def summary(track, out):
    r = subprocess.run([os.path.join(BUILD, "bin", "trajreplay"), "--summary", "-q", "-o", out,
                        os.path.join(ROOT, "tests", "data", track)],
                       capture_output=True, text=True, check=True)
    return replay_summary.parse(r.stderr)


class DocCounts(unittest.TestCase):
    def test_trajreplay_table(self):
        rows = table_rows()
        self.assertGreaterEqual(len(rows), 3)
        with tempfile.TemporaryDirectory() as tmp:
            for track, want in rows:
                out = os.path.join(tmp, "out.csv")
                s = summary(track, out)
                got = {"read": int(s["waypoints"]), "accepted": int(s["accepted"]),
                       "gaps": int(s["gaps"]), "setpoints": int(s["setpoints"]),
                       "CSV bytes": os.path.getsize(out)}
                self.assertEqual(got, want, "daemon/README.md's row for %s is stale" % track)

    def test_smooth_table(self):
        """lib/spline/README.md: visnjan at 10 Hz, cubic and smooth: path length,
        p99 speed, p99 and max acceleration, as the doc rounds them."""
        import numpy as np
        with open(os.path.join(ROOT, "lib", "spline", "README.md"), encoding="utf-8") as f:
            doc = f.read()
        with tempfile.TemporaryDirectory() as tmp:
            for method, label in (("cubic", "cubic (exact)"), ("smooth", "smooth (")):
                row = next(l for l in doc.split("\n") if l.startswith("| " + label))
                want = [float(x) for x in re.findall(r"\| ([0-9.]+) m", row)]
                out = os.path.join(tmp, method + ".csv")
                subprocess.run([os.path.join(BUILD, "bin", "trajreplay"), "-q", "--rate", "10",
                                "--method", method, "-o", out,
                                os.path.join(ROOT, "tests", "data", "gpxgo_visnjan.csv")], check=True)
                d = np.genfromtxt(out, delimiter=",", names=True, dtype=None, encoding=None)
                v = np.hypot(d["vx_m_s"], d["vy_m_s"])
                a = np.hypot(d["ax_m_s2"], d["ay_m_s2"])
                got = [round(float(np.nansum(np.hypot(np.diff(d["x_m"]), np.diff(d["y_m"]))))),
                       round(float(np.nanpercentile(v, 99)), 2), round(float(np.nanpercentile(a, 99)), 2),
                       round(float(np.nanmax(a)), 2)]
                self.assertEqual(got, want, "lib/spline/README.md's %s row is stale" % method)


if __name__ == "__main__":
    unittest.main(argv=sys.argv[:1])
