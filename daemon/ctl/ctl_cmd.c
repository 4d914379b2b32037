/*
 * ctl_cmd.c - the control socket's requests and replies (config/PROTOCOL.md
 * "Control socket"), and the one gate every command passes, ctl_command().
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "csv_shortest.h"
#include "ctl_priv.h"
#include "log.h"
#include "version.h"

/* ---- text ---- */

void ctl_sb_printf(ctl_sb_t *s, const char *fmt, ...)
{
    va_list ap;
    if (s->over)
        return;
    va_start(ap, fmt);
    int n = vsnprintf(s->b + s->len, s->cap - s->len, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= s->cap - s->len)
        s->over = 1;
    else
        s->len += (size_t)n;
}

/* A double in the shortest round-trip form (csv_shortest.h), null when not finite. */
static void ctl_sb_num(ctl_sb_t *s, double x)
{
    if (s->over)
        return;
    if (!isfinite(x)) {
        ctl_sb_printf(s, "null");
        return;
    }
    if (s->cap - s->len < CSV_SHORTEST_MAX + 1) {
        s->over = 1;
        return;
    }
    s->len += (size_t)csv_shortest(s->b + s->len, x);
    s->b[s->len] = 0;
}

void ctl_sb_str(ctl_sb_t *s, const char *str)
{
    ctl_sb_printf(s, "\"");
    for (const unsigned char *p = (const unsigned char *)str; *p && !s->over; p++) {
        if (*p == '"' || *p == '\\')
            ctl_sb_printf(s, "\\%c", *p);
        else if (*p < 0x20)
            ctl_sb_printf(s, "\\u%04x", *p);
        else
            ctl_sb_printf(s, "%c", *p);
    }
    ctl_sb_printf(s, "\"");
}

ctl_sb_t ctl_out_sb(ctl_client_t *cl)
{
    ctl_sb_t sb = {cl->out + cl->outlen, 0, CTL_OUT_BYTES - cl->outlen, 0};
    return sb;
}

int ctl_out_commit(ctl_client_t *cl, const ctl_sb_t *sb)
{
    if (sb->over)
        return -1;
    cl->outlen += sb->len;
    return 0;
}

/* ---- the gate ---- */

typedef enum { CTL_STOP, CTL_START, CTL_CLEAR, CTL_OVERRIDE } ctl_cmd_t;
static const char *const cmd_names[] = {"stop", "start", "clear", "override"};

/* Refusals of the gate beyond the engine's codes. */
#define CTL_ENOTWRITABLE 1000

/*
 * Whether the operator may command o: writable = yes; or not given and its
 * input is a bus that commands it itself (CAN, Modbus: their own default,
 * can_transport.c cmd_mask, modbus_transport.c obj_writable).  A replayed
 * object (writable not given) or writable = no is refused.
 */
static int ctl_writable(const obj_t *o)
{
    if (o->cfg->writable >= 0)
        return o->cfg->writable == 1;
    return o->cfg->input == transport_find("can") || o->cfg->input == transport_find("modbus");
}

/*
 * Every command of the control socket goes through here, and only here: the
 * gate (writable as above, then the daemon or the object stopping), then the
 * object's owner (obj_command, daemon/core/objlife.c: the lifecycle table of
 * lib/engine/LIFECYCLE.md, as the CAN and Modbus commands), logged there with
 * the peer.  Returns 0 or a negative code (-CTL_ENOTWRITABLE, -ENGINE_*).
 */
static int ctl_command(core_t *c, obj_t *o, ctl_cmd_t cmd, unsigned arg, const char *peer)
{
    char src[96];
    if (!ctl_writable(o))
        return -CTL_ENOTWRITABLE;
    if (o->stopping || c->stopping)
        return -ENGINE_ESTATE;
    snprintf(src, sizeof src, "control %s", peer);
    switch (cmd) {
    case CTL_STOP: return obj_command(o, LC_EV_STOP, 0, src);
    case CTL_CLEAR: return obj_command(o, LC_EV_CLEAR, 0, src);
    case CTL_OVERRIDE: return obj_command(o, LC_EV_OVERRIDE, arg, src);
    case CTL_START: return obj_command(o, LC_EV_START, 0, src);
    }
    return -ENGINE_ESTATE;
}

