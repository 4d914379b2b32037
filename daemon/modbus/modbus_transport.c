/* modbus_transport.c - the Modbus transport (see modbus_transport.h). */
#include "modbus_transport.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timex.h>

#include "core.h"
#include "keep.h"
#include "gate.h"
#include "log.h"
#include "mbmap.h"
#include "modbus_server.h"

typedef struct {
    core_t *core;
    modbus_server_t *srv;
    mbmap_object_t *objs;          /* nblock, rewritten every tick (taken at open) */
    unsigned nblock;               /* object blocks in the map: the highest object id + 1 */
    int obj_of[MBMAP_MAX_OBJECTS]; /* block (object id) -> core object index, -1 none */
    int rtu_down_logged;
    int64_t clock_checked_ns; /* when the system clock's sync state was last read */
    uint16_t clock_unsync;    /* 1: adjtimex says TIME_ERROR (not synchronised) */
} mbt_t;

static void cfg_default(void *cfg)
{
    modbus_server_config_t *m = cfg;
    modbus_server_config_default(m);
    m->enabled = 1; /* a [modbus] section or an input = modbus turns it on */
}

static int cfg_key(void *cfg, const cfg_kv_t *kv, char *why, size_t wl)
{
    int rc = modbus_server_config_set(cfg, kv->key, kv->value, why, wl);
    if (rc == -ENOENT)
        return -CFG_EUNKNOWN;
    return rc < 0 ? -CFG_EVALUE : 0;
}

static int check(cfg_t *cfg, int *line, char *why, size_t wl)
{
    const modbus_server_config_t *m = cfg_transport(cfg, &modbus_transport);
    for (unsigned i = 0; i < cfg->nobj; i++)
        if (cfg->obj[i].id >= MBMAP_MAX_OBJECTS) {
            *line = cfg->obj[i].id_line;
            snprintf(why, wl, "object '%s': id %d, the register map holds ids 0..%d",
                     cfg->obj[i].name, cfg->obj[i].id, MBMAP_MAX_OBJECTS - 1);
            return -CFG_EVALUE;
        }
    if (cfg->nobj > MBMAP_MAX_OBJECTS) {
        snprintf(why, wl, "modbus: %u objects, the register map holds %d", cfg->nobj,
                 MBMAP_MAX_OBJECTS);
        return -CFG_EVALUE;
    }
    for (unsigned i = 0; i < cfg->nobj; i++) {
        if (cfg->obj[i].input != &modbus_transport)
            continue;
        if (cfg->obj[i].writable == 0) {
            *line = cfg->obj[i].line;
            snprintf(why, wl, "object '%s' has input = modbus but writable = no", cfg->obj[i].name);
            return -CFG_EVALUE;
        }
        if (!m->enabled || !m->writes_enabled) {
            *line = cfg->obj[i].line;
            snprintf(why, wl, "object '%s' has input = modbus but [modbus] %s", cfg->obj[i].name,
                     m->enabled ? "writes = no (waypoints could never be written)"
                                : "enabled = no");
            return -CFG_EVALUE;
        }
    }
    if (m->enabled && !m->writes_enabled && m->write_allow[0])
        log_msg(LOG_WARNING,
                "%s:%d: [modbus] write_allow is set but has no effect: writes = no (no client "
                "may write)",
                cfg->path, *line);
    if (m->enabled && !m->tcp_address[0] && !m->rtu_device[0]) {
        snprintf(why, wl, "modbus: neither address (TCP) nor rtu_device (RTU) is set");
        return -CFG_EVALUE;
    }
    return 0;
}

/* The one gate of commands and override (gate.h) in Modbus terms: 0, the
 * hook's "no such address" (exception 02: not writable), or -ENGINE_ESTATE
 * (exception 03: the daemon is stopping). */
static int gate(const obj_t *o)
{
    int g = obj_gate(o, &modbus_transport);
    return g == OBJ_GATE_NOT_WRITABLE ? MODBUS_SERVER_HOOK_EADDRESS : g;
}

