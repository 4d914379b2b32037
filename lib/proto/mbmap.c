/* mbmap.c - see mbmap.h. */
#include "mbmap.h"

#include <math.h>
#include <string.h>
#include <strings.h>

const char *mbmap_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case MBMAP_OK: return "ok";
    case MBMAP_EFUNCTION: return "illegal function (not served, or writes disabled)";
    case MBMAP_EADDRESS: return "illegal data address (outside the map, or a partial block)";
    case MBMAP_EVALUE: return "illegal data value (count, length, NaN, command, refused waypoint)";
    case MBMAP_EBUSY: return "server busy (waypoint buffer full, retry later)";
    default: return "unknown mbmap error";
    }
}

/* ---- words ------------------------------------------------------------- */

void mbmap_put_u32(uint16_t *r, uint32_t v)
{
    r[0] = (uint16_t)(v >> 16);
    r[1] = (uint16_t)(v & 0xffffu);
}

uint32_t mbmap_get_u32(const uint16_t *r)
{
    return ((uint32_t)r[0] << 16) | r[1];
}

void mbmap_put_f32(uint16_t *r, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    mbmap_put_u32(r, u);
}

float mbmap_get_f32(const uint16_t *r)
{
    uint32_t u = mbmap_get_u32(r);
    float v;
    memcpy(&v, &u, sizeof v);
    return v;
}

void mbmap_put_f64(uint16_t *r, double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    for (int i = 0; i < 4; i++)
        r[i] = (uint16_t)(u >> (48 - 16 * i));
}

double mbmap_get_f64(const uint16_t *r)
{
    uint64_t u = 0;
    double v;
    for (int i = 0; i < 4; i++)
        u = (u << 16) | r[i];
    memcpy(&v, &u, sizeof v);
    return v;
}

/* ---- word order -------------------------------------------------------- */

int mbmap_order_parse(const char *s)
{
    static const char *names[] = {"ABCD", "CDAB", "BADC", "DCBA"};
    for (int i = 0; i < 4; i++)
        if (!strcasecmp(s, names[i]))
            return i;
    return -1;
}

const char *mbmap_order_name(mbmap_order_t o)
{
    switch (o) {
    case MBMAP_ORDER_ABCD: return "ABCD";
    case MBMAP_ORDER_CDAB: return "CDAB";
    case MBMAP_ORDER_BADC: return "BADC";
    case MBMAP_ORDER_DCBA: return "DCBA";
    default: return "?";
    }
}

void mbmap_order_value(uint16_t *r, unsigned count, mbmap_order_t o)
{
    if (o == MBMAP_ORDER_CDAB || o == MBMAP_ORDER_DCBA)
        for (unsigned i = 0; i < count / 2; i++) {
            uint16_t w = r[i];
            r[i] = r[count - 1 - i];
            r[count - 1 - i] = w;
        }
    if (o == MBMAP_ORDER_BADC || o == MBMAP_ORDER_DCBA)
        for (unsigned i = 0; i < count; i++)
            r[i] = (uint16_t)((r[i] << 8) | (r[i] >> 8));
}

void mbmap_order_image(uint16_t *regs, unsigned n, mbmap_order_t o)
{
    if (o == MBMAP_ORDER_ABCD)
        return;
    size_t nf;
    const mbmap_field_t *f = mbmap_fields(&nf);
    for (size_t i = 0; i < nf; i++) {
        if (f[i].count < 2)
            continue;
        if (!strcmp(f[i].table, "input daemon"))
            mbmap_order_value(regs + f[i].offset, f[i].count, o);
        else if (!strcmp(f[i].table, "input object"))
            for (unsigned k = 0; k < n && k < MBMAP_MAX_OBJECTS; k++)
                mbmap_order_value(regs + MBMAP_OBJ_BASE(k) + f[i].offset, f[i].count, o);
    }
}

void mbmap_order_diag(uint16_t *regs, unsigned n, mbmap_order_t o)
{
    if (o == MBMAP_ORDER_ABCD)
        return;
    size_t nf;
    const mbmap_field_t *f = mbmap_fields(&nf);
    for (size_t i = 0; i < nf; i++)
        if (f[i].count >= 2 && !strcmp(f[i].table, "input diagnostics"))
            for (unsigned k = 0; k < n && k < MBMAP_MAX_OBJECTS; k++)
                mbmap_order_value(regs + MBMAP_X_BASE(k) + f[i].offset, f[i].count, o);
}

/* Counters are 64-bit in the daemon; the map carries their low 32 bits. */
static uint32_t lo32(uint64_t v)
{
    return (uint32_t)(v & 0xffffffffu);
}

/* ---- encode ------------------------------------------------------------ */

