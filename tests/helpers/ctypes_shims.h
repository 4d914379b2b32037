/*
 * ctypes_shims.h - the engine with flat arguments, for the Python oracle
 * tests (ctypes): built into $(BUILD)/libtrajd_test.so with libtrajd's
 * objects, never into the product's libraries.
 */
#ifndef TRAJD_CTYPES_SHIMS_H
#define TRAJD_CTYPES_SHIMS_H

#include <stddef.h>

/*
 * F and O picked for method/param, accuracy and
 * max_lookahead (the defaults otherwise), and the lookahead that results
 * (start_slack auto at its least); 0 if none fits (resolving then picks a
 * local method, engine_method_flat, or refuses).
 */
unsigned engine_pick_flat(int method, int param, double accuracy, unsigned max_lookahead,
                          unsigned *fragment, unsigned *overlap);

/*
 * engine_curve (engine.h) with flat arguments: the default
 * configuration with method, param, ends, fragment, overlap given (0:
 * auto, as the default),
 * max_speed_m_s = 0, max_accel_m_s2 = 0 (every waypoint kept) and
 * max_gap_s = 1e9 (one trajectory).  t_s: n times,
 * xyz: n x 3; seg_out: max_seg x 14 doubles (t0_s, dur_s, then c[axis][0..3]
 * for x, y, z).  Returns the number of segments, or a negated engine_error.
 */
long engine_curve_flat(int method, int param, int ends, unsigned fragment, unsigned overlap,
                       size_t n, const double *t_s, const double *xyz, double *seg_out,
                       size_t max_seg);

/* engine_curve_flat with param time and fragment, overlap auto, and the
 * source's velocities (n x 3, each waypoint has_vel; NULL: none). */
long engine_curve_vel_flat(int method, int ends, size_t n, const double *t_s, const double *xyz,
                           const double *vel, double *seg_out, size_t max_seg);

/* The method the default configuration with max_lookahead and ends
 * resolves to (engine_method_t), its lookahead in *lookahead; -1 if
 * refused. */
int engine_method_flat(unsigned max_lookahead, int ends, unsigned *lookahead);

#endif