/* The object whose block is k (its id = k), or NULL: no object has that id. */
static obj_t *obj_at(mbt_t *t, unsigned k)
{
    if (k >= t->nblock || t->obj_of[k] < 0)
        return NULL;
    return &t->core->obj[t->obj_of[k]];
}

static int hook_waypoint(void *ctx, unsigned k, const engine_waypoint_t *wp)
{
    mbt_t *t = ctx;
    obj_t *o = obj_at(t, k);
    if (!o)
        return MODBUS_SERVER_HOOK_EADDRESS;
    if (o->cfg->input != &modbus_transport || !obj_gate_writable(o, &modbus_transport))
        return MODBUS_SERVER_HOOK_EADDRESS;
    char src[REJLOG_SRC_LEN];
    snprintf(src, sizeof src, "modbus %s", t->srv ? modbus_server_peer(t->srv) : "");
    return obj_push_from(o, wp, src);
}

/* The gate's refusal of a command to o from peer, logged and counted
 * (objlife.c obj_log_refused): the exception alone said nothing per object. */
static int gate_refused(obj_t *o, int g, const char *what, const char *peer)
{
    obj_log_refused(o, what, peer,
                    g == MODBUS_SERVER_HOOK_EADDRESS ? "not writable" : "trajd is stopping");
    return g;
}

static const char *command_name(unsigned cmd)
{
    switch (cmd) {
    case MBMAP_CMD_START: return "start";
    case MBMAP_CMD_STOP: return "stop";
    case MBMAP_CMD_CLEAR: return "clear";
    case MBMAP_CMD_RESET_COUNTERS: return "reset counters";
    case MBMAP_CMD_FINISH: return "finish";
    default: return "unknown";
    }
}

static int hook_command(void *ctx, unsigned k, unsigned cmd)
{
    mbt_t *t = ctx;
    obj_t *o = obj_at(t, k);
    if (!o)
        return MODBUS_SERVER_HOOK_EADDRESS;
    char peer[REJLOG_SRC_LEN];
    snprintf(peer, sizeof peer, "modbus %s", t->srv ? modbus_server_peer(t->srv) : "");
    int g = gate(o); /* writable, stopping (gate.h) */
    if (g)
        return gate_refused(o, g, command_name(cmd), peer);
    switch (cmd) { /* through the object's owner, logged with the peer (objlife.c) */
    case MBMAP_CMD_START: return obj_command(o, LC_EV_START, 0, peer);
    case MBMAP_CMD_STOP: return obj_command(o, LC_EV_STOP, 0, peer);
    case MBMAP_CMD_CLEAR: return obj_command(o, LC_EV_CLEAR, 0, peer);
    case MBMAP_CMD_RESET_COUNTERS: obj_reset_counters_from(o, peer); return 0;
    case MBMAP_CMD_FINISH: return obj_command(o, LC_EV_END_OF_INPUT, 0, peer);
    default: return -ENGINE_ESTATE;
    }
}

static int hook_override(void *ctx, unsigned k, unsigned percent)
{
    mbt_t *t = ctx;
    obj_t *o = obj_at(t, k);
    if (!o)
        return MODBUS_SERVER_HOOK_EADDRESS;
    char peer[REJLOG_SRC_LEN];
    snprintf(peer, sizeof peer, "modbus %s", t->srv ? modbus_server_peer(t->srv) : "");
    int g = gate(o);
    if (g) {
        char what[32];
        snprintf(what, sizeof what, "override %u %%", percent);
        return gate_refused(o, g, what, peer);
    }
    return obj_command(o, LC_EV_OVERRIDE, percent, peer);
}

/* A command or override refused for its value (exception 03): logged with
 * the object and the client, and counted in the object's refused commands,
 * as CAN's are (it was counted in mb_rejected alone). */
