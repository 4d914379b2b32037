"""bench_modbus_server_load.py - Modbus load benchmark (prints numbers, asserts none
about timing): 4 objects ticking at 1 kHz, first idle, then 50 clients on
loopback reading whole object blocks as fast as they can.  Twice: in the
server harness (synthetic snapshot), and in trajd (4 objects replaying the
figure-eight track at 1 kHz; every block read must be a row of trajreplay's
output at the block's track time).  Reports requests/s, tick lateness
p50/p99/max (us) and missed ticks with and without the load, and torn reads
(must be 0: that one is checked).

    MB_BENCH_SECONDS (default 30)  length of the loaded phase (idle phase: a third)
    MB_BENCH_CLIENTS (default 50)
"""
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import mbsim  # noqa: E402

SECONDS = float(os.environ.get("MB_BENCH_SECONDS", "30"))
CLIENTS = int(os.environ.get("MB_BENCH_CLIENTS", "50"))
OBJECTS = 4


def idle(seconds):
    srv = mbsim.Server(["--objects", str(OBJECTS), "--period-us", "1000"])
    # Nothing to wait for but time itself: the tick runs meanwhile.  One
    # client read a second keeps this a measurement of the idle server.
    import time
    end = time.monotonic() + seconds
    s = mbsim.connect(srv.port)
    while time.monotonic() < end:
        mbsim.read_input(s, 0, 3)
        s.settimeout(min(1.0, max(0.0, end - time.monotonic())))
        try:
            s.recv(1)      # no data ever comes: a bounded wait, not a sleep-and-hope
        except OSError:
            pass
    s.close()
    return srv.stop()


def loaded(seconds):
    srv = mbsim.Server(["--objects", str(OBJECTS), "--period-us", "1000",
                        "--max-clients", str(CLIENTS + 8)])
    n, torn, counts, errors = mbsim.load(srv.port, CLIENTS, seconds, OBJECTS)
    return srv.stop(), n, torn, counts, errors


TRACK = os.path.join(mbsim.ROOT, "tests", "data", "n2k_furuno_figure8_src52.csv")


def trajd_conf(tmp):
    objs = "".join("""
[object.o%d]
id = %d
input = replay
replay.track = %s
output = csv
csv.path = %s/o%d.csv
""" % (k, k, TRACK, tmp, k) for k in range(OBJECTS))
    return """
[daemon]
rate_hz = 1000
status_interval_s = 0
[modbus]
port = 0
systemd_socket = no
max_clients = %d
""" % (CLIENTS + 8) + objs


def trajd_phase(clients, seconds, ref):
    """One trajd run: clients (0 = idle) for seconds; returns stats, n, torn, counts, errors."""
    import tempfile
    import time
    from test_modbus_server_trajd import Trajd
    M = mbsim.M

    def check(r, k):
        if mbsim.u32(r, M["MBMAP_O_GEN"]) != mbsim.u32(r, M["MBMAP_O_GEN_TAIL"]):
            return "generation head/tail"
        if r[M["MBMAP_O_STATE"]] != 1:
            return None
        want = ref.get(mbsim.f64(r, M["MBMAP_O_T_S"]))
        got = tuple(mbsim.f32(r, M["MBMAP_O_POS"] + 2 * a) for a in range(3))
        return None if want == got else "t %r: %r, trajreplay %r" % (
            mbsim.f64(r, M["MBMAP_O_T_S"]), got, want)

    with tempfile.TemporaryDirectory() as tmp:
        d = Trajd(trajd_conf(tmp), tmp)
        try:
            s = mbsim.connect(d.port)
            # Wait (bounded) for the objects to stream before measuring.
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                if mbsim.read_input(s, mbsim.obj_base(0) + M["MBMAP_O_STATE"], 1)[0] == 1:
                    break
            if clients:
                n, torn, counts, errors = mbsim.load(d.port, clients, seconds, OBJECTS, check)
            else:
                end = time.monotonic() + seconds
                n, torn, counts, errors = 0, [], [1], []
                while time.monotonic() < end:
                    mbsim.read_input(s, 0, 3)
                    s.settimeout(min(1.0, max(0.0, end - time.monotonic())))
                    try:
                        s.recv(1)
                    except OSError:
                        pass
                    s.settimeout(mbsim.WAIT_S)
            r = mbsim.read_input(s, 0, 30)
            s.close()
        finally:
            d.stop()
    st = {"late_p50_us": mbsim.u32(r, M["MBMAP_D_LATE_P50_US"]),
          "late_p99_us": mbsim.u32(r, M["MBMAP_D_LATE_P99_US"]),
          "late_max_us": mbsim.u32(r, M["MBMAP_D_LATE_MAX_US"]),
          "missed": mbsim.u32(r, M["MBMAP_D_MISSED_TICKS"]),
          "ticks": mbsim.u32(r, M["MBMAP_D_GEN"]),
          "process_mean_ns": 0, "process_max_us": 0}
    return st, n, torn, counts, errors


def trajreplay_ref():
    import csv
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "ref.csv")
        subprocess.run([os.path.join(mbsim.BUILD, "bin", "trajreplay"), "--rate", "1000", "-q",
                        "-o", out, TRACK], check=True, timeout=120)
        with open(out) as f:
            return {float(r["t_s"]): tuple(mbsim.f32_round(float(r[c])) for c in ("x_m", "y_m", "z_m"))
                    for r in csv.DictReader(f)}


def main():
    a = idle(SECONDS / 3)
    b, n, torn, counts, errors = loaded(SECONDS)
    print("| phase | s | requests/s | late p50 us | late p99 us | late max us | missed ticks | ticks "
          "| modbus_server_process mean us | max us |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, secs, rate, st in (("idle", SECONDS / 3, "-", a),
                                 ("%d clients" % CLIENTS, SECONDS, "%.0f" % (n / SECONDS), b)):
        print("| %s | %.0f | %s | %d | %d | %d | %d | %d | %.1f | %d |" % (
            name, secs, rate, st["late_p50_us"], st["late_p99_us"], st["late_max_us"],
            st["missed"], st["ticks"], st["process_mean_ns"] / 1000.0, st["process_max_us"]))
    print("harness: torn reads: %d; clients answered: min %d max %d requests; errors: %d"
          % (len(torn), min(counts), max(counts), len(errors)))
    for e in (errors + torn)[:5]:
        print("  ", e)
    bad = torn or errors or min(counts) == 0

    ref = trajreplay_ref()
    ta = trajd_phase(0, SECONDS / 3, ref)[0]
    tb, tn, ttorn, tcounts, terrors = trajd_phase(CLIENTS, SECONDS, ref)
    print()
    print("trajd, 4 objects replaying at 1 kHz (lateness and missed ticks from its own registers):")
    print("| phase | s | requests/s | late p50 us | late p99 us | late max us | missed ticks | ticks |")
    print("|---|---|---|---|---|---|---|---|")
    for name, secs, rate, st in (("idle", SECONDS / 3, "-", ta),
                                 ("%d clients" % CLIENTS, SECONDS, "%.0f" % (tn / SECONDS), tb)):
        print("| %s | %.0f | %s | %d | %d | %d | %d | %d |" % (
            name, secs, rate, st["late_p50_us"], st["late_p99_us"], st["late_max_us"],
            st["missed"], st["ticks"]))
    print("trajd: torn reads: %d; clients answered: min %d max %d requests; errors: %d"
          % (len(ttorn), min(tcounts), max(tcounts), len(terrors)))
    for e in (terrors + ttorn)[:5]:
        print("  ", e)
    bad = bad or ttorn or terrors or min(tcounts) == 0
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
