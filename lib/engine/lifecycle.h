/*
 * lifecycle.h - the one owner of an object's motion (lib/engine/LIFECYCLE.md).
 *
 * Every event that changes what an object does goes through lc_event(): the
 * state it is in and the event pick one cell of lc_table (state x event ->
 * action, next state), and the action is carried out by its parts, which
 * own nothing of the lifecycle themselves:
 *   - the curve with its time scaling and transfers (engine.h),
 *   - the safety monitor (safety.h),
 *   - the drives' state machine (the caller's, e.g. daemon/can: it reports
 *     LC_EV_DRIVE_* and positions, and sends what lc_tick gives).
 * The owner keeps the COMMANDED STATE AS SENT: the setpoint (position,
 * velocity, acceleration) of the last tick, after the monitor.  Every resume
 * re-anchors there, or at the drives' reported position where there are
 * drives, before the time scaling moves it.
 *
 * Precedence when goals conflict: 1 no step within the object's configured
 * limits; 2 never leave the curve through the data received; 3 exact in
 * space through every kept waypoint; 4 timing yields, reported as lag.
 *
 * Time: lc_tick advances the curve by exactly one period per call, whatever
 * the caller's now_ns did: a caller that stalled N periods (overload,
 * SIGSTOP) gets the setpoint after the last one sent, not one N periods
 * ahead (LC_EV_STALL).  Objects on the epoch clock win the lag back by the
 * clock's catch-up (engine_set_clock, CLOCK.md); relative ones report it
 * (lc_counts_t lag_s).  A caller that wants every missed deadline stepped (a
 * replay faster than real time) calls lc_tick once per deadline.
 *
 * Pure: no I/O, no clock.  lc_init allocates the latch buffer; nothing
 * after.  Not thread-safe (one object, one thread).
 */
#ifndef TRAJD_LIFECYCLE_H
#define TRAJD_LIFECYCLE_H

#include <stdint.h>

#include "engine.h"
#include "repeat.h"
#include "safety.h"

/* States (LIFECYCLE.md has the diagram). */
typedef enum {
    LC_NO_POSITION = 0, /* no position to command from: nothing is sent */
    LC_WAITING = 1,     /* at rest, buffering a trajectory's lookahead, or idle */
    LC_STREAMING = 2,   /* moving along the curve */
    LC_UNDERRUN = 3,    /* waypoints late: the time scaling rides through */
    LC_TRANSFER = 4,    /* moving to a trajectory's start (joining a track) */
    LC_STOPPING = 5,    /* a stop: braking along the path, latched */
    LC_STOPPED = 6,     /* at rest after a stop, latched until start or clear */
    LC_HELD = 7,        /* a fault: the monitor's frozen at once, a drive's braked to rest */
    LC_FEED_HELD = 8,   /* a feed hold (heartbeat lost): override 0 until clear */
    LC_FINISHED = 9,    /* the input ended and the output rests on its end */
    LC_STATE_COUNT
} lc_state_t;

/* Events. */
typedef enum {
    LC_EV_FIRST_POSITION = 0, /* a position for an object that has none */
    LC_EV_WAYPOINT,           /* a waypoint arrives */
    LC_EV_GAP,                /* an interval above max_gap_s (the curve's) */
    LC_EV_UNDERRUN,           /* the curve ahead runs short (the curve's) */
    LC_EV_END_OF_INPUT,       /* FINISH, a replay file or log ends */
    LC_EV_STOP,               /* command stop now */
    LC_EV_START,              /* command start */
    LC_EV_CLEAR,              /* command clear */
    LC_EV_OVERRIDE_ZERO,      /* feed override 0 % */
    LC_EV_OVERRIDE,           /* feed override > 0 % */
    LC_EV_SAFETY,             /* the safety monitor refused a setpoint */
    LC_EV_DRIVE_LOST,         /* a drive left Operation Enabled (fault, quick stop) */
    LC_EV_DRIVE_ENABLED,      /* the drives are enabled again: their position */
    LC_EV_DRIVE_BOOTUP,       /* a drive sent its boot-up (NMT reset) */
    LC_EV_HEARTBEAT_LOST,     /* a drive's heartbeat lost */
    LC_EV_HEARTBEAT_BACK,     /* ... and back */
    LC_EV_STALL,              /* the caller missed N periods */
    LC_EV_CLOCK_STEP,         /* CLOCK_REALTIME stepped (objects on the epoch clock) */
    LC_EV_RELOAD_CHANGED,     /* reload: the object's settings changed */
    LC_EV_RELOAD_REMOVED,     /* reload: the object is gone */
    LC_EV_RELOAD_ADDED,       /* reload: a new object */
    LC_EV_RELOAD_FAILED,      /* reload: the new configuration did not open */
    LC_EV_SHUTDOWN,           /* SIGTERM */
    LC_EV_RESTART,            /* the daemon starts while the drives may run */
    LC_EV_LAG,                /* the per-axis limits made the output lag beyond max_lag_s,
                                 or hold it before a segment beyond the axes
                                 (engine_axis_lag_over; the curve's, issue 32) */
    LC_EV_COUNT
} lc_event_t;

