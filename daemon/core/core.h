/*
 * core.h - the daemon's core: the moving objects, the output clock and the
 * daemon-wide statistics, as seen by the transports (CAN, Modbus, replay,
 * csv) and by trajd.c, which only wires things together.
 *
 * One tick (the output clock: a timerfd on CLOCK_MONOTONIC, absolute
 * deadlines, so the rate does not drift).  Deadline k is at wall time
 * start + k * period_ns / speed and at ENGINE time now_ns = t0_ns + k *
 * period_ns (t0_ns = 0 at start, so a replay matches trajreplay's virtual
 * clock exactly; after a reload engine time continues where the previous
 * core left off, see core_open).  When the timerfd reports n > 1
 * expirations (the daemon was late), the n - 1 older deadlines are skipped
 * and counted in stats.missed_ticks; one tick runs for the latest deadline
 * (never a burst of stale ticks).  Then, in this order:
 *   1. for each object (in config order) whose input has pre_tick, unless stopping:
 *        input->pre_tick(state, o, now_ns)
 *   2. for each object: engine_tick(o->engine, now_ns, &o->sp);
 *        o->status refreshed (engine_status); then the safety monitor
 *        (lib/safety/safety.h) judges o->sp and replaces it by a hold if it
 *        breaks the object's bounds: no output ever sees a refused setpoint
 *   3. for each object, for each of its outputs: output->setpoint(state, o, &o->sp)
 *   4. for each open transport: cycle(state, core, now_ns)
 *   4b. the tap, if set (core_t.tap: the control socket's watchers)
 *   5. lateness (wake-up time - the oldest deadline not yet served, so a
 *      skip counts as lateness >= one period) goes into the histogram; an
 *      overrun is counted if the work ended after the next deadline.
 * All of it runs in the one loop thread: a transport's fd callbacks and the
 * tick never run at the same time, so a callback sees o->sp and o->status of
 * the last complete tick (a consistent snapshot) without locking.  A
 * transport may hand its file output to a thread of its own through a ring
 * (csv_transport.h: spsc.h, outworker.h); its counts come back through the
 * transport's cycle, so core_t, stats_t and obj_t are written by this thread only.
 *
 * Stop policy (SIGTERM/SIGINT, core_stop): inputs stop (no pre_tick,
 * obj_push_from refuses with -ENGINE_ESTATE), every engine gets engine_stop() so
 * it brakes along its path to rest (a category-1 stop by the time scaling,
 * lib/engine/TIMESCALE.md) and stays there (FINISHED), the outputs keep
 * streaming meanwhile; the daemon exits 0 when every object is
 * FINISHED or WAITING (nothing to finish) or held by a fault, or after [daemon] stop_timeout_s,
 * whichever comes first.  A second signal exits at once (still 0).
 */
#ifndef TRAJD_CORE_H
#define TRAJD_CORE_H

#include <stdint.h>

#include "cfg.h"
#include "delay.h"
#include "engine.h"
#include "latency.h"
#include "lifecycle.h"
#include "loop.h"
#include "playout.h"
#include "rejlog.h"
#include "safety.h"
#include "transport.h"

/* A field bus's state as the transport that runs it publishes it into
 * stats_t.bus, for the other transports and the control socket to read
 * (values follow linux/can/netlink.h, plus DOWN). */
#define CORE_BUS_UNUSED 0 /* no transport publishes a bus */
#define CORE_BUS_ACTIVE 1 /* error-active */
#define CORE_BUS_WARNING 2
#define CORE_BUS_PASSIVE 3
#define CORE_BUS_OFF 4
#define CORE_BUS_DOWN 5 /* interface down or gone; reopening */
typedef struct {
    unsigned state;         /* CORE_BUS_*, as of the publisher's last housekeeping */
    uint32_t load_permille; /* worst-case load of the configured traffic, 0.1 % */
    uint64_t err_frames;    /* error frames; entries into warning, passive, bus-off */
    uint64_t warnings, passives, bus_offs;
    uint64_t restarts;       /* controller restarts */
    uint64_t bus_errors;     /* error frames with a bus-error class */
    uint64_t overflows;      /* controller buffer overflows */
    uint64_t rx_dropped;     /* frames the kernel dropped: trajd's receive queue full */
    unsigned tx_err, rx_err; /* last TX/RX error counters the controller reported */
} core_bus_t;

