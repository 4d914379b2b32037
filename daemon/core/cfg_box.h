/*
 * cfg_box.h - an object's position box (issue 24): soft limits
 *
 *   position_min_m = x,y,z     (metres, in [object.NAME])
 *   position_max_m = x,y,z
 *
 * given together, min <= max on every axis, each within max_abs_m.  The
 * safety monitor (lib/safety) keeps every setpoint inside it: one outside is
 * never sent, the object holds (fault "position outside position_min_m ..
 * position_max_m") until the command clear.  An output whose field cannot
 * hold more refuses a box it cannot encode, and derives one where none is
 * given: a CiA 402 target (int32 increments, can_box.h) - so a value is
 * never silently clipped to its field.  And the monitor's speed and
 * acceleration bounds the engine keeps as well (cfg_safety_caps).
 */
#ifndef TRAJD_CFG_BOX_H
#define TRAJD_CFG_BOX_H

#include "cfg.h"

/* The key function of position_min_m / position_max_m: 0, -CFG_EVALUE (why
 * filled) or -CFG_EUNKNOWN (another key). */
int cfg_box_key(cfg_obj_t *o, const cfg_kv_t *kv, char *why, size_t wl);

/* Whole-config rules above: 0, or -CFG_EVALUE with *line and why. */
int cfg_box_check(cfg_t *c, int *line, char *why, size_t wl);

/* The safety monitor's bounds the engine keeps too (engine.h cap_speed_m_s,
 * cap_accel_m_s2): CFG_SAFETY_SPEED_SHARE of a configured speed (or step a
 * period of period_ns) and acceleration bound, where below the engine's own
 * limits; 0 (none) otherwise.  Into o->engine. */
void cfg_safety_caps(cfg_obj_t *o, int64_t period_ns);

#endif
