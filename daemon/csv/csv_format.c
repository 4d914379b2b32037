/* csv_format.c - the text form of a setpoint.  See csv_format.h. */
#include "csv_format.h"
#include "csv_fixed.h"
#include "csv_shortest.h"

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

/* The previous default: printf's %.17g (17 significant digits, also round-trips,
 * but longer and about 8 times slower; trajreplay --precision g17). */
static int format_g17(char *buf, size_t len, const char *object, const engine_setpoint_t *sp)
{
    int n = snprintf(buf, len,
                     "%s,%" PRId64 ",%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                     "%.17g,%.17g,%.17g,%s,%" PRIu32 ",%" PRIu32 ",%" PRIu32 "\n",
                     object, sp->now_ns, sp->t_s, sp->pos_m[0], sp->pos_m[1], sp->pos_m[2],
                     sp->vel_m_s[0], sp->vel_m_s[1], sp->vel_m_s[2], sp->acc_m_s2[0],
                     sp->acc_m_s2[1], sp->acc_m_s2[2], engine_state_name(sp->state), sp->flags,
                     sp->cycle, sp->track);
    if (n < 0 || (size_t)n >= len)
        return -1;
    return n;
}

int csv_format_format(char *buf, size_t len, const char *object, const engine_setpoint_t *sp)
{
    return csv_format_format_prec(buf, len, object, sp, CSV_PREC_SHORTEST);
}

int csv_format_append(char *buf, size_t len, int n, const char *cols)
{
    size_t m = strlen(cols);
    if (n < 1 || buf[n - 1] != '\n' || (size_t)n + m + 1 > len)
        return -1;
    memcpy(buf + n - 1, cols, m);
    buf[n - 1 + m] = '\n';
    buf[n + m] = '\0';
    return n + (int)m;
}

int csv_format_add_age(char *buf, size_t len, int n, const engine_setpoint_t *sp)
{
    char col[CSV_SHORTEST_MAX + 2] = ",age_s";
    if (sp)
        col[1 + csv_shortest(col + 1, sp->age_s)] = '\0'; /* as the other numbers; NaN: nan */
    return csv_format_append(buf, len, n, col);
}

/* Decimal of a uint64 at o; returns the length. */
static int put_u64(char *o, uint64_t v)
{
    char tmp[20];
    int i = 20;
    do {
        tmp[--i] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    memcpy(o, tmp + i, (size_t)(20 - i));
    return 20 - i;
}

int csv_format_format_prec(char *buf, size_t len, const char *object, const engine_setpoint_t *sp,
                           int prec)
{
    if (!buf || !sp || prec < CSV_PREC_G17)
        return -1;
    if (!object)
        object = "";
    if (!object_ok(object))
        return -1;
    if (prec == CSV_PREC_G17)
        return format_g17(buf, len, object, sp);
    const char *state = engine_state_name(sp->state);
    size_t on = strlen(object), sn = strlen(state);
    /* worst case: 10 doubles, 4 integers, the names, 16 separators */
    size_t need = prec == CSV_PREC_SHORTEST ? 10 * (CSV_SHORTEST_LEN + 1) + CSV_SHORTEST_MAX
                                            : 10 * (CSV_FIXED_MAX + 1);
    if (len < on + sn + need + 4 * 21 + 2) {
        /* a short buffer: format into a full one and copy if it fits */
        static _Thread_local char big[CSV_FIXED_MAX * 12 + 256];
        int n = csv_format_format_prec(big, sizeof big, object, sp, prec);
        if (n < 0 || (size_t)n >= len)
            return -1;
        memcpy(buf, big, (size_t)n + 1);
        return n;
    }
    char *o = buf;
    memcpy(o, object, on);
    o += on;
    *o++ = ',';
    if (sp->now_ns < 0) {
        *o++ = '-';
        o += put_u64(o, 0 - (uint64_t)sp->now_ns);
    } else {
        o += put_u64(o, (uint64_t)sp->now_ns);
    }
    const double v[10] = {sp->t_s,         sp->pos_m[0],   sp->pos_m[1],   sp->pos_m[2],
                          sp->vel_m_s[0],  sp->vel_m_s[1], sp->vel_m_s[2], sp->acc_m_s2[0],
                          sp->acc_m_s2[1], sp->acc_m_s2[2]};
    for (int k = 0; k < 10; k++) {
        *o++ = ',';
        o += prec == CSV_PREC_SHORTEST ? csv_shortest(o, v[k]) : csv_fixed(o, v[k], prec);
    }
    *o++ = ',';
    memcpy(o, state, sn);
    o += sn;
    const uint32_t u[3] = {sp->flags, sp->cycle, sp->track};
    for (int k = 0; k < 3; k++) {
        *o++ = ',';
        o += put_u64(o, u[k]);
    }
    *o++ = '\n';
    *o = '\0';
    return (int)(o - buf);
}

static void put_le(unsigned char *b, uint64_t v, int n)
{
    for (int i = 0; i < n; i++)
        b[i] = (unsigned char)(v >> (8 * i));
}

static void put_f64(unsigned char *b, double x)
{
    uint64_t v;
    memcpy(&v, &x, sizeof v);
    put_le(b, v, 8);
}

void csv_format_bin_header(unsigned char *buf, const char *object)
{
    memset(buf, 0, CSV_BIN_HEADER);
    memcpy(buf, CSV_BIN_MAGIC, 8);
    put_le(buf + 8, CSV_BIN_HEADER, 4);
    put_le(buf + 12, CSV_BIN_RECORD, 4);
    if (object) {
        size_t n = strlen(object);
        memcpy(buf + 16, object, n < SPFILE_OBJECT_MAX ? n : SPFILE_OBJECT_MAX);
    }
}

void csv_format_bin_record(unsigned char *buf, const engine_setpoint_t *sp)
{
    put_le(buf, (uint64_t)sp->now_ns, 8);
    put_f64(buf + 8, sp->t_s);
    for (int k = 0; k < 3; k++) {
        put_f64(buf + 16 + 8 * k, sp->pos_m[k]);
        put_f64(buf + 40 + 8 * k, sp->vel_m_s[k]);
        put_f64(buf + 64 + 8 * k, sp->acc_m_s2[k]);
    }
    put_le(buf + 88, (uint32_t)sp->state, 4);
    put_le(buf + 92, sp->flags, 4);
    put_le(buf + 96, sp->cycle, 4);
    put_le(buf + 100, sp->track, 4);
    put_le(buf + 104, 0, 8);
}
