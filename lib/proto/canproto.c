/* canproto.c - trajd's CAN frames (see canproto.h for the layouts). */
#include "canproto.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

/* ---- little-endian fields ---------------------------------------------------- */

static void put_le(uint8_t *p, unsigned nbytes, uint64_t v)
{
    for (unsigned i = 0; i < nbytes; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

static uint64_t get_le(const uint8_t *p, unsigned nbytes)
{
    uint64_t v = 0;
    for (unsigned i = 0; i < nbytes; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

/* Sign-extend the low nbits of v. */
static int64_t sext(uint64_t v, unsigned nbits)
{
    uint64_t m = 1ull << (nbits - 1);
    v &= (m << 1) - 1;
    return (int64_t)((v ^ m) - m);
}

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

/* ---- ids ----------------------------------------------------------------------- */

void canproto_ids_default(canproto_ids_t *ids, unsigned n)
{
    memset(ids, 0, sizeof *ids);
    ids->waypoint_id = CANPROTO_ID_WAYPOINT_BASE + n;
    ids->waypoint_fd_id = CANPROTO_ID_WAYPOINT_FD_BASE + n;
    ids->setpoint_id = CANPROTO_ID_SETPOINT_BASE + n;
    ids->setpoint_fd_id = CANPROTO_ID_SETPOINT_FD_BASE + n;
    ids->status_id = CANPROTO_ID_STATUS_BASE + n;
    ids->status2_id = CANPROTO_ID_STATUS2_BASE + n;
    ids->own = 1;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        ids->cia402_cob_id[a] = CANPROTO_CIA402_RPDO1_BASE + 1 + CANPROTO_CIA402_AXES * n + a;
    ids->cia402_counts_per_m = 10000.0; /* 0.1 mm per increment */
    ids->cia402_controlword_value = 0x000F;
}

unsigned canproto_ids_in_use(const canproto_ids_t *ids, uint32_t out[CANPROTO_IDS_MAX])
{
    unsigned n = 0;
    out[n++] = ids->waypoint_id;
    if (ids->fd)
        out[n++] = ids->waypoint_fd_id;
    if (ids->own)
        out[n++] = ids->fd ? ids->setpoint_fd_id : ids->setpoint_id;
    out[n++] = ids->status_id;
    out[n++] = ids->status2_id;
    if (ids->cia402)
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
            if (ids->cia402_cob_id[a])
                out[n++] = ids->cia402_cob_id[a];
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (canproto_cia402_tpdo(ids, a))
            out[n++] = canproto_cia402_tpdo(ids, a);
    return n;
}

unsigned canproto_cia402_node(const canproto_ids_t *ids, unsigned axis)
{
    if (!ids->cia402 || axis >= CANPROTO_CIA402_AXES || !ids->cia402_cob_id[axis])
        return 0;
    return ids->cia402_cob_id[axis] & 0x7Fu;
}

uint32_t canproto_cia402_tpdo(const canproto_ids_t *ids, unsigned axis)
{
    if (!ids->cia402 || !(ids->cia402_feedback || ids->cia402_enable) ||
        axis >= CANPROTO_CIA402_AXES || !ids->cia402_cob_id[axis])
        return 0;
    return ids->cia402_tpdo_id[axis]
               ? ids->cia402_tpdo_id[axis]
               : CANPROTO_CIA402_TPDO1_BASE + (ids->cia402_cob_id[axis] & 0x7Fu);
}

int canproto_ids_check(const canproto_ids_t *ids, const char **why)
{
    uint32_t use[CANPROTO_IDS_MAX];
    unsigned n = canproto_ids_in_use(ids, use);
    const char *w = NULL;

    for (unsigned i = 0; i < n && !w; i++) {
        if (use[i] > CANPROTO_SFF_MASK)
            w = "CAN ids must be 11-bit (0..0x7FF)";
        for (unsigned j = 0; j < i && !w; j++)
            if (use[i] == use[j])
                w = "an object uses the same CAN id twice";
    }
    if (!w && ids->cia402) {
        /* > 0 and finite; also excludes NaN, for which both comparisons fail */
        if (!(ids->cia402_counts_per_m > 0 && ids->cia402_counts_per_m < 1e12))
            w = "cia402 counts per metre must be > 0 and finite";
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES && !w; a++)
            if (!(ids->cia402_axis_counts_per_m[a] >= 0 && ids->cia402_axis_counts_per_m[a] < 1e12))
                w = "cia402 counts per metre of an axis must be > 0 and finite (0: the object's)";
        unsigned any = 0;
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
            any |= ids->cia402_cob_id[a] != 0;
            if (ids->cia402_enable && ids->cia402_cob_id[a] && !(ids->cia402_cob_id[a] & 0x7Fu))
                w = "cia402_enable: the node-id (low 7 bits of a COB-id) must be 1..127";
        }
        if (!w && !any)
            w = "cia402 enabled but no axis has a COB-id";
    }
    if (!w && !ids->own && !ids->cia402)
        w = "an object must send its own setpoints, CiA 402 RPDOs, or both";
    if (why)
        *why = w;
    return w ? -CANPROTO_ECONFIG : 0;
}

unsigned canproto_ids_rx(const canproto_ids_t *ids, uint32_t *out, unsigned max)
{
    unsigned n = 0;
    if (n < max)
        out[n] = ids->waypoint_id;
    n++;
    if (ids->fd) {
        if (n < max)
            out[n] = ids->waypoint_fd_id;
        n++;
    }
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (canproto_cia402_tpdo(ids, a)) {
            if (n < max)
                out[n] = canproto_cia402_tpdo(ids, a);
            n++;
        }
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        unsigned node = canproto_cia402_node(ids, a);
        if (!ids->cia402_enable || !node)
            continue;
        const uint32_t bring[3] = {0x580u + node, 0x700u + node, 0x080u + node};
        for (unsigned k = 0; k < 3; k++) {
            if (n < max)
                out[n] = bring[k];
            n++;
        }
    }
    return n;
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
    return canproto_encode_cia402_cw(ids, axis, pos_m, ids->cia402_controlword_value, out);
}

int canproto_encode_cia402_cw(const canproto_ids_t *ids, unsigned axis, double pos_m, uint16_t cw,
                              canproto_frame_t *out)
{
    int clamped = 0;
    if (axis >= CANPROTO_CIA402_AXES || !ids->cia402_cob_id[axis])
        return -CANPROTO_ECONFIG;
    int64_t inc = canproto_cia402_counts(ids, axis, pos_m, &clamped);
    if (ids->cia402_controlword) {
        frame_init(out, ids->cia402_cob_id[axis], 6, 0);
        put_le(&out->data[0], 2, cw);
        put_le(&out->data[2], 4, (uint64_t)inc);
    } else {
        frame_init(out, ids->cia402_cob_id[axis], 4, 0);
        put_le(&out->data[0], 4, (uint64_t)inc);
    }
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

/* ---- reassembly ------------------------------------------------------------------------- */

void canproto_rx_init(canproto_rx_t *rx, canproto_slot_t *slots, unsigned nslots)
{
    memset(rx, 0, sizeof *rx);
    rx->slots = slots;
    rx->nslots = nslots;
    canproto_rx_restart(rx);
}

void canproto_rx_restart(canproto_rx_t *rx)
{
    for (unsigned i = 0; i < rx->nslots; i++)
        memset(&rx->slots[i], 0, sizeof rx->slots[i]);
    rx->have_last = 0;
    rx->last_seq = 0;
}

static int malformed(canproto_rx_t *rx, int err)
{
    rx->st.malformed++;
    rx->st.malformed_by[err]++;
    return -err;
}

/* Signed distance of seq8 ahead of the last consumed waypoint (-128..127). */
static int seq_ahead(const canproto_rx_t *rx, uint8_t seq8)
{
    return (int)(int8_t)(uint8_t)(seq8 - (uint8_t)rx->last_seq);
}

/*
 * Duplicate or stale (only with a sequence history)?  Counts and returns 1
 * if the frame is to be ignored.
 */
static int seq_old(canproto_rx_t *rx, uint8_t seq8)
{
    if (!rx->have_last)
        return 0;
    int d = seq_ahead(rx, seq8);
    if (d == 0) {
        rx->st.duplicates++;
        return 1;
    }
    if (d < 0) {
        rx->st.out_of_order++;
        return 1;
    }
    return 0;
}

static void fill_out(const canproto_rx_t *rx, uint8_t seq8, uint64_t t_us,
                     const int64_t pos_um[ENGINE_AXES], canproto_rx_out_t *out)
{
    memset(out, 0, sizeof *out);
    /* Divide by the exact 1e6 rather than multiply by the inexact 1e-6: the
     * result is then the correctly rounded value of the decimal number, the
     * same double strtod gives for a track file with 6 decimals, so CAN input
     * and a replayed file drive the engine bit-identically. */
    out->wp.t_s = (double)t_us / CANPROTO_WP_BITS_PER_S;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        out->wp.pos_m[a] = (double)pos_um[a] / CANPROTO_WP_BITS_PER_M;
    if (rx->have_last) {
        int d = seq_ahead(rx, seq8); /* > 0: seq_old() ruled the rest out */
        out->wp.seq = rx->last_seq + (uint32_t)d;
        out->lost_before = (uint32_t)(d - 1);
    } else {
        out->wp.seq = seq8;
    }
}

static canproto_slot_t *slot_for(canproto_rx_t *rx, uint8_t seq8)
{
    /* nslots >= 1 (canproto_rx_init's contract), so slot 0 exists: the search
     * for the oldest starts there (it only matters when every slot is used) */
    canproto_slot_t *free_slot = NULL, *oldest = &rx->slots[0];
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (s->used && s->seq8 == seq8)
            return s;
        if (!s->used && !free_slot)
            free_slot = s;
        /* oldest = the one opened first: lowest arrival stamp */
        if (s->used && s->stamp < oldest->stamp)
            oldest = s;
    }
    canproto_slot_t *s = free_slot;
    if (!s) {
        /* every slot holds a partial waypoint: abandon the oldest */
        rx->st.incomplete++;
        s = oldest;
    }
    memset(s, 0, sizeof *s);
    s->used = 1;
    s->seq8 = seq8;
    s->stamp = ++rx->stamp;
    return s;
}

int canproto_rx_frame(canproto_rx_t *rx, const canproto_frame_t *f, int is_fd_id,
                      canproto_rx_out_t *out)
{
    rx->st.frames++;
    if (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF))
        return malformed(rx, CANPROTO_ELEN);

    if (is_fd_id) {
        if (!(f->flags & CANPROTO_F_FD) || f->len != CANPROTO_WP_FD_DLEN)
            return malformed(rx, CANPROTO_ELEN);
        if (f->data[0] != CANPROTO_MUX_FD_WAYPOINT)
            return malformed(rx, CANPROTO_EMUX);
        for (unsigned i = 26; i < CANPROTO_WP_FD_DLEN; i++)
            if (f->data[i])
                return malformed(rx, CANPROTO_EVALUE);
        int64_t pos[ENGINE_AXES];
        for (unsigned a = 0; a < ENGINE_AXES; a++) {
            pos[a] = sext(get_le(&f->data[8 + 6 * a], 6), 48);
            if (pos[a] == CANPROTO_I48_MIN)
                return malformed(rx, CANPROTO_EVALUE);
        }
        uint8_t seq8 = f->data[1];
        if (seq_old(rx, seq8))
            return CANPROTO_RX_NONE;
        fill_out(rx, seq8, get_le(&f->data[2], 6), pos, out);
        rx->st.completed++;
        return CANPROTO_RX_WAYPOINT;
    }

    if ((f->flags & CANPROTO_F_FD) || f->len != CANPROTO_WP_DLEN)
        return malformed(rx, CANPROTO_ELEN);
    unsigned mux = f->data[0];
    if (mux == CANPROTO_MUX_COMMAND) {
        unsigned cmd = f->data[2];
        if (cmd < CANPROTO_CMD_FINISH || cmd >= CANPROTO_CMD_COUNT)
            return malformed(rx, CANPROTO_EVALUE);
        unsigned arg = f->data[3];
        if (cmd != CANPROTO_CMD_OVERRIDE && arg != 0) /* above 200 %: the receiver refuses */
            return malformed(rx, CANPROTO_EVALUE);
        for (unsigned i = 4; i < CANPROTO_WP_DLEN; i++)
            if (f->data[i])
                return malformed(rx, CANPROTO_EVALUE);
        memset(out, 0, sizeof *out);
        out->cmd = (canproto_cmd_t)cmd;
        out->cmd_arg = arg;
        rx->st.commands++;
        return CANPROTO_RX_COMMAND;
    }
    if (mux > CANPROTO_MUX_Z)
        return malformed(rx, CANPROTO_EMUX);
    uint64_t raw = get_le(&f->data[2], 6);
    if (mux != CANPROTO_MUX_TIME && sext(raw, 48) == CANPROTO_I48_MIN)
        return malformed(rx, CANPROTO_EVALUE);

    uint8_t seq8 = f->data[1];
    if (seq_old(rx, seq8))
        return CANPROTO_RX_NONE;
    canproto_slot_t *s = slot_for(rx, seq8);
    unsigned bit = 1u << mux;
    if (s->have & bit)
        rx->st.duplicates++; /* the same part twice: the later one wins */
    s->have |= (uint8_t)bit;
    if (mux == CANPROTO_MUX_TIME)
        s->t_us = raw;
    else
        s->pos_um[mux - 1] = sext(raw, 48);
    if (s->have != (1u << CANPROTO_WP_PARTS) - 1)
        return CANPROTO_RX_NONE;
    fill_out(rx, seq8, s->t_us, s->pos_um, out);
    memset(s, 0, sizeof *s);
    rx->st.completed++;
    return CANPROTO_RX_WAYPOINT;
}

