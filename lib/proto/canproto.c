/* canproto.c - trajd's CAN frames (see canproto.h for the layouts). */
#include "canproto.h"
#include "canproto_le.h"

#include <math.h>
#include <string.h>

#include "cia402.h"

static const char *const canproto_errors[CANPROTO_ERROR_COUNT] = {
    [CANPROTO_OK] = "ok",
    [CANPROTO_ELEN] = "wrong frame length or kind for this id",
    [CANPROTO_EMUX] = "unknown multiplexer value",
    [CANPROTO_EVALUE] = "forbidden field value",
    [CANPROTO_EID] = "not one of our ids",
    [CANPROTO_ECONFIG] = "invalid CAN id or profile configuration",
};

const char *canproto_strerror(int err)
{
    if (err < 0)
        err = -err;
    if (err >= CANPROTO_ERROR_COUNT)
        return "unknown canproto error";
    return canproto_errors[err];
}

int canproto_fd_len_valid(unsigned len)
{
    return len <= 8 || len == 12 || len == 16 || len == 20 || len == 24 || len == 32 || len == 48 ||
           len == 64;
}

/* ---- quantization ----------------------------------------------------------------- */

/*
 * The code nearest to x / scale, clamped to [lo, hi].  *clamped is set if x was
 * out of range or not finite (NaN is sent as 0: a setpoint frame must still go out).
 * Every scale is 10^-k, so 1 / scale rounds to an exact integer: x is multiplied
 * by it, and fma() gives the product's rounding error exactly, which decides the
 * values whose product rounded onto (or off) a half-code tie.  Dividing by the
 * inexact scale sent codes up to 1e-4 LSB beyond half an LSB from the value
 * (tests/oracle/test_canproto.py EncodersSendTheNearestCode).
 */
static int64_t quantize(double x, double scale, int64_t lo, int64_t hi, int *clamped)
{
    if (!isfinite(x)) {
        *clamped = 1;
        return isnan(x) ? 0 : (x > 0 ? hi : lo);
    }
    double inv = nearbyint(1.0 / scale);
    double p = x * inv;
    double e = fma(x, inv, -p); /* x * inv == p + e exactly */
    double r = nearbyint(p);
    /* p - r is exact (|p| < 2^53, r within 1/2 of p); ties to even are kept
     * only where the exact value is a tie. */
    double d = p - r; /* in [-1/2, 1/2]: the tests below are for d == +-1/2 */
    if (d >= 0.5 && e > 0)
        r += 1;
    else if (d <= -0.5 && e < 0)
        r -= 1;
    /* Compare in double: lo/hi are at most 2^48 in magnitude here, exact in a double. */
    if (r < (double)lo) {
        *clamped = 1;
        return lo;
    }
    if (r > (double)hi) {
        *clamped = 1;
        return hi;
    }
    return (int64_t)r;
}

static void frame_init(canproto_frame_t *f, uint32_t id, unsigned len, uint8_t flags)
{
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = (uint8_t)len;
    f->flags = flags;
}

/* ---- encoders --------------------------------------------------------------------- */

/* t and position raw values; returns 0, CANPROTO_CLAMPED or -CANPROTO_EVALUE. */
static int waypoint_raw(const engine_waypoint_t *wp, uint64_t *t_us, int64_t pos_um[ENGINE_AXES])
{
    int clamped = 0;
    if (!isfinite(wp->t_s))
        return -CANPROTO_EVALUE;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        if (!isfinite(wp->pos_m[a]))
            return -CANPROTO_EVALUE;
    *t_us = (uint64_t)quantize(wp->t_s, CANPROTO_WP_T_S_PER_BIT, 0, CANPROTO_U48_MAX, &clamped);
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        /* I48_MIN is the "not available" marker: never produce it */
        pos_um[a] = quantize(wp->pos_m[a], CANPROTO_WP_POS_M_PER_BIT, CANPROTO_I48_MIN + 1,
                             CANPROTO_I48_MAX, &clamped);
    return clamped ? CANPROTO_CLAMPED : 0;
}

