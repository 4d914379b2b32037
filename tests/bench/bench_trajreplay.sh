#!/bin/sh
# bench_trajreplay.sh - trajreplay speed and memory on the real tracks and on
# synthetic long tracks (loader throughput).  Prints a table; asserts nothing.
#   BUILD  absolute build directory (set by make bench)
set -u
cd "$(dirname "$0")/../.." || exit 1
: "${BUILD:?BUILD must be set}"
exec /usr/bin/python3 - "$BUILD/bin/trajreplay" <<'PY'
import math, os, subprocess, sys, tempfile, time

exe = sys.argv[1]

TIME = "/usr/bin/time"  # Debian package "time"; without it RSS is not measured


def run(args):
    """Wall time and peak RSS (kB, from GNU time's %M, or None) of one run.
    (Python's RUSAGE_CHILDREN cannot be used: Linux counts the pages a child
    forked from Python shares with it before exec in the child's peak.)"""
    cmd = [exe] + args
    if os.access(TIME, os.X_OK):
        cmd = [TIME, "-f", "rss_kb %M"] + cmd
    t = time.perf_counter()
    r = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t
    lines = r.stderr.splitlines()
    rss = next((int(l.split()[1]) for l in lines if l.startswith("rss_kb ")), None)
    summary = {l.split()[1]: l.split()[2] for l in lines if l.startswith("summary: ")}
    return wall, rss, r.returncode, summary


with tempfile.TemporaryDirectory() as tmp:
    # Synthetic long tracks: 200 000 waypoints at 1 Hz on a circle, CSV and GPX.
    n = 200000
    xyz = os.path.join(tmp, "long.csv")
    with open(xyz, "w") as f:
        f.write("t,x,y,z\n")
        for i in range(n):
            f.write(f"{i},{1000*math.cos(i/500):.3f},{1000*math.sin(i/500):.3f},0\n")
    gpx = os.path.join(tmp, "long.gpx")
    with open(gpx, "w") as f:
        f.write('<?xml version="1.0"?>\n<gpx version="1.1" xmlns="http://www.topografix.com/GPX/1/1"><trk><trkseg>\n')
        for i in range(n):
            s = 1400000000 + i
            tm = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(s))
            f.write(f'<trkpt lat="{45+0.01*math.sin(i/500):.7f}" lon="{13+0.01*math.cos(i/500):.7f}">'
                    f'<ele>{100+i%7}</ele><time>{tm}</time></trkpt>\n')
        f.write("</trkseg></trk></gpx>\n")
    cases = [("tests/data/gpxgo_visnjan.gpx", "100"), ("tests/data/gpxpy_cerknicko-jezero.csv", "100"),
             ("tests/data/n2k_furuno_figure8_src52.csv", "100"), (xyz, "1"), (gpx, "1")]
    print(f"{'track':42} {'rate':>5} {'waypoints':>9} {'setpoints':>9} {'wall s':>7} {'ns/setpoint':>11} {'us/waypoint':>11} {'RSS MB':>7}")
    for path, rate in cases:
        wall, rss, rc, s = run(["--rate", rate, "--summary", "-o", "/dev/null", path])
        if rc != 0:
            print(f"{path}: exit {rc}")
            sys.exit(1)
        wp, sp = int(s["waypoints"]), int(s["setpoints"])
        rss_mb = "n/a" if rss is None else f"{rss / 1024:.1f}"
        name = os.path.basename(path) + (" (synthetic)" if path.startswith(tmp) else "")
        print(f"{name:42} {rate:>5} {wp:>9} {sp:>9} {wall:7.2f} {wall/sp*1e9:11.0f} {wall/wp*1e6:11.2f} {rss_mb:>7}")
print("ns/setpoint and us/waypoint are wall time divided by each count (the same run);")
print("output to /dev/null, so formatting (%.17g x 12 per line) is included, disk is not.")
print("RSS MB: peak resident set of trajreplay (GNU time %M; n/a without /usr/bin/time).")
PY
