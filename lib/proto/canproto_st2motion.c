/* canproto_st2motion.c - STATUS2 page 7, MOTION: the engine's motion counters (canproto.h). */
#include "canproto.h"
#include "canproto_le.h"

#include <string.h>

/* v as an n-byte little-endian field, saturated at the field's maximum (never wrapped). */
static void put_sat(uint8_t *p, unsigned nbytes, uint64_t v)
{
    uint64_t max = (1ull << (8 * nbytes)) - 1;
    put_le(p, nbytes, v > max ? max : v);
}

void canproto_st2_motion_from(const engine_status_t *st, canproto_st2_motion_t *out)
{
    out->underruns = st->underruns;
    out->delay_grown = st->delay_grown;
    out->transfers_moving = st->transfers_moving;
    out->reserve_slowed = st->reserve_slowed;
    out->axis_beyond = st->axis_beyond;
    out->axis_lag_stops = st->axis_lag_stops;
}

void canproto_encode_status2_motion(uint32_t id, const canproto_st2_motion_t *p,
                                    canproto_frame_t *out)
{
    memset(out, 0, sizeof *out);
    out->id = id;
    out->len = CANPROTO_STATUS2_DLEN;
    out->data[0] = CANPROTO_ST2_MOTION;
    put_sat(&out->data[1], 2, p->underruns);
    put_sat(&out->data[3], 1, p->delay_grown);
    put_sat(&out->data[4], 1, p->transfers_moving);
    put_sat(&out->data[5], 1, p->reserve_slowed);
    put_sat(&out->data[6], 1, p->axis_beyond);
    put_sat(&out->data[7], 1, p->axis_lag_stops);
}

int canproto_decode_status2_motion(const canproto_frame_t *f, canproto_st2_motion_t *out)
{
    memset(out, 0, sizeof *out);
    int page = canproto_status2_page(f);
    if (page < 0)
        return page;
    if (page != CANPROTO_ST2_MOTION)
        return -CANPROTO_EMUX;
    out->underruns = get_le(&f->data[1], 2);
    out->delay_grown = f->data[3];
    out->transfers_moving = f->data[4];
    out->reserve_slowed = f->data[5];
    out->axis_beyond = f->data[6];
    out->axis_lag_stops = f->data[7];
    return 0;
}
