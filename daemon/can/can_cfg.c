/* can_cfg.c - the "can" transport's configuration: [can] and can.* keys, each checked
 * here, and the checks of a whole file (ids, clashes, bus load, reload) (can_cfg.h). */
#include "can_cfg.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "can_box.h"
#include "can_drive_cfg.h"
#include "can_logfile.h"
#include "can_transport.h"
#include "log.h"

/* can.cia402_counts_per_m[_x/_y/_z]: its one check (canproto_ids_check does not repeat it). */
#define CAN_COUNTS_MIN 1e-3
#define CAN_COUNTS_MAX 1e9

enum {
    GIVEN_WP = 1u << 0,
    GIVEN_WPFD = 1u << 1,
    GIVEN_SP = 1u << 2,
    GIVEN_SPFD = 1u << 3,
    GIVEN_ST = 1u << 4,
    GIVEN_ST2 = 1u << 5,
    GIVEN_COB = 1u << 6, /* << axis */
};

void can_cfg_default(void *p)
{
    can_cfg_t *c = p;
    snprintf(c->interface, sizeof c->interface, "can0");
    snprintf(c->log_ifname, sizeof c->log_ifname, "can0");
    c->bitrate = 500000;
    c->data_bitrate = 2000000;
    c->max_load_percent = 70;
    c->waypoint_hz = 10;
    c->sync_id = CANPROTO_ID_SYNC_DEFAULT;
    c->status_period_ms = 100;
    c->max_late_ms = -1;
    c->log_out_truncate = -1;
    c->heartbeat_ms = 100;
}

static int get_id(const cfg_kv_t *kv, uint32_t *out, char *why, size_t wl)
{
    long long v;
    int rc = cfg_get_int(kv, 0, CANPROTO_SFF_MASK, &v, why, wl);
    if (rc == 0)
        *out = (uint32_t)v;
    return rc;
}

static int get_str(const cfg_kv_t *kv, char *out, size_t len, char *why, size_t wl)
{
    if (!kv->value[0] || strlen(kv->value) >= len) {
        snprintf(why, wl, "must be 1..%zu characters", len - 1);
        return -CFG_EVALUE;
    }
    snprintf(out, len, "%s", kv->value);
    return 0;
}

int can_cfg_key(void *p, const cfg_kv_t *kv, char *why, size_t wl)
{
    can_cfg_t *c = p;
    const char *k = kv->key;
    long long v;
    int rc;
    if (!strcmp(k, "interface"))
        return get_str(kv, c->interface, 16, why, wl);
    if (!strcmp(k, "log_in")) {
        c->line_log_in = kv->line;
        if (!kv->value[0]) { /* empty: the default, none (the socket) */
            c->log_in[0] = 0;
            return 0;
        }
        return cfg_get_path(kv, c->log_in, sizeof c->log_in, why, wl);
    }
    if (!strcmp(k, "log_out")) {
        if (!kv->value[0]) { /* empty: the default, none */
            c->log_out[0] = 0;
            return 0;
        }
        if (!strcmp(kv->value, "-")) {
            snprintf(c->log_out, sizeof c->log_out, "-");
            return 0;
        }
        return cfg_get_path(kv, c->log_out, sizeof c->log_out, why, wl);
    }
    if (!strcmp(k, "log_ifname"))
        return get_str(kv, c->log_ifname, sizeof c->log_ifname, why, wl);
    if (!strcmp(k, "log_time")) {
        if (strcmp(kv->value, "wall") && strcmp(kv->value, "engine")) {
            snprintf(why, wl, "log_time: '%s' is not wall or engine", kv->value);
            return -CFG_EVALUE;
        }
        c->log_time_engine = !strcmp(kv->value, "engine");
        return 0;
    }
    if (!strcmp(k, "log_out_truncate")) {
        c->log_out_truncate = -1;
        if (!strcmp(kv->value, "auto") ||
            (rc = cfg_get_bool(kv, &c->log_out_truncate, why, wl)) == 0)
            return 0;
        snprintf(why, wl, "expected auto, yes or no, got '%s'", kv->value);
        return rc;
    }
    if (!strcmp(k, "fd"))
        return cfg_get_bool(kv, &c->fd, why, wl);
    if (!strcmp(k, "bitrate"))
        return cfg_get_double(kv, 10e3, 1e6, &c->bitrate, why, wl);
    if (!strcmp(k, "data_bitrate"))
        return cfg_get_double(kv, 10e3, 12e6, &c->data_bitrate, why, wl);
    if (!strcmp(k, "max_load_percent"))
        return cfg_get_double(kv, 0, 100, &c->max_load_percent, why, wl); /* 0: no check (vcan) */
    if (!strcmp(k, "waypoint_hz"))
        return cfg_get_double(kv, 0, 10000, &c->waypoint_hz, why, wl);
    if (!strcmp(k, "sync"))
        return cfg_get_bool(kv, &c->sync, why, wl);
    if (!strcmp(k, "sync_id"))
        return get_id(kv, &c->sync_id, why, wl);
    if (!strcmp(k, "sync_overflow")) {
        if ((rc = cfg_get_int(kv, 0, 240, &v, why, wl)) == 0 && v == 1) {
            snprintf(why, wl, "must be 0 (no counter) or 2..240 (CiA 301)");
            return -CFG_EVALUE;
        }
        c->sync_overflow = (unsigned)v;
        return rc;
    }
    if (!strcmp(k, "status_period_ms"))
        return cfg_get_double(kv, 0, 60000, &c->status_period_ms, why, wl);
    if (!strcmp(k, "max_late_ms"))
        return cfg_get_double(kv, -1, 1000, &c->max_late_ms, why, wl);
    if (!strcmp(k, "heartbeat_node") || !strcmp(k, "heartbeat_ms"))
        return can_cfg_heartbeat(kv, &c->heartbeat_node, &c->heartbeat_ms, why, wl);
    return -CFG_EUNKNOWN;
}