/* ---- replies ---- */

static void reply_error(ctl_client_t *cl, const char *cmd, const char *obj, const char *code,
                        const char *fmt, ...) __attribute__((format(printf, 5, 6)));
static void reply_error(ctl_client_t *cl, const char *cmd, const char *obj, const char *code,
                        const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    ctl_sb_t sb = ctl_out_sb(cl);
    ctl_sb_printf(&sb, "{\"reply\":\"error\",\"cmd\":");
    ctl_sb_str(&sb, cmd ? cmd : "");
    if (obj) {
        ctl_sb_printf(&sb, ",\"object\":");
        ctl_sb_str(&sb, obj);
    }
    ctl_sb_printf(&sb, ",\"error\":\"%s\",\"message\":", code);
    ctl_sb_str(&sb, msg);
    ctl_sb_printf(&sb, "}\n");
    ctl_out_commit(cl, &sb);
}

static void reply_ok(ctl_client_t *cl, const char *cmd, const char *obj)
{
    ctl_sb_t sb = ctl_out_sb(cl);
    ctl_sb_printf(&sb, "{\"reply\":\"ok\",\"cmd\":\"%s\"", cmd);
    if (obj) {
        ctl_sb_printf(&sb, ",\"object\":");
        ctl_sb_str(&sb, obj);
    }
    ctl_sb_printf(&sb, "}\n");
    ctl_out_commit(cl, &sb);
}

static void greet(const ctl_t *t, ctl_client_t *cl)
{
    ctl_sb_t sb = ctl_out_sb(cl);
    ctl_sb_printf(&sb,
                  "{\"reply\":\"hello\",\"trajd\":\"%s\",\"pid\":%ld,\"socket\":", TRAJD_VERSION,
                  (long)getpid());
    ctl_sb_str(&sb, t->path);
    ctl_sb_printf(&sb, ",\"client\":%llu,\"peer_pid\":%ld,\"peer_uid\":%ld,\"peer_gid\":%ld}\n",
                  (unsigned long long)cl->id, (long)cl->pid, (long)(int)cl->uid,
                  (long)(int)cl->gid);
    ctl_out_commit(cl, &sb);
}

/* The health flags of o, comma-separated ("" when all is well). */
static void health(ctl_sb_t *sb, const core_t *c, const obj_t *o)
{
    const char *f[10];
    unsigned n = 0;
    if (safety_fault(&o->safety))
        f[n++] = "safety_fault";
    if (o->held || o->lc.hold) /* a feed hold, a drive's, the monitor's (lifecycle.h) */
        f[n++] = "held";
    if (o->lc.latched) /* a stop command: at rest until start or clear */
        f[n++] = "stopped";
    if (o->out_fault || o->out_lost)
        f[n++] = "output_fault";
    if (o->status.state == ENGINE_STATE_UNDERRUN)
        f[n++] = "underrun";
    if (o->sp.flags & ENGINE_SP_NO_POSITION)
        f[n++] = "no_position";
    if (o->status.hard_stops)
        f[n++] = "hard_stop";
    if (o->stopping || c->stopping)
        f[n++] = "stopping";
    ctl_sb_printf(sb, "\"");
    for (unsigned i = 0; i < n; i++)
        ctl_sb_printf(sb, "%s%s", i ? "," : "", f[i]);
    ctl_sb_printf(sb, "\"");
}

