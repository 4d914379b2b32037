/* ends.c - the bound on ends = clamped velocities (see ends.h). */
#include "ends.h"

#include <math.h>

int engine_ends_within_limit(const engine_config_t *cfg)
{
    double lim = engine_config_max_speed(cfg) > 0 ? engine_config_max_speed(cfg) : cfg->max_abs_m;
    const double *v = cfg->start_vel_m_s, *u = cfg->end_vel_m_s;
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) <= lim &&
           sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) <= lim;
}