void can_obj_cfg_default(void *p)
{
    can_obj_cfg_t *oc = p;
    memset(oc, 0, sizeof *oc);
    oc->index = -1;
    oc->cia402_feedback = 1;
    canproto_ids_default(&oc->ids, 0);
}

/* A key of the former form, still read: one line in the log. */
static void deprecated(const cfg_kv_t *kv, const char *instead)
{
    log_msg(LOG_NOTICE, "%s:%d: can.%s = %s is deprecated: write %s",
            kv->file ? kv->file : "config", kv->line, kv->key, kv->value, instead);
}

/* can.cia402 = off | targets (RPDOs only) | feedback (and the drives' TPDOs) | managed (and
 * their bring-up: NMT, SDO, controlword, heartbeat); yes / no: the former boolean (yes: feedback
 * unless can.cia402_feedback = no), still read. */
static const char *const cia402_modes[] = {"off", "targets", "feedback", "managed"};

/* 0, or -CFG_EVALUE with why if a former key given (can.cia402_feedback, can.cia402_enable)
 * contradicts the mode given (it set it anew: can.cia402 = targets with
 * can.cia402_feedback = yes sent no RPDO); the caller's kv is the later of the two. */
static int cia402_clash(const can_obj_cfg_t *oc, char *why, size_t wl)
{
    int m = oc->mode;
    if (!oc->mode_given || m == CANPROTO_CIA402_OFF)
        return 0;
    if (oc->feedback_given && oc->feedback_value != (m >= CANPROTO_CIA402_FEEDBACK))
        snprintf(why, wl,
                 "can.cia402_feedback = %s contradicts can.cia402 = %s: write can.cia402 alone "
                 "(the former key is deprecated)",
                 oc->feedback_value ? "yes" : "no", cia402_modes[m]);
    else if (oc->enable_given && oc->enable_value != (m == CANPROTO_CIA402_MANAGED))
        snprintf(why, wl,
                 "can.cia402_enable = %s contradicts can.cia402 = %s: write can.cia402 alone "
                 "(the former key is deprecated)",
                 oc->enable_value ? "yes" : "no", cia402_modes[m]);
    else
        return 0;
    return -CFG_EVALUE;
}

static int cia402_mode(const cfg_kv_t *kv, can_obj_cfg_t *oc, char *why, size_t wl)
{
    for (int m = CANPROTO_CIA402_OFF; m <= CANPROTO_CIA402_MANAGED; m++)
        if (!strcmp(kv->value, cia402_modes[m])) {
            oc->cia402_on = m != CANPROTO_CIA402_OFF;
            oc->cia402_feedback = m >= CANPROTO_CIA402_FEEDBACK;
            oc->cia402_enable = m == CANPROTO_CIA402_MANAGED;
            oc->mode = m;
            oc->mode_given = 1;
            return cia402_clash(oc, why, wl);
        }
    int rc = cfg_get_bool(kv, &oc->cia402_on, why, wl);
    if (rc < 0)
        snprintf(why, wl, "expected off, targets, feedback or managed, got '%s'", kv->value);
    else if (oc->cia402_on)
        deprecated(kv, "can.cia402 = feedback (targets without can.cia402_feedback, managed "
                       "with can.cia402_enable)");
    else
        deprecated(kv, "can.cia402 = off");
    return rc;
}