int canproto_encode_waypoint(uint32_t id, const engine_waypoint_t *wp,
                             canproto_frame_t out[CANPROTO_WP_PARTS])
{
    uint64_t t_us;
    int64_t pos[ENGINE_AXES];
    int rc = waypoint_raw(wp, &t_us, pos);
    if (rc < 0)
        return rc;
    for (unsigned k = 0; k < CANPROTO_WP_PARTS; k++) {
        frame_init(&out[k], id, CANPROTO_WP_DLEN, 0);
        out[k].data[0] = (uint8_t)k; /* CANPROTO_MUX_TIME + k */
        out[k].data[1] = (uint8_t)wp->seq;
        put_le(&out[k].data[2], 6, k == 0 ? t_us : (uint64_t)pos[k - 1]);
    }
    return rc;
}

/* wp's velocity in VELOCITY's int16 fields (never -32768, "not available"). */
static int velocity_raw(const engine_waypoint_t *wp, int16_t v[ENGINE_AXES])
{
    int clamped = 0;
    for (unsigned a = 0; a < ENGINE_AXES; a++) {
        if (!isfinite(wp->vel_m_s[a]))
            return -CANPROTO_EVALUE;
        v[a] = (int16_t)quantize(wp->vel_m_s[a], CANPROTO_WP_VEL_M_S_PER_BIT, -32767, 32767,
                                 &clamped);
    }
    return clamped ? CANPROTO_CLAMPED : 0;
}

int canproto_encode_waypoint_vel(uint32_t id, const engine_waypoint_t *wp, canproto_frame_t *out)
{
    int16_t v[ENGINE_AXES];
    int rc = velocity_raw(wp, v);
    if (rc < 0)
        return rc;
    frame_init(out, id, CANPROTO_WP_DLEN, 0);
    out->data[0] = CANPROTO_MUX_VELOCITY;
    out->data[1] = (uint8_t)wp->seq;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        put_le(&out->data[2 + 2 * a], 2, (uint16_t)v[a]);
    return rc;
}

int canproto_encode_waypoint_fd(uint32_t id, const engine_waypoint_t *wp, canproto_frame_t *out)
{
    uint64_t t_us;
    int64_t pos[ENGINE_AXES];
    int rc = waypoint_raw(wp, &t_us, pos);
    if (rc < 0)
        return rc;
    frame_init(out, id, CANPROTO_WP_FD_DLEN, CANPROTO_F_FD);
    out->data[0] = CANPROTO_MUX_FD_WAYPOINT;
    out->data[1] = (uint8_t)wp->seq;
    put_le(&out->data[2], 6, t_us);
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        put_le(&out->data[8 + 6 * a], 6, (uint64_t)pos[a]);
    if (wp->has_vel == 1) {
        int16_t v[ENGINE_AXES];
        int rv = velocity_raw(wp, v);
        if (rv < 0)
            return rv;
        out->data[0] = CANPROTO_MUX_FD_WAYPOINT_VEL;
        for (unsigned a = 0; a < ENGINE_AXES; a++)
            put_le(&out->data[26 + 2 * a], 2, (uint16_t)v[a]);
        rc = rc ? rc : rv;
    }
    return rc;
}

int canproto_encode_command(uint32_t id, canproto_cmd_t cmd, canproto_frame_t *out)
{
    if (cmd < CANPROTO_CMD_FINISH || cmd >= CANPROTO_CMD_COUNT)
        return -CANPROTO_EVALUE;
    frame_init(out, id, CANPROTO_WP_DLEN, 0);
    out->data[0] = CANPROTO_MUX_COMMAND;
    out->data[2] = (uint8_t)cmd;
    return 0;
}

int canproto_encode_override(uint32_t id, unsigned percent, canproto_frame_t *out)
{
    if (percent > CANPROTO_OVERRIDE_MAX_PCT)
        return -CANPROTO_EVALUE;
    canproto_encode_command(id, CANPROTO_CMD_OVERRIDE, out);
    out->data[3] = (uint8_t)percent;
    return 0;
}

static uint8_t sp_state(const engine_setpoint_t *sp)
{
    return (uint8_t)((unsigned)sp->state & 0x7u);
}

/* Position field: the n/a marker without a position, else never the marker. */
static int64_t sp_pos_raw(const engine_setpoint_t *sp, unsigned a, int *clamped)
{
    if (sp->flags & ENGINE_SP_NO_POSITION)
        return CANPROTO_SP_POS_NA;
    return quantize(sp->pos_m[a], CANPROTO_SP_POS_M_PER_BIT, (int64_t)CANPROTO_SP_POS_NA + 1,
                    INT32_MAX, clamped);
}