/* An object's drives as the transport that drives them publishes them into
 * obj_t.drive every tick. */
#define CORE_DRIVE_NONE 0x0Fu     /* state of an axis without a drive */
#define CORE_DRIVE_NMT_NONE 0xFFu /* no heartbeat heard */
typedef struct {
    int published; /* 1: a transport drives this object (else read every state as NONE) */
    uint8_t state[ENGINE_AXES]; /* CiA 402 state per axis (8: not heard yet), or NONE */
    int hb_lost;                /* a drive's heartbeat not heard in time */
    int held;                   /* a drive left Operation Enabled; held until clear */
    uint16_t statusword;  /* of the first drive axis not in Operation Enabled, else the first */
    uint8_t nmt;          /* heartbeat NMT state of that axis' node, or NMT_NONE */
    uint16_t emcy;        /* error code of the last EMCY, 0 = none */
    uint64_t emcy_frames; /* EMCY frames from its drives */
    uint64_t sdo_aborts;
    uint32_t last_abort;  /* abort code of the last SDO abort, 0 = none */
    uint64_t hb_timeouts; /* heartbeat consumer timeouts */
    uint64_t tx_clamped;  /* setpoints with a value clipped to its field */
} core_drive_t;

/* What an input that numbers its waypoints (CAN) lost and resynced, as that
 * transport publishes it into obj_t.rx every tick (zero where none does: a
 * Modbus-fed object's gaps are the Modbus server's own). */
typedef struct {
    uint64_t lost;    /* waypoints never received (gaps in the sequence numbers) */
    uint64_t resyncs; /* a sender that restarted its numbering, followed */
} core_rx_t;

/* obj_t stopping: a reload removes the object (it brakes to rest, then goes). */
#define OBJ_STOPPING_REMOVED 2

