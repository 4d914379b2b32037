/*
 * ends.h - the rule on ends = clamped (issue 24): the given start and end
 * velocities (start_vel_m_s, end_vel_m_s) no faster than the speed limit in
 * force, or without a speed limit than max_abs_m per second.  1e50 m/s ran
 * beyond max_abs_m, 1e308 gave NaN rows; engine_config_check refuses them.
 */
#ifndef TRAJD_ENDS_H
#define TRAJD_ENDS_H

#include "engine.h"

/* 1 if cfg's start and end velocities keep the rule above (any ends). */
int engine_ends_within_limit(const engine_config_t *cfg);

#endif