static void hook_refused(void *ctx, unsigned k, const mbmap_write_t *w)
{
    mbt_t *t = ctx;
    obj_t *o = obj_at(t, k);
    if (!o)
        return;
    char peer[REJLOG_SRC_LEN], what[48], why[64];
    snprintf(peer, sizeof peer, "modbus %s", t->srv ? modbus_server_peer(t->srv) : "");
    if (w->kind == MBMAP_WRITE_OVERRIDE) {
        snprintf(what, sizeof what, "override %u %%", w->override_pct);
        snprintf(why, sizeof why, "above %d %% (exception 03)", MBMAP_OVERRIDE_MAX_PCT);
    } else {
        snprintf(what, sizeof what, "%u", w->command);
        snprintf(why, sizeof why, "no such command: %d..%d (exception 03)", MBMAP_CMD_START,
                 MBMAP_CMD_FINISH);
    }
    obj_log_refused(o, what, peer, why);
}

static void on_ready(loop_t *l, int fd, uint32_t events, void *ctx)
{
    (void)l;
    (void)fd;
    (void)events;
    mbt_t *t = ctx;
    int rc = modbus_server_process(t->srv);
    if (rc < 0)
        log_msg(LOG_ERR, "modbus: %s", strerror(-rc));
    modbus_server_stats_t ms;
    modbus_server_stats(t->srv, &ms);
    if (ms.rtu_down && !t->rtu_down_logged) {
        t->rtu_down_logged = 1;
        log_msg(LOG_ERR, "modbus: RTU line failed; not reopened until a reload");
    }
}

/* Each object's Modbus counters and numbering as the server a reload closed
 * left them, for the server it opens (keep.h): an object carried over keeps
 * them. */
static void seq_kept_store(const mbt_t *t, const core_t *c)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        modbus_server_obj_seq_t q;
        modbus_server_obj_seq(t->srv, (unsigned)c->obj[i].cfg->id, &q);
        (void)keep_put("modbus", c->obj[i].name, &q, sizeof q); /* none kept: afresh */
    }
}

static void seq_kept_take(mbt_t *t, const core_t *c)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        modbus_server_obj_seq_t q;
        if (c->obj[i].carried && keep_take("modbus", c->obj[i].name, &q, sizeof q))
            modbus_server_set_obj_seq(t->srv, (unsigned)c->obj[i].cfg->id, &q);
    }
    keep_drop("modbus");
}

static int open_(core_t *c, void **state, char *why, size_t wl)
{
    const modbus_server_config_t *m = cfg_transport(c->cfg, &modbus_transport);
    *state = NULL;
    if (!m->enabled)
        return 0;
    mbt_t *t = calloc(1, sizeof *t);
    if (!t) {
        snprintf(why, wl, "modbus: out of memory");
        return -ENOMEM;
    }
    t->core = c;
    for (unsigned k = 0; k < MBMAP_MAX_OBJECTS; k++)
        t->obj_of[k] = -1;
    for (unsigned i = 0; i < c->nobj; i++) { /* ids are unique and < MBMAP_MAX_OBJECTS (check) */
        unsigned id = (unsigned)c->obj[i].cfg->id;
        t->obj_of[id] = (int)i;
        if (id + 1 > t->nblock)
            t->nblock = id + 1;
    }
    t->objs = calloc(t->nblock, sizeof *t->objs);
    for (unsigned k = 0; t->objs && k < t->nblock; k++)
        t->objs[k].absent = t->obj_of[k] < 0;
    modbus_server_config_t mc = *m;
    mc.n_objects = t->nblock;
    modbus_server_hooks_t hooks = {hook_waypoint, hook_command, t, hook_override, hook_refused};
    if (t->objs)
        t->srv = modbus_server_new(&mc, &hooks, why, wl);
    else
        snprintf(why, wl, "modbus: out of memory");
    if (!t->srv) {
        free(t->objs);
        free(t);
        return -EIO;
    }
    int rc = loop_add(c->loop, modbus_server_fd(t->srv), EPOLLIN, on_ready, t);
    if (rc < 0) {
        snprintf(why, wl, "modbus: loop_add: %s", strerror(-rc));
        modbus_server_free(t->srv);
        free(t->objs);
        free(t);
        return rc;
    }
    seq_kept_take(t, c); /* a reload: what the carried objects had */
    if (modbus_server_tcp_from_systemd(t->srv))
        log_msg(LOG_INFO, "modbus: TCP on the systemd socket, port %d, writes %s",
                modbus_server_tcp_port(t->srv), mc.writes_enabled ? "on" : "off");
    else if (mc.tcp_address[0])
        log_msg(LOG_INFO, "modbus: TCP on %s port %d, writes %s", mc.tcp_address,
                modbus_server_tcp_port(t->srv), mc.writes_enabled ? "on" : "off");
    if (mc.rtu_device[0])
        log_msg(LOG_INFO, "modbus: RTU on %s %d %d%c%d unit %d", mc.rtu_device, mc.rtu_baud,
                mc.rtu_data_bits, mc.rtu_parity, mc.rtu_stop_bits, mc.unit_id); /* 8E1 */
    *state = t;
    return 0;
}

