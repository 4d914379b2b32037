/*
 * carry.h - what a reload carries over of each object (core_open, core.c):
 *   carry_source: the object of the running core whose engine, input and
 *     owner the new one takes over as they run (the same engine settings,
 *     input and speed bound, and its motion within the new safety bounds);
 *     else the object is a changed one;
 *   carry_objects: step 2 of core_open: the carried objects borrow their
 *     engines, owners and counters; a changed one that moves keeps its old
 *     engine braking to rest (retire_moving), and its counts go on
 *     (obj_t counts_before);
 *   carry_resume_input: a changed object's input goes on after as far as its
 *     old engine played, never from its start again.
 * lib/engine/LIFECYCLE.md "reload" rows; daemon/REFERENCE.md "Reload".
 */
#ifndef TRAJD_CARRY_H
#define TRAJD_CARRY_H

#include "core.h"

/* The clock an object starts on: 0 (relative) for a replay input, with clock
 * = relative, or at a replay speed; 1 with clock = epoch; -1 (the first
 * waypoint decides) with clock = auto. */
int carry_clock_initial(const cfg_t *cfg, const cfg_obj_t *o);

/* The object of prev that o (in the new config) may take over, or NULL; why
 * (NULL: not said) gets the reason where its new safety bounds refuse its
 * motion, or its speed or acceleration cap changed. */
obj_t *carry_source(core_t *prev, const cfg_t *cfg, const cfg_obj_t *o, char *why, size_t len);

/* 1 if object o of a configuration being loaded needs an engine of its own
 * whatever the running objects do: running (NULL: none) has no object of
 * its name, or carry_source's settings differ (caps, engine, input).  The
 * reload's worker builds those beside the running core (cfg_t prebuilt). */
int carry_needs_engine(const cfg_t *running, const cfg_obj_t *o);

/* o->resume_t_s, o->played_t_s/track and o->born_ns from prev's object of
 * its name when o is a changed object with the same input (left NAN where
 * that one played nothing). */
void carry_resume_input(obj_t *o, core_t *prev);

/* Step 2 of core_open (cannot fail; prev untouched: reload_commit or
 * reload_unborrow settles it). */
void carry_objects(core_t *c, core_t *prev);

#endif