int canproto_encode_setpoint(uint32_t id, const engine_setpoint_t *sp,
                             canproto_frame_t out[ENGINE_AXES])
{
    int clamped = 0, nopos = (sp->flags & ENGINE_SP_NO_POSITION) != 0;
    for (unsigned a = 0; a < ENGINE_AXES; a++) {
        canproto_frame_t *f = &out[a];
        frame_init(f, id, CANPROTO_SP_DLEN, 0);
        f->data[0] = (uint8_t)(a | (unsigned)sp_state(sp) << CANPROTO_SP_STATE_SHIFT |
                               ((sp->flags & ENGINE_SP_HOLD) || nopos ? CANPROTO_SP_HOLD : 0));
        f->data[1] = (uint8_t)sp->cycle;
        put_le(&f->data[2], 4, (uint64_t)sp_pos_raw(sp, a, &clamped));
        put_le(&f->data[6], 2,
               nopos ? 0
                     : (uint64_t)quantize(sp->vel_m_s[a], CANPROTO_SP_VEL_M_S_PER_BIT, INT16_MIN,
                                          INT16_MAX, &clamped));
    }
    return clamped ? CANPROTO_CLAMPED : 0;
}

int canproto_encode_setpoint_fd(uint32_t id, int brs, const engine_setpoint_t *sp,
                                canproto_frame_t *out)
{
    int clamped = 0;
    frame_init(out, id, CANPROTO_SP_FD_DLEN, CANPROTO_F_FD | (brs ? CANPROTO_F_BRS : 0));
    put_le(&out->data[0], 4, sp->cycle);
    int nopos = (sp->flags & ENGINE_SP_NO_POSITION) != 0;
    for (unsigned a = 0; a < ENGINE_AXES; a++) {
        put_le(&out->data[4 + 4 * a], 4, (uint64_t)sp_pos_raw(sp, a, &clamped));
        put_le(&out->data[16 + 4 * a], 4,
               nopos ? 0
                     : (uint64_t)quantize(sp->vel_m_s[a], CANPROTO_SPFD_VEL_M_S_PER_BIT, INT32_MIN,
                                          INT32_MAX, &clamped));
    }
    out->data[28] = sp_state(sp);
    out->data[29] = (uint8_t)sp->flags;
    put_le(&out->data[30], 2, sp->track);
    return clamped ? CANPROTO_CLAMPED : 0;
}

void canproto_encode_sync(uint32_t id, uint8_t counter, canproto_frame_t *out)
{
    frame_init(out, id, counter ? 1 : 0, 0);
    out->data[0] = counter;
}

static double axis_cpm(const canproto_ids_t *ids, unsigned axis)
{
    double c = ids->cia402_axis_counts_per_m[axis];
    return c > 0 ? c : ids->cia402_counts_per_m;
}

int32_t canproto_cia402_counts(const canproto_ids_t *ids, unsigned axis, double pos_m, int *clamped)
{
    if (axis >= CANPROTO_CIA402_AXES) {
        *clamped = 1;
        return 0;
    }
    double sign = ids->cia402_invert[axis] ? -1.0 : 1.0;
    int64_t lo = (int64_t)INT32_MIN - ids->cia402_offset[axis];
    int64_t hi = (int64_t)INT32_MAX - ids->cia402_offset[axis];
    /* the offset is added in integers, after rounding: exact */
    int64_t r = quantize(sign * pos_m * axis_cpm(ids, axis), 1.0, lo, hi, clamped);
    return (int32_t)(r + ids->cia402_offset[axis]);
}

double canproto_cia402_pos_m(const canproto_ids_t *ids, unsigned axis, int32_t inc)
{
    if (axis >= CANPROTO_CIA402_AXES)
        return NAN;
    double sign = ids->cia402_invert[axis] ? -1.0 : 1.0;
    return sign * (double)((int64_t)inc - ids->cia402_offset[axis]) / axis_cpm(ids, axis);
}

int canproto_encode_cia402(const canproto_ids_t *ids, unsigned axis, double pos_m,
                           canproto_frame_t *out)
{
    int clamped = 0;
    if (axis >= CANPROTO_CIA402_AXES || !ids->cia402_cob_id[axis])
        return -CANPROTO_ECONFIG;
    int32_t inc = canproto_cia402_counts(ids, axis, pos_m, &clamped);
    cia402_encode_rpdo(ids->cia402_cob_id[axis], ids->cia402_controlword,
                       ids->cia402_controlword_value, inc, out);
    return clamped ? CANPROTO_CLAMPED : 0;
}