void mbmap_encode_daemon(uint16_t *regs, const mbmap_daemon_t *d)
{
    memset(regs, 0, MBMAP_BLOCK * sizeof *regs);
    regs[MBMAP_D_MAGIC] = MBMAP_MAGIC;
    regs[MBMAP_D_VERSION] = MBMAP_VERSION;
    regs[MBMAP_D_OBJECTS] = d->objects;
    regs[MBMAP_D_WRITES] = d->writes_enabled ? 1 : 0;
    mbmap_put_u32(regs + MBMAP_D_GEN, d->generation);
    mbmap_put_u32(regs + MBMAP_D_UPTIME_S, lo32(d->uptime_s));
    mbmap_put_u32(regs + MBMAP_D_PERIOD_US, d->period_us);
    mbmap_put_u32(regs + MBMAP_D_LATE_P50_US, d->late_p50_us);
    mbmap_put_u32(regs + MBMAP_D_LATE_P99_US, d->late_p99_us);
    mbmap_put_u32(regs + MBMAP_D_LATE_MAX_US, d->late_max_us);
    mbmap_put_u32(regs + MBMAP_D_MISSED_TICKS, lo32(d->missed_ticks));
    regs[MBMAP_D_CAN_STATE] = d->can_state;
    regs[MBMAP_D_CAN_LOAD] = d->can_load_permille;
    mbmap_put_u32(regs + MBMAP_D_MB_REQUESTS, lo32(d->mb_requests));
    mbmap_put_u32(regs + MBMAP_D_MB_EXCEPTIONS, lo32(d->mb_exceptions));
    mbmap_put_u32(regs + MBMAP_D_MB_REFUSED, lo32(d->mb_refused));
    regs[MBMAP_D_MB_CLIENTS] = d->mb_clients;
    mbmap_put_u32(regs + MBMAP_D_MB_EVICTED, lo32(d->mb_evicted));
    mbmap_put_u32(regs + MBMAP_D_MB_SLOW, lo32(d->mb_slow));
    mbmap_put_u32(regs + MBMAP_D_OUT_LOST, lo32(d->out_lost));
    mbmap_put_u32(regs + MBMAP_D_LOG_DROPPED, lo32(d->log_dropped));
    regs[MBMAP_D_OUT_FAULT] = d->out_fault ? 1 : 0;
    mbmap_put_u32(regs + MBMAP_D_DRIVE_EMCY, lo32(d->drive_emcy));
    mbmap_put_u32(regs + MBMAP_D_DRIVE_LAST_ABORT, d->drive_last_abort);
    regs[MBMAP_D_DRIVE_SDO_ABORTS] = (uint16_t)(d->drive_sdo_aborts > 0xffff ? 0xffff
                                                                             : d->drive_sdo_aborts);
    regs[MBMAP_D_DRIVE_HB_LOST] = (uint16_t)(d->drive_hb_lost > 0xffff ? 0xffff : d->drive_hb_lost);
    mbmap_put_f32(regs + MBMAP_D_CLOCK_DRIFT, (float)d->clock_drift_ppm);
    mbmap_put_f32(regs + MBMAP_D_CLOCK_DELAY, (float)d->clock_delay_s);
    regs[MBMAP_D_CLOCK_MODE] = d->clock_mode;
    regs[MBMAP_D_CLOCK_OBJECTS] = d->clock_objects;
    mbmap_put_u32(regs + MBMAP_D_MB_CONNECTIONS, lo32(d->mb_connections));
    mbmap_put_u32(regs + MBMAP_D_MB_DROPPED, lo32(d->mb_dropped));
    regs[MBMAP_D_MB_PEERS] = d->mb_peers;
    regs[MBMAP_D_MB_WORST_FAMILY] = d->mb_worst_family;
    mbmap_put_u32(regs + MBMAP_D_MB_WORST_IPV4, d->mb_worst_ipv4);
    mbmap_put_u32(regs + MBMAP_D_MB_WORST_REQUESTS, lo32(d->mb_worst_requests));
    mbmap_put_u32(regs + MBMAP_D_MB_WORST_EXCEPTIONS, lo32(d->mb_worst_exceptions));
    mbmap_put_u32(regs + MBMAP_D_MB_WORST_DROPS, lo32(d->mb_worst_drops));
    mbmap_put_u32(regs + MBMAP_D_CAN_ERR_FRAMES, lo32(d->can_err_frames));
    mbmap_put_u32(regs + MBMAP_D_CAN_WARNINGS, lo32(d->can_warnings));
    mbmap_put_u32(regs + MBMAP_D_CAN_PASSIVES, lo32(d->can_passives));
    mbmap_put_u32(regs + MBMAP_D_CAN_BUS_OFFS, lo32(d->can_bus_offs));
    mbmap_put_u32(regs + MBMAP_D_CAN_RESTARTS, lo32(d->can_restarts));
    mbmap_put_u32(regs + MBMAP_D_CAN_BUS_ERRORS, lo32(d->can_bus_errors));
    mbmap_put_u32(regs + MBMAP_D_CAN_OVERFLOWS, lo32(d->can_overflows));
    mbmap_put_u32(regs + MBMAP_D_CAN_RX_DROPPED, lo32(d->can_rx_dropped));
    regs[MBMAP_D_CAN_TX_ERR] = d->can_tx_err;
    regs[MBMAP_D_CAN_RX_ERR] = d->can_rx_err;
    mbmap_put_u32(regs + MBMAP_D_GEN_TAIL, d->generation);
}

uint16_t mbmap_health(const mbmap_object_t *o)
{
    uint16_t h = 0, ds = o->drive_states;
    if (o->sp.flags & ENGINE_SP_FAULT)
        h |= MBMAP_HEALTH_SAFETY;
    for (int a = 0; a < 3; a++) {
        unsigned st = (ds >> (4 * a)) & 0x0Fu; /* 5 quick stop, 6 fault reaction, 7 fault */
        if (st >= 5 && st <= 7)
            h |= MBMAP_HEALTH_DRIVE;
    }
    if (ds & 0xC000u) /* heartbeat lost, held until clear */
        h |= MBMAP_HEALTH_DRIVE;
    if (o->out_fault)
        h |= MBMAP_HEALTH_OUTPUT;
    if (o->sp.state == ENGINE_STATE_UNDERRUN)
        h |= MBMAP_HEALTH_UNDERRUN;
    if (o->clocked && o->sp.age_s > o->delay_s + 1.0)
        h |= MBMAP_HEALTH_STALE;
    if (o->clocked && o->clock_unsync)
        h |= MBMAP_HEALTH_CLOCK;
    if (o->held)
        h |= MBMAP_HEALTH_HELD;
    return h;
}

int mbmap_encode_object(uint16_t *regs, unsigned k, uint32_t gen, const mbmap_object_t *o)
{
    if (k >= MBMAP_MAX_OBJECTS)
        return -MBMAP_EADDRESS;
    uint16_t *b = regs + MBMAP_OBJ_BASE(k);
    memset(b, 0, MBMAP_BLOCK * sizeof *b);
    mbmap_put_u32(b + MBMAP_O_GEN, gen);
    uint16_t health = mbmap_health(o);
    b[MBMAP_O_STATE] = o->fault_held || (health & (MBMAP_HEALTH_SAFETY | MBMAP_HEALTH_DRIVE |
                                                   MBMAP_HEALTH_HELD))
                           ? MBMAP_STATE_HELD
                       : o->latched ? MBMAP_STATE_STOPPED
                                    : (uint16_t)o->sp.state;
    b[MBMAP_O_HEALTH] = health;
    b[MBMAP_O_FLAGS] = (uint16_t)(o->sp.flags & 0xffffu);
    mbmap_put_u32(b + MBMAP_O_CYCLE, o->sp.cycle);
    mbmap_put_u32(b + MBMAP_O_TRACK, o->sp.track);
    mbmap_put_u32(b + MBMAP_O_BUFFERED, o->st.buffered);
    mbmap_put_u32(b + MBMAP_O_FREE, o->st.free);
    mbmap_put_u32(b + MBMAP_O_LOOKAHEAD, o->st.lookahead);
    mbmap_put_f32(b + MBMAP_O_AHEAD_S, (float)o->st.ahead_s);
    mbmap_put_u32(b + MBMAP_O_LAST_SEQ, o->st.last_seq);
    mbmap_put_f64(b + MBMAP_O_T_S, o->sp.t_s);
    for (int a = 0; a < ENGINE_AXES; a++) {
        mbmap_put_f32(b + MBMAP_O_POS + 2 * a, (float)o->sp.pos_m[a]);
        mbmap_put_f32(b + MBMAP_O_VEL + 2 * a, (float)o->sp.vel_m_s[a]);
        mbmap_put_f32(b + MBMAP_O_ACC + 2 * a, (float)o->sp.acc_m_s2[a]);
    }
    mbmap_put_u32(b + MBMAP_O_ACCEPTED, lo32(o->st.accepted));
    mbmap_put_u32(b + MBMAP_O_REJECTED, lo32(o->st.rejected));
    mbmap_put_u32(b + MBMAP_O_LOST, lo32(o->lost));
    mbmap_put_u32(b + MBMAP_O_UNDERRUNS, lo32(o->st.underruns));
    mbmap_put_u32(b + MBMAP_O_MISSED_TICKS, lo32(o->st.skipped_ticks));
    mbmap_put_u32(b + MBMAP_O_DUPLICATES, lo32(o->st.duplicates));
    mbmap_put_u32(b + MBMAP_O_MB_REJECTED, lo32(o->mb_rejected));
    mbmap_put_u32(b + MBMAP_O_LATE_P99_US, o->late_p99_us);
    mbmap_put_u32(b + MBMAP_O_LATE_MAX_US, o->late_max_us);
    b[MBMAP_O_CAN_STATE] = o->can_state;
    b[MBMAP_O_CAN_LOAD] = o->can_load_permille;
    mbmap_put_u32(b + MBMAP_O_UPTIME_S, lo32(o->uptime_s));
    mbmap_put_u32(b + MBMAP_O_FULL, lo32(o->st.full));
    mbmap_put_u32(b + MBMAP_O_OUT_LOST, lo32(o->out_lost));
    b[MBMAP_O_OUT_FAULT] = o->out_fault ? 1 : 0;
    mbmap_put_u32(b + MBMAP_O_SEQ_JUMPS, lo32(o->seq_jumps));
    mbmap_put_f32(b + MBMAP_O_RATE, (float)o->st.rate);
    b[MBMAP_O_OVERRIDE] = (uint16_t)lround(o->st.override * 100.0);
    mbmap_put_u32(b + MBMAP_O_HARD_STOPS, lo32(o->st.hard_stops));
    b[MBMAP_O_DRIVE_STATES] = o->drive_states;
    b[MBMAP_O_DRIVE_STATUSWORD] = o->drive_statusword;
    b[MBMAP_O_DRIVE_NMT] = o->drive_nmt;
    b[MBMAP_O_DRIVE_EMCY] = o->drive_emcy;
    mbmap_put_f32(b + MBMAP_O_AGE_S, (float)o->sp.age_s);
    b[MBMAP_O_CLOCKED] = o->clocked ? 1 : 0;
    mbmap_put_f64(b + MBMAP_O_LAT, o->lat_deg);
    mbmap_put_f64(b + MBMAP_O_LON, o->lon_deg);
    mbmap_put_f64(b + MBMAP_O_ALT, o->alt_m);
    mbmap_put_u32(b + MBMAP_O_GEN_TAIL, gen);
    return 0;
}

