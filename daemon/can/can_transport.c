/* can_transport.c - the "can" transport (see can_transport.h). */
#include "can_transport.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "can_cfg.h"
#include "can_socket.h"
#include "can_box.h"
#include "can_logfile.h"
#include "can_refused.h"
#include "can_port.h"
#include "can_publish.h"
#include "cia402.h"
#include "core.h"
#include "keep.h"
#include "gate.h"
#include "log.h"

#define CAN_MAINTAIN_NS 100000000LL /* housekeeping: reopen, bus state */

/* ---- runtime ---- */

/* What can_port's hooks get: the object, and its waypoints' source as the
 * rejection log names it ("can IFACE id 0xID"). */
typedef struct {
    obj_t *o;
    char src[48];
    int rest_asked;      /* hk_feedback asked the moving engine to come to rest */
    unsigned clear_seen; /* o->clear_seq as the drives last saw it */
    unsigned reset_seen; /* o->reset_seq as the port's counters last saw it */
} can_hook_ctx_t;

typedef struct {
    core_t *c;
    const can_cfg_t *cfg;
    can_socket_t *bus;
    can_logfile_t *log;
    can_port_t *port;
    int sock_fd; /* registered in the loop, -1 if none */
    int timer_fd;
    unsigned n;
    obj_t *objs[CFG_OBJECTS_MAX];    /* can_port index -> object */
    int port_index[CFG_OBJECTS_MAX]; /* object index -> can_port index or -1 */
    int is_input[CFG_OBJECTS_MAX];
    can_hook_ctx_t hctx[CFG_OBJECTS_MAX]; /* can_port index -> its hooks' context */
    int64_t rx_now_ns;                    /* the step whose pre_tick drained the input */
    int drained;
    int log_ended; /* log_in delivered its last frame (nothing_usable judged) */
    int was_up;
    can_bus_state_t bus_state; /* as of the last housekeeping timer, for Modbus */
    canerr_bus_t err;          /* error-frame counters as of the same timer */
    uint32_t load_permille;    /* worst-case bus load of the configured traffic, 0.1 % */
    can_port_obj_stats_t drive_logged[CFG_OBJECTS_MAX]; /* drive counters already logged */
    unsigned drive_en_logged[CFG_OBJECTS_MAX];          /* the drives' enabled_n as last logged */
    unsigned drive_lost_logged[CFG_OBJECTS_MAX];        /* ... and lost_n */
    uint64_t refused_logged[CFG_OBJECTS_MAX];           /* cmd_refused already logged */
    uint64_t clamped_logged[CFG_OBJECTS_MAX];           /* tx_clamped already logged */
    int64_t refused_log_ns;                             /* when log_refused last logged */
    uint64_t rx_dropped;        /* the socket's rx_overflow, as of the last housekeeping */
    uint64_t rx_dropped_logged; /* ... as last logged */
    can_port_obj_stats_t traffic_logged[CFG_OBJECTS_MAX]; /* can_log_traffic's */
    unsigned wp_id[CFG_OBJECTS_MAX];                      /* the id each object's waypoints
                                                           * come on, for the log */
    can_logfile_stats_t out_seen;   /* log_out counters already put in core stats */
    can_logfile_stats_t out_logged; /* log_out counters already warned about */
    int64_t out_log_ns;             /* when report_log_out last warned, 0: never */
    uint64_t cycles_seen;           /* the port's dropped_pos already put in core stats */
} can_state_t;

/* The kernel's receive-queue drops of the sockets a reload closed. */
static uint64_t rx_dropped_closed;

/* log_out failures: warned at once, then once per CAN_LOG_OUT_WARN_S while lost (as csv). */
#define CAN_LOG_OUT_WARN_S 10

/* New log_out failures into the core's output-fault counters (as csv does): the daemon's and
 * each CAN-output object's fault flag, the frames lost as lines lost (exit status 74), EPIPE
 * on stdout ends the daemon.  No I/O.  objects: 0 at close (the objects may be going). */
static void log_out_faults(can_state_t *s, int objects)
{
    can_logfile_stats_t ls;
    can_logfile_stats(s->log, &ls);
    uint64_t errs = ls.write_errors - s->out_seen.write_errors,
             lost = ls.frames_lost - s->out_seen.frames_lost;
    stats_t *st = s->c->stats;
    st->out_lost += lost;
    if (errs) {
        st->out_errors += errs;
        st->out_errno = ls.last_errno;
        st->out_fault = 1;
        for (unsigned k = 0; objects && k < s->n; k++)
            if (cfg_obj_uses(s->objs[k]->cfg, &can_transport) & 2) {
                s->objs[k]->out_fault = 1;
                s->objs[k]->out_errors += errs;
            }
        if (ls.last_errno == EPIPE && !strcmp(s->cfg->log_out, "-"))
            st->exit_code = CORE_EXIT_EPIPE;
    }
    s->out_seen = ls;
}

/* Warn about new log_out losses, rate-limited (not from the tick). */
static void report_log_out(can_state_t *s, int final)
{
    const can_logfile_stats_t *ls = &s->out_seen, *was = &s->out_logged;
    if (ls->frames_lost == was->frames_lost && ls->write_errors == was->write_errors)
        return;
    int64_t now = core_mono_ns();
    if (!final && s->out_log_ns && now - s->out_log_ns < CAN_LOG_OUT_WARN_S * 1000000000LL)
        return;
    if (ls->write_errors != was->write_errors)
        log_msg(LOG_WARNING,
                "can: log_out %s: write failed: %s (%llu failed writes, %llu frames "
                "lost so far)",
                s->cfg->log_out, strerror(ls->last_errno), (unsigned long long)ls->write_errors,
                (unsigned long long)ls->frames_lost);
    else
        log_msg(LOG_WARNING,
                "can: log_out %s: reader too slow, buffer full: %llu frames lost so "
                "far",
                s->cfg->log_out, (unsigned long long)ls->frames_lost);
    s->out_logged = *ls;
    s->out_log_ns = now;
}

