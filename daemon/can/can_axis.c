/* can_axis.c - one CiA 402 drive axis as trajd commands it (see can_axis.h). */
#include "can_axis.h"

#include <stdlib.h>

static int32_t hold(can_axis_t *x, int32_t t)
{
    x->have_tgt = 1;
    x->tgt = t;
    return t;
}

int can_axis_target(can_axis_t *x, const can_axis_in_t *in, int32_t *out)
{
    if (!in->feedback) { /* blind: the engine's position, when it has one */
        if (!in->eng_ok)
            return 0;
        *out = hold(x, in->eng_inc);
        return 1;
    }
    if (!in->seen)
        return 0;
    if (in->state != CIA402_OPERATION_ENABLED) {
        x->live = x->pending = 0;
        x->fresh = 1;
        *out = hold(x, in->pos_inc);
        return 1;
    }
    if (x->fresh || !x->have_tgt) {
        x->fresh = 0;
        x->live = x->pending && in->may_move;
        x->pending = 0;
        *out = hold(x, in->pos_inc);
        return 1;
    }
    if (!in->may_move || !in->eng_ok)
        x->live = 0;
    else if (!x->live && in->eng_rest && llabs((long long)in->eng_inc - x->tgt) <= 1)
        x->live = 1;
    *out = hold(x, x->live ? in->eng_inc : x->tgt);
    return 1;
}

void can_axis_anchored(can_axis_t *x)
{
    if (x->fresh || !x->have_tgt)
        x->pending = 1;
    else
        x->live = 1;
}

void can_axis_refresh(can_axis_t *x)
{
    x->live = x->pending = 0;
    x->fresh = 1;
}

int can_axis_list_writes(const canproto_ids_t *ids, uint16_t index, uint8_t sub)
{
    for (unsigned k = 0; k < ids->cia402_nsdo; k++)
        if (ids->cia402_sdo[k].index == index && ids->cia402_sdo[k].sub == sub)
            return 1;
    return 0;
}

int32_t can_axis_anchor(const can_axis_t *x, int32_t pos_inc)
{
    return x->fresh || !x->have_tgt ? pos_inc : x->tgt;
}

void can_axis_log_put(can_axis_log_t *l, const can_axis_change_t *c)
{
    l->total++;
    if (l->n == CAN_AXIS_LOG_MAX) {
        l->dropped++;
        return;
    }
    l->e[(l->head + l->n) % CAN_AXIS_LOG_MAX] = *c;
    l->n++;
}

int can_axis_log_take(can_axis_log_t *l, can_axis_change_t *c)
{
    if (!l->n)
        return 0;
    *c = l->e[l->head];
    l->head = (l->head + 1) % CAN_AXIS_LOG_MAX;
    l->n--;
    return 1;
}
