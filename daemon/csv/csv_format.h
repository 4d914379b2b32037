/*
 * csv_format.h - the one text form of a setpoint, shared by trajd's CSV/stdout
 * output and trajreplay, so their outputs can be compared byte for byte.
 * Columns: object,now_ns,t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,ay_m_s2,az_m_s2,state,flags,cycle,track
 * Numbers are printed as the shortest decimal that reads back to the same
 * double, in Python's repr() form (csv_shortest.h), so they round-trip
 * exactly; now_ns, flags, cycle and track as decimal integers; state as engine_state_name()
 * ("waiting", "streaming", "underrun", "finished").
 * printf follows LC_NUMERIC, so a program using csv_format keeps the C locale
 * for numbers (neither trajd nor trajreplay calls setlocale) to get '.'.
 */
#ifndef TRAJD_SPCSV_H
#define TRAJD_SPCSV_H

#include <stddef.h>
#include "engine.h"
#include "spfile.h"

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

/*
 * Append more columns (text starting with ',') to a line or header of length
 * n that ends with '\n', before the '\n'.  Returns the new length, or -1 if it
 * does not fit (or n < 1).
 */
int csv_format_append(char *buf, size_t len, int n, const char *cols);

/*
 * One more column at the end of the header or setpoint line held in buf
 * (length n, ending in '\n'): "age_s" (header: sp NULL) or the setpoint's
 * age_s in the shortest round-trip form of the other numbers ("nan" for
 * relative time): the opt-in data age column of trajd's csv and stdout
 * outputs (csv.age, stdout.age; lib/engine/CLOCK.md).  Same returns.
 */
int csv_format_add_age(char *buf, size_t len, int n, const engine_setpoint_t *sp);

/*
 * The same line with every double (t_s and the nine coordinates) in fixed
 * notation with prec decimals, byte for byte printf("%.*f") (csv_fixed.h),
 * written by a fast formatter (trajreplay --precision).  Same returns.
 *   prec CSV_PREC_SHORTEST: the default shortest round-trip form, as
 *        csv_format_format;
 *   prec CSV_PREC_G17: printf's %.17g, the default before (also round-trips,
 *        17 significant digits always; kept for files compared against it and
 *        as the reference make bench times the default against).
 */
#define CSV_PREC_SHORTEST (-1)
#define CSV_PREC_G17 (-2)
int csv_format_format_prec(char *buf, size_t len, const char *object, const engine_setpoint_t *sp,
                           int prec);

/* Binary setpoint file (trajreplay --binary): the layout is public, in
 * lib/format/spfile.h (installed), and in trajreplay(1) "BINARY FORMAT". */
#define CSV_BIN_MAGIC SPFILE_MAGIC
#define CSV_BIN_HEADER SPFILE_HEADER
#define CSV_BIN_RECORD SPFILE_RECORD

/* The header into buf (CSV_BIN_HEADER bytes). */
void csv_format_bin_header(unsigned char *buf, const char *object);
/* One record into buf (CSV_BIN_RECORD bytes). */
void csv_format_bin_record(unsigned char *buf, const engine_setpoint_t *sp);

#endif
