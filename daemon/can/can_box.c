/* can_box.c - the CAN output's fields against the object's box and speed limit (can_box.h). */
#include "can_box.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "can_transport.h"
#include "canproto.h"
#include "log.h"

/* The positions axis a of ids' CiA 402 target can encode: [*lo, *hi] m. */
static void cia402_range(const canproto_ids_t *ids, unsigned a, double *lo, double *hi)
{
    double cpm = ids->cia402_axis_counts_per_m[a] > 0 ? ids->cia402_axis_counts_per_m[a]
                                                      : ids->cia402_counts_per_m;
    /* counts = offset + sign * round(pos * cpm) within int32, half a count inside */
    double c_lo = ((double)INT32_MIN - ids->cia402_offset[a] + 0.5) / cpm;
    double c_hi = ((double)INT32_MAX - ids->cia402_offset[a] - 0.5) / cpm;
    *lo = ids->cia402_invert[a] ? -c_hi : c_lo;
    *hi = ids->cia402_invert[a] ? -c_lo : c_hi;
}

/* The box the fields of o's CAN output can hold (+-inf: any). */
static void field_box(const canproto_ids_t *ids, double lo[ENGINE_AXES], double hi[ENGINE_AXES],
                      const char *what[ENGINE_AXES])
{
    for (unsigned a = 0; a < ENGINE_AXES; a++) {
        lo[a] = -INFINITY;
        hi[a] = INFINITY;
        what[a] = NULL;
        if (ids->own) { /* 0x80000000 is "no position": one count above */
            lo[a] = (double)(INT32_MIN + 1) * CANPROTO_SP_POS_M_PER_BIT;
            hi[a] = (double)INT32_MAX * CANPROTO_SP_POS_M_PER_BIT;
            what[a] = "the SETPOINT frame's int32 position (0.1 mm)";
        }
        double l, h;
        if (ids->cia402 && a < CANPROTO_CIA402_AXES && ids->cia402_cob_id[a]) {
            cia402_range(ids, a, &l, &h);
            if (l > lo[a] || h < hi[a])
                what[a] = "the CiA 402 target's int32 increments (cia402_counts_per_m, offset)";
            lo[a] = fmax(lo[a], l);
            hi[a] = fmin(hi[a], h);
        }
    }
}

static void speed_warning(const cfg_obj_t *o, const canproto_ids_t *ids)
{
    double v = engine_config_max_speed(&o->engine) * ENGINE_SPEED_CAP;
    double field = INT16_MAX * CANPROTO_SP_VEL_M_S_PER_BIT;
    if (!ids->own || ids->fd || (v > 0 && v <= field))
        return;
    log_msg(LOG_WARNING,
            "object '%s': its speed may reach %s%g m/s, beyond the SETPOINT frame's +-%g m/s: "
            "faster values are clipped, counted (tx_clamped), flagged and logged; can.fd = yes "
            "carries +-2147 m/s, max_speed_m_s <= %g keeps within it",
            o->name, v > 0 ? "" : "any speed (no speed limit), not only ", v > 0 ? v : field, field,
            field / ENGINE_SPEED_CAP);
}

int can_box_check(cfg_t *cfg, int *line, char *why, size_t wl)
{
    for (unsigned i = 0; i < cfg->nobj; i++) {
        cfg_obj_t *o = &cfg->obj[i];
        if (!(cfg_obj_uses(o, &can_transport) & 2))
            continue;
        canproto_ids_t ids;
        can_obj_ids(cfg_obj_transport(o, &can_transport), (unsigned)o->id, &ids);
        double lo[ENGINE_AXES], hi[ENGINE_AXES];
        const char *what[ENGINE_AXES];
        field_box(&ids, lo, hi, what);
        speed_warning(o, &ids);
        for (unsigned a = 0; a < ENGINE_AXES; a++) {
            if (!what[a])
                continue;
            if (o->box == 1 && (o->box_min_m[a] < lo[a] || o->box_max_m[a] > hi[a])) {
                *line = o->box_line;
                snprintf(why, wl,
                         "object '%s': position_min_m .. position_max_m: %c from %g to %g m does "
                         "not fit %s, which holds %g .. %g m",
                         o->name, "xyz"[a], o -> box_min_m[a], o -> box_max_m[a], what[a], lo[a],
                         hi[a]);
                return -CFG_EVALUE;
            }
            if (o->box == 2 || !o->box) { /* derived: the fields' own box */
                if (!o->box)
                    for (unsigned b = 0; b < ENGINE_AXES; b++) {
                        o->box_min_m[b] = -INFINITY;
                        o->box_max_m[b] = INFINITY;
                    }
                o->box = 2;
                o->box_min_m[a] = lo[a];
                o->box_max_m[a] = hi[a];
            }
        }
    }
    return 0;
}