void canproto_rx_consume(canproto_rx_t *rx, const canproto_rx_out_t *out)
{
    rx->st.lost += out->lost_before;
    rx->last_seq = out->wp.seq;
    rx->have_last = 1;
    /* partial waypoints at or behind the consumed one can never be used now */
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (s->used && seq_ahead(rx, s->seq8) <= 0) {
            rx->st.incomplete++;
            memset(s, 0, sizeof *s);
        }
    }
}

/* ---- bus load ----------------------------------------------------------------------------- */

double canproto_frame_time_s(unsigned len, int fd, int brs, int eff, double bitrate,
                             double data_bitrate)
{
    if (!(bitrate > 0) || (fd && brs && !(data_bitrate > 0)))
        return -1;
    if (fd ? !canproto_fd_len_valid(len) : len > 8)
        return -1;
    if (!fd) {
        unsigned g = eff ? 54 : 34; /* bits exposed to stuffing before the data */
        unsigned bits = 8 * len + g + 13 + (g + 8 * len - 1) / 4;
        return bits / bitrate;
    }
    /* Arbitration phase: SOF, id, RRS/SRR, IDE, (id ext, RRS), FDF, res, BRS. */
    unsigned arb = eff ? 36 : 17;
    unsigned arb_stuff = (arb - 1) / 4;
    /* Data phase: ESI, DLC, data with dynamic stuffing; stuff count and CRC
     * with fixed stuff bits (one before the stuff count, one every 4 bits). */
    unsigned dyn = 5 + 8 * len;
    unsigned crc = len <= 16 ? 17 : 21;
    unsigned fsb = len <= 16 ? 6 : 7;
    unsigned data_bits = dyn + dyn / 4 + 4 + crc + fsb;
    unsigned tail = 13; /* CRC delimiter, ACK, ACK delimiter, EOF 7, IFS 3 */
    double data_rate = (brs && data_bitrate > 0) ? data_bitrate : bitrate;
    return (arb + arb_stuff + tail) / bitrate + data_bits / data_rate;
}

