/* csv_format.c - the text form of a setpoint.  See csv_format.h. */
#include "csv_format.h"

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

static const char header[] =
    "object,now_ns,t_s,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,ax_m_s2,ay_m_s2,az_m_s2,"
    "state,flags,cycle,track\n";

int csv_format_header(char *buf, size_t len)
{
    size_t n = sizeof header - 1;
    if (!buf || len < n + 1)
        return -1;
    memcpy(buf, header, n + 1);
    return (int)n;
}

static int object_ok(const char *o)
{
    size_t n = 0;
    for (; o[n]; n++) {
        unsigned char c = (unsigned char)o[n];
        if (c < 0x20 || c == 0x7f || c == ',' || c == '"')
            return 0;
    }
    return n <= CSV_FORMAT_OBJECT_MAX;
}

int csv_format_format(char *buf, size_t len, const char *object, const engine_setpoint_t *sp)
{
    if (!buf || !sp)
        return -1;
    if (!object)
        object = "";
    if (!object_ok(object))
        return -1;
    int n = snprintf(buf, len,
                     "%s,%" PRId64 ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                     "%.17g,%.17g,%.17g,%s,%" PRIu32 ",%" PRIu32 ",%" PRIu32 "\n",
                     object, sp->now_ns, sp->t_s,
                     sp->pos_m[0], sp->pos_m[1], sp->pos_m[2],
                     sp->vel_m_s[0], sp->vel_m_s[1], sp->vel_m_s[2],
                     sp->acc_m_s2[0], sp->acc_m_s2[1], sp->acc_m_s2[2],
                     engine_state_name(sp->state), sp->flags, sp->cycle, sp->track);
    if (n < 0 || (size_t)n >= len)
        return -1;
    return n;
}
