/*
 * transport.h - the seam every input and output plugs into: replay (track
 * files), csv and stdout (setpoint text), and CAN and Modbus.
 *
 * A transport is one const transport_t (like libmodbus's backend tables):
 * its name, what roles it can play, how its config keys are parsed, and the
 * callbacks the daemon makes.  The core reaches it only through that table.
 * To add one:
 *   1. write daemon/<family>/<family>_transport.{h,c} (e.g. daemon/can/can_transport.c)
 *      defining `const transport_t <name>_transport = {` at the start of a
 *      line (one file may define several: csv_transport.c has csv and stdout);
 *   2. document its keys in config/trajd.conf.
 * Nothing else changes: the Makefile generates transport_table[] from every
 * daemon/<family>/<anything>_transport.c (daemon/core/transport_table.sh).
 * Order: by file path (byte order), then by position in the file; it is the
 * order of open, check, cycle and the status line (close runs in reverse).
 * A transport's index is its position, so adding one may shift the indices
 * of those after it (indices live within one run, they are never stored).  Its own state, per-object
 * state and counters stay in its file, behind the callbacks below (per-object
 * state: index its own arrays by obj_t.index; counters that must survive a
 * reload: its row of stats_t.tcount, printed by its summary callback).
 *
 * Config (see cfg.h).  [T] section keys go to cfg_key(cfg block), keys
 * "T.key" in [object.NAME] go to obj_key(that object's block).  Blocks are
 * allocated by the parser (zeroed, cfg_size / obj_cfg_size bytes), filled by
 * cfg_default / obj_cfg_default, then by the key functions, then check() sees
 * the whole config (e.g. CAN ids clashing between objects, bus load).  A key
 * function returns 0, -CFG_EUNKNOWN (the parser reports "unknown key") or
 * -CFG_EVALUE with a message in why (the parser adds file:line).  Key and
 * check functions may read files (e.g. load a track) but must not open
 * sockets or devices: they run for --check-config and for a reload that may
 * still be refused.  Whatever they allocate is released by cfg_fini /
 * obj_cfg_fini.  Every pointer may be NULL if not needed.
 *
 * Runtime (see core.h for the order within a tick).  A transport is opened if
 * cfg_uses() says so (an object uses it, or its [T] section is present).
 *   open      after every object's engine exists and before READY=1: open
 *             sockets/files, loop_add() fds to c->loop.  Failure -> trajd does
 *             not start (or a reload is rolled back: the running core's
 *             transports, closed for it, are opened again on that same core,
 *             its objects marked carried, daemon/core/reload.h).  An object with
 *             o->carried set kept its engine over a reload: an input resumes
 *             where it was (replay: after the last row it gave).
 *   pre_tick  for each object whose INPUT is this transport, just before its
 *             engine_tick: feed waypoints that are due by engine time (replay).
 *             Event-driven inputs (CAN frames, Modbus writes) do not need it.
 *             Every input offers its waypoints through obj_push_from() (core.h),
 *             from pre_tick or from its fd callbacks, never engine_push.
 *   setpoint  for each object that has this transport among its OUTPUTS,
 *             right after its engine_tick, with the new setpoint.
 *   cycle     once per tick after every object was ticked, for every open
 *             transport: one CAN SYNC frame, one Modbus snapshot publish,
 *             flushing buffered output.
 *   stop      SIGTERM received: objects are being brought to rest; inputs
 *             should stop accepting new waypoints (obj_push_from refuses anyway).
 *   close     at exit or before a reload: flush, close fds (loop_del first).
 * pre_tick, setpoint and cycle run in the tick: no allocation, no blocking
 * call, no logging (count, and log from a loop_timer_add housekeeping timer).
 */
#ifndef TRAJD_TRANSPORT_H
#define TRAJD_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "cfg.h"
#include "engine.h"

struct core;
struct obj;

#define TRANSPORT_INPUT 0x1u   /* can be an object's input = */
#define TRANSPORT_OUTPUT 0x2u  /* can be in an object's output = */
#define TRANSPORT_SERVICE 0x4u /* serves all objects (e.g. Modbus status) when [T] is present */

