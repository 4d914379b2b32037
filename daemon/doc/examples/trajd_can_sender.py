#!/usr/bin/env python3
"""trajd_can_sender.py - send a track to trajd as CAN waypoint frames, paced by its STATUS.

Needs python3-can (Debian).  The track is a CSV with a header and columns
t_s, x_m, y_m, z_m (or t, x, y[, z]: seconds of the sender's track clock, metres).  Frames are
config/trajd.dbc's TRAJD_WAYPOINT (0x680 + object): four frames per waypoint,
byte 0 = 0 TIME (uint48, 1 us), 1 X, 2 Y, 3 Z (int48, 1 um), byte 1 = sequence
number (low 8 bits); then command FINISH (byte 0 = 4, byte 2 = 1).

Flow control: trajd's STATUS (0x6C0 + object) gives the last accepted sequence
number (byte 1) and the free waypoint slots (byte 2); the sender keeps at most
`free` waypoints beyond the last accepted one in flight, so it never overruns
trajd's buffer whatever the track's length.

  trajd_can_sender.py TRACK.csv [--channel vcan0] [--interface socketcan]
                      [--object 0] [--timeout 60]
  trajd_can_sender.py TRACK.csv --log OUT.log     # a candump log stamped at t,
                                                   # for [can] log_in (no pacing)

Exit status 0 when trajd accepted every waypoint, nothing was rejected or lost
and the object finished; 1 otherwise (the last STATUS seen is printed).
"""
import argparse
import csv
import struct
import sys
import time

import can

WAYPOINT, STATUS = 0x680, 0x6C0
MUX_TIME, MUX_X, MUX_Y, MUX_Z, MUX_COMMAND = 0, 1, 2, 3, 4
CMD_FINISH = 1
FINISHED = 3


def read_track(path):
    """(t, x, y, z) rows of a CSV in metres: columns t_s or t, x_m or x, y_m or y, and z_m or z
    (optional, 0); a track in degrees (lat/lon) is refused with what to do instead."""
    with open(path) as f:
        rd = csv.DictReader(f)
        cols = set(rd.fieldnames or ())

        def col(*names):
            return next((n for n in names if n in cols), None)
        t, x, y, z = col("t_s", "t"), col("x_m", "x"), col("y_m", "y"), col("z_m", "z")
        if not (t and x and y):
            geo = (" (a track in degrees: this sender sends metres; convert it first, e.g. to "
                   "east/north metres of its first fix with pyproj)"
                   if col("lat", "lat_deg", "latitude") else "")
            sys.exit("%s: needs columns t_s (or t), x_m, y_m (or x, y) and optionally z_m, in "
                     "metres; its header has %s%s" % (path, ", ".join(rd.fieldnames or ["none"]),
                                                      geo))
        return [(float(r[t]), float(r[x]), float(r[y]), float(r[z]) if z else 0.0) for r in rd]


def int48(v):
    """Little-endian 48-bit two's complement."""
    return struct.pack("<q", v)[:6]


def waypoint_frames(obj, seq, t, x, y, z):
    """The four frames of waypoint seq: TIME in us, X/Y/Z in um (rounded)."""
    out = [bytes([MUX_TIME, seq & 0xFF]) + int48(round(t * 1e6))]
    for mux, v in ((MUX_X, x), (MUX_Y, y), (MUX_Z, z)):
        out.append(bytes([mux, seq & 0xFF]) + int48(round(v * 1e6)))
    return [can.Message(arbitration_id=WAYPOINT + obj, data=d, is_extended_id=False) for d in out]


def finish_frame(obj):
    return can.Message(arbitration_id=WAYPOINT + obj, is_extended_id=False,
                       data=bytes([MUX_COMMAND, 0, CMD_FINISH, 0, 0, 0, 0, 0]))


def write_log(rows, obj, path, iface="can0"):
    """The frames as a candump -l log stamped at each waypoint's t."""
    with open(path, "w") as f:
        for i, (t, x, y, z) in enumerate(rows):
            for m in waypoint_frames(obj, i + 1, t, x, y, z):
                f.write("(%.6f) %s %03X#%s\n" % (t, iface, m.arbitration_id, m.data.hex().upper()))
        m = finish_frame(obj)
        f.write("(%.6f) %s %03X#%s\n" % (rows[-1][0], iface, m.arbitration_id,
                                         m.data.hex().upper()))


def send_paced(rows, obj, bus, timeout_s):
    n = len(rows)
    sent = last = 0            # waypoints sent (seq 1..sent); last accepted, unwrapped
    st = None
    finish_sent = False
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        m = bus.recv(timeout=0.5)
        if m is None or m.arbitration_id != STATUS + obj or len(m.data) != 8:
            continue
        d = m.data
        st = {"state": d[0] & 7, "last_seq": d[1], "free": d[2], "lost": d[3],
              "rejected": d[4], "last_err": d[7]}
        last += (d[1] - last) & 0xFF       # last_seq only moves forward
        while sent < n and sent - last < st["free"]:
            for f in waypoint_frames(obj, sent + 1, *rows[sent]):
                bus.send(f)
            sent += 1
        # trajd judges a waypoint with its successor: the newest one is
        # confirmed by FINISH (end of input)
        if sent == n and last >= n - 1 and not finish_sent:
            bus.send(finish_frame(obj))
            finish_sent = True
        if finish_sent and st["state"] == FINISHED and last == n:
            break
    ok = (st is not None and sent == n and last == n and st["state"] == FINISHED
          and st["rejected"] == 0 and st["lost"] == 0)
    print("sent %d of %d waypoints, trajd accepted up to %d; last STATUS %s"
          % (sent, n, last, st))
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("track")
    ap.add_argument("--channel", default="vcan0")
    ap.add_argument("--interface", default="socketcan")
    ap.add_argument("--object", type=int, default=0, help="object number n (ids 0x680+n, 0x6C0+n)")
    ap.add_argument("--timeout", type=float, default=60)
    ap.add_argument("--log", help="write a candump log instead of sending")
    args = ap.parse_args()
    rows = read_track(args.track)
    if not rows:
        print("empty track", file=sys.stderr)
        return 1
    if args.log:
        write_log(rows, args.object, args.log)
        return 0
    bus = can.Bus(interface=args.interface, channel=args.channel,
                  can_filters=[{"can_id": STATUS + args.object, "can_mask": 0x7FF,
                                "extended": False}])
    try:
        return 0 if send_paced(rows, args.object, bus, args.timeout) else 1
    finally:
        bus.shutdown()


if __name__ == "__main__":
    sys.exit(main())