/* One moving object. */
typedef struct obj {
    char name[CFG_NAME_MAX];
    unsigned index;       /* 0-based, config order */
    const cfg_obj_t *cfg; /* its [object.NAME] section (engine settings, transport blocks) */
    engine_t *engine;
    engine_t *retiring;            /* a reload gave the object a new engine while the old
                                     * one moved: the old one brakes to rest (engine_stop,
                                     * its setpoints go out), then the new one starts where
                                     * it rests (no velocity step); NULL otherwise */
    int64_t retire_ns;             /* the retiring engine's own time: one period a tick from
                                     * its owner's last (lifecycle_t eng_ns), as the owner's
                                     * curve goes (a stall is no step of N periods) */
    engine_setpoint_t sp;          /* setpoint of the last tick (zero before the first) */
    engine_status_t status;        /* engine status after the last tick, with counts_before */
    engine_status_t counts_before; /* the counters of the engines it had before a reload that
                                    * changed its settings (engine_status_add_counts): its
                                    * counts go on over the reload; and its last_seq, the last
                                    * waypoint they took, until the new engine takes one */
    int has_counts_before;         /* counts_before holds some (a changed object's) */
    uint64_t skipped_ticks;        /* missed deadlines this object was stepped through with
                                     * no output (added into status.skipped_ticks) */
    int stopping;                  /* obj_push_from refuses: 1 the daemon is stopping,
                                   * OBJ_STOPPING_REMOVED a reload removes the object */
    uint64_t stop_refused;         /* waypoints obj_push_from refused so (logged: the first) */
    unsigned clear_seq;            /* +1 per clear the object accepted (obj_command), from any
                                     * source: a transport whose devices hold on their own (a
                                     * CiA 402 drive's fault, can_transport.c) releases them */
    unsigned reset_seq;            /* +1 per reset of its counters (obj_reset_counters), from
                                   * any source: a transport's own counters follow */
    int carried;                   /* 1 if engine (and counters) were carried over a reload */
    double resume_t_s;             /* a reload gave it a new engine, its input the same: the
                                   * input goes on after this track time, as far as the old
                                   * engine played (core.c resume_input; NAN: from its start) */
    double played_t_s;             /* the furthest track time its output played on its
                                   * trajectory (streaming on the curve, not a transfer; NAN:
                                   * none), kept over reloads: where a changed reload's input
                                   * resumes */
    uint32_t played_track;         /* ... on this trajectory (another one starts it again) */
    int64_t born_ns;               /* engine time when its engine was created (0 at start;
                                     * kept when carried): replay due times count from here */
    uint64_t out_lost;             /* setpoint lines of this object that never reached one of
                                     * its outputs (buffer full, write error) */
    int out_fault;                 /* 1 once a write to one of its outputs failed (ENOSPC,
                                     * EIO, ...); cleared by the reset-counters command */
    uint64_t out_errors;           /* failed writes of its outputs (CAN STATUS2 page 1) */
    safety_t safety;               /* the last check of o->sp before any output sees it
                                     * (kept when carried) */
    uint64_t safety_logged;        /* safety violations already logged */
    int axis_warned;               /* issue 32: the per-axis limits' warning given */
    int limits_warned;             /* ... and the object's own speed/acceleration limits' */
    uint64_t axis_stops_logged;    /* ... and the max_lag_s stops logged */
    double und_t;                  /* issue 26: underrun_t_s of the last underrun logged */
    uint64_t und_logged;           /* ... and how many were (0: und_t unset) */
    uint64_t grown_logged;         /* issue 26: D's growths logged (engine delay_grown) */
    uint64_t reanchors_logged;     /* re-anchors logged (engine reanchors) */
    uint64_t reserve_logged;       /* issue 26: slowdowns for D's reserve logged (reserve_slowed) */
    uint64_t axis_beyond_logged;   /* ... and the stops before a segment beyond the axes */
    int uniform_warned;            /* param = uniform met irregular intervals: warned once */
    rejlog_t rejlog;               /* sources of the last waypoints offered, and the refusals
                                     * to log (rejlog.h; kept when carried) */
    double geo[3];                 /* the setpoint as WGS84 lat, lon (deg), alt (m) when
                                     * o->cfg->geographic (about c->cfg->datum), else NaN:
                                     * read it through core_obj_geo (computed on first use
                                     * in a tick) */
    int geo_pending;               /* geo not computed yet for this tick's setpoint */
    double heading_deg;            /* heading axis at the setpoint's track time, wrapped to
                                     * (-180, 180]; NaN if the object has none */
    double heading_unwrapped_deg;  /* the same, continuous across +-180 (NaN: none) */
    size_t heading_hint;           /* interval of the last heading evaluation */
    int clocked;                   /* one clock (lib/engine/CLOCK.md): 1 played out on the
                                     * daemon's clock, 0 relative, -1 its first waypoint
                                     * decides ([daemon] clock = auto; kept when carried) */
    double clock_window_s;         /* auto: epoch when the first time is this close to now */
    playout_drift_t *drift;        /* the daemon's drift estimate (stats_t), fed with the
                                     * arrivals of a clocked object's waypoints */
    int held;                      /* feed hold (obj_hold, e.g. a CiA 402 drive's heartbeat
                                     * lost): an override > 0 is refused until a clear
                                     * (mirrors lc.hold & LC_HOLD_FEED) */
    lifecycle_t lc;                /* the one owner of its motion (lib/engine/lifecycle.h):
                                     * every command and tick goes through it (kept when
                                     * carried) */
    int64_t cmd_log_s;             /* commands logged: the second of the last one */
    unsigned cmd_log_n;            /* ... how many in it */
    uint64_t cmd_buf_told;         /* the owner's buffered and dropped counts the last
                                   * start or clear line told (objlife.c): each line says
                                   * those of its own latch, not the totals */
    uint64_t cmd_drop_told;
    uint64_t cmd_log_dropped;       /* ... and lines not logged (more than
                                     * OBJ_CMD_LOG_PER_S in a second) */
    core_drive_t drive;             /* its drives, published by the transport that drives
                                   * them in its cycle (zero if none does) */
    core_rx_t rx;                   /* its input's sequence counters, published the same way */
    uint32_t delay_track;           /* the trajectory whose D was logged last (issue 26) */
    uint64_t delay_logs;            /* ... how many were logged */
    int delay_pending;              /* a start noted in the tick, its line not yet logged
                                   * (core_stats_roll logs it: log.h) */
    uint32_t delay_pending_track;   /* ... its trajectory */
    engine_delay_t delay_pending_d; /* ... the D it stated */
    uint64_t delay_superseded;      /* starts noted over a pending one before its line */
} obj_t;

