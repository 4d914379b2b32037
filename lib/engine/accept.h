/*
 * accept.h - which waypoints a trajectory keeps: the acceptance policy of
 * the engine, judged with both neighbours of each waypoint.
 *
 * Pure and allocation-free: an accept_t lives inside the engine.  The engine
 * offers every finite, in-range waypoint (accept_offer) and then asks for
 * verdicts (accept_decide) until there is none: each verdict says what to do
 * with the oldest waypoint held, in arrival order.
 *
 * The rule.  The waypoints held (at most `window`: the engine's start_slack,
 * or ACCEPT_WINDOW_MAX with start_slack auto; a clean track's verdicts come
 * after ACCEPT_LAG, so they cost no latency: see engine_lookahead) are
 * judged together with the anchor, the last waypoint kept (and the one kept
 * before it, for the acceleration test).  Two waypoints are *consistent* if
 * the later one is later in time (by more than 1 ns), the interval is at
 * most max_gap_s, the chord speed is within the speed limit and, with the
 * waypoint before, the implied acceleration is within the acceleration
 * limit (see accept_check).  The oldest waypoint held, c, is
 *   - kept (ACCEPT_TAKE) if the longest consistent chain from the anchor
 *     through the waypoints held goes through c, or ties with the longest
 *     one that skips it (keep every good fix);
 *   - dropped (ACCEPT_DROP) if a longer chain from the anchor skips it: its
 *     neighbours agree without it, so one bad fix never condemns the good
 *     ones after it (they are judged against the anchor, not against it);
 *   - the start of a new trajectory (ACCEPT_START; the engine closes the
 *     current one at rest and transfers) if nothing held is consistent with
 *     the anchor and c begins a chain of `confirm` mutually consistent
 *     waypoints: re-anchoring after a bad anchor, a restarted clock, a gap.
 *     A plausible gap (ACCEPT_FAR_GAP_FACTOR) needs no confirmation once
 *     nothing held continues the anchor: a sparse track keeps its isolated
 *     fixes.  A waypoint far from the current trajectory in time or space that is
 *     not confirmed so is dropped as ENGINE_EUNCONFIRMED (one Modbus
 *     waypoint at t = 1e9 never abandons the current trajectory; nor do
 *     fewer than `confirm` fixes 1 km off, consistent among themselves: each
 *     is unconfirmed, while a lone spike, consistent with nothing held, keeps
 *     its ESPEED or EACCEL);
 *   - (the former policy, ACCEPT_RULES_FORMER; with the rules of issue 27
 *     the repeats of the anchor are a run judged by stops.c: stale or a
 *     stop, see ACCEPT_RULE_STOPS below)
 *     dropped as ENGINE_ESTALE if it repeats the anchor's position (within
 *     ACCEPT_STALE_POS_M) although the object was moving (at least
 *     ACCEPT_STALE_MIN_SPEED_M_S into the anchor) and the next waypoint with
 *     a new position is consistent with the anchor and shows the object kept
 *     at least half its pace across the repeats: a frozen receiver, not a
 *     stop.  A run longer than the window, with no new position yet, is
 *     stale if standing there means stopping dead from the recent pace
 *     within the anchor's interval harder than ACCEPT_STALE_STOP_M_S2.  (profiles with stale
 *     detection only; a toolpath's dwell is a real repeat.)  A later
 *     repeat of c is no evidence against c: chains that skip c leave its
 *     repeats out (a frozen run's copies, stamped later, would outvote the
 *     fix they copy).  Of a fix and its later repeats, the fix is kept (it was
 *     stamped when the position was fixed), even where a chain through a
 *     repeat would bend the track less.
 * A clean stretch is decided as soon as c and the waypoint after it
 * (ACCEPT_LAG) form a consistent chain with the anchor; with at_arrival
 * (max_lookahead 1) as soon as c alone follows the anchor and, where c and
 * the anchor both carry the source's velocity, their chord agrees with it
 * (ACCEPT_VEL_*): the velocity is the second signal that lets a fix be kept
 * before its neighbour confirms it.  A fix that does not is judged as
 * without at_arrival, with its neighbours: the velocity alone refuses
 * nothing (decimetre noise at 10 Hz is metres per second of chord).  Otherwise the
 * verdict comes as soon as the full window's is certain: c that does not
 * follow the anchor is dropped once a later waypoint does (but for its
 * speed alone with a learned limit from fewer than ACCEPT_PACE_CHORDS kept
 * intervals, maybe still its floor: then by the full window); c that follows
 * it is kept once a later waypoint continues it past waypoints that cannot
 * take its place (they do not follow the anchor, or repeat c's position),
 * or once the longest chain through c among the waypoints held is longer
 * than every chain that skips c (a spike that a loose learned limit lets
 * follow the anchor, but that nothing held continues).
 * So one bad fix holds its neighbours one interval more, not a window, and
 * costs the output no underrun (tests/unit/test_accept.c).  Else the verdict
 * waits until the window is full or the input is closed.  The first trajectory (nothing
 * to abandon) starts on a chain of `confirm` waypoints, or at the close on
 * whatever consistent chain there is, or on the oldest waypoint held when
 * the window is full and no two of its waypoints are consistent (every fix
 * stamped alike: the first is kept, the others refused as same_time).
 *
 * The limits (see engine.h, engine_profile_t):
 *   - absolute: chord speed <= max_speed_m_s, implied acceleration
 *     2 |v2 - v1| / (dt1 + dt2) <= max_accel_m_s2 (0 = off).  Every kept
 *     triple satisfies them, so the C2 curve's acceleration stays within
 *     3 x max_accel_m_s2 (max principle of the second-derivative system).
 *   - learned (profile auto): the speed limit is also at most
 *     max(ACCEPT_LEARN_FLOOR_M_S, ACCEPT_LEARN_FACTOR x v_ref), v_ref the
 *     fastest chord of the last ACCEPT_HIST kept intervals or the lower
 *     median chord of the waypoints held, whichever is larger (the window's
 *     median only from ACCEPT_PACE_CHORDS chords: a spike's own two chords
 *     never set the limit that judges it, tests/oracle/test_fault_injection.py
 *     test_spike_every_site, and before the first kept interval too,
 *     tests/unit/test_accept.c test_spike_before_first_interval; but before
 *     any kept interval in a full window, at the close, or with a window of
 *     at most ACCEPT_PACE_CHORDS waypoints (start_slack 1..4), the chords
 *     there are: such a window cannot tell a spike before the first kept
 *     interval by its speed); and a turn is free:
 *     |v2 - v1| may exceed the acceleration allowance by up to
 *     2 min(|v1|, |v2|) (a reversal at the lower of the two speeds), so a
 *     feed-rate-timed corner passes while a change of speed is held to
 *     max_accel_m_s2 (with ACCEPT_RULE_VECTOR: | |v2| - |v1| | within the
 *     allowance itself, so a change of speed along the track is not a turn:
 *     the 100 m / 280 m chords of a jittered ADS-B line passed as one).
 *     The bound becomes 3 (max_accel_m_s2 + 4 min(|v1|, |v2|) / (dt1 +
 *     dt2)) per kept triple.
 * With the rules of issue 27 (accept_config_t.rules, ACCEPT_RULE_*: the
 * engine's, but for profile none) a fix about to be dropped for its speed
 * or acceleration whose position lies on its neighbours' path is kept with
 * its stamp re-estimated (retime.c), a fast object's fix whose stamp bends
 * the pace is re-stamped at the pace of the path (ACCEPT_RULE_SMOOTH), and a
 * repeat of a fix dropped for its position is dropped too (it cannot return
 * by repetition).
 */