/* The register map publishes the bus state the core holds (core.h) as is. */
_Static_assert(MBMAP_CAN_NONE == CORE_BUS_UNUSED && MBMAP_CAN_ACTIVE == CORE_BUS_ACTIVE &&
                   MBMAP_CAN_WARNING == CORE_BUS_WARNING && MBMAP_CAN_PASSIVE == CORE_BUS_PASSIVE &&
                   MBMAP_CAN_BUS_OFF == CORE_BUS_OFF && MBMAP_CAN_DOWN == CORE_BUS_DOWN,
               "mbmap.h MBMAP_CAN_* and core.h CORE_BUS_* disagree");

/* The bus's state, load and error-frame counters (stats_t.bus) into the daemon block. */
static void bus_regs(const core_bus_t *b, mbmap_daemon_t *d)
{
    d->can_state = (uint16_t)b->state;
    d->can_load_permille = (uint16_t)(b->load_permille > 0xffff ? 0xffff : b->load_permille);
    d->can_err_frames = b->err_frames;
    d->can_warnings = b->warnings;
    d->can_passives = b->passives;
    d->can_bus_offs = b->bus_offs;
    d->can_restarts = b->restarts;
    d->can_bus_errors = b->bus_errors;
    d->can_overflows = b->overflows;
    d->can_rx_dropped = b->rx_dropped;
    d->can_tx_err = (uint16_t)b->tx_err;
    d->can_rx_err = (uint16_t)b->rx_err;
}

/* An object's drives (obj_t.drive) into its block, and the daemon's totals. */
static void drive_regs(const core_drive_t *dr, mbmap_object_t *o, mbmap_daemon_t *d)
{
    unsigned st[ENGINE_AXES];
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        st[a] = dr->published ? dr->state[a] : CORE_DRIVE_NONE;
    o->drive_states = (uint16_t)((st[0] & 0x0F) | (st[1] & 0x0F) << 4 | (st[2] & 0x0F) << 8 |
                                 (dr->hb_lost ? 0x4000 : 0) | (dr->held ? 0x8000 : 0));
    o->drive_statusword = dr->statusword;
    o->drive_nmt = dr->published ? dr->nmt : CORE_DRIVE_NMT_NONE;
    o->drive_emcy = dr->emcy;
    o->tx_clamped = dr->tx_clamped;
    d->drive_emcy += dr->emcy_frames;
    d->drive_sdo_aborts += dr->sdo_aborts;
    d->drive_hb_lost += dr->hb_timeouts;
    if (dr->sdo_aborts)
        d->drive_last_abort = dr->last_abort;
}