/* The owner of o's motion, bound to o's engine and monitor (an obj_t built
 * by hand, as the tests do, gets an owner with no latch buffer). */
lifecycle_t *obj_lc(obj_t *o);

/* The play-out delay D object o's output holds (s): the daemon's delay_s on
 * its clock, else its engine's (delay.h engine_delay: stated at its last
 * start, or what its settings and input need so far). */
double obj_delay_s(const struct core *c, const obj_t *o);

/* Command lines logged per object and second at most (the rest are counted
 * and said in the next line). */
#define OBJ_CMD_LOG_PER_S 10

/*
 * A command to o (CAN, Modbus and the control socket; the daemon's signals
 * use core_stop): LC_EV_STOP, LC_EV_START, LC_EV_CLEAR, LC_EV_END_OF_INPUT,
 * LC_EV_OVERRIDE (arg: percent, 0 .. 200) through the owner's table
 * (lifecycle.h), logged with the object and peer (NULL: unknown).  Returns
 * 0, or -ENGINE_ESTATE (refused in this state: the caller counts it),
 * -ENGINE_ERANGE.
 *
 * LC_EV_CLEAR: moving, a controlled stop along its path that drops what is
 * buffered; held (safety monitor, drive), the curve re-anchors at rest where
 * the output was held (or at the drives' reported position) and the monitor
 * is rearmed, so motion resumes from there by a transfer.  Releases every
 * hold and a stop's latch: the only way out of a fault.
 *
 * LC_EV_OVERRIDE: the feed in percent (LC_EV_OVERRIDE_ZERO for 0); refused
 * (-ENGINE_ESTATE) while o is feed-held and percent > 0.  A clear releases
 * a feed hold and sets the feed back to 100 % (an operator's override,
 * given without a hold, stays).
 */
int obj_command(obj_t *o, lc_event_t ev, unsigned arg, const char *peer);

/*
 * Hold o (a CiA 402 drive's heartbeat lost): LC_EV_HEARTBEAT_LOST, feed
 * override 0, a controlled stop along its path by the time scaling; until
 * a clear (obj_command), every source's override above 0 is refused.
 */
void obj_hold(obj_t *o);

/*
 * An event of o's drives (daemon/can raises them; lib/engine/LIFECYCLE.md):
 *   LC_EV_DRIVE_LOST, LC_EV_DRIVE_BOOTUP: a drive no longer follows; o brakes
 *     to rest along its path within its limits and is held until a clear
 *     (obj_command), after which nothing is sent until the drives give their
 *     position;
 *   LC_EV_DRIVE_ENABLED (pos_m: where the drives stand): every drive follows
 *     again; o adopts pos_m if it may (no position, or at rest), notes it
 *     while held by the monitor (where a clear re-anchors; a drive hold's
 *     clear waits for it afresh), refuses it while moving;
 *   LC_EV_HEARTBEAT_LOST (feed hold, as obj_hold), LC_EV_HEARTBEAT_BACK.
 * Returns 1 if o now stands at pos_m (LC_EV_DRIVE_ENABLED adopted), 0 if not
 * (noted, or another event), < 0 refused (-ENGINE_ESTATE: moving).
 */