#ifndef TRAJD_ACCEPT_H
#define TRAJD_ACCEPT_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "motion.h"

/* Waypoints after c that a clean verdict waits for (its next neighbour). */
#define ACCEPT_LAG 1
/* The source's velocity as a second signal (issue 31, at_arrival): the chord
 * of two fixes that both carry one may differ from the mean of the two by
 * a_max dt / 4 (a_max: max_accel_m_s2, or this without one, m/s^2) plus
 * the noise of two positions over dt and of the velocities. */
#define ACCEPT_VEL_ACCEL_M_S2 10.0
#define ACCEPT_VEL_POS_NOISE_M 0.5
#define ACCEPT_VEL_NOISE_M_S 0.5
/* Waypoints judged at once, at most. */
#define ACCEPT_WINDOW_MAX 8
/* Kept intervals whose chord speeds the learned limit looks back on. */
#define ACCEPT_HIST 16
/* Learned speed limit: this many times the recent speed ... */
#define ACCEPT_LEARN_FACTOR 4.0
/* ... but never below this (m/s): GNSS noise of a standing receiver at 5 Hz
 * (3 m at 0.2 s is 15 m/s; the chord median of the window covers it), a
 * walker, and every machine tool's feed. */
#define ACCEPT_LEARN_FLOOR_M_S 5.0
/* The window's chords count towards the learned speed limit only if there
 * are this many (once there is a recent speed): the lower median of 4 is
 * not one outlier's two chords. */