int mbmap_encode_diag(uint16_t *regs, unsigned k, uint32_t gen, const mbmap_object_t *o)
{
    if (k >= MBMAP_MAX_OBJECTS)
        return -MBMAP_EADDRESS;
    uint16_t *b = regs + MBMAP_X_BASE(k);
    memset(b, 0, MBMAP_BLOCK * sizeof *b);
    mbmap_put_u32(b + MBMAP_X_GEN, gen);
    for (int c = 1; c < ENGINE_ERROR_COUNT; c++)
        if (engine_reason_name(c)) /* reasons for data only: EFULL is full */
            mbmap_put_u32(b + MBMAP_X_REJECTED_BY + 2 * (c - 1), lo32(o->st.rejected_by[c]));
    mbmap_put_f64(b + MBMAP_X_AXIS_LOST_S, o->st.axis_lost_s);
    mbmap_put_u32(b + MBMAP_X_AXIS_SLOWED, lo32(o->st.axis_slowed));
    mbmap_put_u32(b + MBMAP_X_TRANSFERS_MOVING, lo32(o->st.transfers_moving));
    mbmap_put_u32(b + MBMAP_X_DELAY_GROWN, lo32(o->st.delay_grown));
    mbmap_put_u32(b + MBMAP_X_AXIS_LAG_STOPS, lo32(o->st.axis_lag_stops));
    mbmap_put_u32(b + MBMAP_X_AXIS_BEYOND, lo32(o->st.axis_beyond));
    mbmap_put_u32(b + MBMAP_X_RESERVE_SLOWED, lo32(o->st.reserve_slowed));
    mbmap_put_f64(b + MBMAP_X_LIMITS_LOST_S, o->st.limits_lost_s);
    mbmap_put_u32(b + MBMAP_X_LIMITS_SLOWED, lo32(o->st.limits_slowed));
    mbmap_put_u32(b + MBMAP_X_RESYNCS, lo32(o->resyncs));
    mbmap_put_f64(b + MBMAP_X_DELAY_S, o->play_delay_s);
    mbmap_put_u32(b + MBMAP_X_DROPPED, lo32(o->st.dropped));
    mbmap_put_u32(b + MBMAP_X_UNJUDGED, lo32(o->st.unjudged));
    mbmap_put_f64(b + MBMAP_X_HEADING, o->heading_deg);
    mbmap_put_f64(b + MBMAP_X_HEADING_UNWRAPPED, o->heading_unwrapped_deg);
    mbmap_put_u32(b + MBMAP_X_TX_CLAMPED, lo32(o->tx_clamped));
    for (unsigned i = 0; i < MBMAP_X_MB_WORST_ADDR_GROUPS; i++)
        b[MBMAP_X_MB_WORST_ADDR + i] = o->mb_worst_addr[i];
    mbmap_put_u32(b + MBMAP_X_GEN_TAIL, gen);
    return 0;
}

/* ---- requests ---------------------------------------------------------- */

static unsigned be16(const uint8_t *p)
{
    return ((unsigned)p[0] << 8) | p[1];
}

int mbmap_check_request(unsigned n, int writes_enabled, const uint8_t *pdu, size_t len)
{
    if (len < 1)
        return -MBMAP_EVALUE;
    unsigned regs = n > MBMAP_MAX_OBJECTS ? MBMAP_REGS(MBMAP_MAX_OBJECTS) : MBMAP_REGS(n);
    unsigned addr, count;

    switch (pdu[0]) {
    case MBMAP_FC_READ_HOLDING:
    case MBMAP_FC_READ_INPUT:
        if (len != 5)
            return -MBMAP_EVALUE;
        addr = be16(pdu + 1);
        count = be16(pdu + 3);
        if (count < 1 || count > MBMAP_MAX_READ)
            return -MBMAP_EVALUE;
        if (pdu[0] == MBMAP_FC_READ_HOLDING && addr >= MBMAP_MIRROR_BASE)
            addr -= MBMAP_MIRROR_BASE; /* the input table, read through the mirror */
        break;
    case MBMAP_FC_WRITE_SINGLE:
        if (!writes_enabled)
            return -MBMAP_EFUNCTION;
        if (len != 5)
            return -MBMAP_EVALUE;
        addr = be16(pdu + 1);
        count = 1;
        break;
    case MBMAP_FC_WRITE_MULTIPLE:
        if (!writes_enabled)
            return -MBMAP_EFUNCTION;
        if (len < 6)
            return -MBMAP_EVALUE;
        addr = be16(pdu + 1);
        count = be16(pdu + 3);
        if (count < 1 || count > MBMAP_MAX_WRITE || pdu[5] != 2 * count ||
            len != 6 + 2 * (size_t)count)
            return -MBMAP_EVALUE;
        break;
    default: return -MBMAP_EFUNCTION;
    }
    /* the daemon and object blocks, or the diagnostics blocks: never both,
     * nor the unserved object slots between them */
    unsigned x_end = MBMAP_X_BASE(n > MBMAP_MAX_OBJECTS ? MBMAP_MAX_OBJECTS : n);
    if (addr + count > regs && (addr < MBMAP_X_BASE(0) || addr + count > x_end))
        return -MBMAP_EADDRESS;
    return 0;
}