static void status_obj(ctl_sb_t *sb, const core_t *c, const obj_t *o)
{
    const engine_status_t *st = &o->status;
    const engine_setpoint_t *sp = &o->sp;
    double speed = sqrt(sp->vel_m_s[0] * sp->vel_m_s[0] + sp->vel_m_s[1] * sp->vel_m_s[1] +
                        sp->vel_m_s[2] * sp->vel_m_s[2]);
    double delay = obj_delay_s(c, o);
    ctl_sb_printf(sb, "{\"object\":");
    ctl_sb_str(sb, o->name);
    ctl_sb_printf(
        sb,
        ",\"id\":%d,\"input\":\"%s\",\"writable\":%s,\"state\":\"%s\",\"lifecycle\":\"%s\","
        "\"health\":",
        o->cfg->id, o->cfg->input->name, ctl_writable(o) ? "true" : "false",
        engine_state_name(sp->state), lc_state_name(lc_state(&o->lc)));
    health(sb, c, o);
    ctl_sb_printf(sb, ",\"tick\":%lld,\"t_s\":", (long long)(sp->now_ns / c->period_ns));
    ctl_sb_num(sb, sp->t_s);
    ctl_sb_printf(sb, ",\"pos\":[");
    for (int a = 0; a < ENGINE_AXES; a++) {
        ctl_sb_printf(sb, a ? "," : "");
        ctl_sb_num(sb, sp->pos_m[a]);
    }
    ctl_sb_printf(sb, "],\"speed\":");
    ctl_sb_num(sb, speed);
    ctl_sb_printf(sb, ",\"age_s\":");
    ctl_sb_num(sb, sp->age_s);
    ctl_sb_printf(sb, ",\"delay_s\":");
    ctl_sb_num(sb, delay);
    ctl_sb_printf(sb, ",\"lag_s\":"); /* relative: the lag the catch-up wins back */
    ctl_sb_num(sb, o->clocked == 1 ? sp->age_s - delay : st->lag_s);
    ctl_sb_printf(sb, ",\"ahead_s\":");
    ctl_sb_num(sb, st->ahead_s);
    ctl_sb_printf(sb, ",\"override\":");
    ctl_sb_num(sb, st->override);
    ctl_sb_printf(sb, ",\"rate\":");
    ctl_sb_num(sb, st->rate);
    ctl_sb_printf(sb,
                  ",\"flags\":%u,\"track\":%u,\"buffered\":%u,\"lookahead\":%u,\"accepted\":%llu,"
                  "\"rejected\":%llu,\"duplicates\":%llu,\"full\":%llu,\"dropped\":%llu,"
                  "\"unjudged\":%llu,"
                  "\"underruns\":%llu,"
                  "\"skipped_ticks\":%llu,\"gaps\":%llu,\"tracks\":%llu,\"hard_stops\":%llu,"
                  "\"setpoints\":%llu,\"out_lost\":%llu,\"out_errors\":%llu}\n",
                  sp->flags, sp->track, st->buffered, st->lookahead,
                  (unsigned long long)st->accepted, (unsigned long long)st->rejected,
                  (unsigned long long)st->duplicates, (unsigned long long)st->full,
                  (unsigned long long)st->dropped, (unsigned long long)st->unjudged,
                  (unsigned long long)st->underruns, (unsigned long long)st->skipped_ticks,
                  (unsigned long long)st->gaps, (unsigned long long)st->tracks,
                  (unsigned long long)st->hard_stops, (unsigned long long)st->setpoints,
                  (unsigned long long)o->out_lost, (unsigned long long)o->out_errors);
}

static void status_head(const ctl_t *t, ctl_client_t *cl)
{
    const core_t *c = t->core;
    const stats_t *s = c->stats;
    unsigned clients = 0, i;
    for (i = 0; i < CTL_CLIENTS_MAX; i++)
        clients += t->cl[i].fd >= 0;
    ctl_sb_t sb = ctl_out_sb(cl);
    ctl_sb_printf(&sb,
                  "{\"reply\":\"status\",\"trajd\":\"%s\",\"pid\":%ld,\"uptime_s\":%.3f,"
                  "\"rate_hz\":",
                  TRAJD_VERSION, (long)getpid(),
                  (double)(core_mono_ns() - s->start_mono_ns) * 1e-9);
    ctl_sb_num(&sb, c->cfg->daemon.rate_hz);
    ctl_sb_printf(&sb,
                  ",\"speed\":%g,\"objects\":%u,\"stopping\":%s,\"ticks\":%llu,"
                  "\"missed_ticks\":%llu,\"overruns\":%llu,\"late_p99_us\":%u,\"late_max_us\":%u,"
                  "\"out_lost\":%llu,\"clients\":%u,\"watchers\":%u,\"watch_lost\":%llu,"
                  "\"busy_refused\":%llu,\"log_dropped\":%llu,\"config\":",
                  c->cfg->daemon.speed, c->nobj, c->stopping ? "true" : "false",
                  (unsigned long long)s->ticks, (unsigned long long)s->missed_ticks,
                  (unsigned long long)s->overruns, s->late.p99_us, s->late.max_us,
                  (unsigned long long)s->out_lost, clients, t->watchers,
                  (unsigned long long)t->watch_lost, (unsigned long long)t->busy_refused,
                  log_dropped_count());
    ctl_sb_str(&sb, c->cfg->path);
    ctl_sb_printf(&sb, "}\n");
    ctl_out_commit(cl, &sb);
}