/* The one mode of the keys read: can.cia402 and the former cia402_feedback (yes unless given)
 * and cia402_enable (implies feedback). */
static canproto_cia402_mode_t cia402_mode_of(const can_obj_cfg_t *oc)
{
    if (!oc->cia402_on)
        return CANPROTO_CIA402_OFF;
    if (oc->cia402_enable)
        return CANPROTO_CIA402_MANAGED;
    return oc->cia402_feedback ? CANPROTO_CIA402_FEEDBACK : CANPROTO_CIA402_TARGETS;
}

/* The per-axis keys (cia402_cob_x, ..._tpdo_, ..._counts_per_m_, ..._invert_,
 * ..._offset_); -CFG_EUNKNOWN if kv is none of them. */
static int axis_key(can_obj_cfg_t *oc, const cfg_kv_t *kv, char *why, size_t wl)
{
    canproto_ids_t *ids = &oc->ids;
    const char *k = kv->key;
    long long v;
    int rc;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++) {
        char name[32];
        snprintf(name, sizeof name, "cia402_cob_%c", "xyz"[a]);
        if (!strcmp(k, name)) {
            oc->given |= GIVEN_COB << a;
            return get_id(kv, &ids->cia402_cob_id[a], why, wl);
        }
        snprintf(name, sizeof name, "cia402_tpdo_%c", "xyz"[a]);
        if (!strcmp(k, name))
            return get_id(kv, &ids->cia402_tpdo_id[a], why, wl);
        snprintf(name, sizeof name, "cia402_counts_per_m_%c", "xyz"[a]);
        if (!strcmp(k, name))
            return cfg_get_double(kv, CAN_COUNTS_MIN, CAN_COUNTS_MAX,
                                  &ids->cia402_axis_counts_per_m[a], why, wl);
        snprintf(name, sizeof name, "cia402_invert_%c", "xyz"[a]);
        if (!strcmp(k, name))
            return cfg_get_bool(kv, &ids->cia402_invert[a], why, wl);
        snprintf(name, sizeof name, "cia402_offset_%c", "xyz"[a]);
        if (!strcmp(k, name)) {
            rc = cfg_get_int(kv, INT32_MIN, INT32_MAX, &v, why, wl);
            ids->cia402_offset[a] = (int32_t)v;
            return rc;
        }
    }
    return -CFG_EUNKNOWN;
}

