/*
 * spcsv.h - the one text form of a setpoint, shared by trajd's CSV/stdout
 * output and trajreplay, so their outputs can be compared byte for byte.
 * Columns: object,now_ns,t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,ay_m_s2,az_m_s2,state,flags,cycle,track
 * Numbers are printed with %.17g so they round-trip exactly.
 */
#ifndef TRAJD_SPCSV_H
#define TRAJD_SPCSV_H

#include <stddef.h>
#include "engine.h"

/* Write the header line (with '\n') into buf.  Returns its length, or -1 if it does not fit. */
int spcsv_header(char *buf, size_t len);

/* Write one setpoint line (with '\n').  Returns its length, or -1 if it does not fit. */
int spcsv_format(char *buf, size_t len, const char *object, const engine_setpoint_t *sp);

#endif