typedef struct transport {
    const char *name; /* section name and "name." key prefix */
    unsigned roles;   /* TRANSPORT_* */

    /* [name] section */
    size_t cfg_size;
    void (*cfg_default)(void *cfg);
    int (*cfg_key)(void *cfg, const cfg_kv_t *kv, char *why, size_t whylen);
    void (*cfg_fini)(void *cfg);

    /* "name.key" in [object.X] */
    size_t obj_cfg_size;
    void (*obj_cfg_default)(void *ocfg);
    int (*obj_key)(void *ocfg, const cfg_kv_t *kv, char *why, size_t whylen);
    void (*obj_cfg_fini)(void *ocfg);
    /* 1 if two per-object blocks configure the same input (decides whether an
     * object is carried over a reload, see core_open).  NULL: memcmp of
     * obj_cfg_size bytes (fine for plain data; blocks are zeroed first). */
    int (*obj_cfg_same)(const void *a, const void *b);

    /* Whole-config rules, after every key was parsed (and the place to finish
     * the blocks, e.g. load a file named by a key).  0, or -CFG_EVALUE /
     * -CFG_EMISSING with why and *line set to the line to report (it starts
     * at the line of the [T] section, 0 if absent; remember a key's
     * cfg_kv_t.line in your block to point at the key). */
    int (*check)(cfg_t *cfg, int *line, char *why, size_t whylen);
    /* Reload (cfg_reload_check): 0 if no address this transport derives for
     * an object present in both old and nw (same name) moves; else -CFG_EVALUE
     * with why and *line (a line of nw) set.  NULL: nothing to compare. */
    int (*reload_check)(const cfg_t *old, const cfg_t *nw, int *line, char *why, size_t whylen);

    /* Runtime.  open returns 0 or a negative code (-errno or the transport's own)
     * with a message in why; *state is then passed to every other callback. */
    int (*open)(struct core *c, void **state, char *why, size_t whylen);
    void (*pre_tick)(void *state, struct obj *o, int64_t now_ns);
    void (*setpoint)(void *state, struct obj *o, const engine_setpoint_t *sp);
    void (*cycle)(void *state, struct core *c, int64_t now_ns);
    void (*stop)(void *state, struct core *c);
    void (*close)(void *state, struct core *c);

    /* 1 if this input has nothing more to give object o (replay at its end);
     * used by [daemon] exit_when_done.  NULL = never done (live inputs). */
    int (*input_done)(void *state, const struct obj *o);

    /* Append this transport's part of the status line (core_summary), e.g.
     * ", out dropped 3", or nothing: returns what snprintf(buf, len, ...)
     * returns.  Called for every transport, open or not (its tcount row may
     * still hold counters from before a reload): c->tstate[its index] is NULL
     * when it is not open.  Not in the tick. */
    int (*summary)(const struct core *c, char *buf, size_t len);

    /* The files cfg makes this transport read or write: add(ctx, path,
     * output, line, what) for each (cfg_files.h compares them by identity at
     * check time).  NULL: none. */
    void (*files)(const cfg_t *cfg,
                  void (*add)(void *ctx, const char *path, int output, int line, const char *what),
                  void *ctx);

    /* The file descriptors cfg makes this transport hold open while it runs
     * (sockets and files), and in *clients those its peers may add at most
     * (connections it accepts): fdlimit.h compares them with RLIMIT_NOFILE.
     * NULL: none. */
    unsigned (*fds)(const cfg_t *cfg, unsigned *clients);
} transport_t;

/* Every transport, NULL-terminated; a transport's index is its position.
 * Generated by the Makefile (build/gen/transport_table.c), see above. */
extern const transport_t *const transport_table[];

/* Number of transports in the table (< CFG_TRANSPORTS_MAX). */
unsigned transport_count(void);

/* Transport by name, or NULL. */
const transport_t *transport_find(const char *name);

/* Index in transport_table, or -1. */
int transport_index(const transport_t *t);

#endif
