"""bench_mbsrv_load.py - Modbus load benchmark (prints numbers, asserts none
about timing): 4 objects ticking at 1 kHz in the server harness, first idle,
then 50 clients on loopback reading whole object blocks as fast as they can.
Reports requests/s, tick lateness p50/p99/max (us) and missed ticks with and
without the load, and torn reads (must be 0: that one is checked).

    MB_BENCH_SECONDS (default 30)  length of the loaded phase (idle phase: a third)
    MB_BENCH_CLIENTS (default 50)
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
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


def main():
    a = idle(SECONDS / 3)
    b, n, torn, counts, errors = loaded(SECONDS)
    print("| phase | s | requests/s | late p50 us | late p99 us | late max us | missed ticks | ticks "
          "| mbsrv_process mean us | max us |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, secs, rate, st in (("idle", SECONDS / 3, "-", a),
                                 ("%d clients" % CLIENTS, SECONDS, "%.0f" % (n / SECONDS), b)):
        print("| %s | %.0f | %s | %d | %d | %d | %d | %d | %.1f | %d |" % (
            name, secs, rate, st["late_p50_us"], st["late_p99_us"], st["late_max_us"],
            st["missed"], st["ticks"], st["process_mean_ns"] / 1000.0, st["process_max_us"]))
    print("torn reads: %d; clients answered: min %d max %d requests; errors: %d"
          % (len(torn), min(counts), max(counts), len(errors)))
    for e in errors[:5]:
        print("  ", e)
    return 1 if torn or errors or min(counts) == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
