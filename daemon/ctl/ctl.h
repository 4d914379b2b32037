/*
 * ctl.h - the control socket: trajctl(1)'s way into a running trajd.
 *
 * A Unix stream socket, always on (config/trajd.conf [daemon] control_socket,
 * control_group; mode 0660), speaking the line protocol of
 * config/PROTOCOL.md "Control socket": a request is one line of words
 * ("status", "stop boat", "override 50 boat", "watch boat", "reload"), every
 * reply line one JSON object.  It covers every object (by name), carries
 * status and commands, and a setpoint subscription that sees every setpoint
 * an object outputs.
 *
 * Not a transport (daemon/core/transport.h): it lives across reloads (a
 * transport is closed and reopened by each, which would cut every
 * subscription and the client that asked for the reload), so trajd.c owns
 * it and hands it each new core (ctl_set_core).  The core calls it once per
 * tick through core_t.tap, where it only copies each watched object's
 * setpoint into the subscriber's ring (CTL_RING entries; a full ring drops
 * the newest, counted, and the subscriber is told where).  Everything else
 * runs in the loop's fd and timer callbacks, non-blocking, with bounded work
 * per callback: requests, replies, and the rings written out every
 * CTL_FLUSH_NS (or as the socket drains).  Every peer is logged with its
 * credentials (SO_PEERCRED: pid, uid, gid), every command with its object
 * and peer.
 *
 * Commands pass one gate, ctl_command() (ctl_cmd.c): the object must be
 * writable (writable = yes, or not given and fed by CAN or Modbus, which
 * command it on their own bus), the daemon not stopping; then it calls the
 * core's obj_* functions as the CAN transport's command hook does.
 */
#ifndef TRAJD_CTL_H
#define TRAJD_CTL_H

#include <stddef.h>

#include "cfg.h"
#include "core.h"
#include "loop.h"

#define CTL_CLIENTS_MAX 16        /* connections at once; more are told "busy" */
#define CTL_RING 8192             /* setpoints buffered per subscriber (8 s at 1 kHz) */
#define CTL_FLUSH_NS 10000000     /* subscribers' rings written out every 10 ms */
#define CTL_SOCKET_NAME "control" /* in the runtime directory */
#define CTL_RUN_DIR "/run/trajd"  /* the unit's RuntimeDirectory=trajd */

typedef struct ctl ctl_t;

/* Reload the configuration as SIGHUP does: 0 (taken), -1 with why (refused,
 * the old one runs on), or 1: being read and checked on a worker thread
 * (cfgload.h), the answer comes with ctl_reload_done.  Given by trajd.c; it
 * calls ctl_set_core itself. */
typedef int (*ctl_reload_fn)(void *ctx, char *why, size_t whylen);

/*
 * Where the socket goes: [daemon] control_socket if given; else, under
 * systemd, $RUNTIME_DIRECTORY/control (RuntimeDirectory=trajd: /run/trajd);
 * else /run/trajd/control if /run/trajd is a writable directory or can be
 * made (root); else $XDG_RUNTIME_DIR/trajd/control (a user's session).
 * Returns 1 when the path was configured, 0 for a default one, -1 with why
 * when there is no place (then trajd runs without one, with a warning).
 */
int ctl_socket_path(const cfg_daemon_t *d, char *out, size_t len, char *why, size_t whylen);

/*
 * Open the socket (a stale one left by a dead trajd is replaced; one a live
 * trajd answers on is not) and listen.  Returns 0, or -errno with why.
 */
int ctl_open(ctl_t **out, loop_t *loop, const cfg_t *cfg, ctl_reload_fn reload, void *reload_ctx,
             char *why, size_t whylen);

/* The running core (after each start: sets c->tap); NULL while there is none. */
void ctl_set_core(ctl_t *t, core_t *c);

/* The reload that answered 1 is done: its client (if still connected) gets
 * ok (rc >= 0) or the refusal with why.  NULL t is a no-op. */
void ctl_reload_done(ctl_t *t, int rc, const char *why);

/* Log subscribers' losses (rate-limited): trajd's 1 s housekeeping. */
void ctl_housekeeping(ctl_t *t);

/* Tell every client trajd is exiting, flush what the sockets take, close,
 * unlink the socket (if still ours).  NULL is a no-op. */
void ctl_close(ctl_t *t);

#endif
