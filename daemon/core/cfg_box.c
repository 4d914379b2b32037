/* cfg_box.c - an object's position box (see cfg_box.h). */
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