double canproto_frame_bits(unsigned len, int fd, int brs, int eff, double bitrate,
                           double data_bitrate)
{
    double t = canproto_frame_time_s(len, fd, brs, eff, bitrate, data_bitrate);
    return t < 0 ? t : t * bitrate;
}

double canproto_busload(const canproto_ids_t *ids, unsigned nobj, int sync, unsigned sync_dlen,
                        const canproto_traffic_t *tr, double bitrate, double data_bitrate)
{
    double busy_s = 0, t;
    if (!(bitrate > 0) || !(tr->rate_hz >= 0) || !(tr->status_hz >= 0) || !(tr->waypoint_hz >= 0) ||
        sync_dlen > 1)
        return -1;
    if (sync) {
        if ((t = canproto_frame_time_s(sync_dlen, 0, 0, 0, bitrate, 0)) < 0)
            return -1;
        busy_s += tr->rate_hz * t;
    }
    for (unsigned i = 0; i < nobj; i++) {
        const canproto_ids_t *o = &ids[i];
        int brs = o->fd && o->brs;
        if (o->own) {
            t = o->fd ? canproto_frame_time_s(CANPROTO_SP_FD_DLEN, 1, brs, 0, bitrate, data_bitrate)
                      : ENGINE_AXES * canproto_frame_time_s(CANPROTO_SP_DLEN, 0, 0, 0, bitrate, 0);
            if (t < 0)
                return -1;
            busy_s += tr->rate_hz * t;
        }
        if (o->cia402)
            for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
                if (o->cia402_cob_id[a])
                    busy_s += tr->rate_hz * canproto_frame_time_s(o->cia402_controlword ? 6 : 4, 0,
                                                                  0, 0, bitrate, 0);
        /* STATUS and the STATUS2 page that follows it */
        busy_s += tr->status_hz *
                  (canproto_frame_time_s(CANPROTO_STATUS_DLEN, 0, 0, 0, bitrate, 0) +
                   canproto_frame_time_s(CANPROTO_STATUS2_DLEN, 0, 0, 0, bitrate, 0));
        t = o->fd
                ? canproto_frame_time_s(CANPROTO_WP_FD_DLEN, 1, brs, 0, bitrate, data_bitrate)
                : CANPROTO_WP_PARTS * canproto_frame_time_s(CANPROTO_WP_DLEN, 0, 0, 0, bitrate, 0);
        if (t < 0)
            return -1;
        busy_s += tr->waypoint_hz * t;
    }
    return busy_s;
}