static const char *cmd_name(unsigned cmd)
{
    static const char *const names[] = {"?",     "finish",         "stop",
                                        "clear", "reset counters", "override"};
    return cmd < sizeof names / sizeof names[0] ? names[cmd] : "?";
}

/* Command frames refused since the last line, at most one line a second. */
static void log_refused(can_state_t *s, int64_t now_ns)
{
    if (s->refused_log_ns && now_ns - s->refused_log_ns < 1000000000LL)
        return;
    for (unsigned k = 0; k < s->n; k++) {
        can_port_obj_stats_t os;
        can_port_obj_stats(s->port, k, &os);
        if (os.tx_clamped > s->clamped_logged[k]) { /* can_box.h; the same 1 s limit */
            log_msg(LOG_WARNING,
                    "can: object '%s': %llu setpoint(s) sent with a value clipped to its field "
                    "(velocity beyond the SETPOINT frame's +-32.767 m/s); %llu in all",
                    s->objs[k]->name, (unsigned long long)(os.tx_clamped - s->clamped_logged[k]),
                    (unsigned long long)os.tx_clamped);
            s->refused_log_ns = now_ns;
        }
        s->clamped_logged[k] = os.tx_clamped;
        if (can_log_traffic(s->objs[k]->name, s->wp_id[k], &os, &s->traffic_logged[k]))
            s->refused_log_ns = now_ns;
        if (os.cmd_refused <= s->refused_logged[k]) {
            s->refused_logged[k] = os.cmd_refused; /* reset counters */
            continue;
        }
        char why[160];
        can_refused_why(why, sizeof why, os.last_refused_err, os.last_refused, s->objs[k]->stopping,
                        s->objs[k]->name);
        log_msg(LOG_WARNING,
                "can: object '%s': %llu command frame(s) refused, the last %s on id 0x%03X: "
                "%s; %llu refused in all",
                s->objs[k]->name, (unsigned long long)(os.cmd_refused - s->refused_logged[k]),
                cmd_name(os.last_refused), (unsigned)os.last_refused_id, why,
                (unsigned long long)os.cmd_refused);
        s->refused_logged[k] = os.cmd_refused;
        s->refused_log_ns = now_ns;
    }
}

/* What the object's drives did since the last housekeeping (once per 100 ms at most). */
static void log_drives(can_state_t *s)
{
    for (unsigned k = 0; k < s->n; k++) {
        can_port_obj_stats_t os, *was = &s->drive_logged[k];
        const can_port_drive_t *d = can_port_drive(s->port, k);
        const char *name = s->objs[k]->name;
        can_port_obj_stats(s->port, k, &os);
        if (os.sdo_aborts != was->sdo_aborts)
            log_msg(LOG_ERR,
                    "can: object '%s': drive refused SDO write of 0x%04X: abort 0x%08X (%s)", name,
                    os.last_abort_index, os.last_abort, cia402_sdo_abort_text(os.last_abort));
        if (os.emcy != was->emcy)
            log_msg(LOG_WARNING,
                    "can: object '%s': EMCY from a drive: error code 0x%04X (%llu so far)", name,
                    os.last_emcy, (unsigned long long)os.emcy);
        if (os.heartbeat_lost != was->heartbeat_lost)
            log_msg(LOG_ERR,
                    "can: object '%s': a drive's heartbeat was not heard in time (%llu): feed "
                    "hold, the object stops along its path; command clear resumes",
                    name, (unsigned long long)os.heartbeat_lost);
        can_axis_change_t ch;
        uint64_t lost = 0, more;
        while (can_port_drive_change(s->port, k, &ch, &more) && (lost += more, 1))
            log_msg(ch.to == CIA402_OPERATION_ENABLED ? LOG_INFO : LOG_WARNING,
                    "can: object '%s': drive %c (node %u): %s -> %s (statusword 0x%04X) at %.3f "
                    "s%s",
                    name, "xyz"[ch.axis % 3], ch.node, cia402_state_name(ch.from),
                    ch.to == CIA402_STATE_UNKNOWN ? "boot-up" : cia402_state_name(ch.to),
                    ch.statusword, (double)ch.t_ns / 1e9,
                    ch.from == CIA402_STATE_UNKNOWN &&
                            (ch.to == CIA402_FAULT || ch.to == CIA402_FAULT_REACTION)
                        ? ": found in a fault, held (the command clear resets it; trajd never "
                          "resets a fault by itself)"
                        : "");
        if ((lost += more) > 0)
            log_msg(LOG_WARNING, "can: object '%s': %llu drive state changes not logged (too many)",
                    name, (unsigned long long)lost);
        if (os.sdo_timeouts != was->sdo_timeouts)
            log_msg(LOG_WARNING, "can: object '%s': SDO request unanswered, resent (%llu)", name,
                    (unsigned long long)os.sdo_timeouts);
        /* each loss and each enable once, in that order, even when both came
         * between two polls (a fault cleared within one: counted in can_drive.c) */
        if (d && d->lost_n != s->drive_lost_logged[k]) {
            s->drive_lost_logged[k] = d->lost_n;
            log_msg(LOG_ERR,
                    "can: object '%s': a drive left Operation Enabled (x: %s, y: %s, "
                    "z: %s): object held, a drive not enabled gets its own position as "
                    "target%s",
                    name, d->seen & 1 ? cia402_state_name(d->state[0]) : "-",
                    d->seen & 2 ? cia402_state_name(d->state[1]) : "-",
                    d->seen & 4 ? cia402_state_name(d->state[2]) : "-",
                    d->held ? "; command clear resets and re-enables it" : "");
        }
        if (d && d->enabled_n != s->drive_en_logged[k]) {
            s->drive_en_logged[k] = d->enabled_n;
            log_msg(LOG_NOTICE,
                    "can: object '%s': drives in Operation Enabled, starting from "
                    "(%.4f, %.4f, %.4f)",
                    name, d->pos_m[0], d->pos_m[1], d->pos_m[2]);
        }
        *was = os;
    }
}