void ctl_status_more(ctl_t *t, ctl_client_t *cl)
{
    const core_t *c = t->core;
    while (cl->status_next >= 0) {
        if (!c || (unsigned)cl->status_next >= c->nobj) {
            ctl_sb_t sb = ctl_out_sb(cl);
            ctl_sb_printf(&sb, "{\"reply\":\"end\",\"objects\":%d}\n", cl->status_next);
            if (ctl_out_commit(cl, &sb) == 0)
                cl->status_next = -1;
            return;
        }
        ctl_sb_t sb = ctl_out_sb(cl);
        status_obj(&sb, c, &c->obj[cl->status_next]);
        if (ctl_out_commit(cl, &sb) < 0)
            return; /* no room: the rest once this is written */
        cl->status_next++;
    }
}

/* One setpoint line (config/PROTOCOL.md "Control socket"). */
static void sp_line(ctl_sb_t *sb, const char *name, const ctl_sp_t *e)
{
    const engine_setpoint_t *sp = &e->sp;
    const double *v[3] = {sp->pos_m, sp->vel_m_s, sp->acc_m_s2};
    static const char *const key[3] = {"pos", "vel", "acc"};
    ctl_sb_printf(sb, "{\"sp\":");
    ctl_sb_str(sb, name);
    ctl_sb_printf(sb,
                  ",\"tick\":%lld,\"now_ns\":%lld,\"t_s\":", (long long)(sp->now_ns / e->period_ns),
                  (long long)sp->now_ns);
    ctl_sb_num(sb, sp->t_s);
    for (int k = 0; k < 3; k++) {
        ctl_sb_printf(sb, ",\"%s\":[", key[k]);
        for (int a = 0; a < ENGINE_AXES; a++) {
            ctl_sb_printf(sb, a ? "," : "");
            ctl_sb_num(sb, v[k][a]);
        }
        ctl_sb_printf(sb, "]");
    }
    ctl_sb_printf(sb, ",\"state\":\"%s\",\"flags\":%u,\"cycle\":%u,\"track\":%u,\"age_s\":",
                  engine_state_name(sp->state), sp->flags, sp->cycle, sp->track);
    ctl_sb_num(sb, sp->age_s);
    ctl_sb_printf(sb, "}\n");
}

void ctl_sub_more(ctl_t *t, ctl_client_t *cl)
{
    (void)t;
    while (cl->head != cl->tail) {
        ctl_sp_t *e = &cl->ring[cl->tail % CTL_RING];
        ctl_sb_t sb = ctl_out_sb(cl);
        if (e->lost_before)
            ctl_sb_printf(&sb,
                          "{\"overflow\":\"%s\",\"lost\":%llu,\"lost_total\":%llu,\"ring\":%u}\n",
                          cl->sub_name, (unsigned long long)e->lost_before,
                          (unsigned long long)cl->lost, CTL_RING);
        sp_line(&sb, cl->sub_name, e);
        if (ctl_out_commit(cl, &sb) < 0)
            return;
        cl->tail++;
        cl->sent++;
    }
}

/* ---- requests ---- */