/* ---- description tables ------------------------------------------------------------------ */

/* Range of a raw field in physical units. */
#define U_MAX(bits) ((double)((1ull << (bits)) - 1))
#define S_MIN(bits) (-(double)(1ull << ((bits)-1)))
#define S_MAX(bits) ((double)((1ull << ((bits)-1)) - 1))
#define SIG_U(name, mux, start, bits, factor, unit)                                                \
    {                                                                                              \
        name, mux, start, bits, 0, factor, 0, 0, U_MAX(bits) * (factor), unit                      \
    }
#define SIG_S(name, mux, start, bits, factor, unit)                                                \
    {                                                                                              \
        name, mux, start, bits, 1, factor, 0, S_MIN(bits) * (factor), S_MAX(bits) * (factor), unit \
    }

static const canproto_signal_t sig_wp[] = {
    SIG_U("WP_Mux", -2, 0, 8, 1, ""),
    SIG_U("WP_Seq", -1, 8, 8, 1, ""),
    SIG_U("WP_Time", CANPROTO_MUX_TIME, 16, 48, CANPROTO_WP_T_S_PER_BIT, "s"),
    SIG_S("WP_X", CANPROTO_MUX_X, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WP_Y", CANPROTO_MUX_Y, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WP_Z", CANPROTO_MUX_Z, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_U("WP_Command", CANPROTO_MUX_COMMAND, 16, 8, 1, ""),
    SIG_U("WP_CommandArg", CANPROTO_MUX_COMMAND, 24, 8, 1, "%"),
};
static const canproto_signal_t sig_wpfd[] = {
    SIG_U("WPFD_Mux", -1, 0, 8, 1, ""),
    SIG_U("WPFD_Seq", -1, 8, 8, 1, ""),
    SIG_U("WPFD_Time", -1, 16, 48, CANPROTO_WP_T_S_PER_BIT, "s"),
    SIG_S("WPFD_X", -1, 64, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WPFD_Y", -1, 112, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WPFD_Z", -1, 160, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
};
static const canproto_signal_t sig_sp[] = {
    SIG_U("SP_Axis", -2, 0, 2, 1, ""),
    SIG_U("SP_State", -1, 4, 3, 1, ""),
    SIG_U("SP_Hold", -1, 7, 1, 1, ""),
    SIG_U("SP_Cycle", -1, 8, 8, 1, ""),
    SIG_S("SP_X_Pos", 0, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_X_Vel", 0, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SP_Y_Pos", 1, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_Y_Vel", 1, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SP_Z_Pos", 2, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_Z_Vel", 2, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
};
static const canproto_signal_t sig_spfd[] = {
    SIG_U("SPFD_Cycle", -1, 0, 32, 1, ""),
    SIG_S("SPFD_X", -1, 32, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_Y", -1, 64, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_Z", -1, 96, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_VX", -1, 128, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SPFD_VY", -1, 160, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SPFD_VZ", -1, 192, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_U("SPFD_State", -1, 224, 8, 1, ""),
    SIG_U("SPFD_Flags", -1, 232, 8, 1, ""),
    SIG_U("SPFD_Track", -1, 240, 16, 1, ""),
};
static const canproto_signal_t sig_st[] = {
    SIG_U("ST_State", -1, 0, 3, 1, ""),      SIG_U("ST_Clamped", -1, 3, 1, 1, ""),
    SIG_U("ST_BusDown", -1, 4, 1, 1, ""),    SIG_U("ST_TxDrop", -1, 5, 1, 1, ""),
    SIG_U("ST_OutFault", -1, 6, 1, 1, ""),   SIG_U("ST_SafetyFault", -1, 7, 1, 1, ""),
    SIG_U("ST_LastSeq", -1, 8, 8, 1, ""),    SIG_U("ST_Free", -1, 16, 8, 1, ""),
    SIG_U("ST_Lost", -1, 24, 8, 1, ""),      SIG_U("ST_Rejected", -1, 32, 8, 1, ""),
    SIG_U("ST_Malformed", -1, 40, 8, 1, ""), SIG_U("ST_Dropped", -1, 48, 8, 1, ""),
    SIG_U("ST_LastErr", -1, 56, 8, 1, ""),
};
static const canproto_signal_t sig_st2[] = {
    SIG_U("ST2_Page", -2, 0, 8, 1, ""),
    SIG_U("ST2_OutLost", CANPROTO_ST2_FAULTS, 8, 24, 1, ""),
    SIG_U("ST2_OutErrors", CANPROTO_ST2_FAULTS, 32, 16, 1, ""),
    SIG_U("ST2_CmdRefused", CANPROTO_ST2_FAULTS, 48, 16, 1, ""),
    SIG_U("ST2_BusState", CANPROTO_ST2_BUS, 8, 8, 1, ""),
    SIG_U("ST2_TxErr", CANPROTO_ST2_BUS, 16, 8, 1, ""),
    SIG_U("ST2_RxErr", CANPROTO_ST2_BUS, 24, 8, 1, ""),
    SIG_U("ST2_BusOffs", CANPROTO_ST2_BUS, 32, 16, 1, ""),
    SIG_U("ST2_ErrFrames", CANPROTO_ST2_BUS, 48, 16, 1, ""),
    SIG_U("ST2_RejBackwards", CANPROTO_ST2_REJECTED, 8, 8, 1, ""),
    SIG_U("ST2_RejSameTime", CANPROTO_ST2_REJECTED, 16, 8, 1, ""),
    SIG_U("ST2_RejSpeed", CANPROTO_ST2_REJECTED, 24, 8, 1, ""),
    SIG_U("ST2_RejAccel", CANPROTO_ST2_REJECTED, 32, 8, 1, ""),
    SIG_U("ST2_RejUnconfirmed", CANPROTO_ST2_REJECTED, 40, 8, 1, ""),
    SIG_U("ST2_RejStale", CANPROTO_ST2_REJECTED, 48, 8, 1, ""),
    SIG_U("ST2_RejOther", CANPROTO_ST2_REJECTED, 56, 8, 1, ""),
    SIG_S("ST2_Age", CANPROTO_ST2_CLOCK, 8, 24, CANPROTO_ST2_AGE_S_PER_BIT, "s"),
    SIG_S("ST2_Drift", CANPROTO_ST2_CLOCK, 32, 16, CANPROTO_ST2_DRIFT_PPM_PER_BIT, "ppm"),
    SIG_U("ST2_Clocked", CANPROTO_ST2_CLOCK, 48, 8, 1, ""),
    SIG_U("ST2_StateX", CANPROTO_ST2_DRIVE, 8, 4, 1, ""),
    SIG_U("ST2_StateY", CANPROTO_ST2_DRIVE, 12, 4, 1, ""),
    SIG_U("ST2_StateZ", CANPROTO_ST2_DRIVE, 16, 4, 1, ""),
    SIG_U("ST2_HbLost", CANPROTO_ST2_DRIVE, 22, 1, 1, ""),
    SIG_U("ST2_Held", CANPROTO_ST2_DRIVE, 23, 1, 1, ""),
    SIG_U("ST2_Statusword", CANPROTO_ST2_DRIVE, 24, 16, 1, ""),
    SIG_U("ST2_Nmt", CANPROTO_ST2_DRIVE, 40, 8, 1, ""),
    SIG_U("ST2_Emcy", CANPROTO_ST2_DRIVE, 48, 16, 1, ""),
};
static const canproto_signal_t sig_rpdo[] = {
    SIG_S("Target_Position_607A", -1, 0, 32, 1, "inc"),
};
static const canproto_signal_t sig_rpdo_cw[] = {
    SIG_U("Controlword_6040", -1, 0, 16, 1, ""),
    SIG_S("Target_Position_607A", -1, 16, 32, 1, "inc"),
};
static const canproto_signal_t sig_tpdo_fb[] = {
    SIG_U("Statusword_6041", -1, 0, 16, 1, ""),
    SIG_S("Position_Actual_6064", -1, 16, 32, 1, "inc"),
};

static const canproto_message_t canproto_msgs[] = {
    {"TRAJD_WAYPOINT", CANPROTO_ID_WAYPOINT_BASE, CANPROTO_WP_DLEN, 0, "SENDER", sig_wp,
     sizeof sig_wp / sizeof sig_wp[0]},
    {"TRAJD_WAYPOINT_FD", CANPROTO_ID_WAYPOINT_FD_BASE, CANPROTO_WP_FD_DLEN, 1, "SENDER", sig_wpfd,
     sizeof sig_wpfd / sizeof sig_wpfd[0]},
    {"TRAJD_SETPOINT", CANPROTO_ID_SETPOINT_BASE, CANPROTO_SP_DLEN, 0, "TRAJD", sig_sp,
     sizeof sig_sp / sizeof sig_sp[0]},
    {"TRAJD_SETPOINT_FD", CANPROTO_ID_SETPOINT_FD_BASE, CANPROTO_SP_FD_DLEN, 1, "TRAJD", sig_spfd,
     sizeof sig_spfd / sizeof sig_spfd[0]},
    {"TRAJD_STATUS", CANPROTO_ID_STATUS_BASE, CANPROTO_STATUS_DLEN, 0, "TRAJD", sig_st,
     sizeof sig_st / sizeof sig_st[0]},
    {"TRAJD_STATUS2", CANPROTO_ID_STATUS2_BASE, CANPROTO_STATUS2_DLEN, 0, "TRAJD", sig_st2,
     sizeof sig_st2 / sizeof sig_st2[0]},
    {"SYNC", CANPROTO_ID_SYNC_DEFAULT, 0, 0, "TRAJD", NULL, 0},
    {"RPDO1_NODE1", CANPROTO_CIA402_RPDO1_BASE + 1, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO1_NODE2", CANPROTO_CIA402_RPDO1_BASE + 2, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO1_NODE3", CANPROTO_CIA402_RPDO1_BASE + 3, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO_CW_NODE1", CANPROTO_CIA402_RPDO2_BASE + 1, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"RPDO_CW_NODE2", CANPROTO_CIA402_RPDO2_BASE + 2, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"RPDO_CW_NODE3", CANPROTO_CIA402_RPDO2_BASE + 3, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"TPDO1_NODE1", CANPROTO_CIA402_TPDO1_BASE + 1, 6, 0, "SENDER", sig_tpdo_fb, 2},
    {"TPDO1_NODE2", CANPROTO_CIA402_TPDO1_BASE + 2, 6, 0, "SENDER", sig_tpdo_fb, 2},
    {"TPDO1_NODE3", CANPROTO_CIA402_TPDO1_BASE + 3, 6, 0, "SENDER", sig_tpdo_fb, 2},
};

const canproto_message_t *canproto_messages(unsigned *count)
{
    *count = sizeof canproto_msgs / sizeof canproto_msgs[0];
    return canproto_msgs;
}

/* snprintf into buf at *pos, tracking the length needed even when it does not fit. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static void
emit(char *buf, size_t len, size_t *pos, const char *fmt, ...);

static void emit(char *buf, size_t len, size_t *pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(*pos < len ? buf + *pos : NULL, *pos < len ? len - *pos : 0, fmt, ap);
    va_end(ap);
    if (n > 0)
        *pos += (size_t)n;
}

int canproto_dbc(char *buf, size_t len)
{
    size_t pos = 0;
    unsigned n;
    const canproto_message_t *m = canproto_messages(&n);

    if (len)
        buf[0] = '\0';
    emit(buf, len, &pos,
         "VERSION \"trajd\"\n\n"
         "NS_ :\n\tCM_\n\tBA_DEF_\n\tBA_\n\tBA_DEF_DEF_\n\tVAL_\n\n"
         "BS_:\n\n"
         "BU_: TRAJD SENDER\n\n");
    for (unsigned i = 0; i < n; i++) {
        emit(buf, len, &pos, "BO_ %u %s: %u %s\n", (unsigned)m[i].id, m[i].name, m[i].dlen,
             m[i].sender);
        for (unsigned k = 0; k < m[i].nsignals; k++) {
            const canproto_signal_t *s = &m[i].signals[k];
            char mux[16] = "";
            if (s->mux == -2)
                snprintf(mux, sizeof mux, " M");
            else if (s->mux >= 0)
                snprintf(mux, sizeof mux, " m%d", s->mux);
            emit(buf, len, &pos, " SG_ %s%s : %u|%u@1%c (%.15g,%.15g) [%.15g|%.15g] \"%s\" %s\n",
                 s->name, mux, s->start_bit, s->bits, s->is_signed ? '-' : '+', s->factor,
                 s->offset, s->min, s->max, s->unit,
                 strcmp(m[i].sender, "TRAJD") ? "TRAJD" : "SENDER");
        }
        emit(buf, len, &pos, "\n");
    }
    emit(buf, len, &pos,
         "CM_ \"trajd CAN protocol, generated from lib/proto/canproto.h by canproto_dbc(); ids are "
         "the defaults of object 0 (object n: + n), RPDOs for CiA 402 nodes 1..3 (RPDO_CW: the "
         "layout sent with can.cia402_controlword = yes, shown on the RPDO2 ids 0x301..0x303; "
         "TPDO1: the drive feedback trajd reads, statusword 0x6041 and position actual value "
         "0x6064). Setpoint positions 0x80000000: no position yet, do not move.\";\n"
         "CM_ SG_ %u WP_Command \"1 finish, 2 stop now, 3 clear, 4 reset counters, 5 feed "
         "override\";\n"
         "CM_ SG_ %u WP_CommandArg \"feed override in percent (0..200) for command 5, else 0\";\n"
         "CM_ SG_ %u ST_LastErr \"1..11 engine_error of the last rejected waypoint, 0x40 "
         "malformed, 0x41 lost, 0x42 out of order, 0x43 setpoints dropped, 0x44 bus down, 0x45 "
         "csv/stdout output lost lines, 0x46 safety monitor fault (object held until clear), 0x47 "
         "a CiA 402 "
         "drive left Operation Enabled, 0x48 a command refused (object not writable, or held: an "
         "override above 0 during a feed hold)\";\n"
         "CM_ SG_ %u ST2_Page \"STATUS2 page: 1 faults, 2 rejected waypoints per reason, 3 clock, "
         "4 drive, 5 bus; "
         "counters saturate at their maximum\";\n"
         "CM_ SG_ %u ST2_OutLost \"setpoint lines lost by the object's csv/stdout outputs\";\n"
         "CM_ SG_ %u ST2_OutErrors \"failed writes of the object's csv/stdout outputs\";\n"
         "CM_ SG_ %u ST2_CmdRefused \"command frames refused: the object is not writable, or held "
         "(an override above 0 during a feed hold)\";\n"
         "CM_ SG_ %u ST2_RejSpeed \"waypoints refused per reason (engine_error: backwards 3, "
         "same time 4, speed 5, acceleration 11, unconfirmed 12, stale 13; other: not finite 1, "
         "out of range 2, numeric 10), saturating at 255; exact counts in the Modbus diagnostics "
         "block\";\n"
         "CM_ SG_ %u ST2_BusState \"CAN bus state from the controller's error frames\";\n"
         "CM_ SG_ %u ST2_TxErr \"TX error counter, as last reported (CAN_ERR_CNT)\";\n"
         "CM_ SG_ %u ST2_RxErr \"RX error counter, as last reported (CAN_ERR_CNT)\";\n"
         "CM_ SG_ %u ST2_BusOffs \"entries into bus-off\";\n"
         "CM_ SG_ %u ST2_ErrFrames \"error frames received\";\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_ID_WAYPOINT_BASE, CANPROTO_ID_STATUS_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE);
    emit(buf, len, &pos,
         "CM_ SG_ %u ST2_Age \"page 3: data age now - t_s of the setpoint on the sender's time "
         "base (lib/engine/CLOCK.md; D when on time, negative while waiting for the clock to "
         "reach the start), -8388.608: none (relative time, no position), saturating at "
         "+-8388.607\";\n"
         "CM_ SG_ %u ST2_Drift \"page 3: sender clock drift absorbed by the play-out clock (+ = "
         "sender fast), one estimate per daemon; -3276.8: none\";\n"
         "CM_ SG_ %u ST2_Clocked \"page 3: 0 relative time, 1 on the daemon's clock, 2 "
         "undecided (clock = auto: the first waypoint decides)\";\n"
         "CM_ SG_ %u ST2_Statusword \"page 4: statusword 0x6041 of the first drive axis not in "
         "Operation Enabled, else of the first\";\n"
         "CM_ SG_ %u ST2_Nmt \"page 4: heartbeat NMT state of the same node\";\n"
         "CM_ SG_ %u ST2_Held \"page 4: a drive left Operation Enabled: no target sent, drives "
         "disabled until the command clear\";\n"
         "CM_ SG_ %u ST2_HbLost \"page 4: a drive's heartbeat not heard within "
         "can.cia402_heartbeat_ms\";\n"
         "CM_ SG_ %u ST2_Emcy \"page 4: error code of the last EMCY from the object's drives, 0: "
         "none\";\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE);
    emit(buf, len, &pos,
         "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\","
         "\"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\","
         "\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\","
         "\"ExtendedCAN_FD\";\n"
         "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n");
    for (unsigned i = 0; i < n; i++)
        if (m[i].fd)
            emit(buf, len, &pos, "BA_ \"VFrameFormat\" BO_ %u 14;\n", (unsigned)m[i].id);
    /* value tables of every enum field, from the enums of canproto.h / motion.h */
    const char *states = "0 \"waiting\" 1 \"streaming\" 2 \"underrun\" 3 \"finished\"";
    emit(buf, len, &pos, "VAL_ %u WP_Mux %d \"time\" %d \"x\" %d \"y\" %d \"z\" %d \"command\" ;\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_MUX_TIME, CANPROTO_MUX_X, CANPROTO_MUX_Y,
         CANPROTO_MUX_Z, CANPROTO_MUX_COMMAND);
    emit(buf, len, &pos, "VAL_ %u WPFD_Mux %d \"whole waypoint\" ;\n", CANPROTO_ID_WAYPOINT_FD_BASE,
         CANPROTO_MUX_FD_WAYPOINT);
    emit(buf, len, &pos,
         "VAL_ %u WP_Command %d \"finish\" %d \"stop\" %d \"clear\" %d \"reset counters\" %d "
         "\"feed override\" ;\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_CMD_FINISH, CANPROTO_CMD_STOP, CANPROTO_CMD_CLEAR,
         CANPROTO_CMD_RESET_COUNTERS, CANPROTO_CMD_OVERRIDE);
    emit(buf, len, &pos, "VAL_ %u SP_Axis 0 \"x\" 1 \"y\" 2 \"z\" ;\n", CANPROTO_ID_SETPOINT_BASE);
    emit(buf, len, &pos, "VAL_ %u SP_State %s ;\n", CANPROTO_ID_SETPOINT_BASE, states);
    emit(buf, len, &pos, "VAL_ %u SPFD_State %s ;\n", CANPROTO_ID_SETPOINT_FD_BASE, states);
    emit(buf, len, &pos, "VAL_ %u ST_State %s ;\n", CANPROTO_ID_STATUS_BASE, states);
    emit(buf, len, &pos,
         "VAL_ %u ST_LastErr 0 \"ok\" 1 \"not finite\" 2 \"out of range\" 3 \"backwards\" "
         "4 \"same time\" 5 \"speed\" 6 \"full\" 7 \"config\" 8 \"no memory\" 9 \"state\" "
         "10 \"numeric\" 11 \"acceleration\" %d \"malformed\" %d \"lost\" %d \"out of order\" "
         "%d \"setpoints dropped\" %d \"bus down\" %d \"output lost lines\" %d \"safety fault\" "
         "%d \"drive not enabled\" %d \"command refused\" ;\n",
         CANPROTO_ID_STATUS_BASE, CANPROTO_STERR_MALFORMED, CANPROTO_STERR_LOST,
         CANPROTO_STERR_OUT_OF_ORDER, CANPROTO_STERR_TX_DROPPED, CANPROTO_STERR_BUS_DOWN,
         CANPROTO_STERR_OUTPUT, CANPROTO_STERR_SAFETY, CANPROTO_STERR_DRIVE,
         CANPROTO_STERR_REFUSED);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Page %d \"faults\" %d \"rejected\" %d \"clock\" %d \"drive\" %d \"bus\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ST2_FAULTS, CANPROTO_ST2_REJECTED, CANPROTO_ST2_CLOCK,
         CANPROTO_ST2_DRIVE, CANPROTO_ST2_BUS);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Clocked %d \"relative\" %d \"on the clock\" %d \"undecided\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ST2_CLOCK_RELATIVE, CANPROTO_ST2_CLOCK_ON,
         CANPROTO_ST2_CLOCK_UNDECIDED);
    emit(buf, len, &pos,
         "VAL_ %u ST2_BusState 1 \"error-active\" 2 \"error-warning\" 3 \"error-passive\" "
         "4 \"bus-off\" 5 \"down\" ;\n",
         CANPROTO_ID_STATUS2_BASE);

    for (unsigned a = 0; a < 3; a++)
        emit(buf, len, &pos,
             "VAL_ %u ST2_State%c 0 \"not ready to switch on\" 1 \"switch on disabled\" "
             "2 \"ready to switch on\" 3 \"switched on\" 4 \"operation enabled\" "
             "5 \"quick stop active\" 6 \"fault reaction active\" 7 \"fault\" 8 \"not heard\" "
             "%u \"no drive\" ;\n",
             CANPROTO_ID_STATUS2_BASE, "XYZ"[a], CANPROTO_S2_NO_DRIVE);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Nmt 0 \"boot-up\" 4 \"stopped\" 5 \"operational\" 127 "
         "\"pre-operational\" %u \"none heard\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_S2_NMT_NONE);
    for (unsigned k = 1; k <= 3; k++)
        emit(buf, len, &pos,
             "VAL_ %u Controlword_6040 0 \"disable voltage\" 2 \"quick stop\" 6 \"shutdown\" "
             "7 \"switch on\" 15 \"enable operation\" 128 \"fault reset\" ;\n",
             CANPROTO_CIA402_RPDO2_BASE + k);
    return pos > (size_t)INT32_MAX ? -1 : (int)pos;
}