static uint8_t sat8(uint32_t v)
{
    return v > 255 ? 255 : (uint8_t)v;
}

void canproto_encode_status(uint32_t id, const canproto_status_t *st, canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS_DLEN, 0);
    out->data[0] = (uint8_t)((st->state & CANPROTO_ST_STATE_MASK) |
                             (st->flags &
                              (CANPROTO_ST_CLAMPED | CANPROTO_ST_BUS_DOWN | CANPROTO_ST_TX_DROP |
                               CANPROTO_ST_OUT_FAULT | CANPROTO_ST_FAULT)));
    out->data[1] = (uint8_t)st->last_seq;
    out->data[2] = sat8(st->free);
    out->data[3] = (uint8_t)st->lost;
    out->data[4] = (uint8_t)st->rejected;
    out->data[5] = (uint8_t)st->malformed;
    out->data[6] = (uint8_t)st->dropped;
    out->data[7] = st->last_err;
}

static uint64_t sat_max(uint64_t v, uint64_t max)
{
    return v > max ? max : v;
}

void canproto_encode_status2_faults(uint32_t id, const canproto_st2_faults_t *p,
                                    canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_FAULTS;
    put_le(&out->data[1], 3, sat_max(p->out_lost, CANPROTO_ST2_U24_MAX));
    put_le(&out->data[4], 2, sat_max(p->out_errors, 0xFFFF));
    put_le(&out->data[6], 2, sat_max(p->cmd_refused, 0xFFFF));
}

void canproto_st2_rejected_from(const uint64_t rejected_by[ENGINE_ERROR_COUNT],
                                canproto_st2_rejected_t *out)
{
    out->backwards = rejected_by[ENGINE_EBACKWARDS];
    out->same_time = rejected_by[ENGINE_ESAMETIME];
    out->speed = rejected_by[ENGINE_ESPEED];
    out->accel = rejected_by[ENGINE_EACCEL];
    out->unconfirmed = rejected_by[ENGINE_EUNCONFIRMED];
    out->stale = rejected_by[ENGINE_ESTALE];
    out->other = rejected_by[ENGINE_ENOTFINITE] + rejected_by[ENGINE_ERANGE] +
                 rejected_by[ENGINE_ENUMERIC];
}

void canproto_encode_status2_rejected(uint32_t id, const canproto_st2_rejected_t *p,
                                      canproto_frame_t *out)
{
    const uint64_t v[7] = {p->backwards,   p->same_time, p->speed, p->accel,
                           p->unconfirmed, p->stale,     p->other};
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_REJECTED;
    for (int i = 0; i < 7; i++)
        out->data[1 + i] = (uint8_t)sat_max(v[i], 0xFF);
}

/* v / lsb to the nearest integer, saturated at +-max (v finite). */
static int64_t sat_signed(double v, double lsb, int64_t max)
{
    if (v >= (double)max * lsb)
        return max;
    if (v <= -(double)max * lsb)
        return -max;
    return llround(v / lsb);
}

void canproto_encode_status2_clock(uint32_t id, const canproto_st2_clock_t *p,
                                   canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_CLOCK;
    int64_t age = isfinite(p->age_s)
                      ? sat_signed(p->age_s, CANPROTO_ST2_AGE_S_PER_BIT, CANPROTO_ST2_AGE_MAX)
                      : CANPROTO_ST2_AGE_NA;
    put_le(&out->data[1], 3, (uint64_t)age & 0xFFFFFFu);
    int64_t drift = isfinite(p->drift_ppm)
                        ? sat_signed(p->drift_ppm, CANPROTO_ST2_DRIFT_PPM_PER_BIT, 32767)
                        : CANPROTO_ST2_DRIFT_NA;
    put_le(&out->data[4], 2, (uint64_t)drift & 0xFFFFu);
    out->data[6] = p->clocked;
}