int obj_drive_event(obj_t *o, lc_event_t ev, const double *pos_m);

/*
 * Offer a waypoint to o (LC_EV_WAYPOINT): the one path every input uses
 * (replay from its pre_tick, CAN and Modbus from their fd callbacks).  src
 * says where it came from (replay "file:line", Modbus "modbus PEER", CAN
 * "can IFACE id 0xID seq N"; NULL: unknown): a refusal is logged with it
 * (rejlog.h), rate-limited, once a second by core_stats_roll.
 * Returns what engine_push returns (0, ENGINE_DUPLICATE, -ENGINE_*; 0 when
 * the owner buffers it while stopped or held), or -ENGINE_ESTATE while the
 * daemon is stopping.  The engine counts the outcome (o->status).
 */
int obj_push_from(obj_t *o, const engine_waypoint_t *wp, const char *src);

/* Reset o's counters: the engine's and the daemon's own (the reset command). */
void obj_reset_counters(obj_t *o);
/* Add the counters of e, an engine o gives up (a reload that changed its
 * settings), to o->counts_before: its counts go on. */
void obj_counts_take(obj_t *o, const engine_t *e);
/* The waypoints o accepted in all, as of now: its engine's, those of the
 * engines it gave up (o->counts_before) and of the one still braking. */
uint64_t obj_accepted(const obj_t *o);
/* The safety monitor's bounds of configured object o (the derived ones
 * from its engine's limits). */
void obj_safety_limits(const cfg_obj_t *o, safety_limits_t *lim);
/* The same, asked by peer: logged as a command is (obj_command's rate). */
void obj_reset_counters_from(obj_t *o, const char *peer);
/* A command (what: "stop", "override 50 %" ...) from peer that the gate
 * refused before the owner saw it (why: "not writable", "trajd is
 * stopping"): counted in the owner's refused and logged at warning level,
 * at obj_command's rate. */
void obj_log_refused(obj_t *o, const char *what, const char *peer, const char *why);

/* Counters per transport in stats_t.tcount. */
#define STATS_TCOUNT_MAX 4

/* Daemon-wide statistics.  The core fills the tick part; transports their tcount row. */
typedef struct {
    int64_t start_mono_ns; /* CLOCK_MONOTONIC at start (uptime = now - this) */
    uint64_t ticks;        /* ticks run */
    uint64_t missed_ticks; /* deadlines skipped (timerfd expirations - 1, summed) */
    int64_t clock_next_ns; /* CLOCK_MONOTONIC of the next deadline of the last clock that
                            * stopped (core_close), 0 before: the next core's first */
    uint64_t overruns;     /* ticks whose work ended after the next deadline */
    lat_hist_t late_hist;  /* lateness since start / reset, us */
    lat_summary_t late;    /* summary of late_hist, refreshed every second */
    lat_hist_t work_hist;  /* each tick's own CPU time (CLOCK_THREAD_CPUTIME_ID), us */
    lat_summary_t work;    /* summary of work_hist, refreshed every second */
    /* Counters a transport keeps across reloads (a reload rebuilds its state):
     * tcount[transport_index(t)][0 .. STATS_TCOUNT_MAX - 1], meaning defined by
     * transport t, printed by its summary callback. */
    uint64_t tcount[CFG_TRANSPORTS_MAX][STATS_TCOUNT_MAX];
    /* Output faults, any output transport (they also count in their own way):
     * any line lost makes trajd exit with CORE_EXIT_OUTPUT_LOST. */
    uint64_t out_lost;   /* setpoint lines lost (buffer full, write error, left at exit) */
    uint64_t out_errors; /* failed writes (not EAGAIN) */
    int out_errno;       /* errno of the last one */
    int out_fault;       /* 1 once an output write failed */
    /* setpoint cycles a field bus did not take (CAN: late, its transmit queue
     * full, the interface down, a write error), summed over reloads: like a
     * lost line, any makes trajd exit with CORE_EXIT_OUTPUT_LOST */
    uint64_t out_cycles_lost;
    /* One clock (lib/engine/CLOCK.md): the sender's drift and the play-out
     * clock, kept across reloads. */
    playout_drift_t drift;
    playout_clock_t pclock;
    double clock_rate;    /* d now_sender / dt of the last tick */
    int64_t clock_now_ns; /* now on the sender's time base at the last tick */
    /* times a replayed track or CAN log_in ended with no usable waypoint for an
     * object: trajd exits with CORE_EXIT_NO_INPUT at the end */
    uint64_t no_input;
    /* The field bus, published by the transport that runs it in its cycle;
     * zeroed when a core opens (CORE_BUS_UNUSED until a transport publishes). */
    core_bus_t bus;
    /* nonzero: a transport asks the daemon to end now with this status
     * (stdout's reader left: CORE_EXIT_EPIPE); the tick stops the loop with it */
    int exit_code;
} stats_t;