/* What the port a reload closed had of each object, for the port it opens
 * next (keep.h): its counters and waypoint reassembly (can_port_kept_t), and
 * its drives, running, adopted as they are (never brought up again, never
 * re-anchored while they follow the object), with the SYNC counter. */
typedef struct {
    can_drive_t drv;
    uint8_t sync;
    can_port_kept_t port;
} kept_drives_t;

static void kept_store(const can_state_t *s)
{
    static kept_drives_t k; /* (large: not on the stack) */
    for (unsigned i = 0; s->port && i < s->n; i++) {
        memset(&k, 0, sizeof k);
        k.drv = *can_port_drive_state(s->port, i);
        k.sync = can_port_sync_counter(s->port);
        can_port_keep(s->port, i, &k.port);
        (void)keep_put("can", s->objs[i]->name, &k, sizeof k); /* none kept: brought up again */
    }
}

/* Object k of s takes what its name had in the port closed before (the same
 * ids: cfg_reload_check): its counters and reassembly, and (drives) the
 * drives: 1 if it took those. */
static int kept_adopt(can_state_t *s, unsigned k, int drives)
{
    static kept_drives_t kd;
    if (!keep_take("can", s->objs[k]->name, &kd, sizeof kd))
        return 0;
    can_port_restore(s->port, k, &kd.port);
    can_port_obj_stats(s->port, k, &s->traffic_logged[k]); /* logged before the reload */
    if (!drives || !can_port_adopt(s->port, k, &kd.drv, kd.sync))
        return 0;
    const can_port_drive_t *d = can_port_drive(s->port, k);
    s->drive_en_logged[k] = d ? d->enabled_n : 0; /* told by the port before */
    s->drive_lost_logged[k] = d ? d->lost_n : 0;
    can_port_obj_stats(s->port, k, &s->drive_logged[k]);
    log_msg(LOG_INFO, "can: object '%s': its drives kept as they run over the reload",
            s->objs[k]->name);
    return 1;
}

static int hk_push(void *ctx, const engine_waypoint_t *wp)
{
    const can_hook_ctx_t *h = ctx;
    char src[REJLOG_SRC_LEN];
    snprintf(src, sizeof src, "%s seq %" PRIu32, h->src, wp->seq);
    return obj_push_from(h->o, wp, src);
}

static int hk_command(void *ctx, canproto_cmd_t cmd, unsigned arg)
{
    const can_hook_ctx_t *h = ctx;
    obj_t *o = h->o;
    if (o->stopping) /* the one gate (gate.h); writable is cmd_mask's */
        return -ENGINE_ESTATE;
    if (cmd == CANPROTO_CMD_OVERRIDE && arg > CANPROTO_OVERRIDE_MAX_PCT)
        return -ENGINE_ERANGE; /* refused and logged as such (log_refused) */
    switch (cmd) {             /* through the object's owner, logged with the peer (objlife.c) */
    case CANPROTO_CMD_FINISH: return obj_command(o, LC_EV_END_OF_INPUT, 0, h->src);
    case CANPROTO_CMD_STOP: return obj_command(o, LC_EV_STOP, 0, h->src);
    case CANPROTO_CMD_START: return obj_command(o, LC_EV_START, 0, h->src);
    case CANPROTO_CMD_CLEAR: {
        int rc = obj_command(o, LC_EV_CLEAR, 0, h->src);
        ((can_hook_ctx_t *)ctx)->clear_seen = o->clear_seq; /* can_port does the drives' part */
        return rc;
    }
    case CANPROTO_CMD_RESET_COUNTERS: /* can_port resets its own */
        obj_reset_counters(o);
        ((can_hook_ctx_t *)ctx)->reset_seen = o->reset_seq;
        break;
    case CANPROTO_CMD_OVERRIDE: return obj_command(o, LC_EV_OVERRIDE, arg, h->src);
    default: break;
    }
    return 0;
}

/* The drives' events to the object's owner (lib/engine/LIFECYCLE.md): a drive
 * lost or booted is a drive hold (the object brakes to rest within its
 * limits, held until clear), a heartbeat lost a feed hold. */
static void hk_drive_event(void *ctx, lc_event_t ev)
{
    (void)obj_drive_event(((const can_hook_ctx_t *)ctx)->o, ev, NULL);
}

/*
 * A drive's feedback for one axis.  Each drive gets the engine's targets only
 * once the engine stands where the drive does (can_axis.h): when every drive
 * of the object is in Operation Enabled and one is not yet following (at
 * start, after a fault, a quick stop or a boot-up and the clear), the engine
 * is re-anchored at rest there (the drives' 0x6064, or the target a drive
 * held), and reaches the track by a transfer.  An engine still moving is
 * brought to rest first (a clear), and re-anchored at a later frame.
 * The loss itself holds the object (hk_drive_event).  While the object is
 * held, the position is only noted (a clear re-anchors there): the drives
 * keep their own targets until the engine really stands there.
 */
static int hk_feedback(void *ctx, const can_port_drive_t *d)
{
    can_hook_ctx_t *h = ctx;
    if (!d->need_anchor)
        return 0;
    int rc = obj_drive_event(h->o, LC_EV_DRIVE_ENABLED, d->anchor_m);
    if (rc >= 0) {
        h->rest_asked = 0;
        return rc; /* 1: adopted; 0: noted while held */
    }
    if (!h->rest_asked) /* once: to rest along its path (a clear), re-anchored later */
        (void)obj_command(h->o, LC_EV_CLEAR, 0, "can: drives enabled again, re-anchoring");
    h->rest_asked = 1;
    return 0;
}

