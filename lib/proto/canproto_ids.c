/* canproto_ids.c - trajd's CAN ids of an object and the bus load they make (canproto.h). */
#include "canproto.h"

#include <string.h>

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
    if (ids->cia402 < CANPROTO_CIA402_FEEDBACK || axis >= CANPROTO_CIA402_AXES ||
        !ids->cia402_cob_id[axis])
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
        unsigned any = 0;
        for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
            any |= ids->cia402_cob_id[a] != 0;
            if (ids->cia402 == CANPROTO_CIA402_MANAGED && ids->cia402_cob_id[a] &&
                !(ids->cia402_cob_id[a] & 0x7Fu))
                w = "cia402 managed: the node-id (low 7 bits of a COB-id) must be 1..127";
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
        if (ids->cia402 != CANPROTO_CIA402_MANAGED || !node)
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
