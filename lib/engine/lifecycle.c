/* lifecycle.c - the one owner of an object's motion; see lifecycle.h and
 * lib/engine/LIFECYCLE.md (the same table, with a diagram). */
#include "lifecycle.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define AXN ENGINE_AXES

/* A cell: action, next state. */
#define C(a, n)                                                                                    \
    {                                                                                              \
        LC_A_##a, n                                                                                \
    }
#define SAME LC_NEXT_SAME
#define CURVE LC_NEXT_CURVE

/* The reload, shutdown and restart columns, alike in every state an object
 * with a position is in (the daemon core carries them out: core.h). */
#define RELOADS_MOVING                                                                             \
    [LC_EV_RELOAD_CHANGED] = C(RELOAD_NEW, CURVE),                                                 \
    [LC_EV_RELOAD_REMOVED] = C(RETIRE, LC_FINISHED), [LC_EV_RELOAD_ADDED] = C(NOTE, SAME),         \
    [LC_EV_RELOAD_FAILED] = C(KEEP, SAME), [LC_EV_SHUTDOWN] = C(SHUTDOWN, LC_FINISHED),            \
    [LC_EV_RESTART] = C(NOTE, SAME)
#define RELOADS_KEPT                                                                               \
    [LC_EV_RELOAD_CHANGED] = C(RELOAD_NEW, SAME), [LC_EV_RELOAD_REMOVED] = C(RETIRE, LC_FINISHED), \
    [LC_EV_RELOAD_ADDED] = C(NOTE, SAME), [LC_EV_RELOAD_FAILED] = C(KEEP, SAME),                   \
    [LC_EV_SHUTDOWN] = C(SHUTDOWN, LC_FINISHED), [LC_EV_RESTART] = C(NOTE, SAME)
/* The drive and fault columns of a state whose output moves or may move: the
 * monitor's refusal freezes at once (its own hold); a drive that no longer
 * follows holds the object too, but the other axes brake to rest along the
 * path within the object's limits (issue 23). */
#define FAULTS_FREEZE                                                                              \
    [LC_EV_SAFETY] = C(FREEZE, LC_HELD), [LC_EV_DRIVE_LOST] = C(DRIVE_HOLD, LC_HELD),              \
    [LC_EV_DRIVE_BOOTUP] = C(DRIVE_HOLD, LC_HELD), [LC_EV_HEARTBEAT_BACK] = C(NOTE, SAME)