void canproto_encode_status2_time(uint32_t id, double t_s, canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_TIME;
    int64_t us = isfinite(t_s)
                     ? sat_signed(t_s, CANPROTO_ST2_TIME_S_PER_BIT, -(CANPROTO_ST2_TIME_NA + 1))
                     : CANPROTO_ST2_TIME_NA;
    put_le(&out->data[1], 7, (uint64_t)us & 0xFFFFFFFFFFFFFFull);
}

int canproto_decode_status2_time(const canproto_frame_t *f, double *t_s)
{
    *t_s = NAN;
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_TIME)
        return -CANPROTO_EMUX;
    int64_t us = sext(get_le(&f->data[1], 7), 56);
    *t_s = us == CANPROTO_ST2_TIME_NA ? NAN : (double)us * CANPROTO_ST2_TIME_S_PER_BIT;
    return 0;
}

int canproto_decode_status2_clock(const canproto_frame_t *f, canproto_st2_clock_t *out)
{
    memset(out, 0, sizeof *out);
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_CLOCK)
        return -CANPROTO_EMUX;
    int64_t age = sext(get_le(&f->data[1], 3), 24);
    out->age_s = age == CANPROTO_ST2_AGE_NA ? NAN : (double)age * CANPROTO_ST2_AGE_S_PER_BIT;
    int64_t drift = sext(get_le(&f->data[4], 2), 16);
    out->drift_ppm = drift == CANPROTO_ST2_DRIFT_NA
                         ? NAN
                         : (double)drift * CANPROTO_ST2_DRIFT_PPM_PER_BIT;
    out->clocked = f->data[6];
    return 0;
}

void canproto_encode_status2_drive(uint32_t id, const canproto_status2_drive_t *d,
                                   canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_DRIVE;
    out->data[1] = (uint8_t)((d->state[0] & 0x0F) | (d->state[1] & 0x0F) << 4);
    out->data[2] = (uint8_t)((d->state[2] & 0x0F) | (d->hb_lost ? 0x40 : 0) | (d->held ? 0x80 : 0));
    put_le(&out->data[3], 2, d->statusword);
    out->data[5] = d->nmt;
    put_le(&out->data[6], 2, d->emcy);
}

/* ---- decoders ------------------------------------------------------------------------ */

void canproto_encode_status2_bus(uint32_t id, const canproto_st2_bus_t *p, canproto_frame_t *out)
{
    frame_init(out, id, CANPROTO_STATUS2_DLEN, 0);
    out->data[0] = CANPROTO_ST2_BUS;
    out->data[1] = p->state;
    out->data[2] = p->tx_err;
    out->data[3] = p->rx_err;
    put_le(&out->data[4], 2, sat_max(p->bus_offs, 0xFFFF));
    put_le(&out->data[6], 2, sat_max(p->err_frames, 0xFFFF));
}

int canproto_decode_status2_bus(const canproto_frame_t *f, canproto_st2_bus_t *out)
{
    memset(out, 0, sizeof *out);
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_BUS)
        return -CANPROTO_EMUX;
    out->state = f->data[1];
    out->tx_err = f->data[2];
    out->rx_err = f->data[3];
    out->bus_offs = get_le(&f->data[4], 2);
    out->err_frames = get_le(&f->data[6], 2);
    return 0;
}

int canproto_status2_page(const canproto_frame_t *f)
{
    if (f->len != CANPROTO_STATUS2_DLEN ||
        (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF | CANPROTO_F_FD)))
        return -CANPROTO_ELEN;
    if (f->data[0] == 0 || f->data[0] >= CANPROTO_ST2_PAGES)
        return -CANPROTO_EMUX;
    return f->data[0];
}

int canproto_decode_status2_faults(const canproto_frame_t *f, canproto_st2_faults_t *out)
{
    memset(out, 0, sizeof *out);
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_FAULTS)
        return -CANPROTO_EMUX;
    out->out_lost = get_le(&f->data[1], 3);
    out->out_errors = get_le(&f->data[4], 2);
    out->cmd_refused = get_le(&f->data[6], 2);
    return 0;
}

int canproto_decode_status2_rejected(const canproto_frame_t *f, canproto_st2_rejected_t *out)
{
    memset(out, 0, sizeof *out);
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_REJECTED)
        return -CANPROTO_EMUX;
    out->backwards = f->data[1];
    out->same_time = f->data[2];
    out->speed = f->data[3];
    out->accel = f->data[4];
    out->unconfirmed = f->data[5];
    out->stale = f->data[6];
    out->other = f->data[7];
    return 0;
}

