"""A waypoint sender that paces itself by trajd's STATUS frames (python-can on
vcan0, frames encoded by canmatrix from config/trajd.dbc): it keeps at most
`free` waypoints in flight, where free and last_seq come from STATUS.

usage: pacer.py TRACK_XYZ.csv OUT_DIR
Exit 0 if every waypoint was accepted (STATUS last_seq reached the last one,
nothing rejected or lost) and the sender was held back by flow control at
least once; writes OUT_DIR/pacer.txt with what it saw.
"""
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "helpers"))
import cantools_trajd as ct  # noqa: E402
import can  # noqa: E402

TIMEOUT_S = 40


def main():
    xyz, out = sys.argv[1], sys.argv[2]
    db = ct.load_db()
    rows = ct.read_xyz(xyz)
    n = len(rows)
    bus = can.Bus(interface="socketcan", channel="vcan0",
                  can_filters=[{"can_id": 0x6C0, "can_mask": 0x7FF, "extended": False}])
    sent = 0            # waypoints sent (seq 1..sent)
    last = 0            # last accepted seq, unwrapped
    free = 0
    held = 0            # times we had waypoints to send but flow control said wait
    min_free = 1 << 30
    rejected = lost = None
    state = None
    finish_sent = False
    deadline = time.monotonic() + TIMEOUT_S
    log = []
    while time.monotonic() < deadline:
        m = bus.recv(timeout=0.5)
        # python-can binds before it sets the filter: frames of other ids can
        # slip in during that window, so check the id here too
        if m is None or m.arbitration_id != 0x6C0 or len(m.data) != 8:
            continue
        d = m.data
        state, seq8, free, lost, rejected = d[0] & 7, d[1], d[2], d[3], d[4]
        last += (seq8 - last) & 0xFF  # unwrap: last_seq only moves forward
        min_free = min(min_free, free)
        log.append("%s: state %d last %d free %d lost %d rejected %d sent %d" % (bytes(d).hex(), state, last, free, lost, rejected, sent))
        while sent < n and sent - last < free:
            t, x, y, z = rows[sent]
            for can_id, data, _ in ct.waypoint_frames(db, sent + 1, t, x, y, z):
                bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
            sent += 1
        if sent < n and sent - last >= free:
            held += 1
        # The engine judges a waypoint with its next neighbour (lib/engine/accept.h),
        # so the newest one is confirmed only by the next or by FINISH.
        if sent == n and last >= n - 1 and not finish_sent:
            can_id, data, _ = ct.command_frame(db, 1)
            bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
            finish_sent = True
        if finish_sent and state == 3 and last == n:
            break
    bus.shutdown()
    with open(os.path.join(out, "pacer.txt"), "w") as fh:
        fh.write("sent %d last %d held %d min_free %d rejected %s lost %s state %s\n"
                 % (sent, last, held, min_free, rejected, lost, state))
        fh.write("\n".join(log) + "\n")
    ok = sent == n and last == n and rejected == 0 and lost == 0 and state == 3 and held > 0
    print("pacer: sent %d, accepted up to %d, held back %d times, min free %d, rejected %s, lost %s, state %s"
          % (sent, last, held, min_free, rejected, lost, state))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
