/*
 * csv_format.h - the one text form of a setpoint, shared by trajd's CSV/stdout
 * output and trajreplay, so their outputs can be compared byte for byte.
 * Columns: object,now_ns,t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,ay_m_s2,az_m_s2,state,flags,cycle,track
 * Numbers are printed with %.17g so they round-trip exactly; now_ns, flags,
 * cycle and track as decimal integers; state as engine_state_name()
 * ("waiting", "streaming", "underrun", "finished").
 * printf follows LC_NUMERIC, so a program using csv_format keeps the C locale
 * for numbers (neither trajd nor trajreplay calls setlocale) to get '.'.
 */
#ifndef TRAJD_SPCSV_H
#define TRAJD_SPCSV_H

#include <stddef.h>
#include "engine.h"

/* A buffer this size always holds one line (16 doubles at most 24 chars each,
 * integers, a state name and an object name of up to CSV_FORMAT_OBJECT_MAX bytes). */
#define CSV_FORMAT_OBJECT_MAX 64
#define CSV_FORMAT_LINE_MAX 640

/* Write the header line (with '\n') into buf.  Returns its length, or -1 if it does not fit. */
int csv_format_header(char *buf, size_t len);

/*
 * Write one setpoint line (with '\n').  object may be NULL (empty column).
 * Returns its length, or -1 if it does not fit, or if object is longer than
 * CSV_FORMAT_OBJECT_MAX or holds a comma, a quote or a control character (it
 * would break the column structure; the CSV is not quoted).
 */
int csv_format_format(char *buf, size_t len, const char *object, const engine_setpoint_t *sp);

#endif