int canproto_decode_setpoint(const canproto_frame_t *f, canproto_setpoint_t *out)
{
    memset(out, 0, sizeof *out);
    if (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF))
        return -CANPROTO_ELEN;
    if (f->flags & CANPROTO_F_FD) {
        if (f->len != CANPROTO_SP_FD_DLEN)
            return -CANPROTO_ELEN;
        out->cycle = (uint32_t)get_le(&f->data[0], 4);
        for (unsigned a = 0; a < ENGINE_AXES; a++) {
            int64_t raw = sext(get_le(&f->data[4 + 4 * a], 4), 32);
            out->pos_m[a] = raw == CANPROTO_SP_POS_NA ? NAN
                                                      : (double)raw * CANPROTO_SP_POS_M_PER_BIT;
            out->vel_m_s[a] = (double)sext(get_le(&f->data[16 + 4 * a], 4), 32) *
                              CANPROTO_SPFD_VEL_M_S_PER_BIT;
        }
        out->state = f->data[28];
        out->flags = f->data[29];
        out->track = (uint16_t)get_le(&f->data[30], 2);
        return out->state > ENGINE_STATE_FINISHED ? -CANPROTO_EVALUE : 0;
    }
    if (f->len != CANPROTO_SP_DLEN)
        return -CANPROTO_ELEN;
    unsigned axis = f->data[0] & CANPROTO_SP_AXIS_MASK;
    if (axis >= ENGINE_AXES || (f->data[0] & 0x0Cu))
        return -CANPROTO_EVALUE;
    out->axis = axis;
    out->state = (uint8_t)((f->data[0] & CANPROTO_SP_STATE_MASK) >> CANPROTO_SP_STATE_SHIFT);
    out->flags = (f->data[0] & CANPROTO_SP_HOLD) ? ENGINE_SP_HOLD : 0;
    out->cycle = f->data[1];
    int64_t raw = sext(get_le(&f->data[2], 4), 32);
    if (raw == CANPROTO_SP_POS_NA) {
        out->pos_m[axis] = NAN;
        out->flags |= ENGINE_SP_NO_POSITION;
    } else {
        out->pos_m[axis] = (double)raw * CANPROTO_SP_POS_M_PER_BIT;
    }
    out->vel_m_s[axis] = (double)sext(get_le(&f->data[6], 2), 16) * CANPROTO_SP_VEL_M_S_PER_BIT;
    return out->state > ENGINE_STATE_FINISHED ? -CANPROTO_EVALUE : 0;
}

int canproto_decode_status(const canproto_frame_t *f, canproto_status_t *out)
{
    memset(out, 0, sizeof *out);
    if (f->len != CANPROTO_STATUS_DLEN ||
        (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF)))
        return -CANPROTO_ELEN;
    out->state = f->data[0] & CANPROTO_ST_STATE_MASK;
    out->flags = f->data[0] & (CANPROTO_ST_CLAMPED | CANPROTO_ST_BUS_DOWN | CANPROTO_ST_TX_DROP |
                               CANPROTO_ST_OUT_FAULT | CANPROTO_ST_FAULT);
    out->last_seq = f->data[1];
    out->free = f->data[2];
    out->lost = f->data[3];
    out->rejected = f->data[4];
    out->malformed = f->data[5];
    out->dropped = f->data[6];
    out->last_err = f->data[7];
    return 0;
}

int canproto_decode_status2_drive(const canproto_frame_t *f, canproto_status2_drive_t *out)
{
    memset(out, 0, sizeof *out);
    if (f->len != CANPROTO_STATUS2_DLEN ||
        (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF | CANPROTO_F_FD)))
        return -CANPROTO_ELEN;
    if (f->data[0] != CANPROTO_ST2_DRIVE)
        return -CANPROTO_EMUX;
    out->state[0] = f->data[1] & 0x0F;
    out->state[1] = f->data[1] >> 4;
    out->state[2] = f->data[2] & 0x0F;
    out->hb_lost = !!(f->data[2] & 0x40);
    out->held = !!(f->data[2] & 0x80);
    out->statusword = (uint16_t)(f->data[3] | f->data[4] << 8);
    out->nmt = f->data[5];
    out->emcy = (uint16_t)(f->data[6] | f->data[7] << 8);
    return 0;
}
