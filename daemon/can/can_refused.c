/* can_refused.c - see can_refused.h. */
#include "can_refused.h"

#include <stdio.h>
#include <syslog.h>

#include "can_transport.h"
#include "canproto.h"
#include "engine.h"
#include "log.h"

void can_refused_why(char *buf, size_t len, int err, unsigned cmd, int stopping, const char *name)
{
    if (err == 0)
        snprintf(buf, len,
                 "the object is not writable (writable = yes in [object.%s] lets CAN command it)",
                 name);
    else if (err == -ENGINE_ERANGE && cmd == CANPROTO_CMD_OVERRIDE)
        snprintf(buf, len, "an override above %d %%", CANPROTO_OVERRIDE_MAX_PCT);
    else if (err == -ENGINE_ESTATE && stopping)
        snprintf(buf, len, "the daemon is stopping (SIGTERM)");
    else if (err == -ENGINE_ESTATE)
        snprintf(buf, len,
                 "the object is held (a feed hold: a drive's lost heartbeat or a fault); "
                 "only the command clear releases it");
    else
        snprintf(buf, len, "%s", engine_strerror(-err));
}

/* now - was, or now where it went back (reset counters) */
static uint64_t since(uint64_t now, uint64_t was)
{
    return now >= was ? now - was : now;
}

int can_log_traffic(const char *name, unsigned wp_id, const can_port_obj_stats_t *now,
                    can_port_obj_stats_t *logged)
{
    const canproto_rx_stats_t *r = &now->rx, *w = &logged->rx;
    int n = 0;
    uint64_t d = since(r->lost, w->lost);
    if (d) {
        log_msg(LOG_WARNING,
                "can: object '%s': %llu waypoint(s) lost (sequence numbers skipped, or a "
                "waypoint left incomplete) on id 0x%03X; %llu in all",
                name, (unsigned long long)d, wp_id, (unsigned long long)r->lost);
        n++;
    }
    d = since(r->malformed, w->malformed);
    if (d) {
        char by[160] = "";
        size_t off = 0;
        for (int e = 1; e < CANPROTO_ERROR_COUNT && off < sizeof by; e++) {
            uint64_t k = since(r->malformed_by[e], w->malformed_by[e]);
            if (k) {
                int m = snprintf(by + off, sizeof by - off, "%s%llu %s", off ? ", " : "",
                                 (unsigned long long)k, canproto_strerror(-e));
                off += m > 0 ? (size_t)m : 0;
            }
        }
        log_msg(LOG_WARNING,
                "can: object '%s': %llu malformed frame(s) on id 0x%03X (%s); %llu in all", name,
                (unsigned long long)d, wp_id, by, (unsigned long long)r->malformed);
        n++;
    }
    d = since(r->out_of_order, w->out_of_order);
    if (d) {
        log_msg(LOG_WARNING,
                "can: object '%s': %llu frame(s) of waypoints older than the last one taken "
                "(sequence 1..128 behind, and their time not later) dropped on id 0x%03X; "
                "%llu in all",
                name, (unsigned long long)d, wp_id, (unsigned long long)r->out_of_order);
        n++;
    }
    d = since(r->resyncs, w->resyncs);
    if (d) {
        log_msg(LOG_NOTICE,
                "can: object '%s': sender restarted its numbering: waypoint seq %u after %u, "
                "its time later: resynced on id 0x%03X (%llu time(s) since the last line, the "
                "last one shown; %llu in all)",
                name, (unsigned)r->resync_seq, (unsigned)r->resync_after, wp_id,
                (unsigned long long)d, (unsigned long long)r->resyncs);
        n++;
    }
    uint64_t late = since(now->dropped_late, logged->dropped_late),
             full = since(now->dropped_full, logged->dropped_full),
             down = since(now->dropped_down, logged->dropped_down),
             err = since(now->dropped_error, logged->dropped_error);
    uint64_t st_lost = since(now->status_dropped, logged->status_dropped);
    if (late + full + err + st_lost) { /* (down: the interface's own line says so) */
        log_msg(LOG_WARNING,
                "can: object '%s': %llu setpoint cycle(s) not sent (%llu late, %llu with the "
                "transmit queue full, %llu down, %llu write errors), %llu STATUS frames not "
                "sent; %llu cycles in all",
                name, (unsigned long long)(late + full + down + err), (unsigned long long)late,
                (unsigned long long)full, (unsigned long long)down, (unsigned long long)err,
                (unsigned long long)st_lost,
                (unsigned long long)(now->dropped_late + now->dropped_full + now->dropped_down +
                                     now->dropped_error));
        n++;
    }
    *logged = *now;
    return n;
}

unsigned can_transport_fds(const cfg_t *cfg, unsigned *clients)
{
    const can_cfg_t *c = cfg_transport(cfg, &can_transport);
    (void)clients;
    if (!cfg_uses(cfg, &can_transport))
        return 0;
    /* the raw socket (or log_in instead of it), log_out, and a spare for the
     * socket a reopen makes before the old one closes */
    return 2u + (c->log_in[0] != 0) + (c->log_out[0] != 0);
}

void can_transport_files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx)
{
    const can_cfg_t *c = cfg_transport(cfg, &can_transport);
    int line = cfg->tline[transport_index(&can_transport)];
    add(ctx, c->log_in, 0, line, "[can] log_in");
    add(ctx, c->log_out, 1, line, "[can] log_out");
}
