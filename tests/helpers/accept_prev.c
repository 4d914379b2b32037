/*
 * accept_prev.c - the former acceptance policy (accept_prev.h): the files
 * of tests/helpers/accept_prev/, verbatim, compiled here with their
 * external names renamed (accept_* to aprev_*), so they link beside
 * lib/engine/accept.c in the same test.
 */
#define accept_t aprev_t
#define accept_init aprev_init
#define accept_reset aprev_reset
#define accept_close aprev_close
#define accept_offer aprev_offer
#define accept_decide aprev_decide
#define accept_check aprev_check
#define accept_speed_limit aprev_speed_limit
#define accept_run_offer aprev_run_offer
#define accept_run_decide aprev_run_decide
#define accept_decide_counted aprev_decide_counted
#define accept_anchor_at aprev_anchor_at
#define accept_dist aprev_dist
#define accept_recent_median aprev_recent_median
#define accept_retime aprev_retime
#define accept_retime_soft aprev_retime_soft
#define accept_retime_either aprev_retime_either

/* the former header first: its include guard then keeps lib/engine/accept.h out */
#include "accept_prev/accept.h"

#include <stdlib.h>

#include "accept_prev/accept.c"
#include "accept_prev/retime.c"
#include "accept_prev/stops.c"

/* after the former files: accept_prev.h names accept.h, kept out by its guard */
#include "accept_prev.h"

struct accept_prev {
    aprev_t a;
};

accept_prev_t *accept_prev_new(const accept_config_t *cfg)
{
    accept_prev_t *p = malloc(sizeof *p);
    if (p)
        aprev_init(&p->a, cfg);
    return p;
}

void accept_prev_free(accept_prev_t *p)
{
    free(p);
}

void accept_prev_reset(accept_prev_t *p)
{
    aprev_reset(&p->a);
}

void accept_prev_close(accept_prev_t *p)
{
    aprev_close(&p->a);
}

int accept_prev_offer(accept_prev_t *p, const engine_waypoint_t *wp)
{
    return aprev_offer(&p->a, wp);
}

int accept_prev_decide(accept_prev_t *p, int closing, accept_verdict_t *v)
{
    return aprev_decide(&p->a, closing, v);
}

int accept_prev_decide_counted(accept_prev_t *p, int closing, accept_verdict_t *v,
                               engine_status_t *st)
{
    return aprev_decide_counted(&p->a, closing, v, st);
}

int accept_prev_check(const accept_prev_t *p, const engine_waypoint_t *pre,
                      const engine_waypoint_t *q, const engine_waypoint_t *b, double vlim)
{
    return aprev_check(&p->a, pre, q, b, vlim);
}

double accept_prev_speed_limit(accept_prev_t *p)
{
    return aprev_speed_limit(&p->a);
}

unsigned accept_prev_pending(const accept_prev_t *p)
{
    return accept_pending(&p->a);
}

double accept_prev_first_t(const accept_prev_t *p)
{
    return accept_first_t(&p->a);
}

double accept_prev_recent_speed(const accept_prev_t *p)
{
    return accept_recent_speed(&p->a);
}

double accept_prev_recent_median(const accept_prev_t *p)
{
    return aprev_recent_median(&p->a);
}
