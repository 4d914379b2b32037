/* gate.c - who may command an object (see gate.h). */
#include "gate.h"

int obj_gate_writable(const obj_t *o, const transport_t *via)
{
    return o->cfg->writable == 1 || (o->cfg->writable < 0 && o->cfg->input == via);
}

int obj_gate(const obj_t *o, const transport_t *via)
{
    if (!obj_gate_writable(o, via))
        return OBJ_GATE_NOT_WRITABLE;
    if (o->stopping)
        return -ENGINE_ESTATE;
    return 0;
}