/* The object's status as the core took it this tick (core.c, tick): its
 * counts summed over a reload that changed its settings and the braking
 * predecessor's, the room of the latch while it is stopped or held; what
 * Modbus and the status line show too, not the current engine's alone. */
static void hk_status(void *ctx, engine_status_t *st)
{
    *st = ((const can_hook_ctx_t *)ctx)->o->status;
}

/* Objects that are not CAN inputs must not get waypoints from the bus. */
static int hk_push_refuse(void *ctx, const engine_waypoint_t *wp)
{
    (void)ctx;
    (void)wp;
    return -ENGINE_ESTATE;
}

static int io_send(void *io, const canproto_frame_t *f)
{
    can_state_t *s = io;
    return s->bus ? can_socket_send(s->bus, f) : can_logfile_send(s->log, f);
}

static int io_recv(void *io, int64_t now_ns, canproto_frame_t *f)
{
    can_state_t *s = io;
    if (s->bus) {
        int rc = can_socket_recv(s->bus, f);
        return rc;
    }
    return can_logfile_recv(s->log, now_ns, f);
}

static int io_maintain(void *io, int64_t now_ns)
{
    can_state_t *s = io;
    return s->bus ? can_socket_maintain(s->bus, now_ns) : 0;
}

static int io_is_up(const void *io)
{
    const can_state_t *s = io;
    return s->bus ? can_socket_state(s->bus) == CAN_SOCKET_UP : 1;
}

static void on_readable(loop_t *l, int fd, uint32_t ev, void *ctx);

/* Keep the loop registration in step with the socket (it changes on reopen). */
static void sync_fd(can_state_t *s)
{
    int fd = s->bus ? can_socket_fd(s->bus) : -1;
    if (fd == s->sock_fd)
        return;
    if (s->sock_fd >= 0)
        loop_del(s->c->loop, s->sock_fd);
    s->sock_fd = -1;
    if (fd >= 0 && loop_add(s->c->loop, fd, EPOLLIN, on_readable, s) == 0)
        s->sock_fd = fd;
}

/* Refresh the bus state the cycle publishes to the core (can_publish.h). */
static void publish_state(can_state_t *s)
{
    const canerr_bus_t *e = can_port_bus_errors(s->port);
    can_bus_state_t was = s->bus_state;
    s->bus_state = io_is_up(s) ? (can_bus_state_t)e->state : CAN_BUS_DOWN;
    if (was && s->bus_state != was && s->bus_state != CAN_BUS_DOWN && was != CAN_BUS_DOWN)
        log_msg(s->bus_state == CAN_BUS_ERROR_ACTIVE ? LOG_NOTICE : LOG_WARNING,
                "can: %s controller %s (error frames %llu, TX/RX error counters %u/%u, "
                "bus-off %llu, restarts %llu)",
                s->cfg->interface[0] ? s->cfg->interface : "log", canerr_state_name(e->state),
                (unsigned long long)e->frames, e->tx_err, e->rx_err,
                (unsigned long long)e->bus_offs, (unsigned long long)e->restarts);
    s->err = *e;
}

static void on_readable(loop_t *l, int fd, uint32_t ev, void *ctx)
{
    can_state_t *s = ctx;
    (void)l;
    (void)fd;
    (void)ev;
    can_port_rx(s->port, s->c->now_ns);
    sync_fd(s); /* the socket may have gone DOWN (EPOLLERR -> ENETDOWN) */
}

static void on_timer(loop_t *l, uint64_t exp, void *ctx)
{
    can_state_t *s = ctx;
    (void)l;
    (void)exp;
    if (can_port_maintain(s->port, core_mono_ns()))
        log_msg(LOG_NOTICE, "can: %s is up again, streaming resumes", s->cfg->interface);
    sync_fd(s);
    int up = io_is_up(s);
    if (s->was_up && !up) {
        can_socket_stats_t bs;
        can_socket_stats(s->bus, &bs);
        log_msg(LOG_WARNING, "can: %s is down (%s): setpoints dropped, reopening",
                s->cfg->interface, strerror(bs.last_errno));
    }
    s->was_up = up;
    if (s->bus) {
        can_socket_stats_t bs;
        can_socket_stats(s->bus, &bs);
        s->rx_dropped = rx_dropped_closed + bs.rx_overflow;
    }
    if (s->rx_dropped != s->rx_dropped_logged &&
        !(s->refused_log_ns && core_mono_ns() - s->refused_log_ns < 1000000000LL)) {
        log_msg(LOG_WARNING,
                "can: %s: %llu frame(s) dropped by the kernel, trajd's receive queue full (a "
                "stall of trajd): waypoints among them are counted lost; %llu in all",
                s->cfg->interface, (unsigned long long)(s->rx_dropped - s->rx_dropped_logged),
                (unsigned long long)s->rx_dropped);
        s->rx_dropped_logged = s->rx_dropped;
        s->refused_log_ns = core_mono_ns();
    }
    if (s->log)
        report_log_out(s, 0);
    log_drives(s);
    log_refused(s, core_mono_ns());
    publish_state(s);
}