int can_obj_key(void *p, const cfg_kv_t *kv, char *why, size_t wl)
{
    can_obj_cfg_t *oc = p;
    canproto_ids_t *ids = &oc->ids;
    const char *k = kv->key;
    long long v;
    int rc;
    static const struct {
        const char *key;
        size_t off;
        unsigned bit;
    } idkeys[] = {
        {"waypoint_id", offsetof(canproto_ids_t, waypoint_id), GIVEN_WP},
        {"waypoint_fd_id", offsetof(canproto_ids_t, waypoint_fd_id), GIVEN_WPFD},
        {"setpoint_id", offsetof(canproto_ids_t, setpoint_id), GIVEN_SP},
        {"setpoint_fd_id", offsetof(canproto_ids_t, setpoint_fd_id), GIVEN_SPFD},
        {"status_id", offsetof(canproto_ids_t, status_id), GIVEN_ST},
        {"status2_id", offsetof(canproto_ids_t, status2_id), GIVEN_ST2},
    };
    for (size_t i = 0; i < sizeof idkeys / sizeof idkeys[0]; i++)
        if (!strcmp(k, idkeys[i].key)) {
            oc->given |= idkeys[i].bit;
            return get_id(kv, (uint32_t *)(void *)((char *)ids + idkeys[i].off), why, wl);
        }
    rc = axis_key(oc, kv, why, wl);
    if (rc != -CFG_EUNKNOWN)
        return rc;
    if (!strcmp(k, "index")) {
        rc = cfg_get_int(kv, 0, CAN_INDEX_MAX, &v, why, wl);
        oc->index = (int)v;
        return rc;
    }
    if (!strcmp(k, "fd"))
        return cfg_get_bool(kv, &ids->fd, why, wl);
    if (!strcmp(k, "brs"))
        return cfg_get_bool(kv, &ids->brs, why, wl);
    if (!strcmp(k, "own"))
        return cfg_get_bool(kv, &ids->own, why, wl);
    if (!strcmp(k, "cia402"))
        return cia402_mode(kv, oc, why, wl);
    if (!strcmp(k, "cia402_counts_per_m"))
        return cfg_get_double(kv, CAN_COUNTS_MIN, CAN_COUNTS_MAX, &ids->cia402_counts_per_m, why,
                              wl);
    if (!strcmp(k, "cia402_controlword"))
        return cfg_get_bool(kv, &ids->cia402_controlword, why, wl);
    if (!strcmp(k, "cia402_feedback")) {
        deprecated(kv, "can.cia402 = feedback or targets");
        if ((rc = cfg_get_bool(kv, &oc->feedback_value, why, wl)) < 0)
            return rc;
        oc->feedback_given = 1;
        if (oc->mode_given) /* the mode given stands; a contradiction is refused */
            return cia402_clash(oc, why, wl);
        oc->cia402_feedback = oc->feedback_value;
        return 0;
    }
    if (!strcmp(k, "cia402_enable")) {
        deprecated(kv, "can.cia402 = managed");
        if ((rc = cfg_get_bool(kv, &oc->enable_value, why, wl)) < 0)
            return rc;
        oc->enable_given = 1;
        if (oc->mode_given)
            return cia402_clash(oc, why, wl);
        oc->cia402_enable = oc->enable_value;
        return 0;
    }
    if (!strcmp(k, "cia402_heartbeat_ms")) {
        rc = cfg_get_int(kv, 0, 60000, &v, why, wl);
        ids->cia402_heartbeat_ms = (uint32_t)v;
        return rc;
    }
    if (!strcmp(k, "cia402_sdo"))
        return can_cfg_sdo_list(kv, ids, why, wl);
    return -CFG_EUNKNOWN;
}

void can_obj_ids(const can_obj_cfg_t *oc, unsigned obj_id, canproto_ids_t *ids)
{
    canproto_ids_default(ids, oc->index >= 0 ? (unsigned)oc->index : obj_id);
    const canproto_ids_t *g = &oc->ids;
    if (oc->given & GIVEN_WP)
        ids->waypoint_id = g->waypoint_id;
    if (oc->given & GIVEN_WPFD)
        ids->waypoint_fd_id = g->waypoint_fd_id;
    if (oc->given & GIVEN_SP)
        ids->setpoint_id = g->setpoint_id;
    if (oc->given & GIVEN_SPFD)
        ids->setpoint_fd_id = g->setpoint_fd_id;
    if (oc->given & GIVEN_ST)
        ids->status_id = g->status_id;
    if (oc->given & GIVEN_ST2)
        ids->status2_id = g->status2_id;
    for (unsigned a = 0; a < CANPROTO_CIA402_AXES; a++)
        if (oc->given & (GIVEN_COB << a))
            ids->cia402_cob_id[a] = g->cia402_cob_id[a];
    ids->fd = g->fd;
    ids->brs = g->brs;
    ids->own = g->own;
    ids->cia402 = cia402_mode_of(oc);
    ids->cia402_counts_per_m = g->cia402_counts_per_m;
    ids->cia402_controlword = g->cia402_controlword;
    memcpy(ids->cia402_axis_counts_per_m, g->cia402_axis_counts_per_m,
           sizeof ids->cia402_axis_counts_per_m);
    memcpy(ids->cia402_invert, g->cia402_invert, sizeof ids->cia402_invert);
    memcpy(ids->cia402_offset, g->cia402_offset, sizeof ids->cia402_offset);
    memcpy(ids->cia402_tpdo_id, g->cia402_tpdo_id, sizeof ids->cia402_tpdo_id);
    memcpy(ids->cia402_sdo, g->cia402_sdo, sizeof ids->cia402_sdo);
    ids->cia402_nsdo = g->cia402_nsdo;
    ids->cia402_heartbeat_ms = g->cia402_heartbeat_ms;
}

/* ---- config check: ids, clashes, bus load ---- */

int can_cfg_uses(const cfg_obj_t *o)
{
    return cfg_obj_uses(o, &can_transport) != 0;
}

