/* motion.c - the names of motion.h's codes and states (see motion.h). */
#include "motion.h"

#include <stddef.h>

const char *engine_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case ENGINE_OK: return "success";
    case ENGINE_ENOTFINITE: return "time or coordinate is NaN or infinite";
    case ENGINE_ERANGE: return "coordinate above max_abs_m or time absurd";
    case ENGINE_EBACKWARDS: return "timestamp earlier than the previous waypoint";
    case ENGINE_ESAMETIME: return "same timestamp as the previous waypoint, different position";
    case ENGINE_ESPEED: return "implied speed from the previous waypoint above max_speed_m_s";
    case ENGINE_EFULL: return "waypoint buffer full: retry later";
    case ENGINE_ECONFIG: return "invalid engine configuration";
    case ENGINE_ENOMEM: return "out of memory";
    case ENGINE_ESTATE: return "call not valid in this state";
    case ENGINE_ENUMERIC: return "solver failed (singular system)";
    case ENGINE_EACCEL:
        return "implied acceleration from the previous two waypoints above max_accel_m_s2";
    case ENGINE_EUNCONFIRMED:
        return "far from the trajectory in time or space, or at odds with its neighbours, "
               "and not confirmed by consistent waypoints";
    case ENGINE_ESTALE: return "stale: the same position again while the object was moving";
    default: return "unknown engine error";
    }
}

const char *engine_reason_name(int err)
{
    switch (err < 0 ? -err : err) {
    case ENGINE_ENOTFINITE: return "not_finite";
    case ENGINE_ERANGE: return "range";
    case ENGINE_EBACKWARDS: return "backwards";
    case ENGINE_ESAMETIME: return "same_time";
    case ENGINE_ESPEED: return "speed";
    case ENGINE_ENUMERIC: return "numeric";
    case ENGINE_EACCEL: return "accel";
    case ENGINE_EUNCONFIRMED: return "unconfirmed";
    case ENGINE_ESTALE: return "stale";
    default: return NULL;
    }
}

const char *engine_state_name(engine_state_t s)
{
    switch (s) {
    case ENGINE_STATE_WAITING: return "waiting";
    case ENGINE_STATE_STREAMING: return "streaming";
    case ENGINE_STATE_UNDERRUN: return "underrun";
    case ENGINE_STATE_FINISHED: return "finished";
    default: return "unknown";
    }
}
