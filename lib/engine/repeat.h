/*
 * repeat.h - one waypoint offered again: a sender told "full" (-ENGINE_EFULL)
 * offers the same waypoint once more (a replay at every tick, a Modbus client
 * retrying), which is the same refusal, counted once.  Used by the engine's
 * buffer (engine_input.c) and the owner's latch buffer (lifecycle.c).
 */
#ifndef TRAJD_REPEAT_H
#define TRAJD_REPEAT_H

#include <stdint.h>
#include <string.h>

#include "engine.h"

typedef struct {
    int have; /* a refusal was counted for the waypoint seq, t_s */
    uint32_t seq;
    double t_s;
} engine_repeat_t;

/* A refusal of wp: 1 if it is the one counted last (the same seq and the same
 * time, bit for bit), else 0 (then it is the one counted last from now on). */
static inline int engine_repeat_refused(engine_repeat_t *r, const engine_waypoint_t *wp)
{
    int again = r->have && r->seq == wp->seq && memcmp(&r->t_s, &wp->t_s, sizeof r->t_s) == 0;
    r->have = 1;
    r->seq = wp->seq;
    r->t_s = wp->t_s;
    return again;
}

/* A waypoint taken: the next refusal is a new one. */
static inline void engine_repeat_taken(engine_repeat_t *r)
{
    r->have = 0;
}

#endif