static int null_send(void *io, const canproto_frame_t *f)
{
    (void)io;
    (void)f;
    return 0;
}
static int null_recv(void *io, int64_t t, canproto_frame_t *f)
{
    (void)io;
    (void)t;
    (void)f;
    return 0;
}
static int null_up(const void *io)
{
    (void)io;
    return 1;
}
static int null_push(void *ctx, const engine_waypoint_t *wp)
{
    (void)ctx;
    (void)wp;
    return 0;
}
static void null_status(void *ctx, engine_status_t *st)
{
    (void)ctx;
    memset(st, 0, sizeof *st);
}

/* period_ns: wall-clock period (engine period / speed): lateness is wall time. */
void can_cfg_port(const can_cfg_t *c, int64_t period_ns, can_port_config_t *pc)
{
    can_port_config_default(pc);
    pc->sync = c->sync;
    pc->sync_id = c->sync_id;
    pc->sync_overflow = (uint8_t)c->sync_overflow;
    pc->status_period_ns = (int64_t)llround(c->status_period_ms * 1e6);
    pc->max_late_ns = c->max_late_ms < 0 ? period_ns / 2 : (int64_t)llround(c->max_late_ms * 1e6);
    if (c->log_in[0] || c->log_out[0])
        pc->max_late_ns = 0; /* a log file: no bus is late, nothing dropped (issue 24) */
    pc->hb_node = (uint8_t)c->heartbeat_node;
    pc->hb_period_ns = (int64_t)c->heartbeat_ms * 1000000;
}

/* Ids that must not come from a default: the defaults of an object id above
 * 15 (they would run into the next id range), and CiA 402 COB-IDs (they are
 * the drives' node ids: a drive must be named, never numbered by trajd). */
static int ids_explicit(const cfg_obj_t *o, char *why, size_t wl)
{
    const can_obj_cfg_t *oc = cfg_obj_transport(o, &can_transport);
    const unsigned all = GIVEN_WP | GIVEN_WPFD | GIVEN_SP | GIVEN_SPFD | GIVEN_ST;
    const unsigned cobs = (GIVEN_COB << CANPROTO_CIA402_AXES) - GIVEN_COB;
    if (oc->index < 0 && o->id > CAN_INDEX_MAX && (oc->given & all) != all) {
        snprintf(why, wl,
                 "object '%s': id %d has no default CAN ids (0..%d): give can.index = 0..%d or "
                 "every CAN id (can.waypoint_id, waypoint_fd_id, setpoint_id, setpoint_fd_id, "
                 "status_id)",
                 o->name, o->id, CAN_INDEX_MAX, CAN_INDEX_MAX);
        return -CFG_EVALUE;
    }
    if (oc->cia402_on && (oc->given & cobs) != cobs) {
        snprintf(
            why, wl,
            "object '%s': can.cia402 other than off needs every COB-ID explicit (can.cia402_cob_x, "
            "can.cia402_cob_y, can.cia402_cob_z; 0 = axis not sent): they name the drives' "
            "nodes and never follow the object's id or place in the file",
            o->name);
        return -CFG_EVALUE;
    }
    return 0;
}

/* An id moved: changed, unless optional and sent before or after only (a
 * CiA 402 axis switched on or off is not a move). */
static int id_moved(uint32_t was, uint32_t now, int optional)
{
    return was != now && (!optional || (was && now));
}

/* What of the drives' set-up differs between a (running) and b, whose ids
 * are the same; NULL: nothing, or no drives before. */
static const char *drive_changed(const canproto_ids_t *a, const canproto_ids_t *b)
{
    if (a->cia402 == CANPROTO_CIA402_OFF)
        return NULL;
    if (a->cia402 != b->cia402)
        return "mode (can.cia402)";
    if (memcmp(&a->cia402_counts_per_m, &b->cia402_counts_per_m, sizeof a->cia402_counts_per_m) ||
        memcmp(a->cia402_axis_counts_per_m, b->cia402_axis_counts_per_m,
               sizeof a->cia402_axis_counts_per_m) != 0)
        return "scale (can.cia402_counts_per_m*)";
    if (memcmp(a->cia402_offset, b->cia402_offset, sizeof a->cia402_offset) != 0)
        return "zero (can.cia402_offset_*)";
    if (memcmp(a->cia402_invert, b->cia402_invert, sizeof a->cia402_invert) != 0)
        return "direction (can.cia402_invert_*)";
    if (a->cia402_controlword != b->cia402_controlword ||
        a->cia402_controlword_value != b->cia402_controlword_value)
        return "controlword (can.cia402_controlword*)";
    if (memcmp(a->cia402_tpdo_id, b->cia402_tpdo_id, sizeof a->cia402_tpdo_id) != 0)
        return "feedback TPDO ids (can.cia402_tpdo_*)";
    if (a->cia402_heartbeat_ms != b->cia402_heartbeat_ms)
        return "heartbeat (can.cia402_heartbeat_ms)";
    if (a->cia402_nsdo != b->cia402_nsdo ||
        memcmp(a->cia402_sdo, b->cia402_sdo, a->cia402_nsdo * sizeof a->cia402_sdo[0]) != 0)
        return "bring-up SDO list (can.cia402_sdo)";
    return NULL;
}

