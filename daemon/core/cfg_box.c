/* cfg_box.c - an object's position box, and the safety bounds its engine keeps (see
 * cfg_box.h). */
#include "cfg_box.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cfg_box_key(cfg_obj_t *o, const cfg_kv_t *kv, char *why, size_t wl)
{
    int max = strcmp(kv->key, "position_max_m") == 0;
    if (!max && strcmp(kv->key, "position_min_m") != 0)
        return -CFG_EUNKNOWN;
    double v[ENGINE_AXES];
    char *end = NULL;
    const char *q = kv->value;
    if (!q[0]) { /* empty: the default, no box on that side */
        o->box_keys &= max ? ~2u : ~1u;
        return 0;
    }
    for (int a = 0; a < ENGINE_AXES; a++) {
        v[a] = strtod(q, &end);
        if (end == q || !isfinite(v[a]) || (a < ENGINE_AXES - 1 ? *end != ',' : *end != '\0')) {
            snprintf(why, wl, "expected x,y,z in metres, got '%s'", kv->value);
            return -CFG_EVALUE;
        }
        q = end + 1;
    }
    memcpy(max ? o->box_max_m : o->box_min_m, v, sizeof v);
    o->box_keys |= max ? 2u : 1u;
    o->box_line = kv->line;
    return 0;
}

int cfg_box_check(cfg_t *c, int *line, char *why, size_t wl)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        cfg_obj_t *o = &c->obj[i];
        if (!o->box_keys)
            continue;
        *line = o->box_line;
        if (o->box_keys != 3) {
            snprintf(why, wl, "[object.%s]: position_%s_m without position_%s_m: give both",
                     o->name, o->box_keys & 1 ? "min" : "max", o->box_keys & 1 ? "max" : "min");
            return -CFG_EVALUE;
        }
        for (int a = 0; a < ENGINE_AXES; a++) {
            double lo = o->box_min_m[a], hi = o->box_max_m[a], m = o->engine.max_abs_m;
            if (!(lo <= hi) || fabs(lo) > m || fabs(hi) > m) {
                snprintf(why, wl,
                         "[object.%s]: position_min_m .. position_max_m: %c from %g to %g m: "
                         "min must not exceed max, and both lie within max_abs_m (%g m)",
                         o->name, "xyz"[a], lo, hi, m);
                return -CFG_EVALUE;
            }
        }
        o->box = 1;
    }
    return 0;
}

void cfg_safety_caps(cfg_obj_t *o, int64_t period_ns)
{
    /* the monitor's speed bound, where one is configured (safety_max_speed_m_s,
     * or safety_max_step_m a period: a speed too), kept by the engine along
     * the path (engine.h cap_speed_m_s): it slows there rather than be held in
     * one tick (derived, the bound is twice the speed limit, above the
     * engine's own cap) */
    double vb = o->safety_max_speed_m_s > 0 ? o->safety_max_speed_m_s : 0.0;
    if (o->safety_max_step_m > 0) {
        double vs = o->safety_max_step_m / ((double)period_ns * 1e-9);
        vb = vb > 0 && vb < vs ? vb : vs;
    }
    /* (none where the engine's own cap, ENGINE_SPEED_CAP x its speed limit,
     * is lower: the documented default written out changes nothing) */
    double own = ENGINE_SPEED_CAP * engine_config_max_speed(&o->engine);
    o->engine.cap_speed_m_s = own > 0 && CFG_SAFETY_SPEED_SHARE * vb >= own
                                  ? 0.0
                                  : CFG_SAFETY_SPEED_SHARE * vb;
    /* and its acceleration bound (engine.h cap_accel_m_s2), where one is
     * configured and lies below what the engine's own limits let the output
     * reach: the profile's acceleration limit, the curve held to it by the
     * rate ceilings (a configured max_accel_m_s2 bounds the waypoints' chords
     * only: none then), and a transfer's configured acceleration */
    double ab = o->safety_max_accel_m_s2 > 0 ? CFG_SAFETY_SPEED_SHARE * o->safety_max_accel_m_s2
                                             : 0.0;
    double aown = o->engine.max_accel_m_s2 < 0 ? engine_config_max_accel(&o->engine) : 0.0;
    aown = aown > 0 ? fmax(aown, o->engine.transfer_accel_m_s2) : 0.0; /* 0: unbounded */
    o->engine.cap_accel_m_s2 = aown > 0 && ab >= aown ? 0.0 : ab;
}