/* The float32 waypoint block (MBMAP_H_WPF). */
static int decode_wpf(mbmap_order_t o, const uint8_t *val, mbmap_write_t *out)
{
    uint16_t r[MBMAP_H_WPF_COUNT];
    for (unsigned i = 0; i < MBMAP_H_WPF_COUNT; i++)
        r[i] = (uint16_t)be16(val + 2 * i);
    for (unsigned i = 0; i < MBMAP_H_WPF_COUNT; i += 2)
        mbmap_order_value(r + i, 2, o);
    out->kind = MBMAP_WRITE_WAYPOINT;
    out->wp.seq = mbmap_get_u32(r + (MBMAP_H_WPF_SEQ - MBMAP_H_WPF));
    out->wp.t_s = mbmap_get_f32(r + (MBMAP_H_WPF_T_S - MBMAP_H_WPF));
    int bad = !isfinite(out->wp.t_s); /* every field decoded: a refusal tells them all */
    for (int a = 0; a < ENGINE_AXES; a++) {
        out->wp.pos_m[a] = mbmap_get_f32(r + (MBMAP_H_WPF_POS - MBMAP_H_WPF) + 2 * a);
        bad |= !isfinite(out->wp.pos_m[a]);
    }
    return bad ? -MBMAP_EVALUE : 0;
}

/* The float64 waypoint block (MBMAP_H_WP), or with the velocity (MBMAP_H_WPV):
 * the same layout from the block's start, then vx, vy, vz. */
static int decode_wp(mbmap_order_t o, const uint8_t *val, int with_vel, mbmap_write_t *out)
{
    uint16_t r[MBMAP_H_WPV_COUNT];
    unsigned count = with_vel ? MBMAP_H_WPV_COUNT : MBMAP_H_WP_COUNT;
    for (unsigned i = 0; i < count; i++)
        r[i] = (uint16_t)be16(val + 2 * i);
    mbmap_order_value(r, 2, o); /* seq, then f64 from register 2 on */
    for (unsigned i = 2; i < count; i += 4)
        mbmap_order_value(r + i, 4, o);
    out->kind = MBMAP_WRITE_WAYPOINT;
    out->wp.seq = mbmap_get_u32(r + (MBMAP_H_WP_SEQ - MBMAP_H_WP));
    out->wp.t_s = mbmap_get_f64(r + (MBMAP_H_WP_T_S - MBMAP_H_WP));
    int bad = !isfinite(out->wp.t_s); /* every field decoded: a refusal tells them all */
    for (int a = 0; a < ENGINE_AXES; a++) {
        out->wp.pos_m[a] = mbmap_get_f64(r + (MBMAP_H_WP_POS - MBMAP_H_WP) + 4 * a);
        bad |= !isfinite(out->wp.pos_m[a]);
    }
    if (with_vel) {
        out->wp.has_vel = 1;
        for (int a = 0; a < ENGINE_AXES; a++) {
            out->wp.vel_m_s[a] = mbmap_get_f64(r + (MBMAP_H_WPV_VEL - MBMAP_H_WPV) + 4 * a);
            bad |= !isfinite(out->wp.vel_m_s[a]);
        }
    }
    return bad ? -MBMAP_EVALUE : 0;
}

int mbmap_decode_write_order(unsigned n, mbmap_order_t o, const uint8_t *pdu, size_t len,
                             mbmap_write_t *out)
{
    int rc = mbmap_check_request(n, 1, pdu, len);
    if (rc < 0)
        return rc;
    if (pdu[0] != MBMAP_FC_WRITE_SINGLE && pdu[0] != MBMAP_FC_WRITE_MULTIPLE)
        return -MBMAP_EFUNCTION;

    unsigned addr = be16(pdu + 1);
    unsigned count = pdu[0] == MBMAP_FC_WRITE_SINGLE ? 1 : be16(pdu + 3);
    const uint8_t *val = pdu[0] == MBMAP_FC_WRITE_SINGLE ? pdu + 3 : pdu + 6;

    /* The daemon block (below MBMAP_OBJ_BASE(0)) is read-only. */
    if (addr < MBMAP_OBJ_BASE(0))
        return -MBMAP_EADDRESS;
    unsigned k = addr / MBMAP_BLOCK - 1;
    unsigned off = addr % MBMAP_BLOCK;
    if (k >= n)
        return -MBMAP_EADDRESS;

    memset(out, 0, sizeof *out);
    out->object = k;
    if (off == MBMAP_H_COMMAND && count == 1) {
        unsigned cmd = be16(val);
        out->kind = MBMAP_WRITE_COMMAND; /* also when refused: the server logs it */
        out->command = cmd;
        return cmd < MBMAP_CMD_START || cmd > MBMAP_CMD_FINISH ? -MBMAP_EVALUE : 0;
    }
    if (off == MBMAP_H_OVERRIDE && count == 1) {
        unsigned pct = be16(val);
        out->kind = MBMAP_WRITE_OVERRIDE; /* also when refused: the server logs it */
        out->override_pct = pct;
        return pct > MBMAP_OVERRIDE_MAX_PCT ? -MBMAP_EVALUE : 0;
    }
    if (off == MBMAP_H_WPF && count == MBMAP_H_WPF_COUNT)
        return decode_wpf(o, val, out);
    if (off == MBMAP_H_WP && count == MBMAP_H_WP_COUNT)
        return decode_wp(o, val, 0, out);
    if (off == MBMAP_H_WPV && count == MBMAP_H_WPV_COUNT)
        return decode_wp(o, val, 1, out);
    return -MBMAP_EADDRESS;
}

int mbmap_from_engine(int engine_result)
{
    if (engine_result >= 0)
        return 0;
    return engine_result == -ENGINE_EFULL ? -MBMAP_EBUSY : -MBMAP_EVALUE;
}

/* ---- RTU framing ------------------------------------------------------- */

uint16_t mbmap_crc16(const uint8_t *buf, size_t len)
{
    uint16_t crc = 0xffffu;
    for (size_t i = 0; i < len; i++) {
        crc ^= buf[i];
        for (int b = 0; b < 8; b++)
            crc = (crc & 1u) ? (uint16_t)((crc >> 1) ^ 0xa001u) : (uint16_t)(crc >> 1);
    }
    return crc;
}

int mbmap_rtu_frame_len(const uint8_t *buf, size_t len)
{
    if (len < 2)
        return 0;
    switch (buf[1]) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x05:
    case 0x06: return 8; /* addr fc a a n n crc crc */
    case 0x0f:
    case 0x10:
        if (len < 7)
            return 0;
        return 9 + buf[6]; /* addr fc a a n n bc data crc crc */
    case 0x17:
        if (len < 11)
            return 0;
        return 13 + buf[10];
    case 0x07:
    case 0x0b:
    case 0x0c:
    case 0x11: return 4; /* addr fc crc crc */
    default: return -1;
    }
}

/* ---- documentation ----------------------------------------------------- */

#define F(tab, off, cnt, ty, name, unit, doc)                                                      \
    {                                                                                              \
        tab, off, cnt, ty, name, unit, doc                                                         \
    }
#define ID "input daemon"
#define IO "input object"
#define HO "holding object"
#define IX "input diagnostics"