/* Actions (LIFECYCLE.md says what each does). */
typedef enum {
    LC_A_UNDEFINED = 0, /* never in lc_table (test_lifecycle checks every cell) */
    LC_A_CURVE,         /* to the curve: push, finish; its underrun and gap handling */
    LC_A_ADOPT,         /* the position given is the commanded state */
    LC_A_BUFFER,        /* kept in the latch buffer (counted), given to the curve on resume */
    LC_A_NOTE,          /* counted; nothing moves */
    LC_A_STOP,          /* controlled stop along the path, latched */
    LC_A_START,      /* unlatch: past waypoints dropped (counted), the rest joins by a transfer */
    LC_A_PLAY,       /* start while waiting with waypoints buffered: end of input */
    LC_A_CLEAR,      /* controlled stop along the path, then drop; holds and latch released */
    LC_A_REANCHOR,   /* holds and latch released, the curve re-anchored at rest at the
                           commanded state (or the drives' position), buffered waypoints
                           joined by a transfer */
    LC_A_RATE,       /* feed override to the time scaling */
    LC_A_REFUSE,     /* refused (-ENGINE_ESTATE), counted */
    LC_A_FREEZE,     /* held at once: the commanded state stops moving, the curve is not
                           advanced */
    LC_A_FEED_HOLD,  /* override 0 latched (brakes along the path); > 0 refused until clear */
    LC_A_POSITION,   /* the drives' position noted: the re-anchor point */
    LC_A_ONE_STEP,   /* the curve advances one period: targets go on from the last sent */
    LC_A_CLOCK,      /* the play time follows the clock; the time scaling catches up or
                           waits within its limits: no step */
    LC_A_RELOAD_NEW, /* a new curve: the old one brakes to rest, the new one starts there */
    LC_A_RETIRE,     /* brakes to rest, then goes (logged) */
    LC_A_KEEP,       /* untouched */
    LC_A_FRESH,      /* a new object: no position until given (initial_position, drives) */
    LC_A_SHUTDOWN,   /* controlled stop to rest, FINISHED */
    LC_A_RESTART,    /* adopt the drives' positions (bumpless) or initial_position */
    LC_A_DRIVE_HOLD, /* a drive no longer follows (it gets its own 0x6064, the caller's): the
                           others brake to rest along the path within the limits, held until
                           clear; clear re-anchors at the drives' position */
    LC_ACTION_COUNT
} lc_action_t;

/* Next state: one of lc_state_t, or: */
#define LC_NEXT_SAME 0xFEu  /* unchanged */
#define LC_NEXT_CURVE 0xFFu /* the curve's own state decides (waiting, streaming, ...) */

typedef struct {
    uint8_t action; /* lc_action_t */
    uint8_t next;   /* lc_state_t, LC_NEXT_SAME or LC_NEXT_CURVE */
} lc_cell_t;

/* THE table. */
extern const lc_cell_t lc_table[LC_STATE_COUNT][LC_EV_COUNT];

const char *lc_state_name(lc_state_t s);
const char *lc_event_name(lc_event_t ev);
const char *lc_action_name(lc_action_t a);

/* Why the object is held (bits). */
#define LC_HOLD_SAFETY 0x1u /* the safety monitor refused a setpoint */
#define LC_HOLD_DRIVE 0x2u  /* a drive left Operation Enabled or booted */
#define LC_HOLD_FEED 0x4u   /* feed hold: a drive's heartbeat lost */

typedef struct {
    uint64_t events[LC_EV_COUNT]; /* every event, by kind */
    uint64_t refused;             /* events refused (LC_A_REFUSE) */
    uint64_t buffered;            /* waypoints kept while latched or held */
    uint64_t dropped_past;        /* ... dropped on resume: already in the past */
    uint64_t dropped_full;        /* ... dropped by a reload into a smaller buffer */
    uint64_t refused_full;        /* ... refused, the buffer full, each waypoint once
                                     (offered again, not counted again; -ENGINE_EFULL: the sender
                                     is told, as by the engine's own full buffer) */
    uint64_t stalled_periods;     /* periods the caller missed (LC_EV_STALL: N each) */
    uint64_t clock_steps;         /* CLOCK_REALTIME steps seen */
    double lag_s;                 /* a relative object: time lost to stalls since its
                                     trajectory began (clocked: the data age tells) */
} lc_counts_t;