static obj_t *find_obj(ctl_t *t, ctl_client_t *cl, const char *cmd, const char *name)
{
    obj_t *o = name ? core_obj_find(t->core, name) : NULL;
    if (!name)
        reply_error(cl, cmd, NULL, "usage", "%s: an object name is needed", cmd);
    else if (!o)
        reply_error(cl, cmd, name, "no-object", "no object '%s'", name);
    return o;
}

static void do_command(ctl_t *t, ctl_client_t *cl, ctl_cmd_t cmd, char **w, int n)
{
    const char *name = cmd_names[cmd];
    unsigned arg = 0;
    if (cmd == CTL_OVERRIDE) {
        char *end = NULL;
        long v = n >= 2 ? strtol(w[1], &end, 10) : -1;
        if (n != 3 || !end || *end || v < 0 || v > 200) {
            reply_error(cl, name, NULL, "usage", "override N OBJECT: N percent, 0 to 200");
            return;
        }
        arg = (unsigned)v;
        w++, n--;
    }
    if (n != 2) {
        reply_error(cl, name, NULL, "usage", "%s OBJECT", name);
        return;
    }
    obj_t *o = find_obj(t, cl, name, w[1]);
    char what[32] = "";
    if (cmd == CTL_OVERRIDE)
        snprintf(what, sizeof what, " %u %%", arg);
    if (!o) { /* refused as a command is, so logged as one (the name as printable text) */
        char shown[65];
        size_t k = 0;
        for (const unsigned char *c = (const unsigned char *)w[1]; *c && k + 1 < sizeof shown; c++)
            shown[k++] = *c >= 0x20 && *c < 0x7f ? (char)*c : '?';
        shown[k] = 0;
        log_peer(LOG_WARNING, cl->peer, "control: %s%s '%s' from %s refused: no such object", name,
                 what, shown, cl->peer);
        return;
    }
    int rc = ctl_command(t->core, o, cmd, arg, cl->peer);
    if (rc == -CTL_ENOTWRITABLE) {
        obj_lc(o)->n.refused++; /* counted as CAN's and Modbus's are (the exit line) */
        log_peer(LOG_WARNING, cl->peer, "control: %s%s '%s' from %s refused: not writable", name,
                 what, o->name, cl->peer);
        reply_error(cl, name, o->name, "not-writable",
                    "object '%s' is not writable: writable = yes in [object.%s] lets trajctl "
                    "command it",
                    o->name, o->name);
        return;
    }
    if (rc < 0) {
        lc_state_t ls = lc_state(&o->lc);
        const char *why = (o->stopping || t->core->stopping) ? "trajd is stopping"
                          : o->held && cmd == CTL_OVERRIDE
                              ? "the object is held (feed hold): clear it first"
                          : (ls == LC_HELD || ls == LC_FEED_HELD) && cmd == CTL_START
                              ? "the object is held (a fault, a drive, a lost heartbeat): only "
                                "clear releases it"
                              : engine_strerror(rc);
        log_peer(LOG_WARNING, cl->peer, "control: %s%s '%s' from %s refused: %s", name, what,
                 o->name, cl->peer, why);
        reply_error(cl, name, o->name, "refused", "%s '%s' refused: %s", name, o->name, why);
        return;
    }
    log_peer(LOG_NOTICE, cl->peer, "control: %s%s '%s' from %s", name, what, o->name, cl->peer);
    reply_ok(cl, name, o->name);
}

static void do_watch(ctl_t *t, ctl_client_t *cl, char **w, int n)
{
    if (n != 2) {
        reply_error(cl, "watch", NULL, "usage", "watch OBJECT");
        return;
    }
    obj_t *o = find_obj(t, cl, "watch", w[1]);
    if (!o)
        return;
    if (cl->sub_obj >= 0) {
        reply_error(cl, "watch", o->name, "usage", "this connection already watches '%s'",
                    cl->sub_name);
        return;
    }
    if (ctl_sub_start(t, cl, (int)o->index, o->name) < 0) {
        reply_error(cl, "watch", o->name, "busy", "out of memory");
        return;
    }
    log_peer(LOG_NOTICE, cl->peer, "control: client #%llu (%s) watches '%s'",
             (unsigned long long)cl->id, cl->peer, o->name);
    ctl_sb_t sb = ctl_out_sb(cl);
    ctl_sb_printf(&sb, "{\"reply\":\"ok\",\"cmd\":\"watch\",\"object\":");
    ctl_sb_str(&sb, o->name);
    ctl_sb_printf(&sb, ",\"rate_hz\":");
    ctl_sb_num(&sb, t->core->cfg->daemon.rate_hz);
    ctl_sb_printf(&sb, ",\"ring\":%u}\n", CTL_RING);
    ctl_out_commit(cl, &sb);
}