/* The bus side's counters at close: what came in, the SYNCs, the cycles. */
static void log_port(const can_state_t *s)
{
    can_port_stats_t ps;
    can_port_stats(s->port, &ps);
    log_msg(LOG_INFO,
            "can: %s: frames received %llu (%llu for no object, %llu errors, %llu dropped by the "
            "kernel: the receive queue full); SYNC sent %llu,"
            " dropped %llu; cycles %llu (%llu down), reopens %llu",
            s->log ? "candump logs" : s->cfg->interface, (unsigned long long)ps.rx_frames,
            (unsigned long long)ps.rx_foreign, (unsigned long long)ps.rx_errors,
            (unsigned long long)s->rx_dropped, (unsigned long long)ps.sync_sent,
            (unsigned long long)ps.sync_dropped, (unsigned long long)ps.cycles,
            (unsigned long long)ps.down_cycles, (unsigned long long)ps.reopens);
}

static void close_(void *state, core_t *c)
{
    can_state_t *s = state;
    if (!s)
        return;
    if (s->sock_fd >= 0)
        loop_del(s->c->loop, s->sock_fd);
    if (s->timer_fd > 0)
        loop_timer_del(s->c->loop, s->timer_fd);
    if (s->log && s->cfg->log_in[0]) /* a reload goes on from here (log_in_resume) */
        can_logfile_keep_pos(s->log, s->cfg->log_in);
    if (s->log) { /* the last lines, counted before the counters are read */
        can_logfile_finish(s->log);
        log_out_faults(s, 0);
        report_log_out(s, 1);
    }
    if (s->port) {
        s->refused_log_ns = 0; /* the refusals of the last second, with their reason */
        log_refused(s, core_mono_ns());
        log_port(s);
        for (unsigned k = 0; k < s->n; k++) {
            can_port_obj_stats_t os;
            can_port_obj_stats(s->port, k, &os);
            log_msg(LOG_INFO,
                    "can: %s: setpoints sent %llu, dropped late %llu / queue full %llu / down %llu"
                    " / error %llu (%llu with a position); waypoints %llu accepted, %llu rejected, "
                    "%llu full, %llu lost,"
                    " %llu duplicate frames, %llu out of order, %llu resynced, %llu malformed"
                    " frames;"
                    " %llu commands refused; STATUS frames sent %llu, not sent %llu",
                    s->objs[k]->name, (unsigned long long)os.setpoints_sent,
                    (unsigned long long)os.dropped_late, (unsigned long long)os.dropped_full,
                    (unsigned long long)os.dropped_down, (unsigned long long)os.dropped_error,
                    (unsigned long long)os.dropped_pos, (unsigned long long)os.waypoints_accepted,
                    (unsigned long long)os.waypoints_rejected,
                    (unsigned long long)os.waypoints_full, (unsigned long long)os.rx.lost,
                    (unsigned long long)os.rx.duplicates, (unsigned long long)os.rx.out_of_order,
                    (unsigned long long)os.rx.resyncs, (unsigned long long)os.rx.malformed,
                    (unsigned long long)os.cmd_refused, (unsigned long long)os.status_sent,
                    (unsigned long long)os.status_dropped);
        }
    }
    if (c && !c->stopping)
        kept_store(s); /* the next open (a reload's) adopts them */
    rx_dropped_closed = s->rx_dropped;
    can_port_free(s->port);
    can_socket_free(s->bus);
    can_logfile_close(s->log);
    free(s);
}

/* The objects that use CAN, in config order, as can_port indices. */
static void collect_objects(can_state_t *s, core_t *c)
{
    for (unsigned i = 0; i < c->nobj; i++) {
        s->port_index[i] = -1;
        if (!can_cfg_uses(c->obj[i].cfg))
            continue;
        s->port_index[i] = (int)s->n;
        s->is_input[s->n] = c->obj[i].cfg->input == &can_transport;
        s->objs[s->n++] = &c->obj[i];
    }
}

/*
 * The commands CAN may give object k: all if it is writable (writable = yes,
 * or not given and its input is CAN); otherwise none, except FINISH for a CAN
 * input (the end of its own input, as the end of a replay file).  Refused
 * commands are counted, reported in STATUS / STATUS2 and logged (log_refused).
 */
static uint32_t cmd_mask(const can_state_t *s, unsigned k)
{
    if (obj_gate_writable(s->objs[k], &can_transport)) /* gate.h: Modbus's rule too */
        return CAN_PORT_CMD_ALL;
    return s->is_input[k] ? 1u << CANPROTO_CMD_FINISH : 0;
}

/* Give every object its ids and hooks; the ids to receive go to rx_ids. */
static int set_objects(can_state_t *s, uint32_t *rx_ids, unsigned *nrx, char *why, size_t wl)
{
    for (unsigned k = 0; k < s->n; k++) {
        canproto_ids_t ids;
        can_obj_ids(cfg_obj_transport(s->objs[k]->cfg, &can_transport),
                    (unsigned)s->objs[k]->cfg->id, &ids);
        can_port_hooks_t hk = {s->is_input[k] ? hk_push : hk_push_refuse, hk_command, hk_status,
                               hk_feedback, hk_drive_event};
        s->drive_en_logged[k] = s->drive_lost_logged[k] = 0;
        s->hctx[k].o = s->objs[k];
        s->hctx[k].clear_seen = s->objs[k]->clear_seq;
        s->hctx[k].reset_seen = s->objs[k]->reset_seq;
        snprintf(s->hctx[k].src, sizeof s->hctx[k].src, "can %s id 0x%03" PRIX32,
                 s->cfg->log_in[0] || s->cfg->log_out[0] ? s->cfg->log_ifname : s->cfg->interface,
                 ids.fd ? ids.waypoint_fd_id : ids.waypoint_id);
        s->wp_id[k] = ids.fd ? ids.waypoint_fd_id : ids.waypoint_id;
        if (can_port_set_object(s->port, k, &ids, &hk, &s->hctx[k]) < 0) {
            snprintf(why, wl, "can: object '%s': invalid or clashing ids", s->objs[k]->name);
            return -EINVAL;
        }
        /* a reload: the drives it ran go on as they are (a changed object's
         * new engine starts where its output stood: core.c) */
        int adopted = kept_adopt(s, k, ids.cia402 >= CANPROTO_CIA402_FEEDBACK);
        if (ids.cia402 >= CANPROTO_CIA402_FEEDBACK && !s->objs[k]->carried && !adopted)
            engine_require_position(s->objs[k]->engine, 1);      /* the drive says where it is */
        else if (ids.cia402 && !s->objs[k]->carried && !adopted) /* check(): initial_position */
            log_msg(LOG_NOTICE,
                    "can: object '%s': no drive feedback (can.cia402 = targets): the drives "
                    "are taken to stand at initial_position, and are sent targets from there",
                    s->objs[k]->name);
        can_port_allow_commands(s->port, k, cmd_mask(s, k));
        uint32_t mine[24];
        /* waypoint ids for inputs and for objects that take commands */
        unsigned m = canproto_ids_rx(&ids, mine, 24),
                 from = s->is_input[k] || cmd_mask(s, k) ? 0 : 1 + (unsigned)ids.fd;
        for (unsigned j = from; j < m && j < 24; j++) { /* waypoint ids (inputs), feedback TPDOs */
            if (*nrx >= CAN_SOCKET_MAX_FILTERS) {
                snprintf(why, wl, "can: more than %d ids to receive (waypoints, drive feedback)",
                         CAN_SOCKET_MAX_FILTERS);
                return -EINVAL;
            }
            rx_ids[(*nrx)++] = mine[j];
        }
    }
    return 0;
}