static const mbmap_field_t fields[] = {
    F(ID, MBMAP_D_MAGIC, 1, MBMAP_T_U16, "magic", "", "0x7444, identifies trajd"),
    F(ID, MBMAP_D_VERSION, 1, MBMAP_T_U16, "version", "", "register map version"),
    F(ID, MBMAP_D_OBJECTS, 1, MBMAP_T_U16, "objects", "",
      "object blocks: highest object id + 1 (GEN 0: no object has that id)"),
    F(ID, MBMAP_D_WRITES, 1, MBMAP_T_U16, "writes_enabled", "",
      "1 if holding registers accept writes"),
    F(ID, MBMAP_D_GEN, 2, MBMAP_T_U32, "generation", "", "snapshot generation, +1 per tick"),
    F(ID, MBMAP_D_UPTIME_S, 2, MBMAP_T_U32, "uptime", "s", "since the daemon started"),
    F(ID, MBMAP_D_PERIOD_US, 2, MBMAP_T_U32, "period", "us", "output period"),
    F(ID, MBMAP_D_LATE_P50_US, 2, MBMAP_T_U32, "lateness_p50", "us", "tick lateness, median"),
    F(ID, MBMAP_D_LATE_P99_US, 2, MBMAP_T_U32, "lateness_p99", "us",
      "tick lateness, 99th percentile"),
    F(ID, MBMAP_D_LATE_MAX_US, 2, MBMAP_T_U32, "lateness_max", "us", "tick lateness, maximum"),
    F(ID, MBMAP_D_MISSED_TICKS, 2, MBMAP_T_U32, "missed_ticks", "",
      "timer expirations missed by the loop"),
    F(ID, MBMAP_D_CAN_STATE, 1, MBMAP_T_U16, "can_state", "",
      "0 none, 1 active, 2 warning, 3 passive, 4 bus-off, 5 down"),
    F(ID, MBMAP_D_CAN_LOAD, 1, MBMAP_T_U16, "can_load", "0.1 %", "CAN bus load"),
    F(ID, MBMAP_D_MB_REQUESTS, 2, MBMAP_T_U32, "mb_requests", "", "Modbus requests answered"),
    F(ID, MBMAP_D_MB_EXCEPTIONS, 2, MBMAP_T_U32, "mb_exceptions", "", "exception responses sent"),
    F(ID, MBMAP_D_MB_REFUSED, 2, MBMAP_T_U32, "mb_refused", "",
      "connections refused (allow-list; at max_clients only if every client is under 250 ms old)"),
    F(ID, MBMAP_D_MB_CLIENTS, 1, MBMAP_T_U16, "mb_clients", "", "TCP clients connected"),
    F(ID, MBMAP_D_MB_EVICTED, 2, MBMAP_T_U32, "mb_evicted", "",
      "clients evicted at max_clients to admit a newcomer"),
    F(ID, MBMAP_D_MB_SLOW, 2, MBMAP_T_U32, "mb_slow", "",
      "clients dropped: a request not whole within request_timeout_ms"),
    F(ID, MBMAP_D_OUT_LOST, 2, MBMAP_T_U32, "out_lost", "",
      "setpoint lines lost by csv/stdout outputs (write error or full buffer)"),
    F(ID, MBMAP_D_OUT_FAULT, 1, MBMAP_T_U16, "out_fault", "",
      "1 once an output failed to write (disk full, I/O error)"),
    F(ID, MBMAP_D_DRIVE_EMCY, 2, MBMAP_T_U32, "drive_emcy", "",
      "EMCY frames from CiA 402 drives (all objects)"),
    F(ID, MBMAP_D_DRIVE_LAST_ABORT, 2, MBMAP_T_U32, "drive_last_abort", "",
      "abort code of the last SDO write a drive refused (CiA 301 table 22), 0 none"),
    F(ID, MBMAP_D_DRIVE_SDO_ABORTS, 1, MBMAP_T_U16, "drive_sdo_aborts", "",
      "SDO writes drives refused (saturates at 65535)"),
    F(ID, MBMAP_D_DRIVE_HB_LOST, 1, MBMAP_T_U16, "drive_hb_lost", "",
      "drive heartbeats not heard within can.cia402_heartbeat_ms (saturates)"),
    F(ID, MBMAP_D_CLOCK_DRIFT, 2, MBMAP_T_F32, "clock_drift", "ppm",
      "sender clock drift absorbed by the play-out clock (+ = sender fast), lib/engine/CLOCK.md"),
    F(ID, MBMAP_D_CLOCK_DELAY, 2, MBMAP_T_F32, "clock_delay", "s",
      "play-out delay D: objects on the clock stand at now - D"),
    F(ID, MBMAP_D_CLOCK_MODE, 1, MBMAP_T_U16, "clock_mode", "",
      "[daemon] clock: 0 auto, 1 epoch, 2 relative"),
    F(ID, MBMAP_D_CLOCK_OBJECTS, 1, MBMAP_T_U16, "clock_objects", "",
      "objects played out on the daemon's clock"),
    F(ID, MBMAP_D_MB_CONNECTIONS, 2, MBMAP_T_U32, "mb_connections", "", "TCP connections accepted"),
    F(ID, MBMAP_D_MB_DROPPED, 2, MBMAP_T_U32, "mb_dropped", "",
      "clients closed by the server: bad framing, idle, answers not read, slow (evictions: "
      "mb_evicted)"),
    F(ID, MBMAP_D_MB_PEERS, 1, MBMAP_T_U16, "mb_peers", "",
      "client addresses seen (the 32 most recent kept)"),
    F(ID, MBMAP_D_MB_WORST_FAMILY, 1, MBMAP_T_U16, "mb_worst_family", "",
      "the client address with the most drops, then exceptions: 0 none, 4 IPv4, 6 IPv6"),
    F(ID, MBMAP_D_MB_WORST_IPV4, 2, MBMAP_T_U32, "mb_worst_ipv4", "",
      "its IPv4 address, a.b.c.d as a*2^24 + b*2^16 + c*2^8 + d (0 if IPv6: any address is in "
      "the diagnostics blocks, mb_worst_addr0..7)"),
    F(ID, MBMAP_D_MB_WORST_REQUESTS, 2, MBMAP_T_U32, "mb_worst_requests", "", "requests it sent"),
    F(ID, MBMAP_D_MB_WORST_EXCEPTIONS, 2, MBMAP_T_U32, "mb_worst_exceptions", "",
      "exception responses it got"),
    F(ID, MBMAP_D_MB_WORST_DROPS, 2, MBMAP_T_U32, "mb_worst_drops", "",
      "its connections evicted, dropped slow or closed by the server"),
    F(ID, MBMAP_D_CAN_ERR_FRAMES, 2, MBMAP_T_U32, "can_err_frames", "",
      "CAN error frames received (SocketCAN CAN_ERR_*; they set can_state)"),
    F(ID, MBMAP_D_CAN_WARNINGS, 2, MBMAP_T_U32, "can_warnings", "",
      "CAN controller entries into error-warning"),
    F(ID, MBMAP_D_CAN_PASSIVES, 2, MBMAP_T_U32, "can_passives", "",
      "CAN controller entries into error-passive"),
    F(ID, MBMAP_D_CAN_BUS_OFFS, 2, MBMAP_T_U32, "can_bus_offs", "",
      "CAN controller entries into bus-off"),
    F(ID, MBMAP_D_CAN_RESTARTS, 2, MBMAP_T_U32, "can_restarts", "",
      "CAN controller restarts (error-active again)"),
    F(ID, MBMAP_D_CAN_BUS_ERRORS, 2, MBMAP_T_U32, "can_bus_errors", "",
      "CAN error frames reporting protocol, ACK, arbitration, transceiver or TX timeout errors"),
    F(ID, MBMAP_D_CAN_OVERFLOWS, 2, MBMAP_T_U32, "can_overflows", "",
      "CAN controller RX/TX buffer overflows"),
    F(ID, MBMAP_D_CAN_TX_ERR, 1, MBMAP_T_U16, "can_tx_err", "",
      "CAN TX error counter, as last reported by the controller"),
    F(ID, MBMAP_D_CAN_RX_ERR, 1, MBMAP_T_U16, "can_rx_err", "",
      "CAN RX error counter, as last reported by the controller"),
    F(ID, MBMAP_D_LOG_DROPPED, 2, MBMAP_T_U32, "log_dropped", "",
      "log lines dropped: the log thread's queue was full"),
    F(ID, MBMAP_D_CAN_RX_DROPPED, 2, MBMAP_T_U32, "can_rx_dropped", "",
      "CAN frames the kernel dropped because trajd's receive queue was full (a stall of trajd); "
      "waypoints among them count as lost"),
    F(ID, MBMAP_D_GEN_TAIL, 2, MBMAP_T_U32, "generation_tail", "",
      "copy of generation (whole-block reads)"),

    F(IO, MBMAP_O_GEN, 2, MBMAP_T_U32, "generation", "", "snapshot generation of this block"),
    F(IO, MBMAP_O_STATE, 1, MBMAP_T_U16, "state", "",
      "0 waiting, 1 streaming, 2 underrun, 3 finished, 4 held until clear (a fault or a feed hold: "
      "health bit 0, 1 or 6), 5 stopped (a stop latched until start or clear)"),
    F(IO, MBMAP_O_FLAGS, 1, MBMAP_T_U16, "flags", "",
      "bit 0 hold, 1 new track, 2 ticks skipped, 3 transfer, 4 no position yet (x, y, z NaN: "
      "do not move), 5 safety fault, 6 time-scaled (Setpoint flags)"),
    F(IO, MBMAP_O_CYCLE, 2, MBMAP_T_U32, "cycle", "", "setpoint tick counter"),
    F(IO, MBMAP_O_TRACK, 2, MBMAP_T_U32, "track", "", "trajectory number"),
    F(IO, MBMAP_O_BUFFERED, 2, MBMAP_T_U32, "buffered", "", "waypoints buffered"),
    F(IO, MBMAP_O_FREE, 2, MBMAP_T_U32, "free", "", "waypoints that can still be written"),
    F(IO, MBMAP_O_LOOKAHEAD, 2, MBMAP_T_U32, "lookahead_needed", "",
      "waypoints of lookahead needed to stream"),
    F(IO, MBMAP_O_AHEAD_S, 2, MBMAP_T_F32, "lookahead_available", "s",
      "track time of the solved curve ahead of the output (the waypoints beyond it, which "
      "the solver's lookahead still needs, are in buffered)"),
    F(IO, MBMAP_O_LAST_SEQ, 2, MBMAP_T_U32, "last_seq", "",
      "sequence number of the last accepted waypoint"),
    F(IO, MBMAP_O_T_S, 4, MBMAP_T_F64, "t", "s", "track time of the setpoint"),
    F(IO, MBMAP_O_POS + 0, 2, MBMAP_T_F32, "x", "m", "position"),
    F(IO, MBMAP_O_POS + 2, 2, MBMAP_T_F32, "y", "m", "position"),
    F(IO, MBMAP_O_POS + 4, 2, MBMAP_T_F32, "z", "m", "position"),
    F(IO, MBMAP_O_VEL + 0, 2, MBMAP_T_F32, "vx", "m/s", "velocity"),
    F(IO, MBMAP_O_VEL + 2, 2, MBMAP_T_F32, "vy", "m/s", "velocity"),
    F(IO, MBMAP_O_VEL + 4, 2, MBMAP_T_F32, "vz", "m/s", "velocity"),
    F(IO, MBMAP_O_ACC + 0, 2, MBMAP_T_F32, "ax", "m/s2", "acceleration"),
    F(IO, MBMAP_O_ACC + 2, 2, MBMAP_T_F32, "ay", "m/s2", "acceleration"),
    F(IO, MBMAP_O_ACC + 4, 2, MBMAP_T_F32, "az", "m/s2", "acceleration"),
    F(IO, MBMAP_O_ACCEPTED, 2, MBMAP_T_U32, "accepted", "", "waypoints accepted"),
    F(IO, MBMAP_O_REJECTED, 2, MBMAP_T_U32, "rejected", "",
      "waypoints rejected by the engine (bad data; a full buffer is in full)"),
    F(IO, MBMAP_O_LOST, 2, MBMAP_T_U32, "lost", "",
      "waypoints lost (sequence gaps of its Modbus waypoint blocks or its CAN input)"),
    F(IO, MBMAP_O_UNDERRUNS, 2, MBMAP_T_U32, "underruns", "", "transitions into underrun"),
    F(IO, MBMAP_O_MISSED_TICKS, 2, MBMAP_T_U32, "missed_ticks", "", "ticks stepped over"),
    F(IO, MBMAP_O_DUPLICATES, 2, MBMAP_T_U32, "duplicates", "",
      "exact duplicate waypoints dropped"),
    F(IO, MBMAP_O_MB_REJECTED, 2, MBMAP_T_U32, "mb_rejected", "",
      "Modbus writes refused with exception 03"),
    F(IO, MBMAP_O_LATE_P99_US, 2, MBMAP_T_U32, "lateness_p99", "us",
      "tick lateness, 99th percentile"),
    F(IO, MBMAP_O_LATE_MAX_US, 2, MBMAP_T_U32, "lateness_max", "us", "tick lateness, maximum"),
    F(IO, MBMAP_O_CAN_STATE, 1, MBMAP_T_U16, "can_state", "",
      "as can_state of the daemon block, for this object's bus"),
    F(IO, MBMAP_O_CAN_LOAD, 1, MBMAP_T_U16, "can_load", "0.1 %", "this object's CAN bus load"),
    F(IO, MBMAP_O_UPTIME_S, 2, MBMAP_T_U32, "uptime", "s", "since the daemon started"),
    F(IO, MBMAP_O_FULL, 2, MBMAP_T_U32, "full", "",
      "waypoints refused with a full buffer (flow control, exception 06; not in rejected)"),
    F(IO, MBMAP_O_OUT_LOST, 2, MBMAP_T_U32, "out_lost", "",
      "setpoint lines of this object lost by its outputs"),
    F(IO, MBMAP_O_OUT_FAULT, 1, MBMAP_T_U16, "out_fault", "",
      "1 once an output of this object failed to write"),
    F(IO, MBMAP_O_SEQ_JUMPS, 2, MBMAP_T_U32, "seq_jumps", "",
      "Modbus sequence numbers outside the plausible window (not counted in lost)"),
    F(IO, MBMAP_O_RATE, 2, MBMAP_T_F32, "rate", "",
      "time-scaling rate of the output: 1 as solved, below 1 slowing (underrun, stop, override), "
      "lib/engine/TIMESCALE.md"),
    F(IO, MBMAP_O_OVERRIDE, 1, MBMAP_T_U16, "override", "%", "feed override in force"),
    F(IO, MBMAP_O_HARD_STOPS, 2, MBMAP_T_U32, "hard_stops", "",
      "times the solved curve ended under a moving output (velocity to 0 in one tick); should stay "
      "0"),
    F(IO, MBMAP_O_DRIVE_STATES, 1, MBMAP_T_U16, "drive_states", "",
      "CiA 402 drive state per axis, 4 bits each (x bits 0..3, y 4..7, z 8..11): 0 not ready, 1 "
      "switch on disabled, 2 ready, 3 switched on, 4 operation enabled, 5 quick stop, 6 fault "
      "reaction, 7 fault, 8 not heard, 15 no drive; bit 14 heartbeat lost, bit 15 held until "
      "clear"),
    F(IO, MBMAP_O_DRIVE_STATUSWORD, 1, MBMAP_T_U16, "drive_statusword", "",
      "statusword 0x6041 of the first drive axis not in operation enabled, else of the first"),
    F(IO, MBMAP_O_DRIVE_NMT, 1, MBMAP_T_U16, "drive_nmt", "",
      "heartbeat NMT state of that node: 0 boot-up, 4 stopped, 5 operational, 127 "
      "pre-operational, 255 none heard"),
    F(IO, MBMAP_O_DRIVE_EMCY, 1, MBMAP_T_U16, "drive_emcy", "",
      "error code of the last EMCY from the object's drives, 0 none"),
    F(IO, MBMAP_O_AGE_S, 2, MBMAP_T_F32, "age", "s",
      "data age: now - t_s on the sender's time base, D plus any lag (lib/engine/CLOCK.md); NaN "
      "for relative time"),
    F(IO, MBMAP_O_CLOCKED, 1, MBMAP_T_U16, "clocked", "",
      "1 if played out on the daemon's clock (epoch time), 0 relative"),
    F(IO, MBMAP_O_HEALTH, 1, MBMAP_T_U16, "health", "",
      "0 well; bit 0 safety hold, 1 drive fault (fault, quick stop, heartbeat lost), 2 output "
      "fault, 3 underrun (the output slows for want of waypoints; when an input simply stops it "
      "shows until the silence is judged its end, lib/engine/silence.h, and is then not counted "
      "in underruns), 4 stale input (on the clock, age > D + 1 s), 5 clock not synchronised "
      "(on the clock), 6 feed hold until clear"),
    F(IO, MBMAP_O_LAT, 4, MBMAP_T_F64, "lat", "deg",
      "latitude of the setpoint (WGS84), for an object whose track is geographic: its "
      "east/north/up about the daemon's one datum converted back; NaN otherwise or with no "
      "position"),
    F(IO, MBMAP_O_LON, 4, MBMAP_T_F64, "lon", "deg", "longitude of the setpoint (WGS84), as lat"),
    F(IO, MBMAP_O_ALT, 4, MBMAP_T_F64, "alt", "m",
      "height of the setpoint above the WGS84 ellipsoid, as lat"),
    F(IO, MBMAP_O_GEN_TAIL, 2, MBMAP_T_U32, "generation_tail", "",
      "copy of generation (whole-block reads)"),

    F(IX, MBMAP_X_GEN, 2, MBMAP_T_U32, "generation", "",
      "snapshot generation (the object block's)"),
    F(IX, MBMAP_X_REJ_NOTFINITE, 2, MBMAP_T_U32, "rejected_not_finite", "",
      "waypoints refused: time or coordinate NaN or infinite (engine_error 1)"),
    F(IX, MBMAP_X_REJ_RANGE, 2, MBMAP_T_U32, "rejected_range", "",
      "refused: a coordinate above max_abs_m or an absurd time (2)"),
    F(IX, MBMAP_X_REJ_BACKWARDS, 2, MBMAP_T_U32, "rejected_backwards", "",
      "refused: earlier than the waypoint kept before it (3)"),
    F(IX, MBMAP_X_REJ_SAMETIME, 2, MBMAP_T_U32, "rejected_same_time", "",
      "refused: same time as the waypoint kept before it, another position (4)"),
    F(IX, MBMAP_X_REJ_SPEED, 2, MBMAP_T_U32, "rejected_speed", "",
      "refused: chord speed above the limit (5)"),
    F(IX, MBMAP_X_REJ_NUMERIC, 2, MBMAP_T_U32, "rejected_numeric", "",
      "refused by the solver (10; unreachable with finite data)"),
    F(IX, MBMAP_X_REJ_ACCEL, 2, MBMAP_T_U32, "rejected_accel", "",
      "refused: implied acceleration above the limit (11; timestamp jitter, position jump)"),
    F(IX, MBMAP_X_REJ_UNCONFIRMED, 2, MBMAP_T_U32, "rejected_unconfirmed", "",
      "refused: far from the trajectory or at odds with its neighbours, not confirmed (12)"),
    F(IX, MBMAP_X_REJ_STALE, 2, MBMAP_T_U32, "rejected_stale", "",
      "refused: the same position again while the object was moving (13)"),
    F(IX, MBMAP_X_AXIS_LOST_S, 4, MBMAP_T_F64, "axis_lost_s", "s",
      "time lost to the per-axis limits (axis_max_*): the time scaling slowed the output "
      "along its path"),
    F(IX, MBMAP_X_AXIS_SLOWED, 2, MBMAP_T_U32, "axis_slowed", "",
      "segments the per-axis limits slow"),
    F(IX, MBMAP_X_TRANSFERS_MOVING, 2, MBMAP_T_U32, "transfers_moving", "",
      "re-anchors joined moving: the output met the new trajectory without braking to rest "
      "(lib/engine/join.c)"),
    F(IX, MBMAP_X_DELAY_GROWN, 2, MBMAP_T_U32, "delay_grown", "",
      "times the play-out delay D grew with the input's intervals or top speed "
      "(lib/engine/delay.h)"),
    F(IX, MBMAP_X_HEADING, 4, MBMAP_T_F64, "heading", "deg",
      "heading axis at the setpoint's track time, wrapped to (-180, 180] (a track column heading: "
      "unwrapped, monotone cubic, lib/util/angle.h); NaN without one"),
    F(IX, MBMAP_X_HEADING_UNWRAPPED, 4, MBMAP_T_F64, "heading_unwrapped", "deg",
      "the same heading, continuous across +-180 (turns counted): the target of a rotary axis"),
    F(IX, MBMAP_X_TX_CLAMPED, 2, MBMAP_T_U32, "tx_clamped", "",
      "CAN setpoints sent with a value clipped to its field (the SETPOINT frame's velocity "
      "beyond +-32.767 m/s: can.fd = yes carries more); also STATUS bit 3 and a log line"),
    F(IX, MBMAP_X_MB_WORST_ADDR, 1, MBMAP_T_U16, "mb_worst_addr0", "",
      "the daemon's worst Modbus client (daemon mb_worst_*), its address as 8 groups of 16 bits "
      "in the order IPv6 text writes them (RFC 4291 2.2): group 0; an IPv4 client as "
      "::ffff:a.b.c.d (RFC 4291 2.5.5.2); all 0: none; the same in every diagnostics block"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 1, 1, MBMAP_T_U16, "mb_worst_addr1", "", "group 1"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 2, 1, MBMAP_T_U16, "mb_worst_addr2", "", "group 2"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 3, 1, MBMAP_T_U16, "mb_worst_addr3", "", "group 3"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 4, 1, MBMAP_T_U16, "mb_worst_addr4", "", "group 4"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 5, 1, MBMAP_T_U16, "mb_worst_addr5", "",
      "group 5 (0xffff for an IPv4 client)"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 6, 1, MBMAP_T_U16, "mb_worst_addr6", "", "group 6"),
    F(IX, MBMAP_X_MB_WORST_ADDR + 7, 1, MBMAP_T_U16, "mb_worst_addr7", "", "group 7"),
    F(IX, MBMAP_X_AXIS_LAG_STOPS, 2, MBMAP_T_U32, "axis_lag_stops", "",
      "stops on the path because the per-axis limits made the output lag its input by more "
      "than max_lag_s (lifecycle event 'lag beyond max_lag_s')"),
    F(IX, MBMAP_X_AXIS_BEYOND, 2, MBMAP_T_U32, "axis_beyond", "",
      "stops before a segment over 100 times faster on an axis than its axis_max_* (it would "
      "need a rate below ENGINE_CEIL_MIN)"),
    F(IX, MBMAP_X_RESERVE_SLOWED, 2, MBMAP_T_U32, "reserve_slowed", "",
      "slowdowns along the path short of D's stop reserve on input that came on time: an "
      "object faster than the speed the reserve was sized for, or a fix lost within the "
      "lookahead (not underruns; D grows with it, lib/engine/delay.h)"),
    F(IX, MBMAP_X_LIMITS_LOST_S, 4, MBMAP_T_F64, "limits_lost_s", "s",
      "time lost to the object's own speed and acceleration limits (max_speed_m_s, "
      "max_accel_m_s2, the profile's): the time scaling slowed the output along its path and "
      "the lag is not won back; also on the exit line"),
    F(IX, MBMAP_X_LIMITS_SLOWED, 2, MBMAP_T_U32, "limits_slowed", "", "segments those limits slow"),
    F(IX, MBMAP_X_RESYNCS, 2, MBMAP_T_U32, "resyncs", "",
      "waypoints taken from a CAN sender that restarted its numbering (behind the last one, "
      "later in time): followed, not lost; also logged and on the exit line"),
    F(IX, MBMAP_X_DELAY_S, 4, MBMAP_T_F64, "delay_s", "s",
      "the play-out delay D this object's output holds: on the daemon's clock the daemon's "
      "delay_s, else its own (stated at its trajectory's start, lib/engine/delay.h)"),
    F(IX, MBMAP_X_DROPPED, 2, MBMAP_T_U32, "dropped", "",
      "waypoints accepted that a stop or clear dropped before the output passed them (a part "
      "of accepted); also on the exit line"),
    F(IX, MBMAP_X_UNJUDGED, 2, MBMAP_T_U32, "unjudged", "",
      "waypoints taken and dropped before their verdict: still being judged at a stop or "
      "clear, or kept by a stop's latch and dropped (past at the start, a clear); not in "
      "accepted: written = accepted + rejected + duplicates + unjudged + the one or two still "
      "being judged"),
    F(IX, MBMAP_X_GEN_TAIL, 2, MBMAP_T_U32, "generation_tail", "",
      "copy of generation (whole-block reads)"),

    F(HO, MBMAP_H_COMMAND, 1, MBMAP_T_U16, "command", "",
      "1 start, 2 stop now (latched until start or clear), 3 clear, 4 reset counters, 5 "
      "finish"),
    F(HO, MBMAP_H_OVERRIDE, 1, MBMAP_T_U16, "override", "%",
      "feed override 0..200: the same path at this % of the solved speed, ramped "
      "(lib/engine/TIMESCALE.md); reads the override in force, whoever set it"),
    F(HO, MBMAP_H_WP_SEQ, 2, MBMAP_T_U32, "wp_seq", "", "waypoint sequence number"),
    F(HO, MBMAP_H_WP_T_S, 4, MBMAP_T_F64, "wp_t", "s", "waypoint time"),
    F(HO, MBMAP_H_WP_POS + 0, 4, MBMAP_T_F64, "wp_x", "m", "waypoint position"),
    F(HO, MBMAP_H_WP_POS + 4, 4, MBMAP_T_F64, "wp_y", "m", "waypoint position"),
    F(HO, MBMAP_H_WP_POS + 8, 4, MBMAP_T_F64, "wp_z", "m",
      "waypoint position; the 18 registers 10..27 go in one FC 16"),
    F(HO, MBMAP_H_WPF_SEQ, 2, MBMAP_T_U32, "wpf_seq", "",
      "float32 waypoint (for PLCs without float64): sequence number"),
    F(HO, MBMAP_H_WPF_T_S, 2, MBMAP_T_F32, "wpf_t", "s",
      "waypoint time, kept to t x 2^-24 (6 us at 100 s): relative times"),
    F(HO, MBMAP_H_WPF_POS + 0, 2, MBMAP_T_F32, "wpf_x", "m", "waypoint position, to x x 2^-24"),
    F(HO, MBMAP_H_WPF_POS + 2, 2, MBMAP_T_F32, "wpf_y", "m", "waypoint position"),
    F(HO, MBMAP_H_WPF_POS + 4, 2, MBMAP_T_F32, "wpf_z", "m",
      "waypoint position; the 10 registers 30..39 go in one FC 16"),
    F(HO, MBMAP_H_WPV_SEQ, 2, MBMAP_T_U32, "wpv_seq", "",
      "waypoint with the source's velocity (the local methods, method = hermite): sequence "
      "number"),
    F(HO, MBMAP_H_WPV_T_S, 4, MBMAP_T_F64, "wpv_t", "s", "waypoint time"),
    F(HO, MBMAP_H_WPV_POS + 0, 4, MBMAP_T_F64, "wpv_x", "m", "waypoint position"),
    F(HO, MBMAP_H_WPV_POS + 4, 4, MBMAP_T_F64, "wpv_y", "m", "waypoint position"),
    F(HO, MBMAP_H_WPV_POS + 8, 4, MBMAP_T_F64, "wpv_z", "m", "waypoint position"),
    F(HO, MBMAP_H_WPV_VEL + 0, 4, MBMAP_T_F64, "wpv_vx", "m/s", "velocity at the waypoint"),
    F(HO, MBMAP_H_WPV_VEL + 4, 4, MBMAP_T_F64, "wpv_vy", "m/s", "velocity at the waypoint"),
    F(HO, MBMAP_H_WPV_VEL + 8, 4, MBMAP_T_F64, "wpv_vz", "m/s",
      "velocity at the waypoint; the 30 registers 40..69 go in one FC 16"),
};

const mbmap_field_t *mbmap_fields(size_t *n)
{
    *n = sizeof fields / sizeof fields[0];
    return fields;
}

const char *mbmap_type_name(mbmap_type_t t)
{
    switch (t) {
    case MBMAP_T_U16: return "u16";
    case MBMAP_T_U32: return "u32";
    case MBMAP_T_F32: return "f32";
    case MBMAP_T_F64: return "f64";
    default: return "?";
    }
}