static void do_reload(ctl_t *t, ctl_client_t *cl)
{
    char why[1024] = "";
    log_peer(LOG_NOTICE, cl->peer, "control: reload asked by %s", cl->peer);
    int rc = t->reload ? t->reload(t->reload_ctx, why, sizeof why) : -1;
    if (rc < 0) {
        reply_error(cl, "reload", NULL, "refused", "reload refused: %s",
                    why[0] ? why : "not possible now");
        return;
    }
    if (rc > 0) { /* read and checked on a worker: ctl_reload_done answers */
        t->reload_waiter = cl->id;
        return;
    }
    reply_ok(cl, "reload", NULL);
}

void ctl_reload_done(ctl_t *t, int rc, const char *why)
{
    if (!t || !t->reload_waiter)
        return;
    uint64_t id = t->reload_waiter;
    t->reload_waiter = 0;
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++) {
        ctl_client_t *cl = &t->cl[i];
        if (cl->fd < 0 || cl->id != id)
            continue;
        if (rc < 0)
            reply_error(cl, "reload", NULL, "refused", "reload refused: %s",
                        why && why[0] ? why : "not possible now");
        else
            reply_ok(cl, "reload", NULL);
        ctl_client_pump(t, cl);
    }
}

#define CTL_WORDS_MAX 4

void ctl_request(ctl_t *t, ctl_client_t *cl, char *line)
{
    char *w[CTL_WORDS_MAX + 1], *save = NULL;
    int n = 0;
    if (!line) {
        greet(t, cl);
        return;
    }
    for (char *p = strtok_r(line, " \t", &save); p && n <= CTL_WORDS_MAX;
         p = strtok_r(NULL, " \t", &save))
        w[n++] = p;
    if (n == 0)
        return;
    if (n > CTL_WORDS_MAX) {
        reply_error(cl, w[0], NULL, "usage", "too many words");
        return;
    }
    if (strcmp(w[0], "quit") == 0) {
        cl->closing = 1;
        return;
    }
    if (!t->core) {
        reply_error(cl, w[0], NULL, "refused", "no configuration running");
        return;
    }
    for (int k = 0; k < (int)(sizeof cmd_names / sizeof *cmd_names); k++)
        if (strcmp(w[0], cmd_names[k]) == 0) {
            do_command(t, cl, (ctl_cmd_t)k, w, n);
            return;
        }
    if (strcmp(w[0], "status") == 0 && n <= 2) {
        if (n == 2) {
            obj_t *o = find_obj(t, cl, "status", w[1]);
            if (!o)
                return;
            status_head(t, cl);
            ctl_sb_t sb = ctl_out_sb(cl);
            status_obj(&sb, t->core, o);
            ctl_sb_printf(&sb, "{\"reply\":\"end\",\"objects\":1}\n");
            ctl_out_commit(cl, &sb);
            return;
        }
        status_head(t, cl);
        cl->status_next = 0; /* the objects follow, as the socket takes them */
        return;
    }
    if (strcmp(w[0], "watch") == 0)
        do_watch(t, cl, w, n);
    else if (strcmp(w[0], "reload") == 0 && n == 1)
        do_reload(t, cl);
    else
        reply_error(cl, w[0], NULL, "usage",
                    "unknown request '%s' (status [OBJECT], stop|start|clear OBJECT, override N "
                    "OBJECT, watch OBJECT, reload, quit)",
                    w[0]);
}