/* Why log_out is truncated at this open, or NULL: it is appended to.
 * auto: truncated when stamps are engine time starting from 0 (a start, not
 * a reload: engine time goes on across a reload), so a log never goes back
 * in time; wall stamps go on with the clock, appended. */
static const char *log_out_truncates(const can_state_t *s)
{
    if (s->cfg->log_out_truncate >= 0)
        return s->cfg->log_out_truncate ? "log_out_truncate = yes" : NULL;
    return s->cfg->log_time_engine && s->c->now_ns == 0
               ? "log_time = engine: its stamps start again from 0"
               : NULL;
}

/* Says whether log_out was truncated or appended to; appended, warns if its last stamp is later
 * than this run's first (first_us): time goes back there (speed > 1 puts wall stamps ahead). */
static void report_log_out_open(can_state_t *s, const char *why_trunc, int64_t first_us)
{
    long long kept = can_logfile_out_kept(s->log);
    int64_t last_us = can_logfile_out_last_us(s->log);
    if (!why_trunc && last_us != INT64_MIN && last_us > first_us)
        log_msg(LOG_WARNING,
                "can: log_out %s: its last stamp (%.6f) is later than this run's first "
                "(%.6f): the log goes back in time here (log_out_truncate = yes avoids it)",
                s->cfg->log_out, (double)last_us / 1e6, (double)first_us / 1e6);
    if (why_trunc)
        log_msg(LOG_INFO, "can: log_out %s: truncated (%s)", s->cfg->log_out, why_trunc);
    else if (kept > 0)
        log_msg(LOG_INFO, "can: log_out %s: appending after the %lld bytes already there",
                s->cfg->log_out, kept);
    else if (kept == 0)
        log_msg(LOG_INFO, "can: log_out %s: appending (it was empty)", s->cfg->log_out);
}

/* A reload that carries a CAN-input object over goes on where log_in stopped. */
static void log_in_resume(can_state_t *s)
{
    int carried = 0;
    for (unsigned k = 0; k < s->n; k++)
        carried |= s->is_input[k] && s->objs[k]->carried;
    size_t pos = can_logfile_resume(s->log, carried ? s->cfg->log_in : NULL);
    if (pos)
        log_msg(LOG_INFO, "can: log_in %s: going on after its %zu frames already played",
                s->cfg->log_in, pos);
}

/* The candump logs if configured, else the socket (a missing or down
 * interface is not an error: the port runs DOWN and keeps reopening).  log_in
 * is not read here, in the loop: the check read it on the configuration's
 * worker (can_cfg.h log_in_frames), and the log replays those frames. */