/* A reload may not move a CAN id of an object that stays (same name), nor
 * change the set-up of its running drives. */
int can_cfg_reload_check(const cfg_t *old, const cfg_t *nw, int *line, char *why, size_t wl)
{
    for (unsigned k = 0; k < nw->nobj; k++) {
        const cfg_obj_t *o = &nw->obj[k];
        const cfg_obj_t *was = cfg_obj_by_name(old, o->name);
        if (!was || !can_cfg_uses(o) || !can_cfg_uses(was))
            continue;
        canproto_ids_t a, b;
        can_obj_ids(cfg_obj_transport(was, &can_transport), (unsigned)was->id, &a);
        can_obj_ids(cfg_obj_transport(o, &can_transport), (unsigned)o->id, &b);
        static const struct {
            const char *name;
            size_t off;
        } f[] = {{"waypoint", offsetof(canproto_ids_t, waypoint_id)},
                 {"FD waypoint", offsetof(canproto_ids_t, waypoint_fd_id)},
                 {"setpoint", offsetof(canproto_ids_t, setpoint_id)},
                 {"FD setpoint", offsetof(canproto_ids_t, setpoint_fd_id)},
                 {"status", offsetof(canproto_ids_t, status_id)}};
        uint32_t va[8], vb[8];
        const char *what[8];
        unsigned n = 0;
        for (size_t i = 0; i < sizeof f / sizeof f[0]; i++, n++) {
            memcpy(&va[n], (const char *)&a + f[i].off, sizeof va[n]);
            memcpy(&vb[n], (const char *)&b + f[i].off, sizeof vb[n]);
            what[n] = f[i].name;
        }
        for (unsigned ax = 0; ax < CANPROTO_CIA402_AXES; ax++, n++) {
            va[n] = a.cia402 ? a.cia402_cob_id[ax] : 0;
            vb[n] = b.cia402 ? b.cia402_cob_id[ax] : 0;
            what[n] = ax == 0   ? "CiA 402 COB-ID x"
                      : ax == 1 ? "CiA 402 COB-ID y"
                                : "CiA 402 COB-ID z";
        }
        for (unsigned i = 0; i < n; i++)
            if (id_moved(va[i], vb[i], i >= 5)) {
                *line = o->line;
                snprintf(why, wl, "[object.%s]: its %s id would move from 0x%03X to 0x%03X",
                         o->name, what[i], (unsigned)va[i], (unsigned)vb[i]);
                return -CFG_EVALUE;
            }
        const char *drive = drive_changed(&a, &b);
        if (drive) {
            *line = o->line;
            snprintf(why, wl,
                     "[object.%s]: its CiA 402 drives' %s would change: a reload keeps running "
                     "drives only as they were set up (their bring-up again and the old "
                     "engine's braking in the new units would step them); stop trajd and start "
                     "it with this file (a start adopts running drives as it finds them)",
                     o->name, drive);
            return -CFG_EVALUE;
        }
    }
    return 0;
}

void can_cfg_fini(void *p)
{
    can_cfg_t *c = p;
    can_logfile_input_free(c->log_in_frames);
    c->log_in_frames = NULL;
}

/* The log_in read whole into c->log_in_frames, here on the configuration's worker
 * (cfgload.h): the transport's open, in the loop at the swap, only adopts them.  One
 * that cannot be read or holds no frame is refused at its line (it would be accepted,
 * then replay nothing). */