/* Exit statuses of trajd beyond sysexits.h (daemon/REFERENCE.md "Output faults are errors"). */
#define CORE_EXIT_OUTPUT_LOST 74 /* EX_IOERR: setpoint lines were lost by an output */
#define CORE_EXIT_NO_INPUT 65    /* EX_DATAERR: a replayed track or log_in had no usable waypoint */
/* EX_TEMPFAIL: an object ended held (safety fault, drive fault or lost
 * heartbeat): the run did not deliver its motion */
#define CORE_EXIT_HELD 75
#define CORE_EXIT_EPIPE                                                                            \
    141 /* stdout's reader went away (128 + SIGPIPE, what a shell
                                     * reports for a filter ended by SIGPIPE) */

/* The daemon core. Fields are read-only for transports except their own stats->tcount row,
 * stats->out_* (out_cycles_lost: the bus's), exit_code and bus (its publisher), and obj_t.out_lost/.out_fault/.drive.
 * Transports' cycles run in transport_table order (path order: daemon/can before
 * daemon/modbus), so a later one reads what an earlier one published this tick. */
typedef struct core {
    loop_t *loop;     /* the event loop: loop_add your fds here */
    const cfg_t *cfg; /* the running configuration */
    obj_t *obj;       /* nobj objects, config order */
    unsigned nobj;
    int64_t period_ns;                /* engine time per tick */
    int64_t t0_ns;                    /* engine time of deadline 0 (0 at start; after a
                                     * reload, continues the previous core's clock) */
    int64_t now_ns;                   /* engine time of the last tick: t0_ns + cycle * period_ns */
    uint64_t cycle;                   /* index k of the last tick's deadline (0 after a reload) */
    int64_t late_ns;                  /* how late the last tick woke up after the deadline it
                                     * serves (the newest, after a skip), wall ns: how stale
                                     * its setpoint is (CAN drops late cycles).  The stats
                                     * histogram counts from the oldest missed deadline. */
    int stopping;                     /* SIGTERM received: bringing objects to rest */
    stats_t *stats;                   /* survives reloads */
    void *tstate[CFG_TRANSPORTS_MAX]; /* each open transport's state (NULL if not open) */
    /* A tap the tick calls last (after step 4), with every object's setpoint
     * of this tick: the control socket's setpoint subscriptions (daemon/ctl/,
     * set by trajd.c after each core_open).  Runs in the tick: copies only,
     * no system call that blocks, no allocation, no logging.  NULL: none. */
    void (*tap)(void *ctx, const struct core *c);
    void *tap_ctx;
} core_t;

/* Object by name, or NULL. */
obj_t *core_obj_find(core_t *c, const char *name);

/* o->geo for this tick's setpoint, computed on the first call in the tick
 * (geodetic conversion: atan2, sincos; most objects' outputs never ask). */