/* In the tick: no allocation, no blocking call, no logging. */
static void cycle(void *state, core_t *c, int64_t now_ns)
{
    (void)now_ns;
    mbt_t *t = state;
    if (!t)
        return;
    const stats_t *s = c->stats;
    uint64_t up_s = (uint64_t)((core_mono_ns() - s->start_mono_ns) / 1000000000);
    mbmap_daemon_t d;
    memset(&d, 0, sizeof d);
    d.out_lost = s->out_lost;
    d.log_dropped = log_dropped_count(); /* never silent: log.h */
    d.out_fault = (uint16_t)(s->out_fault != 0);
    d.uptime_s = up_s;
    d.period_us = (uint32_t)(c->period_ns / 1000);
    d.late_p50_us = s->late.p50_us;
    d.late_p99_us = s->late.p99_us;
    d.late_max_us = s->late.max_us;
    d.missed_ticks = s->missed_ticks;
    d.clock_drift_ppm = s->clock_rate > 0 ? (s->clock_rate - 1.0) * 1e6 : 0;
    d.clock_delay_s = c->cfg->daemon.delay_s;
    d.clock_mode = (uint16_t)c->cfg->daemon.clock;
    bus_regs(&s->bus, &d);
    int64_t mono = core_mono_ns();
    if (mono - t->clock_checked_ns >= 1000000000) { /* once a second: a cheap syscall */
        struct timex tx;
        memset(&tx, 0, sizeof tx);
        t->clock_unsync = (uint16_t)(adjtimex(&tx) == TIME_ERROR);
        t->clock_checked_ns = mono;
    }
    for (unsigned k = 0; k < t->nblock; k++) {
        if (t->obj_of[k] < 0)
            continue;
        obj_t *ob = &c->obj[t->obj_of[k]];
        mbmap_object_t *o = &t->objs[k];
        o->sp = ob->sp;
        o->st = ob->status;
        /* sequence gaps: the CAN input's here, the server adds its own */
        o->lost = ob->rx.lost;
        o->resyncs = ob->rx.resyncs;
        o->late_p99_us = d.late_p99_us;
        o->late_max_us = d.late_max_us;
        o->can_state = d.can_state;
        o->can_load_permille = d.can_load_permille;
        o->uptime_s = up_s;
        const double *geo = core_obj_geo(c, ob);
        o->lat_deg = geo[0];
        o->lon_deg = geo[1];
        o->alt_m = geo[2];
        o->heading_deg = ob->heading_deg;
        o->heading_unwrapped_deg = ob->heading_unwrapped_deg;
        o->out_lost = ob->out_lost;
        o->out_fault = (uint16_t)(ob->out_fault != 0);
        o->seq_jumps = 0; /* the server adds its own */
        drive_regs(&ob->drive, o, &d);
        o->clocked = (uint16_t)(ob->clocked == 1);
        o->delay_s = c->cfg->daemon.delay_s;
        o->play_delay_s = obj_delay_s(c, ob);
        o->clock_unsync = t->clock_unsync;
        o->held = (uint16_t)(ob->held != 0);
        /* the lifecycle's (lib/engine/LIFECYCLE.md): held for a fault, or a stop latched */
        o->fault_held = (uint16_t)((ob->lc.hold & (LC_HOLD_SAFETY | LC_HOLD_DRIVE)) != 0);
        o->latched = (uint16_t)(ob->lc.latched != 0);
        d.clock_objects += o->clocked;
    }
    modbus_server_publish(t->srv, &d, t->objs);
}

static void close_(void *state, core_t *c)
{
    mbt_t *t = state;
    if (!t)
        return;
    loop_del(c->loop, modbus_server_fd(t->srv));
    if (!c->stopping)
        seq_kept_store(t, c); /* the next open (a reload's) takes them */
    modbus_server_free(t->srv);
    free(t->objs);
    free(t);
}

/* the listening socket or the serial line, the fd kept in reserve to tell a
 * client why it is refused (modbus_accept.c), and its clients */
static unsigned fds(const cfg_t *cfg, unsigned *clients)
{
    const modbus_server_config_t *m = cfg_transport(cfg, &modbus_transport);
    if (!m->enabled || !cfg_uses(cfg, &modbus_transport))
        return 0;
    if (m->tcp_address[0])
        *clients += m->max_clients;
    return (m->tcp_address[0] ? 2u : 0u) + (m->rtu_device[0] ? 1u : 0u);
}

const transport_t modbus_transport = {
    .name = "modbus",
    .roles = TRANSPORT_INPUT | TRANSPORT_SERVICE,
    .cfg_size = sizeof(modbus_server_config_t),
    .cfg_default = cfg_default,
    .cfg_key = cfg_key,
    .check = check,
    .open = open_,
    .cycle = cycle,
    .close = close_,
    .fds = fds,
};
