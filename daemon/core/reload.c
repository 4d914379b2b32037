/* reload.c - what a reload does to each object (see reload.h). */
#include "reload.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "log.h"

void reload_commit(core_t *c, core_t *prev)
{
    for (unsigned i = 0; i < prev->nobj; i++) { /* removed: what it refused while it braked */
        const obj_t *q = &prev->obj[i];
        if (q->stop_refused && !core_obj_find(c, q->name))
            log_msg(LOG_NOTICE,
                    "object '%s' removed: %llu waypoint(s) refused while it braked to rest",
                    q->name, (unsigned long long)q->stop_refused);
    }
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i], *q = core_obj_find(prev, o->name);
        if (!q)
            continue;
        if (o->carried) { /* what its outputs lost as they closed for the reload */
            o->out_lost = q->out_lost;
            o->out_fault |= q->out_fault;
            o->out_errors = q->out_errors;
        }
        if (o->carried && q->engine == o->engine)
            q->engine = NULL;
        if (!o->retiring)
            continue;
        if (q->retiring == o->retiring) { /* still braking from an earlier reload */
            q->retiring = NULL;
        } else if (q->engine == o->retiring) { /* changed: the old engine brakes */
            q->engine = NULL;
            engine_stop(o->retiring);
        }
    }
}

void reload_unborrow(core_t *c)
{
    for (unsigned i = 0; c->obj && i < c->nobj; i++) {
        if (c->obj[i].carried)
            c->obj[i].engine = NULL;
        c->obj[i].retiring = NULL; /* always a borrowed one before the commit */
    }
}

void reload_mark_resume(core_t *prev)
{
    for (unsigned i = 0; i < prev->nobj; i++)
        if (prev->obj[i].engine)
            prev->obj[i].carried = 1;
}

static int reload_obj_at_rest(const obj_t *o)
{
    const engine_setpoint_t *sp = &o->sp;
    if (o->retiring)
        return 0;
    if (sp->cycle == 0 || (sp->flags & ENGINE_SP_NO_POSITION))
        return 1;
    return (sp->flags & ENGINE_SP_HOLD) && sp->state != ENGINE_STATE_STREAMING &&
           sp->state != ENGINE_STATE_UNDERRUN;
}

int reload_rate_check(const core_t *c, const cfg_t *nc, char *err, size_t errlen)
{
    if (nc->daemon.period_ns == c->cfg->daemon.period_ns)
        return 0;
    for (unsigned i = 0; i < c->nobj; i++) {
        if (reload_obj_at_rest(&c->obj[i]))
            continue;
        snprintf(err, errlen,
                 "%s: [daemon] rate_hz %g, running at %g: not while object '%s' moves (its "
                 "braking runs on the period its engine was built for): stop the objects "
                 "first (trajctl stop), or restart trajd",
                 nc->path, 1e9 / (double)nc->daemon.period_ns,
                 1e9 / (double)c->cfg->daemon.period_ns, c->obj[i].name);
        return -1;
    }
    return 0;
}

static int removed(const cfg_t *nc, const char *name)
{
    for (unsigned i = 0; i < nc->nobj; i++)
        if (strcmp(nc->obj[i].name, name) == 0)
            return 0;
    return 1;
}

unsigned reload_brake_removed(core_t *c, const cfg_t *nc)
{
    unsigned n = 0;
    for (unsigned i = 0; i < c->nobj; i++) {
        obj_t *o = &c->obj[i];
        if (!removed(nc, o->name) || reload_obj_at_rest(o))
            continue;
        const double *v = o->sp.vel_m_s;
        log_msg(LOG_NOTICE,
                "object '%s' removed: braking to rest from %.3f m/s along its path before the "
                "reload",
                o->name, sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
        o->stopping = OBJ_STOPPING_REMOVED; /* its input is refused from now on */
        if (o->retiring)
            engine_stop(o->retiring);
        engine_stop(o->engine);
        n++;
    }
    return n;
}

void reload_release_removed(core_t *c, const cfg_t *nc)
{
    for (unsigned i = 0; i < c->nobj; i++)
        if (removed(nc, c->obj[i].name) && !c->stopping)
            c->obj[i].stopping = 0;
}

int reload_removed_at_rest(const core_t *c, const cfg_t *nc)
{
    for (unsigned i = 0; i < c->nobj; i++)
        if (removed(nc, c->obj[i].name) && !reload_obj_at_rest(&c->obj[i]))
            return 0;
    return 1;
}