static int open_io(can_state_t *s, const uint32_t *rx_ids, unsigned nrx, char *why, size_t wl)
{
    const can_cfg_t *cfg = s->cfg;
    if (cfg->log_in[0] || cfg->log_out[0]) {
        const char *why_trunc = log_out_truncates(s);
        if (cfg->log_in[0] && !cfg->log_in_frames) { /* the check reads it: never here */
            snprintf(why, wl, "can: log_in %s: not read by the configuration's check", cfg->log_in);
            return -EINVAL;
        }
        s->log = can_logfile_open_input(cfg->log_in[0] ? cfg->log_in_frames : NULL,
                                        cfg->log_out[0] ? cfg->log_out : NULL, cfg->log_ifname, 0,
                                        !why_trunc, why, wl);
        int64_t epoch_ns = 0;
        if (s->log && !cfg->log_time_engine) {
            /* epoch stamps: the wall clock now is the engine's now */
            struct timespec ts;
            clock_gettime(CLOCK_REALTIME, &ts);
            epoch_ns = (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec - s->c->now_ns;
            can_logfile_set_epoch(s->log, epoch_ns);
        }
        if (s->log && strcmp(cfg->log_out, "-") && cfg->log_out[0])
            report_log_out_open(s, why_trunc, (epoch_ns + s->c->now_ns) / 1000);
        if (s->log && cfg->log_in[0])
            log_in_resume(s);
        return s->log ? 0 : -EIO;
    }
    s->bus = can_socket_new(cfg->interface, cfg->fd, rx_ids, nrx);
    if (!s->bus) {
        snprintf(why, wl, "can: bad interface name '%s'", cfg->interface);
        return -EINVAL;
    }
    int rc = can_socket_open(s->bus);
    if (rc == -EAFNOSUPPORT || rc == -EPERM || rc == -EACCES) {
        snprintf(why, wl, "can: cannot open a CAN socket: %s", strerror(-rc));
        return rc;
    }
    if (rc < 0) /* missing or down: run DOWN and keep reopening */
        log_msg(LOG_WARNING, "can: %s: %s; setpoints dropped until it is up", cfg->interface,
                strerror(-rc));
    sync_fd(s);
    return 0;
}

static int open_(core_t *c, void **state, char *why, size_t wl)
{
    const can_cfg_t *cfg = cfg_transport(c->cfg, &can_transport);
    can_state_t *s = calloc(1, sizeof *s);
    if (s) /* the drops of the sockets before a reload go on counting */
        s->rx_dropped = s->rx_dropped_logged = rx_dropped_closed;
    int rc = 0;
    if (!s) {
        snprintf(why, wl, "out of memory");
        return -ENOMEM;
    }
    s->c = c;
    s->cfg = cfg;
    s->sock_fd = -1;
    collect_objects(s, c);
    if (!s->n) {
        *state = s; /* [can] present but no object uses it: nothing to do */
        return 0;
    }
    can_port_config_t pc;
    can_cfg_port(cfg, (int64_t)llround((double)c->period_ns / c->cfg->daemon.speed), &pc);
    pc.period_ns = c->period_ns; /* engine time per tick, as the now_ns the port gets */
    can_port_io_t io = {io_send, io_recv, io_maintain, io_is_up};
    s->port = can_port_new(&pc, &io, s, s->n);
    if (!s->port) {
        snprintf(why, wl, "can: out of memory");
        rc = -ENOMEM;
        goto fail;
    }
    uint32_t rx_ids[CAN_SOCKET_MAX_FILTERS];
    unsigned nrx = 0;
    rc = set_objects(s, rx_ids, &nrx, why, wl);
    keep_drop("can"); /* taken (or not the same drives) */
    if (rc < 0 || (rc = open_io(s, rx_ids, nrx, why, wl)) < 0)
        goto fail;
    double load = can_port_busload(s->port, c->cfg->daemon.rate_hz, cfg->waypoint_hz, cfg->bitrate,
                                   cfg->data_bitrate);
    s->load_permille = load > 0 ? (uint32_t)llround(load * 1000) : 0;
    log_msg(LOG_INFO, "can: %u object(s) on %s, worst-case bus load %.1f %% at %g bit/s", s->n,
            s->log ? "candump logs" : cfg->interface, load * 100, cfg->bitrate);
    s->was_up = io_is_up(s);
    publish_state(s);
    s->timer_fd = loop_timer_add(c->loop, CAN_MAINTAIN_NS, on_timer, s);
    if (s->timer_fd < 0) {
        rc = s->timer_fd;
        snprintf(why, wl, "can: timer: %s", strerror(-rc));
        goto fail;
    }
    *state = s;
    return 0;
fail:
    close_(s, c);
    return rc ? rc : -EINVAL;
}

/* log_in delivered its last frame: it ends as a replayed track does, each object fed by it
 * runs to its last waypoint (engine_finish, as FINISH; a no-op after one).  One that accepted
 * no waypoint had nothing usable (issue 11): logged, trajd exits with CORE_EXIT_NO_INPUT. */
static void log_in_ended(can_state_t *s)
{
    can_logfile_stats_t ls;
    can_logfile_stats(s->log, &ls);
    for (unsigned k = 0; k < s->n; k++) {
        if (!s->is_input[k])
            continue;
        engine_status_t st;
        engine_status(s->objs[k]->engine, &st);
        if (st.accepted && !s->objs[k]->stopping)
            (void)engine_finish(s->objs[k]->engine); /* 0 or ENUMERIC: counted by it */
        /* the object's (a reload that changed its settings may have left a
         * new engine that the log gave nothing before it ended) */
        if (obj_accepted(s->objs[k]))
            continue;
        can_port_obj_stats_t os;
        can_port_obj_stats(s->port, k, &os);
        can_port_stats_t ps;
        can_port_stats(s->port, &ps);
        char other[200] = ""; /* frames on ids no object uses: a log for another id? */
        if (ps.rx_foreign)
            snprintf(other, sizeof other,
                     "; %llu frames on ids no object uses, the first on 0x%0*" PRIX32
                     ", while its waypoints come on 0x%03" PRIX32 " (from its id; or set "
                     "can.waypoint_id)",
                     (unsigned long long)ps.rx_foreign,
                     (ps.rx_foreign_first_flags & CANPROTO_F_EFF) ? 8 : 3, ps.rx_foreign_first,
                     s->wp_id[k]);
        log_msg(LOG_ERR,
                "can: object '%s': log_in %s ended with no usable waypoint for it (0 accepted, "
                "%llu rejected, %llu malformed frames, %llu bad lines%s); trajd will exit with "
                "status %d",
                s->objs[k]->name, s->cfg->log_in, (unsigned long long)os.waypoints_rejected,
                (unsigned long long)os.rx.malformed, (unsigned long long)ls.bad_lines, other,
                CORE_EXIT_NO_INPUT);
        s->c->stats->no_input++;
    }
}

static void pre_tick(void *state, obj_t *o, int64_t now_ns)
{
    can_state_t *s = state;
    (void)o;
    /* once per step: frames due by now (log input), or anything the socket
     * has.  Keyed on the step's time, not the tick's cycle: stepping through
     * missed deadlines (speed != 1, core.c tick) every step is one cycle, and
     * the frames of a log_in due within those deadlines were held back to the
     * next tick: under load a sender 500 ppm slow met underruns
     * (tests/e2e/test_drift_daemon.py, 2 runs in 3 with both CPUs busy). */
    if (s->drained && s->rx_now_ns == now_ns)
        return;
    s->drained = 1;
    s->rx_now_ns = now_ns;
    if (s->port) {
        can_port_rx(s->port, now_ns);
        sync_fd(s);
    }
    if (s->port && s->log && s->cfg->log_in[0] && !s->log_ended && can_logfile_done(s->log)) {
        s->log_ended = 1;
        log_in_ended(s);
    }
}

/* STATUS2 page 3: the data age of the setpoint, the daemon's drift estimate
 * (as Modbus clock_drift gives it) and the object's clock. */
static void status2_clock(const can_state_t *s, const obj_t *o, const engine_setpoint_t *sp,
                          canproto_frame_t *f)
{
    double rate = s->c->stats->clock_rate;
    canproto_st2_clock_t pg = {sp->age_s, rate > 0 ? (rate - 1.0) * 1e6 : 0,
                               o->clocked == 1   ? CANPROTO_ST2_CLOCK_ON
                               : o->clocked == 0 ? CANPROTO_ST2_CLOCK_RELATIVE
                                                 : CANPROTO_ST2_CLOCK_UNDECIDED};
    canproto_encode_status2_clock(0, &pg, f);
}

static void setpoint(void *state, obj_t *o, const engine_setpoint_t *sp)
{
    can_state_t *s = state;
    if (s->port && s->port_index[o->index] >= 0) {
        unsigned k = (unsigned)s->port_index[o->index];
        can_port_obj_stats_t os;
        canproto_frame_t f;
        can_port_output_fault(s->port, k, o->out_lost, o->out_fault);
        can_port_obj_stats(s->port, k, &os);
        canproto_st2_faults_t pg = {o->out_lost, o->out_errors, os.cmd_refused};
        canproto_encode_status2_faults(0, &pg, &f);
        can_port_status2(s->port, k, &f);
        canproto_st2_bus_t bus = {(uint8_t)s->bus_state, s->err.tx_err, s->err.rx_err,
                                  s->err.bus_offs, s->err.frames};
        canproto_encode_status2_bus(0, &bus, &f);
        can_port_status2(s->port, k, &f);
        canproto_st2_rejected_t rj;
        canproto_st2_rejected_from(o->status.rejected_by, &rj);
        canproto_encode_status2_rejected(0, &rj, &f);
        can_port_status2(s->port, k, &f);
        canproto_st2_motion_t mo; /* page 7: issues 26, 32 */
        canproto_st2_motion_from(&o->status, &mo);
        canproto_encode_status2_motion(0, &mo, &f);
        can_port_status2(s->port, k, &f);
        status2_clock(s, o, sp, &f);
        can_port_status2_value(s->port, k, &f);
        canproto_encode_status2_time(0, sp->t_s, &f); /* page 6: beside the waypoints */
        can_port_status2_value(s->port, k, &f);
        can_port_setpoint(s->port, k, sp);
    }
}

static void cycle(void *state, core_t *c, int64_t now_ns)
{
    can_state_t *s = state;
    if (!s->port)
        return;
    if (s->log && !(s->drained && s->rx_now_ns == now_ns)) {
        /* no CAN input ticked (only outputs, e.g. a writable replay object):
         * commands due in log_in still arrive once per tick */
        pre_tick(s, NULL, now_ns);
    }
    if (s->log)
        can_logfile_set_time(s->log, now_ns);
    /* a clear from trajctl or Modbus: the drives' part, as a CAN CLEAR's */
    for (unsigned k = 0; k < s->n; k++)
        if (s->hctx[k].o && s->hctx[k].clear_seen != s->hctx[k].o->clear_seq) {
            s->hctx[k].clear_seen = s->hctx[k].o->clear_seq;
            can_port_cleared(s->port, k);
        }
    /* ... and a reset of its counters: the port's too */
    for (unsigned k = 0; k < s->n; k++)
        if (s->hctx[k].o && s->hctx[k].reset_seen != s->hctx[k].o->reset_seq) {
            s->hctx[k].reset_seen = s->hctx[k].o->reset_seq;
            can_port_reset_counters(s->port, k);
        }
    can_port_cycle(s->port, now_ns, c->late_ns);
    can_port_stats_t ps; /* motion the drives missed: the exit status's (core.h) */
    can_port_stats(s->port, &ps);
    c->stats->out_cycles_lost += ps.dropped_pos - s->cycles_seen;
    s->cycles_seen = ps.dropped_pos;
    if (s->log) {
        can_logfile_flush(s->log);
        log_out_faults(s, 1);
    }
    can_publish(c, s->port, s->port_index, s->bus_state, s->rx_dropped, s->load_permille, &s->err);
}

static int input_done(void *state, const obj_t *o)
{
    const can_state_t *s = state;
    (void)o;
    /* a log input is done once every frame was delivered; a bus never is */
    return s->log && s->cfg->log_in[0] && can_logfile_done(s->log);
}

const transport_t can_transport = {
    .name = "can",
    .roles = TRANSPORT_INPUT | TRANSPORT_OUTPUT,
    .cfg_size = sizeof(can_cfg_t),
    .cfg_default = can_cfg_default,
    .cfg_key = can_cfg_key,
    .cfg_fini = can_cfg_fini,
    .obj_cfg_size = sizeof(can_obj_cfg_t),
    .obj_cfg_default = can_obj_cfg_default,
    .obj_key = can_obj_key,
    .check = can_cfg_check,
    .reload_check = can_cfg_reload_check,
    .open = open_,
    .pre_tick = pre_tick,
    .setpoint = setpoint,
    .cycle = cycle,
    .close = close_,
    .input_done = input_done,
    .files = can_transport_files,
    .fds = can_transport_fds,
};