typedef struct {
    engine_t *engine;  /* part: the curve (not owned) */
    safety_t *safety;  /* part: the monitor (not owned; may be NULL) */
    int64_t period_ns; /* one tick of the curve */
    unsigned hold;     /* LC_HOLD_* */
    int latched;       /* a stop holds until start or clear */
    int end_pending;   /* end of input came while latched or held */
    int clear_pending; /* clear came while a drive hold still braked: done at rest */
    int drive_pos;     /* the position must come from the drives (after a drive
                                hold): NO_POSITION until LC_EV_DRIVE_ENABLED */
    int have_reported; /* reported[] holds the drives' position since the hold */
    double reported[ENGINE_AXES];
    engine_setpoint_t sent; /* the commanded state as sent */
    int have_sent;          /* sent holds a position */
    int have_tick;
    int64_t eng_ns;      /* the curve's time: one period per lc_tick */
    int64_t last_now_ns; /* the caller's now at the last lc_tick */
    int64_t clk_now_ns;  /* the clock's now at the last lc_tick (clocked) */
    int have_clk;
    int64_t play_ns;        /* now - D at the last tick (clocked; for dropping past waypoints) */
    double newest_t;        /* the newest waypoint time offered (NAN: none) */
    double delay_s;         /* newest_t - t_s when the output last stopped or froze: how
                                far behind its data the object ran (relative objects) */
    engine_waypoint_t *buf; /* the latch buffer (ring) */
    unsigned cap, head, len;
    engine_repeat_t full; /* the waypoint refused_full counted last (repeat.h) */
    lc_counts_t n;
} lifecycle_t;

/* Args of an event (lc_event). */
typedef struct {
    double ratio;                /* LC_EV_OVERRIDE*: 0 .. 2 */
    const engine_waypoint_t *wp; /* LC_EV_WAYPOINT */
    const double *pos_m;         /* LC_EV_FIRST_POSITION, LC_EV_DRIVE_ENABLED */
} lc_arg_t;

/*
 * Own engine (and safety, may be NULL) with a latch buffer of cap waypoints
 * (0: the lookahead the engine needs, twice, at least LC_LATCH_MIN; full, it
 * refuses more with -ENGINE_EFULL).  Returns 0 or
 * -ENGINE_ENOMEM.
 */
int lc_init(lifecycle_t *lc, engine_t *engine, safety_t *safety, int64_t period_ns, unsigned cap);
#define LC_LATCH_MIN 256 /* 16 kB an object: a job of 256 waypoints written while stopped */
void lc_free(lifecycle_t *lc);

/* The state now. */
lc_state_t lc_state(const lifecycle_t *lc);

/*
 * Give event ev (arg as the event needs, may be NULL otherwise): the cell
 * lc_table[lc_state(lc)][ev] is carried out.  Returns what the part
 * returned (engine_push's code for a waypoint, 0), -ENGINE_ESTATE if the
 * cell refuses, -ENGINE_ERANGE for a bad argument.
 */
int lc_event(lifecycle_t *lc, lc_event_t ev, const lc_arg_t *arg);

/* Shorthands. */
int lc_push(lifecycle_t *lc, const engine_waypoint_t *wp);
int lc_set_position(lifecycle_t *lc, const double pos_m[ENGINE_AXES]);

/*
 * One tick at the caller's now_ns (the scheduled deadline): the curve
 * advances one period (unless held), clk (may be NULL: relative) is passed
 * to it, the monitor judges the setpoint, and sp is what goes out (also kept
 * as the commanded state).  Returns 0, or -ENGINE_ESTATE if now_ns went
 * backwards (sp repeats the last one).
 */
int lc_tick(lifecycle_t *lc, int64_t now_ns, const engine_clock_t *clk, engine_setpoint_t *sp);

/*
 * A reload gave the object a new curve (LC_EV_RELOAD_CHANGED): lc, freshly
 * lc_init'ed on it, takes from's holds, latch, feed override (from's
 * curve's), commanded state as sent and counters (the buffered waypoints
 * are not carried: counted as dropped), so a stopped object stays stopped,
 * a held one held and a paused one paused.  The caller sets the new curve's
 * position (the one sent).
 */
void lc_inherit(lifecycle_t *lc, const lifecycle_t *from);

/*
 * A deadline the caller steps over without output (a replay faster than
 * real time, which stays identical to trajreplay by stepping every missed
 * deadline): the curve advances one period as lc_tick would, but nothing is
 * judged or sent, and the commanded state stays the last one sent.
 */
void lc_step_unsent(lifecycle_t *lc, int64_t now_ns, const engine_clock_t *clk);

/* Waypoints in the latch buffer now. */
unsigned lc_buffered(const lifecycle_t *lc);
/* The time of the newest waypoint the latch buffer keeps (NAN: none). */
double lc_buffered_newest_t(const lifecycle_t *lc);
/* The room left for waypoints: in a state that keeps them in the latch
 * buffer (stopping, stopped, held), what is left of it, at most free (the
 * engine's own); else free. */
uint32_t lc_free_room(const lifecycle_t *lc, uint32_t free);

#endif
