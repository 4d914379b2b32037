"""ctypes view of lib/proto/canproto.h and lib/format/candump.h (used by the CAN tests).

Only the layouts of the structs the tests pass across are mirrored here;
test_canproto.py checks sizes it can observe (frame length) and everything
else is cross-checked by value against canmatrix / python-can.
"""
import ctypes
import os

AXES = 3
F_EFF, F_RTR, F_ERR, F_FD, F_BRS, F_ESI = 0x01, 0x02, 0x04, 0x08, 0x10, 0x20


class Frame(ctypes.Structure):
    _fields_ = [("id", ctypes.c_uint32), ("len", ctypes.c_uint8), ("flags", ctypes.c_uint8),
                ("data", ctypes.c_uint8 * 64)]

    def payload(self):
        return bytes(self.data[: self.len])


class Waypoint(ctypes.Structure):
    _fields_ = [("t_s", ctypes.c_double), ("pos_m", ctypes.c_double * AXES),
                ("seq", ctypes.c_uint32), ("has_vel", ctypes.c_uint32),
                ("vel_m_s", ctypes.c_double * AXES)]


class Setpoint(ctypes.Structure):
    _fields_ = [("now_ns", ctypes.c_int64), ("t_s", ctypes.c_double),
                ("pos_m", ctypes.c_double * AXES), ("vel_m_s", ctypes.c_double * AXES),
                ("acc_m_s2", ctypes.c_double * AXES), ("state", ctypes.c_int),
                ("flags", ctypes.c_uint32), ("cycle", ctypes.c_uint32),
                ("track", ctypes.c_uint32), ("age_s", ctypes.c_double)]


class RxOut(ctypes.Structure):
    _fields_ = [("wp", Waypoint), ("cmd", ctypes.c_int), ("cmd_arg", ctypes.c_uint),
                ("lost_before", ctypes.c_uint32), ("resync", ctypes.c_uint32)]


class CiaSdo(ctypes.Structure):
    _fields_ = [("index", ctypes.c_uint16), ("sub", ctypes.c_uint8), ("size", ctypes.c_uint8),
                ("value", ctypes.c_uint32)]


class Ids(ctypes.Structure):
    _fields_ = [("waypoint_id", ctypes.c_uint32), ("waypoint_fd_id", ctypes.c_uint32),
                ("setpoint_id", ctypes.c_uint32), ("setpoint_fd_id", ctypes.c_uint32),
                ("status_id", ctypes.c_uint32), ("fd", ctypes.c_int), ("brs", ctypes.c_int),
                ("own", ctypes.c_int), ("cia402", ctypes.c_int),  # canproto_cia402_mode_t
                ("cia402_cob_id", ctypes.c_uint32 * AXES),
                ("cia402_counts_per_m", ctypes.c_double), ("cia402_controlword", ctypes.c_int),
                ("cia402_controlword_value", ctypes.c_uint16),
                ("cia402_axis_counts_per_m", ctypes.c_double * AXES),
                ("cia402_invert", ctypes.c_int * AXES), ("cia402_offset", ctypes.c_int32 * AXES),
                ("cia402_tpdo_id", ctypes.c_uint32 * AXES), ("cia402_sdo", CiaSdo * 8),
                ("cia402_nsdo", ctypes.c_uint), ("cia402_heartbeat_ms", ctypes.c_uint32),
                ("status2_id", ctypes.c_uint32)]


class St2Faults(ctypes.Structure):
    _fields_ = [("out_lost", ctypes.c_uint64), ("out_errors", ctypes.c_uint64),
                ("cmd_refused", ctypes.c_uint64)]


class St2Bus(ctypes.Structure):
    _fields_ = [("state", ctypes.c_uint8), ("tx_err", ctypes.c_uint8), ("rx_err", ctypes.c_uint8),
                ("bus_offs", ctypes.c_uint64), ("err_frames", ctypes.c_uint64)]


class St2Rejected(ctypes.Structure):
    _fields_ = [(n, ctypes.c_uint64) for n in ("backwards", "same_time", "speed", "accel",
                                               "unconfirmed", "stale", "other")]


class St2Clock(ctypes.Structure):
    _fields_ = [("age_s", ctypes.c_double), ("drift_ppm", ctypes.c_double),
                ("clocked", ctypes.c_uint8)]


class St2Motion(ctypes.Structure):
    _fields_ = [(n, ctypes.c_uint64) for n in ("underruns", "delay_grown", "transfers_moving",
                                               "reserve_slowed", "axis_beyond", "axis_lag_stops")]


