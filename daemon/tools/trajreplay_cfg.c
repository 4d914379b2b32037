/* trajreplay_cfg.c - trajreplay -c FILE: an object's settings from a trajd
 * config (trajreplay_cfg.h). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "can_cfg.h"
#include "can_transport.h"
#include "cfg.h"
#include "replay_transport.h"
#include "trajreplay_cfg.h"

/* An object whose drives report where they stand (can.cia402 = feedback or
 * managed): trajd holds it until they are enabled, and starts it there; no
 * file says where that is, so trajreplay starts without it, and says so. */
static void notice_drives(const cfg_obj_t *obj)
{
    if (!(cfg_obj_uses(obj, &can_transport) & 2))
        return;
    canproto_ids_t ids;
    can_obj_ids(cfg_obj_transport(obj, &can_transport), (unsigned)obj->id, &ids);
    if (ids.cia402 >= CANPROTO_CIA402_FEEDBACK)
        fprintf(stderr,
                "trajreplay: notice: object %s: can.cia402 = %s ignored: where its drives "
                "stand is not known offline (starts at %s)\n",
                obj->name, ids.cia402 == CANPROTO_CIA402_MANAGED ? "managed" : "feedback",
                obj->has_initial_position ? "initial_position" : "the first waypoint");
}

int trajreplay_load_config(trajreplay_opts_t *o)
{
    cfg_t *c = NULL;
    char err[CFG_WHY_MAX + PATH_MAX];
    if (cfg_load(o->config, &c, err, sizeof err) < 0) {
        fprintf(stderr, "trajreplay: %s\n", err);
        return EXIT_USAGE;
    }
    const cfg_obj_t *obj = NULL;
    char names[CFG_OBJECTS_MAX * (CFG_NAME_MAX + 2)] = "";
    for (unsigned i = 0; i < c->nobj; i++) {
        size_t n = strlen(names);
        snprintf(names + n, sizeof names - n, "%s%s", i ? ", " : "", c->obj[i].name);
        if (o->object ? strcmp(c->obj[i].name, o->object) == 0 : c->nobj == 1)
            obj = &c->obj[i];
    }
    int rc = -1;
    if (!obj) {
        fprintf(stderr, "trajreplay: %s: %s (objects: %s)\n", o->config,
                o->object ? "no such object" : "several objects: choose one with --object", names);
        rc = EXIT_USAGE;
        goto out;
    }
    snprintf(o->object_buf, sizeof o->object_buf, "%s", obj->name);
    o->object = o->object_buf;
    o->cfg = obj->engine; /* period_ns from the daemon's rate_hz */
    if (!o->rate_given)
        o->rate_hz = c->daemon.rate_hz;
    o->catchup = c->daemon.catchup; /* as trajd's new_objects: every engine */
    o->has_initial_position = obj->has_initial_position;
    memcpy(o->initial_position_m, obj->initial_position_m, sizeof o->initial_position_m);
    notice_drives(obj);
    if (obj->input == &replay_transport) {
        const replay_transport_obj_cfg_t *r = cfg_obj_transport(obj, &replay_transport);
        if (!o->input) {
            snprintf(o->track_buf, sizeof o->track_buf, "%s", r->path);
            o->input = o->track_buf;
            o->format = r->format;
            if (r->skip_bad) /* as trajd reads it */
                o->load_flags |= TRACK_SKIP_BAD;
        }
        o->start_ns = llround(r->start_s * 1e9);
        if (c->datum_set) {
            o->origin_set = 1;
            o->origin[0] = c->datum.lat0_deg;
            o->origin[1] = c->datum.lon0_deg;
            o->origin[2] = c->datum.alt0_m;
        }
    } else if (!o->input) {
        fprintf(stderr, "trajreplay: %s: object %s has input = %s, not replay: give a TRACK\n",
                o->config, obj->name, obj->input->name);
        rc = EXIT_USAGE;
    }
out:
    cfg_free(c);
    return rc;
}