#define ACCEPT_PACE_CHORDS 4
/* A repeat within this distance is the same position (metres): positions
 * decoded from one fix are bit-identical. */
#define ACCEPT_STALE_POS_M 1e-6
/* A gap (interval above max_gap_s) up to this many times max_gap_s, covered
 * within the speed limit, is plausible: a sparse track, a receiver that lost
 * the sky for a while.  Beyond it, it is "far in time" (a seconds-for-
 * microseconds slip, t = 1e9): only `confirm` consistent waypoints start a
 * trajectory there. */
#define ACCEPT_FAR_GAP_FACTOR 60.0
/* The object was moving into the repeat at least this fast (m/s). */
#define ACCEPT_STALE_MIN_SPEED_M_S 0.5
/* A run of repeats longer than the window (no new position to judge it by
 * yet) is stale if standing there means stopping dead, from the recent pace
 * (the lower median of the last ACCEPT_HIST kept chords, at least
 * ACCEPT_STALE_MIN_SPEED_M_S) within the anchor's interval, harder than
 * this (m/s^2, 1 g: a car's emergency stop on dry asphalt; a boat or an
 * aircraft cannot come near it): 5 m/s at 5 Hz is 25 m/s^2, an airliner at
 * 1 Hz 230; a walker at 1.5 m/s and 1 Hz (1.5 m/s^2) stands still, and a
 * moored boat whose 10 Hz messages repeat a 1 Hz fix has no pace (its
 * chords are mostly 0): their repeats are kept. */
#define ACCEPT_STALE_STOP_M_S2 9.81
/* ACCEPT_RULE_STOPS: a run of ACCEPT_STOP_RUN repeats, with no new
 * position yet, is taken as a stop at once (the output comes to rest on
 * it instead of running out of curve) if stopping dead there from the
 * recent pace within the anchor's interval takes at most this (m/s^2,
 * 2 g: a machine axis or a robot stops so; a boat, a car or an aircraft
 * does not: 5 m/s at 5 Hz is 25, while a machine at 1 m/s and 10 Hz is
 * 10, a walker at 1.5 m/s and 0.25 Hz 0.4); else the run waits for the next
 * new position (stops.c). */
#define ACCEPT_STOP_MAX_M_S2 19.62
/* ... at least this many repeats, and as many as the window holds: shorter
 * runs may be a message received again or a receiver frozen for a fix or two
 * (the next new position tells them stale: tests/oracle/test_fault_injection.py),
 * a run the window's length from an object that could have stopped dead there
 * within ACCEPT_STALE_STOP_M_S2 is its stop (waiting for the next new position,
 * the output ran out of curve short of the stop and stood in underrun as long
 * as the object stood); a faster stop waits for the next new position, as a
 * frozen receiver's repeats must (stops.c) */
#define ACCEPT_STOP_RUN 2u
/* Repeats of the anchor held for one verdict at most (stops.c): a longer
 * run with no new position yet is judged there and then. */
#define ACCEPT_RUN_MAX 256
/* Stamp re-estimation (rules ACCEPT_RULE_RETIME): a fix's stamp moves by
 * at most this many times the lower median interval of the waypoints it is
 * judged with (from the anchor),
 * staying between its neighbours, and only for a fix on their path: its
 * detour from the chord of its neighbours at most ACCEPT_RETIME_DETOUR of
 * that chord (a spike off the path is no jitter).  The figure-8's fix
 * stamped 0.296 s late at 5 Hz is 1.5 intervals off. */