/* clang-format off */
const lc_cell_t lc_table[LC_STATE_COUNT][LC_EV_COUNT] = {
    [LC_NO_POSITION] = {
        [LC_EV_FIRST_POSITION] = C(ADOPT, CURVE),  [LC_EV_WAYPOINT] = C(CURVE, CURVE),
        [LC_EV_GAP] = C(CURVE, SAME),              [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, CURVE),
        [LC_EV_STOP] = C(STOP, LC_STOPPED),        [LC_EV_START] = C(PLAY, CURVE),
        [LC_EV_CLEAR] = C(CLEAR, SAME),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        [LC_EV_SAFETY] = C(NOTE, SAME),            [LC_EV_DRIVE_LOST] = C(NOTE, SAME),
        [LC_EV_DRIVE_ENABLED] = C(ADOPT, CURVE),   [LC_EV_DRIVE_BOOTUP] = C(NOTE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, SAME), [LC_EV_HEARTBEAT_BACK] = C(NOTE, SAME),
        [LC_EV_STALL] = C(NOTE, SAME),             [LC_EV_CLOCK_STEP] = C(NOTE, SAME),
        [LC_EV_RELOAD_CHANGED] = C(RELOAD_NEW, SAME), [LC_EV_RELOAD_REMOVED] = C(RETIRE, LC_FINISHED),
        [LC_EV_RELOAD_ADDED] = C(FRESH, SAME),     [LC_EV_RELOAD_FAILED] = C(KEEP, SAME),
        [LC_EV_SHUTDOWN] = C(SHUTDOWN, LC_FINISHED), [LC_EV_RESTART] = C(RESTART, CURVE),
        [LC_EV_LAG] = C(NOTE, SAME),
    },
    [LC_WAITING] = {
        [LC_EV_FIRST_POSITION] = C(ADOPT, SAME),   [LC_EV_WAYPOINT] = C(CURVE, CURVE),
        [LC_EV_GAP] = C(CURVE, CURVE),             [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, CURVE),
        [LC_EV_STOP] = C(STOP, LC_STOPPED),        [LC_EV_START] = C(PLAY, CURVE),
        [LC_EV_CLEAR] = C(CLEAR, SAME),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(ADOPT, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, LC_FEED_HELD),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_MOVING,
        [LC_EV_LAG] = C(STOP, LC_STOPPED),
    },
    [LC_STREAMING] = {
        [LC_EV_FIRST_POSITION] = C(REFUSE, SAME),  [LC_EV_WAYPOINT] = C(CURVE, CURVE),
        [LC_EV_GAP] = C(CURVE, CURVE),             [LC_EV_UNDERRUN] = C(CURVE, LC_UNDERRUN),
        [LC_EV_END_OF_INPUT] = C(CURVE, CURVE),
        [LC_EV_STOP] = C(STOP, LC_STOPPING),       [LC_EV_START] = C(NOTE, SAME),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(REFUSE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, LC_FEED_HELD),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_MOVING,
        [LC_EV_LAG] = C(STOP, LC_STOPPING),
    },
    [LC_UNDERRUN] = {
        [LC_EV_FIRST_POSITION] = C(REFUSE, SAME),  [LC_EV_WAYPOINT] = C(CURVE, CURVE),
        [LC_EV_GAP] = C(CURVE, CURVE),             [LC_EV_UNDERRUN] = C(CURVE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, CURVE),
        [LC_EV_STOP] = C(STOP, LC_STOPPING),       [LC_EV_START] = C(NOTE, SAME),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(REFUSE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, LC_FEED_HELD),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_MOVING,
        [LC_EV_LAG] = C(STOP, LC_STOPPING),
    },
    [LC_TRANSFER] = {
        [LC_EV_FIRST_POSITION] = C(REFUSE, SAME),  [LC_EV_WAYPOINT] = C(CURVE, SAME),
        [LC_EV_GAP] = C(CURVE, SAME),              [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, SAME),
        [LC_EV_STOP] = C(STOP, LC_STOPPING),       [LC_EV_START] = C(NOTE, SAME),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(REFUSE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, LC_FEED_HELD),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_MOVING,
        [LC_EV_LAG] = C(STOP, LC_STOPPING),
    },
    [LC_STOPPING] = {
        [LC_EV_FIRST_POSITION] = C(REFUSE, SAME),  [LC_EV_WAYPOINT] = C(BUFFER, SAME),
        [LC_EV_GAP] = C(NOTE, SAME),               [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(BUFFER, SAME),
        [LC_EV_STOP] = C(NOTE, SAME),              [LC_EV_START] = C(START, CURVE),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(REFUSE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, SAME),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_KEPT,
        [LC_EV_LAG] = C(NOTE, SAME),
    },
    [LC_STOPPED] = {
        [LC_EV_FIRST_POSITION] = C(ADOPT, SAME),   [LC_EV_WAYPOINT] = C(BUFFER, SAME),
        [LC_EV_GAP] = C(NOTE, SAME),               [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(BUFFER, SAME),
        [LC_EV_STOP] = C(NOTE, SAME),              [LC_EV_START] = C(START, CURVE),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(ADOPT, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, SAME),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_KEPT,
        [LC_EV_LAG] = C(NOTE, SAME),
    },
    [LC_HELD] = {
        [LC_EV_FIRST_POSITION] = C(POSITION, SAME), [LC_EV_WAYPOINT] = C(BUFFER, SAME),
        [LC_EV_GAP] = C(NOTE, SAME),               [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(BUFFER, SAME),
        [LC_EV_STOP] = C(NOTE, SAME),              [LC_EV_START] = C(REFUSE, SAME),
        [LC_EV_CLEAR] = C(REANCHOR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        [LC_EV_SAFETY] = C(FREEZE, SAME),          [LC_EV_DRIVE_LOST] = C(DRIVE_HOLD, SAME),
        [LC_EV_DRIVE_ENABLED] = C(POSITION, SAME), [LC_EV_DRIVE_BOOTUP] = C(DRIVE_HOLD, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, SAME), [LC_EV_HEARTBEAT_BACK] = C(NOTE, SAME),
        [LC_EV_STALL] = C(NOTE, SAME),             [LC_EV_CLOCK_STEP] = C(NOTE, SAME),
        RELOADS_KEPT,
        [LC_EV_LAG] = C(NOTE, SAME),
    },
    [LC_FEED_HELD] = {
        [LC_EV_FIRST_POSITION] = C(REFUSE, SAME),  [LC_EV_WAYPOINT] = C(CURVE, SAME),
        [LC_EV_GAP] = C(CURVE, SAME),              [LC_EV_UNDERRUN] = C(CURVE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, SAME),
        [LC_EV_STOP] = C(STOP, LC_STOPPING),       [LC_EV_START] = C(REFUSE, SAME),
        [LC_EV_CLEAR] = C(CLEAR, CURVE),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(REFUSE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(REFUSE, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(NOTE, SAME),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_KEPT,
        [LC_EV_LAG] = C(NOTE, SAME),
    },
    [LC_FINISHED] = {
        [LC_EV_FIRST_POSITION] = C(ADOPT, SAME),   [LC_EV_WAYPOINT] = C(CURVE, CURVE),
        [LC_EV_GAP] = C(CURVE, CURVE),             [LC_EV_UNDERRUN] = C(NOTE, SAME),
        [LC_EV_END_OF_INPUT] = C(CURVE, SAME),
        [LC_EV_STOP] = C(STOP, LC_STOPPED),        [LC_EV_START] = C(PLAY, CURVE),
        [LC_EV_CLEAR] = C(CLEAR, LC_WAITING),
        [LC_EV_OVERRIDE_ZERO] = C(RATE, SAME),     [LC_EV_OVERRIDE] = C(RATE, SAME),
        FAULTS_FREEZE,                             [LC_EV_DRIVE_ENABLED] = C(ADOPT, SAME),
        [LC_EV_HEARTBEAT_LOST] = C(FEED_HOLD, LC_FEED_HELD),
        [LC_EV_STALL] = C(ONE_STEP, SAME),         [LC_EV_CLOCK_STEP] = C(CLOCK, SAME),
        RELOADS_KEPT,
        [LC_EV_LAG] = C(STOP, LC_STOPPED),
    },
};
/* clang-format on */

static const char *const state_names[LC_STATE_COUNT] = {
    "no position", "waiting", "streaming", "underrun",  "transfer",
    "stopping",    "stopped", "held",      "feed held", "finished"};
static const char *const event_names[LC_EV_COUNT] = {
    "first position", "waypoint",      "gap",           "underrun",       "end of input",
    "stop",           "start",         "clear",         "override 0",     "override",
    "safety",         "drive lost",    "drive enabled", "drive boot-up",  "heartbeat lost",
    "heartbeat back", "stall",         "clock step",    "reload changed", "reload removed",
    "reload added",   "reload failed", "shutdown",      "restart",        "lag beyond max_lag_s"};
static const char *const action_names[LC_ACTION_COUNT] = {
    "undefined", "curve",      "adopt",  "buffer", "note",   "stop",      "start",    "play",
    "clear",     "reanchor",   "rate",   "refuse", "freeze", "feed hold", "position", "one step",
    "clock",     "reload new", "retire", "keep",   "fresh",  "shutdown",  "restart",  "drive hold"};

const char *lc_state_name(lc_state_t s)
{
    return (unsigned)s < LC_STATE_COUNT ? state_names[s] : "?";
}

const char *lc_event_name(lc_event_t ev)
{
    return (unsigned)ev < LC_EV_COUNT ? event_names[ev] : "?";
}

const char *lc_action_name(lc_action_t a)
{
    return (unsigned)a < LC_ACTION_COUNT ? action_names[a] : "?";
}

int lc_init(lifecycle_t *lc, engine_t *engine, safety_t *safety, int64_t period_ns, unsigned cap)
{
    memset(lc, 0, sizeof *lc);
    lc->engine = engine;
    lc->safety = safety;
    lc->period_ns = period_ns > 0 ? period_ns : 1;
    if (cap == 0) {
        engine_status_t st;
        engine_status(engine, &st);
        cap = 2 * (st.lookahead + 1);
        if (cap < LC_LATCH_MIN)
            cap = LC_LATCH_MIN;
    }
    lc->newest_t = NAN;
    lc->buf = calloc(cap, sizeof *lc->buf);
    if (!lc->buf)
        return -ENGINE_ENOMEM;
    lc->cap = cap;
    return 0;
}

void lc_free(lifecycle_t *lc)
{
    free(lc->buf);
    lc->buf = NULL;
    lc->cap = lc->len = lc->head = 0;
}

void lc_inherit(lifecycle_t *lc, const lifecycle_t *from)
{
    lc->n = from->n;
    lc->n.events[LC_EV_RELOAD_CHANGED]++;
    for (unsigned i = 0; i < from->len; i++) { /* the waypoints it kept, kept (counted then) */
        if (lc->len < lc->cap)
            lc->buf[(lc->head + lc->len++) % lc->cap] = from->buf[(from->head + i) % from->cap];
        else
            lc->n.dropped_full++;
    }
    lc->hold = from->hold;
    lc->latched = from->latched;
    lc->end_pending = from->end_pending;
    lc->clear_pending = from->clear_pending;
    lc->drive_pos = from->drive_pos;
    lc->have_reported = from->have_reported;
    memcpy(lc->reported, from->reported, sizeof lc->reported);
    lc->sent = from->sent;
    lc->have_sent = from->have_sent;
    lc->newest_t = from->newest_t;
    lc->delay_s = from->delay_s;
    if (lc->hold & LC_HOLD_FEED) {
        (void)engine_set_override(lc->engine, 0.0);
    } else if (from->engine) {
        /* the operator's feed override goes with the object too: a reload
         * that changed its settings had set a paused object off again */
        engine_status_t st;
        engine_status(from->engine, &st);
        (void)engine_set_override(lc->engine, st.override);
    }
    if (lc->drive_pos)
        engine_require_position(lc->engine, 1);
}

uint32_t lc_free_room(const lifecycle_t *lc, uint32_t free)
{
    lc_state_t s = lc_state(lc);
    if (s != LC_STOPPING && s != LC_STOPPED && s != LC_HELD)
        return free;
    uint32_t room = lc->cap > lc->len ? lc->cap - lc->len : 0;
    return room < free ? room : free;
}

unsigned lc_buffered(const lifecycle_t *lc)
{
    return lc->len;
}

double lc_buffered_newest_t(const lifecycle_t *lc)
{
    double t = NAN;
    for (unsigned i = 0; i < lc->len; i++) { /* (in the order offered: the latest time) */
        double ti = lc->buf[(lc->head + i) % lc->cap].t_s;
        if (!(ti <= t))
            t = ti;
    }
    return t;
}

/* The monitor's hold: the curve is not advanced. */
static int frozen(const lifecycle_t *lc)
{
    return (lc->hold & LC_HOLD_SAFETY) != 0;
}

/* A fault holds: the monitor's (frozen), or a drive's (braking to rest). */
static int held(const lifecycle_t *lc)
{
    return (lc->hold & (LC_HOLD_SAFETY | LC_HOLD_DRIVE)) != 0;
}

static int curve_moving(const lifecycle_t *lc)
{
    engine_status_t st;
    engine_status(lc->engine, &st);
    return st.state == ENGINE_STATE_STREAMING || st.state == ENGINE_STATE_UNDERRUN;
}

lc_state_t lc_state(const lifecycle_t *lc)
{
    engine_status_t st;
    if (held(lc))
        return LC_HELD;
    engine_status(lc->engine, &st);
    int moving = st.state == ENGINE_STATE_STREAMING || st.state == ENGINE_STATE_UNDERRUN;
    if (lc->latched)
        return moving ? LC_STOPPING : LC_STOPPED;
    if (lc->drive_pos || !engine_has_position(lc->engine))
        return LC_NO_POSITION;
    if (lc->hold & LC_HOLD_FEED)
        return LC_FEED_HELD;
    switch (st.state) {
    case ENGINE_STATE_STREAMING:
        return (lc->sent.flags & ENGINE_SP_TRANSFER) ? LC_TRANSFER : LC_STREAMING;
    case ENGINE_STATE_UNDERRUN: return LC_UNDERRUN;
    case ENGINE_STATE_FINISHED: return LC_FINISHED;
    default: return LC_WAITING;
    }
}

/* ---- the latch buffer ---------------------------------------------------- */

/* Kept for the resume; a full buffer refuses it as the engine's would
 * (-ENGINE_EFULL: flow control, the sender told, nothing taken and then
 * lost).  It dropped the oldest: 181 of 200 waypoints written to a stopped
 * object over Modbus, each acknowledged, were gone at start. */
static int buf_add(lifecycle_t *lc, const engine_waypoint_t *wp)
{
    if (lc->len >= lc->cap) {
        if (!engine_repeat_refused(&lc->full, wp))
            lc->n.refused_full++; /* (offered again: the same refusal) */
        return -ENGINE_EFULL;
    }
    engine_repeat_taken(&lc->full);
    lc->buf[(lc->head + lc->len) % lc->cap] = *wp;
    lc->len++;
    lc->n.buffered++;
    return 0;
}

/* Waypoints the object would already have passed: on the epoch clock, those
 * before the play time now - D; relative, those further behind the newest
 * than the object ran behind its data when it stopped (delay_s); none when
 * that is unknown (the object never streamed: a job written while it was
 * stopped is played whole; all but the newest lookahead + 1 dropped 181 of
 * 200). */
static unsigned buf_past(const lifecycle_t *lc)
{
    unsigned past = 0;
    if (lc->have_clk) {
        long double play = (long double)lc->play_ns * 1e-9L;
        while (past < lc->len && (long double)lc->buf[(lc->head + past) % lc->cap].t_s < play)
            past++;
        return past;
    }
    if (lc->len && lc->delay_s > 0) {
        double from = lc->buf[(lc->head + lc->len - 1) % lc->cap].t_s - lc->delay_s;
        while (past < lc->len && lc->buf[(lc->head + past) % lc->cap].t_s < from)
            past++;
        return past;
    }
    return 0;
}

/* How far behind its data the object runs now (kept when it stops). */
static void note_delay(lifecycle_t *lc)
{
    if (lc->have_sent && isfinite(lc->newest_t) && isfinite(lc->sent.t_s) &&
        lc->newest_t > lc->sent.t_s)
        lc->delay_s = lc->newest_t - lc->sent.t_s;
}

/* Resume: the buffered waypoints not in the past to the curve (they start a
 * new trajectory, joined by a transfer from where the output rests), then
 * the end of input if one came meanwhile. */
static void buf_flush(lifecycle_t *lc)
{
    unsigned past = buf_past(lc);
    lc->n.dropped_past += past;
    for (unsigned i = past; i < lc->len; i++)
        (void)engine_push(lc->engine, &lc->buf[(lc->head + i) % lc->cap]); /* counted there */
    lc->head = lc->len = 0;
    if (lc->end_pending)
        (void)engine_finish(lc->engine);
    lc->end_pending = 0;
}

static void buf_drop(lifecycle_t *lc)
{
    lc->n.dropped_past += lc->len;
    lc->head = lc->len = 0;
    lc->end_pending = 0;
}

/* ---- actions ------------------------------------------------------------- */

static int pos_ok(const lifecycle_t *lc, const double *p)
{
    (void)lc;
    if (!p)
        return 0;
    for (int k = 0; k < AXN; k++)
        if (!isfinite(p[k]))
            return 0;
    return 1;
}

/* The drives' (or a configured) position becomes the commanded state. */
static int act_adopt(lifecycle_t *lc, const double *p)
{
    if (!pos_ok(lc, p))
        return -ENGINE_ENOTFINITE;
    int rc;
    if (lc->drive_pos) { /* after a drive hold: re-anchored there, then the track */
        rc = engine_halt(lc->engine, p);
        if (rc < 0)
            return rc;
        lc->drive_pos = 0;
        engine_require_position(lc->engine, 0);
        if (lc->safety)
            safety_forget(lc->safety);
        if (!lc->latched)
            buf_flush(lc);
        return 0;
    }
    rc = engine_set_position(lc->engine, p);
    if (rc == 0 && lc->safety)
        safety_forget(lc->safety); /* the next output is its first: judged from there */
    return rc;
}

static void act_clear(lifecycle_t *lc)
{
    lc->latched = 0;
    buf_drop(lc);
    if (lc->hold & LC_HOLD_FEED) { /* the operator's: the feed back at 100 % */
        lc->hold &= ~LC_HOLD_FEED;
        (void)engine_set_override(lc->engine, 1.0);
    }
    engine_clear(lc->engine);
}

/* Clear after a fault: every hold and the latch released, the curve stands
 * at rest where the output was held (or where the drives report they are),
 * and what came meanwhile joins by a transfer. */
static int act_reanchor(lifecycle_t *lc)
{
    unsigned was = lc->hold;
    if (!frozen(lc) && (was & LC_HOLD_DRIVE) && curve_moving(lc)) {
        lc->clear_pending = 1; /* a drive hold still brakes: re-anchored once at rest */
        return 0;
    }
    lc->clear_pending = 0;
    double p[AXN];
    int have = 0;
    if (lc->have_reported) {
        memcpy(p, lc->reported, sizeof p);
        have = 1;
    } else if (lc->have_sent && !(was & LC_HOLD_DRIVE)) { /* the drives' own, or none */
        memcpy(p, lc->sent.pos_m, sizeof p);
        have = pos_ok(lc, p);
    }
    lc->hold = 0;
    lc->latched = 0;
    if (was & LC_HOLD_FEED)
        (void)engine_set_override(lc->engine, 1.0);
    if (have && engine_halt(lc->engine, p) < 0)
        have = 0;
    if (lc->safety) {
        if (safety_fault(lc->safety))
            safety_rearm(lc->safety); /* judged from the held position at rest */
        if (lc->have_reported)
            safety_forget(lc->safety); /* the drives' position: the next output is the first */
    }
    lc->have_reported = 0;
    if ((was & LC_HOLD_DRIVE) && !have) {
        /* the drives must say where they are before anything is sent: the
         * frozen curve stops where it was sent, then forgets that position */
        if (lc->have_sent)
            (void)engine_halt(lc->engine, lc->sent.pos_m);
        if (lc->safety)
            safety_forget(lc->safety); /* the next position is the drives': judged from there */
        lc->drive_pos = 1;
        engine_require_position(lc->engine, 1);
        return 0;
    }
    lc->drive_pos = 0;
    engine_require_position(lc->engine, 0);
    if (!have)
        engine_clear(lc->engine); /* nothing was ever sent: nowhere to stand */
    buf_flush(lc);
    return 0;
}

static int act_freeze(lifecycle_t *lc)
{
    if (!held(lc))
        note_delay(lc);
    lc->hold |= LC_HOLD_SAFETY;
    /* the freeze itself is the hold (the monitor's own stop at once): what
     * resumes is judged afresh */
    if (lc->safety && !safety_fault(lc->safety))
        safety_forget(lc->safety);
    return 0;
}

/* A drive no longer follows (it left Operation Enabled, or booted): the
 * caller gives that drive its own position; the object brakes to rest along
 * its path within its limits (the other axes stop as a stop stops them) and
 * is held until clear, which re-anchors at the drives' position. */
static int act_drive_hold(lifecycle_t *lc)
{
    if (!held(lc))
        note_delay(lc);
    lc->hold |= LC_HOLD_DRIVE;
    lc->have_reported = 0; /* where the drives are must come again */
    if (!frozen(lc))
        (void)engine_stop(lc->engine);
    return 0;
}

static int act_play(lifecycle_t *lc)
{
    engine_status_t st;
    engine_status(lc->engine, &st);
    if (st.state != ENGINE_STATE_WAITING)
        return 0;
    if (st.buffered == 0 && !st.judging)
        return -ENGINE_ESTATE;
    return engine_finish(lc->engine);
}

static int run_action(lifecycle_t *lc, lc_action_t a, lc_event_t ev, const lc_arg_t *arg)
{
    switch (a) {
    case LC_A_CURVE:
        if (ev == LC_EV_WAYPOINT)
            return arg && arg->wp ? engine_push(lc->engine, arg->wp) : -ENGINE_ERANGE;
        if (ev == LC_EV_END_OF_INPUT)
            return engine_finish(lc->engine);
        return 0; /* the curve's own events (gap, underrun) */
    case LC_A_ADOPT: return act_adopt(lc, arg ? arg->pos_m : NULL);
    case LC_A_BUFFER:
        if (ev == LC_EV_END_OF_INPUT) {
            lc->end_pending = 1;
            return 0;
        }
        if (!arg || !arg->wp)
            return -ENGINE_ERANGE;
        {
            engine_config_t cfg; /* the checks on the waypoint alone, now */
            engine_config_default(&cfg);
            cfg.max_abs_m = INFINITY;
            int rc = engine_waypoint_check(&cfg, arg->wp);
            if (rc < 0)
                return rc;
        }
        return buf_add(lc, arg->wp);
    case LC_A_STOP:
        note_delay(lc);
        lc->latched = 1;
        return engine_stop(lc->engine);
    case LC_A_START:
        lc->latched = 0;
        buf_flush(lc);
        return 0;
    case LC_A_PLAY: return act_play(lc);
    case LC_A_CLEAR: act_clear(lc); return 0;
    case LC_A_REANCHOR: return act_reanchor(lc);
    case LC_A_RATE:
        if (!arg || !(arg->ratio >= 0))
            return -ENGINE_ERANGE;
        if ((lc->hold & LC_HOLD_FEED) && arg->ratio > 0) {
            lc->n.refused++;
            return -ENGINE_ESTATE; /* moving again after a feed hold is clear's */
        }
        return engine_set_override(lc->engine, arg->ratio);
    case LC_A_REFUSE: lc->n.refused++; return -ENGINE_ESTATE;
    case LC_A_FREEZE: return act_freeze(lc);
    case LC_A_DRIVE_HOLD: return act_drive_hold(lc);
    case LC_A_FEED_HOLD: lc->hold |= LC_HOLD_FEED; return engine_set_override(lc->engine, 0.0);
    case LC_A_POSITION:
        if (!arg || !pos_ok(lc, arg->pos_m))
            return -ENGINE_ENOTFINITE;
        if (lc->hold & LC_HOLD_DRIVE)
            return 0; /* a drive hold: after its clear the drives report afresh (each axis
                         at its 0x6064); while it brakes they do not stand there yet */
        memcpy(lc->reported, arg->pos_m, sizeof lc->reported);
        lc->have_reported = 1;
        return 0;
    case LC_A_SHUTDOWN:
    case LC_A_RETIRE:
        if (!frozen(lc))
            (void)engine_stop(lc->engine); /* brakes along its path to rest */
        return 0;
    case LC_A_RESTART: return arg && arg->pos_m ? act_adopt(lc, arg->pos_m) : 0;
    default: return 0; /* NOTE, ONE_STEP, CLOCK (lc_tick), KEEP, RELOAD_NEW, FRESH (core) */
    }
}

int lc_event(lifecycle_t *lc, lc_event_t ev, const lc_arg_t *arg)
{
    if ((unsigned)ev >= LC_EV_COUNT)
        return -ENGINE_ERANGE;
    if (ev == LC_EV_WAYPOINT && arg && arg->wp && isfinite(arg->wp->t_s))
        lc->newest_t = arg->wp->t_s;
    lc->n.events[ev]++;
    lc_cell_t c = lc_table[lc_state(lc)][ev];
    return run_action(lc, (lc_action_t)c.action, ev, arg);
}

int lc_push(lifecycle_t *lc, const engine_waypoint_t *wp)
{
    lc_arg_t a = {0, wp, NULL};
    return lc_event(lc, LC_EV_WAYPOINT, &a);
}

int lc_set_position(lifecycle_t *lc, const double pos_m[ENGINE_AXES])
{
    lc_arg_t a = {0, NULL, pos_m};
    return lc_event(lc,
                    engine_has_position(lc->engine) && !lc->drive_pos ? LC_EV_DRIVE_ENABLED
                                                                      : LC_EV_FIRST_POSITION,
                    &a);
}

/* ---- the tick ------------------------------------------------------------ */

/* The missed periods since the last tick (LC_EV_STALL); 0 normally. */
static int64_t missed(lifecycle_t *lc, int64_t now_ns)
{
    if (!lc->have_tick)
        return 0;
    int64_t k = (now_ns - lc->last_now_ns + lc->period_ns / 2) / lc->period_ns;
    if (k <= 1)
        return 0;
    lc->n.events[LC_EV_STALL]++;
    lc->n.stalled_periods += (uint64_t)(k - 1);
    if (!lc->have_clk)
        lc->n.lag_s += (double)((k - 1) * lc->period_ns) * 1e-9;
    return k - 1;
}

/* CLOCK_REALTIME stepped: the clock moved other than by the time that passed. */
static void clock_watch(lifecycle_t *lc, int64_t now_ns, const engine_clock_t *clk)
{
    if (!clk)
        return;
    if (lc->have_clk && lc->have_tick) {
        double expect = (double)(now_ns - lc->last_now_ns) * clk->rate;
        if (fabs((double)(clk->now_ns - lc->clk_now_ns) - expect) > 1e6) {
            lc->n.events[LC_EV_CLOCK_STEP]++;
            lc->n.clock_steps++;
        }
    }
    lc->have_clk = 1;
    lc->clk_now_ns = clk->now_ns;
    lc->play_ns = clk->now_ns - clk->delay_ns;
}

/* Frozen: the commanded state as sent, at rest; the curve is not advanced. */
static void held_sp(lifecycle_t *lc, int64_t now_ns, engine_setpoint_t *sp)
{
    *sp = lc->sent;
    sp->now_ns = now_ns;
    for (int k = 0; k < AXN; k++)
        sp->vel_m_s[k] = sp->acc_m_s2[k] = 0.0;
    sp->flags = ENGINE_SP_HOLD | (lc->have_sent ? 0 : ENGINE_SP_NO_POSITION);
    if (!lc->have_sent)
        for (int k = 0; k < AXN; k++)
            sp->pos_m[k] = NAN;
    if (lc->safety && safety_fault(lc->safety)) {
        sp->now_ns = lc->eng_ns;            /* judged on the curve's time: see lc_tick */
        (void)safety_check(lc->safety, sp); /* the monitor's hold: FAULT, counted */
        sp->now_ns = now_ns;
    }
}

void lc_step_unsent(lifecycle_t *lc, int64_t now_ns, const engine_clock_t *clk)
{
    engine_setpoint_t sp;
    if (lc->have_tick && now_ns < lc->last_now_ns)
        return;
    clock_watch(lc, now_ns, clk);
    lc->last_now_ns = now_ns;
    if (lc->clear_pending && !frozen(lc) && !curve_moving(lc))
        (void)act_reanchor(lc);
    if (frozen(lc)) {
        lc->have_tick = 1;
        return;
    }
    lc->eng_ns = lc->have_tick ? lc->eng_ns + lc->period_ns : now_ns;
    lc->have_tick = 1;
    if (clk)
        (void)engine_set_clock(lc->engine, clk);
    engine_tick(lc->engine, lc->eng_ns, &sp);
}

int lc_tick(lifecycle_t *lc, int64_t now_ns, const engine_clock_t *clk, engine_setpoint_t *sp)
{
    if (lc->have_tick && now_ns < lc->last_now_ns) {
        *sp = lc->sent;
        return -ENGINE_ESTATE;
    }
    int64_t skip = missed(lc, now_ns);
    clock_watch(lc, now_ns, clk);
    lc->last_now_ns = now_ns;
    if (lc->clear_pending && !frozen(lc) && !curve_moving(lc))
        (void)act_reanchor(lc); /* the clear that came while a drive hold braked */
    if (frozen(lc)) {
        lc->have_tick = 1;
        held_sp(lc, now_ns, sp);
        lc->sent = *sp;
        return 0;
    }
    lc->eng_ns = lc->have_tick ? lc->eng_ns + lc->period_ns : now_ns;
    lc->have_tick = 1;
    if (clk)
        (void)engine_set_clock(lc->engine, clk); /* bounds: the caller's */
    engine_tick(lc->engine, lc->eng_ns, sp);
    if (engine_axis_lag_over(lc->engine)) /* issue 32: stop on the path, latched */
        (void)lc_event(lc, LC_EV_LAG, NULL);
    if (skip)
        sp->flags |= ENGINE_SP_SKIPPED;
    if ((sp->flags & ENGINE_SP_NEW_TRACK) && !lc->have_clk)
        lc->n.lag_s = 0; /* a relative trajectory starts its own time */
    /* The monitor judges the targets as sent, one period of the curve each
     * (sp->now_ns is still the curve's time here): after a stall the next
     * target is one period on, which is what it must see; the stall itself
     * is LC_EV_STALL, counted, not motion of trajd's. */
    if (lc->safety) {
        /* a fault latched before (e.g. judging a reload's braking) freezes too */
        if (safety_check(lc->safety, sp) != SAFETY_OK && !(lc->hold & LC_HOLD_SAFETY))
            (void)lc_event(lc, LC_EV_SAFETY, NULL); /* sp is already the monitor's hold */
    }
    sp->now_ns = now_ns;
    lc->sent = *sp;
    lc->have_sent = !(sp->flags & ENGINE_SP_NO_POSITION);
    return 0;
}