class Status(ctypes.Structure):
    _fields_ = [("state", ctypes.c_uint8), ("flags", ctypes.c_uint8),
                ("last_seq", ctypes.c_uint32), ("free", ctypes.c_uint32),
                ("lost", ctypes.c_uint32), ("rejected", ctypes.c_uint32),
                ("malformed", ctypes.c_uint32), ("dropped", ctypes.c_uint32),
                ("last_err", ctypes.c_uint8)]


def load():
    build = os.environ.get("BUILD", os.path.join(os.path.dirname(__file__), "..", "..", "build"))
    lib = ctypes.CDLL(os.path.join(build, "libtrajd.so"))
    P = ctypes.POINTER
    lib.canproto_encode_waypoint.argtypes = [ctypes.c_uint32, P(Waypoint), P(Frame)]
    lib.canproto_encode_waypoint_fd.argtypes = [ctypes.c_uint32, P(Waypoint), P(Frame)]
    lib.canproto_encode_waypoint_vel.argtypes = [ctypes.c_uint32, P(Waypoint), P(Frame)]
    lib.canproto_encode_setpoint.argtypes = [ctypes.c_uint32, P(Setpoint), P(Frame)]
    lib.canproto_encode_setpoint_fd.argtypes = [ctypes.c_uint32, ctypes.c_int, P(Setpoint),
                                                P(Frame)]
    lib.canproto_encode_status.argtypes = [ctypes.c_uint32, P(Status), P(Frame)]
    lib.canproto_encode_status2_faults.argtypes = [ctypes.c_uint32, P(St2Faults), P(Frame)]
    lib.canproto_decode_status2_faults.argtypes = [P(Frame), P(St2Faults)]
    lib.canproto_encode_status2_bus.argtypes = [ctypes.c_uint32, P(St2Bus), P(Frame)]
    lib.canproto_decode_status2_bus.argtypes = [P(Frame), P(St2Bus)]
    lib.canproto_encode_status2_rejected.argtypes = [ctypes.c_uint32, P(St2Rejected), P(Frame)]
    lib.canproto_decode_status2_rejected.argtypes = [P(Frame), P(St2Rejected)]
    lib.canproto_encode_status2_clock.argtypes = [ctypes.c_uint32, P(St2Clock), P(Frame)]
    lib.canproto_decode_status2_clock.argtypes = [P(Frame), P(St2Clock)]
    lib.canproto_encode_status2_time.argtypes = [ctypes.c_uint32, ctypes.c_double, P(Frame)]
    lib.canproto_decode_status2_time.argtypes = [P(Frame), P(ctypes.c_double)]
    lib.canproto_encode_status2_motion.argtypes = [ctypes.c_uint32, P(St2Motion), P(Frame)]
    lib.canproto_decode_status2_motion.argtypes = [P(Frame), P(St2Motion)]
    lib.canproto_encode_cia402.argtypes = [P(Ids), ctypes.c_uint, ctypes.c_double, P(Frame)]
    lib.canproto_cia402_pos_m.argtypes = [P(Ids), ctypes.c_uint, ctypes.c_int32]
    lib.canproto_cia402_pos_m.restype = ctypes.c_double
    lib.canproto_ids_default.argtypes = [P(Ids), ctypes.c_uint]
    lib.canproto_rx_init.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_uint]
    lib.canproto_rx_frame.argtypes = [ctypes.c_void_p, P(Frame), ctypes.c_int, P(RxOut)]
    lib.canproto_rx_consume.argtypes = [ctypes.c_void_p, P(RxOut)]
    lib.candump_parse_line.argtypes = [ctypes.c_char_p, ctypes.c_void_p]
    lib.candump_format_line.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_int64,
                                        ctypes.c_char_p, P(Frame)]
    return lib


class CandumpLine(ctypes.Structure):
    _fields_ = [("ts_us", ctypes.c_int64), ("ifname", ctypes.c_char * 16), ("frame", Frame)]


class Rx:
    """A reassembler on buffers big enough for canproto_rx_t and its slots."""

    def __init__(self, lib, nslots=2):
        self.lib = lib
        self.mem = ctypes.create_string_buffer(4096)
        self.slots = ctypes.create_string_buffer(128 * nslots)
        lib.canproto_rx_init(self.mem, self.slots, nslots)

    def frame(self, f, is_fd_id=0):
        out = RxOut()
        rc = self.lib.canproto_rx_frame(self.mem, ctypes.byref(f), is_fd_id, ctypes.byref(out))
        return rc, out

    def consume(self, out):
        self.lib.canproto_rx_consume(self.mem, ctypes.byref(out))
