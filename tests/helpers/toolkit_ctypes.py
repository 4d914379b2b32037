"""ctypes declarations of the spline toolkit in $BUILD/libtrajd.so, shared by
tests/oracle/test_toolkit_scipy.py and tests/pictures/make_pictures.py (the structs
mirror lib/spline/bspline.h, nurbs.h, cspline.h, surf.h, path.h and engine.h)."""
import ctypes as C
import os

BUILD = os.environ.get("BUILD", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "build"))
lib = C.CDLL(os.path.join(BUILD, "libtrajd.so"))
dp = C.POINTER(C.c_double)


def ptr(a):
    return a.ctypes.data_as(dp)


class Bspline(C.Structure):
    _fields_ = [("order", C.c_uint), ("n_ctrl", C.c_size_t), ("dim", C.c_size_t),
                ("knots", dp), ("ctrl", dp)]


class Nurbs(C.Structure):
    _fields_ = [("order", C.c_uint), ("n_ctrl", C.c_size_t), ("dim", C.c_size_t),
                ("knots", dp), ("ctrl", dp), ("w", dp)]


class Cspline(C.Structure):
    _fields_ = [("n", C.c_size_t), ("dim", C.c_size_t), ("t", dp), ("p", dp),
                ("s", dp), ("periodic", C.c_int)]


class Surf(C.Structure):
    _fields_ = [("m", C.c_size_t), ("n", C.c_size_t), ("dim", C.c_size_t), ("ctrl", dp)]


class Waypoint(C.Structure):
    _fields_ = [("t_s", C.c_double), ("pos_m", C.c_double * 3), ("seq", C.c_uint32)]


class PathElem(C.Structure):
    _fields_ = [("kind", C.c_int), ("xyz_m", C.c_double * 3), ("t_s", C.c_double),
                ("value", C.c_double), ("centre_m", C.c_double * 2), ("radius_m", C.c_double),
                ("start_rad", C.c_double), ("sweep_rad", C.c_double)]


lib.bspline_check.argtypes = [C.POINTER(Bspline)]
lib.bspline_eval.argtypes = [C.POINTER(Bspline), C.c_double, dp]
lib.bspline_eval_derivs.argtypes = [C.POINTER(Bspline), C.c_double, C.c_uint, dp]
lib.cspline_solve.argtypes = [C.c_size_t, C.c_size_t, dp, dp, C.c_int, dp, dp, dp, dp,
                              C.POINTER(Cspline)]
lib.cspline_scratch_len.restype = C.c_size_t
lib.cspline_scratch_len.argtypes = [C.c_size_t, C.c_size_t]
lib.cspline_params.argtypes = [C.c_size_t, C.c_size_t, dp, C.c_int, dp]
lib.cspline_eval.argtypes = [C.POINTER(Cspline), C.c_double, C.c_uint, dp]
lib.lsq_work_len.restype = C.c_size_t
lib.lsq_work_len.argtypes = [C.c_size_t, C.c_uint, C.c_size_t]
lib.lsq_chord_params.argtypes = [C.c_size_t, C.c_size_t, dp, dp]
lib.lsq_knots.argtypes = [C.c_size_t, C.c_uint, C.c_double, C.c_double, dp]
lib.lsq_fit.argtypes = [C.c_size_t, C.c_size_t, dp, dp, C.c_uint, C.c_size_t, dp,
                        C.c_uint, dp, dp]
lib.surf_scratch_len.restype = C.c_size_t
lib.surf_scratch_len.argtypes = [C.c_size_t, C.c_size_t, C.c_size_t]
lib.surf_interpolate.argtypes = [C.c_size_t, C.c_size_t, C.c_size_t, dp, dp, dp,
                                 C.POINTER(Surf)]
lib.surf_eval.argtypes = [C.POINTER(Surf), C.c_double, C.c_double, C.c_uint, dp]
lib.nurbs_eval.argtypes = [C.POINTER(Nurbs), C.c_double, dp]
lib.nurbs_unit_circle.argtypes = [dp, dp, dp, C.POINTER(Nurbs)]
lib.nurbs_conic.argtypes = [dp, C.c_size_t, C.c_double, dp, dp, dp, C.POINTER(Nurbs)]
lib.path_parse_line.argtypes = [C.c_char_p, C.POINTER(PathElem)]
lib.path_expand.argtypes = [C.POINTER(PathElem), C.c_size_t, C.POINTER(Waypoint), C.c_size_t,
                            C.POINTER(C.c_size_t)]