const double *core_obj_geo(const core_t *c, obj_t *o);

/* CLOCK_REALTIME in ns since the epoch. */
int64_t core_real_ns(void);

/* Monotonic clock in ns (CLOCK_MONOTONIC). */
int64_t core_mono_ns(void);

/* ---- lifecycle, for trajd.c and the tests ---- */

/*
 * Create the objects and engines of cfg and open every transport cfg uses.
 * Does not start the clock.  cfg and stats must outlive the core.
 *
 * Reload: *prev is the running core being replaced (or prev / *prev NULL at
 * start).  An object of *prev is CARRIED OVER when the new config has an
 * object of the same name with the same engine settings, the same input and
 * the same input keys: the new object takes its engine (position, buffered
 * waypoints, trajectory, counters), so a reload does not interrupt its motion;
 * engine time continues from *prev's clock.  Other objects start afresh
 * (WAITING), where the old one stood (its old engine brakes to rest first).
 * The new core borrows *prev's engines; *prev's transports are closed (a
 * transport may hold an exclusive resource, a TCP port, that the new one
 * needs); then the new transports open.  If one cannot, the new core is
 * discarded, *prev's transports are opened again (inputs resume where their
 * objects are) and *prev runs on with its engines untouched.  On success
 * *prev is freed and set to NULL (daemon/core/reload.h).
 *
 * Returns 0, or a negative code with a message in why and nothing of the new
 * core left open.  After a failure *prev keeps running with every engine as
 * it was; a transport of it that does not reopen is left closed (logged: its
 * outputs' setpoints are counted lost, its inputs give nothing).
 */
int core_open(loop_t *loop, const cfg_t *cfg, stats_t *stats, core_t **prev, core_t **out,
              char *why, size_t whylen);

/* Arm the output clock: first deadline one period from now; a later core
 * (a reload's, or the old configuration opened from scratch after a failed
 * one) keeps the phase of the clock closed before it instead: its first
 * deadline is the one that clock was to serve next (stats.clock_next_ns), so
 * a reload never restarts the clock and every deadline that passes while it
 * swaps is counted in stats.missed_ticks (issue 28 item 2).  Returns 0 or -errno. */
int core_start(core_t *c);

/*
 * Begin the stop policy above.  Calls each transport's stop.  Idempotent.
 * core_done() then reports when the daemon may exit.
 */
void core_stop(core_t *c);

/* 1 when stopping and every object is at rest or the stop timeout passed,
 * or when exit_when_done is set and every input is done and object finished (or held by a fault).
 * The tick checks it and then calls loop_stop(loop, 0), so loop_run returns 0. */
int core_done(const core_t *c);

/* Close transports (in reverse order), free engines and the core. NULL is a no-op. */
void core_close(core_t *c);

/* One-line summary ("12 s, 3 objects: boat streaming ..., late p99 40 us ..."). */
int core_summary(const core_t *c, char *buf, size_t len);

/* objlog.c, an object's log lines.  In the tick: note a trajectory that
 * started streaming, with the D it stated (a copy; no line is made there). */
void objlog_note_start(obj_t *o);
/* Every object's D and its parts (at start and at each reload). */
void objlog_delays(const core_t *c);
/* Every object's first seconds of output, from its settings (a line each, at
 * start: trajd logs them before its output clock starts). */
void objlog_first_seconds(const cfg_t *cfg);
/* Housekeeping (core_stats_roll, core_close): each object's lines since the
 * last call, up to start_budget lines of trajectory starts (the rest the
 * next time: many objects starting together are not dropped by the log's
 * queue). */
#define OBJLOG_STARTS_PER_ROLL 128
void objlog_roll(core_t *c, unsigned start_budget);

/* Refresh stats->late and log what happened since the last call (refused
 * waypoints, rate-limited; safety faults): called every second by trajd. */
void core_stats_roll(core_t *c);

#endif