#define ACCEPT_RETIME_FRAC 2.0
#define ACCEPT_RETIME_DETOUR 0.25
/* ACCEPT_RULE_SMOOTH (retime.c accept_retime_soft): a fix about to be kept,
 * at a pace of at least ACCEPT_RETIME_SOFT_SPEED_M_S (m/s: there a stamp's
 * jitter moves a fix far more than its position's noise; 0.1 s at 250 m/s
 * is 25 m, at a boat's 5 m/s 0.5 m), whose stamp implies a change of speed
 * above ACCEPT_RETIME_SOFT x max_accel_m_s2 (the curve through kept triples
 * stays within 3 x their implied acceleration, and jitter is not motion),
 * is re-stamped: at the pace of the last ACCEPT_RETIME_PACE kept intervals
 * (their path length over their stamps), pulled ACCEPT_RETIME_GAIN of the
 * way towards the time its own stamp and the later stamps held tell for it
 * (their jitter averages out over about 1 / ACCEPT_RETIME_GAIN fixes); kept
 * so if that moves it by at most ACCEPT_RETIME_SOFT_SHIFT of its shorter
 * interval (ADS-B's latency is 0..0.2 s at 1 Hz).  Tuned on the built
 * airliner of tests/oracle/test_profile_kinds.py (lib/engine/DESIGN.md
 * "Profiles"). */
#define ACCEPT_RETIME_SOFT (1.0 / 6.0)
#define ACCEPT_RETIME_PACE 10u
#define ACCEPT_RETIME_GAIN 0.25
#define ACCEPT_RETIME_SOFT_SHIFT 0.25
#define ACCEPT_RETIME_SOFT_SPEED_M_S 50.0

/* The rules of issue 27 (accept_config_t.rules; the engine sets them all,
 * 0 is the former policy, which tests/helpers/accept_ref.h keeps):
 *   STOPS   a run of repeats of the anchor is a stop (the trajectory ends at
 *           rest at the anchor, a new one starts from rest at the last
 *           repeat) unless the next new position shows the object kept
 *           moving (then the repeats are stale): stops.c;
 *   VECTOR  the free turn frees the direction of the velocity only: the
 *           change of speed along it stays within max_accel_m_s2;
 *   RETIME  a fix whose position is consistent but whose stamp is not
 *           (jitter) is kept with its stamp re-estimated from the local
 *           pace, within ACCEPT_RETIME_FRAC of its intervals;
 *   NORETURN a repeat of a refused fix's position is refused too;
 *   SMOOTH   a fast object's fix (an aircraft's: ADS-B stamps are times of
 *           arrival) whose stamp implies a change of speed above
 *           ACCEPT_RETIME_SOFT x max_accel_m_s2 is re-stamped at the pace
 *           of the last kept intervals, kept or refused alike: retime.c
 *           accept_retime_soft;
 *   LATE     a fix that follows the anchor, followed by one that follows the
 *           anchor too but not it (two fixes that cannot both be kept at their
 *           stamps), whose position lies on the path between and whose stamp
 *           is late for the pace of the last kept intervals, is re-stamped at
 *           that pace and kept at once, where the full window would hold both
 *           until its chains break the tie (the output underran meanwhile):
 *           retime.c accept_retime_late. */
#define ACCEPT_RULE_STOPS 1u
#define ACCEPT_RULE_VECTOR 2u
#define ACCEPT_RULE_RETIME 4u
#define ACCEPT_RULE_NORETURN 8u
#define ACCEPT_RULE_SMOOTH 16u
#define ACCEPT_RULE_LATE 32u
#define ACCEPT_RULES_ALL 63u
/* ACCEPT_RULE_LATE: a fix re-stamped at the pace of the last
 * ACCEPT_LATE_PACE kept intervals is later than it by more than
 * ACCEPT_LATE_MIN of the interval into the anchor, and its interval from the
 * anchor longer, the one to the next fix shorter, by as much */
#define ACCEPT_LATE_MIN 0.25
#define ACCEPT_LATE_PACE 2u
/* accept_config_t.rules: none of them (the former policy, for the test that
 * compares it with tests/helpers/accept_ref.h); 0 means all */
#define ACCEPT_RULES_FORMER 0x80000000u
/* the engine's: all of them, none for profile none (the solver alone) */
#define ACCEPT_RULES_OF(none) ((none) ? ACCEPT_RULES_FORMER : 0u)

typedef struct {
    double max_speed_m_s;  /* absolute speed limit, 0 = none */
    double max_accel_m_s2; /* acceleration limit, 0 = none */
    double max_gap_s;      /* a longer interval is not a continuation */
    int learned;           /* learned speed limit and free turns (profile auto) */
    int stale;             /* drop stale repeats */
    unsigned window;       /* waypoints held for judgement, confirm..ACCEPT_WINDOW_MAX */
    unsigned confirm;      /* mutually consistent waypoints that start a new trajectory */
    unsigned rules;        /* ACCEPT_RULE_*; 0 = all (the engine's), ACCEPT_RULES_FORMER = none */
    int at_arrival;        /* 1: a fix that follows the anchor is kept as it arrives (no
                              ACCEPT_LAG; max_lookahead 1, issue 31): see accept_decide */
} accept_config_t;

