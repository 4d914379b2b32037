/*
 * accept_prev.h - the acceptance policy as it was before its incremental
 * chain search (lib/engine/accept.c, accept.h, accept_int.h, retime.c and
 * stops.c at commit 5bc98ca6, kept verbatim in tests/helpers/accept_prev/),
 * behind functions of its own: tests/unit/test_accept_same.c drives it and
 * lib/engine/accept.c with the same tracks and checks every verdict is the
 * same.  The configuration and the verdicts are lib/engine/accept.h's (the
 * same types: accept_config_t, accept_verdict_t, engine_status_t).
 */
#ifndef TRAJD_ACCEPT_PREV_H
#define TRAJD_ACCEPT_PREV_H

#include "accept.h"

typedef struct accept_prev accept_prev_t;

/* A policy set up with cfg (accept_init), allocated; NULL if out of memory. */
accept_prev_t *accept_prev_new(const accept_config_t *cfg);
void accept_prev_free(accept_prev_t *p);

/* accept_reset, accept_close, accept_offer, accept_decide,
 * accept_decide_counted, accept_check, accept_speed_limit of the policy as
 * it was */
void accept_prev_reset(accept_prev_t *p);
void accept_prev_close(accept_prev_t *p);
int accept_prev_offer(accept_prev_t *p, const engine_waypoint_t *wp);
int accept_prev_decide(accept_prev_t *p, int closing, accept_verdict_t *v);
int accept_prev_decide_counted(accept_prev_t *p, int closing, accept_verdict_t *v,
                               engine_status_t *st);
int accept_prev_check(const accept_prev_t *p, const engine_waypoint_t *pre,
                      const engine_waypoint_t *q, const engine_waypoint_t *b, double vlim);
double accept_prev_speed_limit(accept_prev_t *p);
/* accept_pending, accept_first_t, accept_recent_speed, accept_recent_median */
unsigned accept_prev_pending(const accept_prev_t *p);
double accept_prev_first_t(const accept_prev_t *p);
double accept_prev_recent_speed(const accept_prev_t *p);
double accept_prev_recent_median(const accept_prev_t *p);

#endif
