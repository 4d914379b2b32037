/*
 * reload.h - what a reload does to each object (SIGHUP, daemon/REFERENCE.md
 * "Reload"), beside core_open (core.h), which builds the new core:
 *
 *   unchanged object  carried over: the new core takes its engine, motion
 *                     goes on untouched;
 *   changed object    a new engine; the old one brakes to rest along its path
 *                     (engine_stop) and the new one starts where it rests;
 *   removed object    brakes to rest along its path before the reload swaps
 *                     (reload_brake_removed), its outputs streaming until it
 *                     rests; logged;
 *   added object      starts afresh (WAITING);
 *   failed reload     (a transport of the new config cannot open) the old core
 *                     reopens its transports and runs on, every engine as it
 *                     was: no object restarts.
 *
 * core_open borrows the engines of the carried objects (the new core points
 * at them, the old still owns them) until the new transports are open; then
 * reload_commit gives them to the new core, or reload_unborrow back.
 */
#ifndef TRAJD_RELOAD_H
#define TRAJD_RELOAD_H

#include "core.h"

/* The new core c keeps the engines it borrowed from prev: prev lets go of
 * them, and an old engine that now retires (its object changed) brakes. */
void reload_commit(core_t *c, core_t *prev);

/* The new core c is discarded: forget the engines it borrowed (prev's). */
void reload_unborrow(core_t *c);

/* prev's transports reopen after a failed reload: every object that has an
 * engine resumes where it is (o->carried: replay goes on after the row its
 * engine accepted last). */
void reload_mark_resume(core_t *prev);

/*
 * Objects of the running core c that the new configuration nc removes and
 * that move: each brakes to rest along its path (engine_stop; obj_push_from then
 * refuses its input) and the log says so.  Returns how many brake.
 */
unsigned reload_brake_removed(core_t *c, const cfg_t *nc);

/* The reload that removed them failed: their inputs are taken again (they
 * rest, braked; the next waypoint starts a new trajectory by a transfer). */
void reload_release_removed(core_t *c, const cfg_t *nc);

/*
 * 0 if nc keeps c's output rate, or every object of c is at rest; else -1
 * with the reason in err: a changed object's old engine brakes on the period
 * it was built for, one period a tick, so a new rate would step it (the
 * monitor froze it: 977 m/s^2 against 70).  Stop the objects, or restart.
 */
int reload_rate_check(const core_t *c, const cfg_t *nc, char *err, size_t errlen);

/* 1 once every object of c that nc removes is at rest. */
int reload_removed_at_rest(const core_t *c, const cfg_t *nc);

#endif