typedef enum {
    ACCEPT_TAKE = 0,  /* append to the open trajectory */
    ACCEPT_START = 1, /* close the open trajectory (if any), start a new one with it */
    ACCEPT_DROP = 2,  /* refused: reason says why */
    ACCEPT_HALT = 3,  /* a stop: end the open trajectory at rest on its last
                         waypoint; wp (a repeat of it) is kept as the dwell */
    ACCEPT_DWELL = 4, /* kept as the dwell of a stop (no knot) */
} accept_kind_t;

typedef struct {
    int kind;       /* accept_kind_t */
    int reason;     /* ACCEPT_DROP: an engine_error */
    int gap;        /* ACCEPT_START: the interval from the anchor exceeds max_gap_s */
    int stop;       /* ACCEPT_START of a stop (accept_decide_counted): ACCEPT_STOP_ONE (a
                   run of one repeat: this one starts the next trajectory, the open one
                   ends at rest), ACCEPT_STOP_AFTER (after a HALT), ACCEPT_STOP_HALT (a
                   HALT: the open trajectory ends at rest, wp is dwell, not a knot) */
    double shift_s; /* ACCEPT_TAKE: wp.t_s minus the stamp it came with
                       (ACCEPT_RULE_RETIME; 0 if kept as stamped) */
    engine_waypoint_t wp;
} accept_verdict_t;

/* Slots for the waypoints the policy holds: the window, the anchor a1 and
 * a0 before it, the last far waypoint dropped (burst) and the one offered
 * (the window has at most ACCEPT_WINDOW_MAX - 1 when one is offered). */
#define ACCEPT_SLOTS (ACCEPT_WINDOW_MAX + 3)

/* What the tests need of two waypoints p, b (b offered after p), computed
 * once while both are held: the chord, and the velocity across it. */
typedef struct {
    double d;              /* |b - p| (metres) */
    double v[ENGINE_AXES]; /* (b - p) / (t_b - t_p) per axis */
    double vn;             /* |v| */
    double c;              /* d / (t_b - t_p): the chord speed */
} accept_pair_t;

/* The search of the longest chains from the anchor through c and skipping
 * it among the waypoints held, with their costs where one is NaN (chains.c
 * accept_longest_both), kept for the next search: while the same waypoints
 * stay held with the same speed limit, a search over them and the
 * waypoints offered since judges the new steps alone. */
#define ACCEPT_NODES (ACCEPT_WINDOW_MAX + 1)
typedef struct {
    unsigned m;                     /* nodes searched, 0: none */
    unsigned char nd[ACCEPT_NODES]; /* their slots: the anchor, then the window */
    unsigned char pre;              /* the slot before the anchor, NO_SLOT if none */
    uint64_t since[ACCEPT_NODES];   /* their slots' last change (accept_t.since) */
    uint64_t pre_since;
    double vlim; /* the speed limit searched with */
    /* step i -> j: 1 if its time test passes, 2 if its speed test too */
    unsigned char step[ACCEPT_NODES][ACCEPT_NODES];
    /* the best chain ending with step i -> j through c (k = 0) and skipping
     * it (k = 1): its length (0: none) and cost, as longest_both has them */
    unsigned char len[2][ACCEPT_NODES][ACCEPT_NODES];
    double cst[2][ACCEPT_NODES][ACCEPT_NODES];
    unsigned best[2]; /* the best chains so far */
    double cost[2];
} accept_search_t;

/* The lengths of the longest chains after each step among the waypoints
 * held (chains.c accept_longest_len): the most waypoints a consistent chain
 * x -> y -> ... has after y depends on the waypoints after y alone, so it is
 * kept while waypoints leave the window, and brought up to date as they
 * arrive. */