static int read_log_in(can_cfg_t *c, int *line, char *why, size_t wl)
{
    char read_why[512];
    can_cfg_fini(c); /* checked again: read again */
    if (!c->log_in[0] ||
        (c->log_in_frames = can_logfile_input_read(c->log_in, read_why, sizeof read_why)))
        return 0;
    *line = c->line_log_in;
    snprintf(why, wl, "log_in %s: %s", c->log_in, read_why);
    return -CFG_EVALUE;
}

int can_cfg_check(cfg_t *cfg, int *line, char *why, size_t wl)
{
    can_cfg_t *c = cfg->tcfg[transport_index(&can_transport)]; /* read_log_in fills it */
    unsigned n = 0, idx[CFG_OBJECTS_MAX];
    for (unsigned i = 0; i < cfg->nobj; i++)
        if (can_cfg_uses(&cfg->obj[i]))
            idx[n++] = i;
    if (!n)
        return 0;
    if (read_log_in(c, line, why, wl) < 0)
        return -CFG_EVALUE;
    can_port_config_t pc;
    can_cfg_port(c, (int64_t)llround((double)cfg->daemon.period_ns / cfg->daemon.speed), &pc);
    can_port_io_t io = {null_send, null_recv, NULL, null_up};
    can_port_hooks_t hk = {null_push, NULL, null_status, NULL, NULL};
    can_port_t *p = can_port_new(&pc, &io, NULL, n);
    if (!p) {
        snprintf(why, wl, "[can] sync settings invalid or out of memory");
        return -CFG_EVALUE;
    }
    int rc = 0;
    for (unsigned k = 0; k < n && !rc; k++) {
        const cfg_obj_t *o = &cfg->obj[idx[k]];
        canproto_ids_t ids;
        const char *rule = NULL;
        const can_obj_cfg_t *oc = cfg_obj_transport(o, &can_transport);
        can_obj_ids(oc, (unsigned)o->id, &ids);
        if (ids.cia402 == CANPROTO_CIA402_OFF &&
            (oc->given & ((GIVEN_COB << CANPROTO_CIA402_AXES) - GIVEN_COB))) /* said, not refused */
            log_msg(LOG_WARNING,
                    "%s:%d: object '%s': can.cia402_cob_* is set but has no effect: can.cia402 "
                    "is off (no CiA 402 frames are sent)",
                    cfg->path, o->line, o->name);
        if (ids_explicit(o, why, wl) < 0) {
            *line = o->line;
            rc = -CFG_EVALUE;
        } else if (canproto_ids_check(&ids, &rule) < 0) {
            *line = o->line;
            snprintf(why, wl, "object '%s': %s", o->name, rule);
            rc = -CFG_EVALUE;
        } else if (ids.cia402 == CANPROTO_CIA402_TARGETS && !o->has_initial_position) {
            *line = o->line;
            snprintf(why, wl,
                     "object '%s': can.cia402 = targets (no drive feedback) "
                     "needs initial_position: where the drives stand is never taken from a "
                     "waypoint",
                     o->name);
            rc = -CFG_EVALUE;
        } else if (ids.fd && !c->fd && !c->log_out[0] && !c->log_in[0]) {
            *line = o->line;
            snprintf(why, wl, "object '%s': can.fd = yes needs [can] fd = yes", o->name);
            rc = -CFG_EVALUE;
        } else if (can_port_set_object(p, k, &ids, &hk, NULL) < 0) {
            *line = o->line;
            snprintf(why, wl, "object '%s': a CAN id is used twice (by another object or the SYNC)",
                     o->name);
            rc = -CFG_EVALUE;
        }
    }
    if (!rc && c->max_load_percent > 0) {
        double load = can_port_busload(p, cfg->daemon.rate_hz, c->waypoint_hz, c->bitrate,
                                       c->data_bitrate);
        if (!(load >= 0) || load * 100 > c->max_load_percent) {
            snprintf(why, wl,
                     "CAN bus load %.1f %% (worst case with bit stuffing: %u object(s) at %g Hz, "
                     "%g waypoints/s each, %g bit/s) is above max_load_percent = %g: lower "
                     "rate_hz, send fewer frames (can.fd, can.own = no), or raise the bitrate",
                     load * 100, n, cfg->daemon.rate_hz, c->waypoint_hz, c->bitrate,
                     c->max_load_percent);
            rc = -CFG_EVALUE;
        }
    }
    can_port_free(p);
    return rc ? rc : can_box_check(cfg, line, why, wl); /* fields vs box and speed */
}