typedef struct {
    unsigned m;                     /* nodes: an anchor, then waypoints of the window */
    unsigned char nd[ACCEPT_NODES]; /* their slots, in order */
    uint64_t since[ACCEPT_NODES];   /* their slots' last change (accept_t.since) */
    double vlim;                    /* the speed limit of the steps */
    /* by slots x -> y (y after x; rows of 16, an index is a shift and an
     * add): step 0 if its time test fails, 1 if its speed test does, 2 if
     * both pass (y in the window); more: the most nodes after y on a
     * consistent chain x -> y -> ... */
    unsigned char step[ACCEPT_SLOTS][16], more[ACCEPT_SLOTS][16];
    /* more by value (at most ACCEPT_NODES): bit x of by[y][v] if more[x][y]
     * is v (x before y in the list; bits of other slots mean nothing) */
    uint16_t by[ACCEPT_SLOTS][16];
} accept_reach_t;

/* accept_t.wait */
typedef struct {
    int valid, r;
    unsigned char a1, pre;
    unsigned n, scan, tpo;
    uint64_t since_a1, since_pre;
    double vlim;
    unsigned char pend[ACCEPT_WINDOW_MAX];
    uint64_t since[ACCEPT_WINDOW_MAX];
} accept_wait_t;

typedef struct {
    accept_config_t cfg;
    engine_waypoint_t wp[ACCEPT_SLOTS];    /* the waypoints, by slot */
    unsigned char pend[ACCEPT_WINDOW_MAX]; /* slots of the waypoints held, oldest first */
    unsigned npend;
    int open;                  /* a trajectory is open: a1 is its last waypoint */
    int have_a0;               /* a0 is the waypoint before a1 in it */
    unsigned char a0, a1;      /* their slots */
    double vhist[ACCEPT_HIST]; /* chord speeds of the last kept intervals */
    unsigned nhist, hnext;
    double vrecent;      /* the fastest of them (accept_recent_speed) */
    int full;            /* the last accept_decide judged a full window */
    int have_burst;      /* burst: the last waypoint dropped as a far */
    unsigned char burst; /* burst's slot (since the last kept or started) */
    /* the pairs of slots x < y, at y (y - 1) / 2 + x (accept_int.h pair()):
     * bit i of pknown if pair[i] is computed */
    accept_pair_t pair[ACCEPT_SLOTS * (ACCEPT_SLOTS - 1) / 2];
    uint64_t pknown;
    uint64_t clock;               /* counts the changes of slots */
    uint64_t since[ACCEPT_SLOTS]; /* the clock at a slot's last change */
    /* ACCEPT_RULE_STOPS (stops.c): repeats of the anchor's position, older
     * than every waypoint in the window, awaiting their verdict */
    double run_t[ACCEPT_RUN_MAX];
    uint32_t run_seq[ACCEPT_RUN_MAX];
    unsigned run_n, run_head; /* members, and the first not yet judged */
    int run_verdict;          /* 0 undecided, 1 stale, 2 stop */
    int standing;             /* the trajectory ended at rest on the anchor (HALT) */
    /* ACCEPT_RULE_NORETURN: the last fix refused for its position */
    int have_refused, refused_reason;
    engine_waypoint_t refused;
    /* ACCEPT_RULE_SMOOTH: the time and the path length along the open
     * trajectory of its last ACCEPT_RETIME_PACE + 1 waypoints (a ring at
     * npace % that; npace counts them since its start) */
    double pace_t[ACCEPT_RETIME_PACE + 1], pace_s[ACCEPT_RETIME_PACE + 1];
    unsigned npace;
    double shift_now; /* the shift of the waypoint being kept (pop) */
    /* the acceleration test of slots x -> p -> y (accept_int.h triple()),
     * computed once while the three are held: bit x of tknown[p][y] if
     * computed, of tok[p][y] if it passes (or there is no acceleration
     * limit) (its implied acceleration is computed when asked); a slot's
     * change clears its bit in every tknown and its rows */
    uint16_t tknown[ACCEPT_SLOTS][16], tok[ACCEPT_SLOTS][16];
    /* accept_decide's last wait with a trajectory open (no verdict, the
     * window not full), for the next call over the same waypoints and more
     * (accept.c waited()): its anchor, the slot before it (NO_SLOT: none),
     * speed limit, the n waypoints held and their slots' changes, c's test
     * after the anchor (r), how far continues_anchor found nothing (scan:
     * the waypoints 1..scan-1; 0 if not asked) and where taken_past_outliers
     * stopped (tpo: 0 if it went through all n) */
    accept_wait_t wait;
    accept_search_t search; /* the last chain search (chains.c) */
    accept_reach_t reach;   /* the chains' lengths (chains.c) */
} accept_t;

/* Set up with cfg (window and confirm clamped to 1..ACCEPT_WINDOW_MAX,
 * confirm <= window). */
void accept_init(accept_t *a, const accept_config_t *cfg);

/* Forget the waypoints held and the open trajectory (engine_clear); the
 * recent speeds are kept: they describe the object, not the trajectory. */
void accept_reset(accept_t *a);

/* The engine ended the open trajectory (finish, stop): the next waypoint
 * kept starts a new one. */
void accept_close(accept_t *a);

/* Waypoints held (the window and a run of repeats awaiting its verdict). */
static inline unsigned accept_pending(const accept_t *a)
{
    return a->npend + (a->run_n - a->run_head);
}

/* The oldest waypoint held, or NULL. */
static inline const engine_waypoint_t *accept_first(const accept_t *a)
{
    return a->npend ? &a->wp[a->pend[0]] : NULL;
}

/* The stamp of the oldest waypoint held (a run of repeats' first, else the
 * window's), NaN if none. */
static inline double accept_first_t(const accept_t *a)
{
    return a->run_n > a->run_head ? a->run_t[a->run_head]
           : a->npend             ? a->wp[a->pend[0]].t_s
                                  : (double)NAN;
}

/* The newest waypoint held, or NULL. */
static inline const engine_waypoint_t *accept_last(const accept_t *a)
{
    return a->npend ? &a->wp[a->pend[a->npend - 1]] : NULL;
}

/*
 * Hold wp for judgement.  Returns 0, or ENGINE_DUPLICATE if it repeats a
 * waypoint held or the last one kept, to 1 ns and 1 nm (not held).  The caller must take every verdict before offering again, so
 * there is always room.
 */
int accept_offer(accept_t *a, const engine_waypoint_t *wp);

/*
 * The verdict on the oldest waypoint held, if it can be given now; closing
 * = the input ends here (finish): give every verdict with what is held.
 * Returns 1 with *v filled (the waypoint leaves the window, and on TAKE or
 * START becomes the anchor), or 0 when it must wait for more waypoints.
 */
int accept_decide(accept_t *a, int closing, accept_verdict_t *v);

/*
 * The test of b following p (pre: the waypoint before p, or NULL), with the
 * speed limit vlim (0 = none): 0 if consistent, else the engine_error that
 * fails first (EBACKWARDS, ESAMETIME, EUNCONFIRMED for an interval above
 * max_gap_s, ESPEED, EACCEL).  Exposed for the tests.
 */
int accept_check(const accept_t *a, const engine_waypoint_t *pre, const engine_waypoint_t *p,
                 const engine_waypoint_t *b, double vlim);

/* The speed limit now in force (m/s, 0 = none): max_speed_m_s, and with
 * `learned` the learned limit from the recent speeds and the window. */
double accept_speed_limit(accept_t *a);

/* stops.c (ACCEPT_RULE_STOPS): 1 if wp joins the run of repeats of the
 * anchor (not held in the window); the verdict on the oldest run member
 * if it can be given now (1, *v filled), 0 if the run waits, -1 if there
 * is no run (accept_decide goes on with the window). */
int accept_run_offer(accept_t *a, const engine_waypoint_t *wp);
int accept_run_decide(accept_t *a, int closing, accept_verdict_t *v);
/* accept_decide for the engine: the verdict counted into st (its share of
 * engine_status: stops, stop_fixes, retimed),
 * DWELL verdicts taken here (counted, nothing else to do), HALT given as
 * ACCEPT_START with stop = ACCEPT_STOP_HALT; so the engine sees TAKE, START
 * and DROP only. */
#define ACCEPT_STOP_ONE 1
#define ACCEPT_STOP_AFTER 2
#define ACCEPT_STOP_HALT 3
int accept_decide_counted(accept_t *a, int closing, accept_verdict_t *v, engine_status_t *st);
/* accept.c, for stops.c: make wp the anchor of a trajectory started at it
 * (no waypoint before it); the distance between two waypoints */
void accept_anchor_at(accept_t *a, const engine_waypoint_t *wp);
double accept_dist(const engine_waypoint_t *p, const engine_waypoint_t *q);
/* the chord speeds kept: lower median of the last ACCEPT_HIST (0 if none) */
double accept_recent_median(const accept_t *a);

/* Fastest chord speed of the last ACCEPT_HIST kept intervals (m/s, 0 if none). */
static inline double accept_recent_speed(const accept_t *a)
{
    return a->vrecent;
}

#endif
