/*
 * gate.h - the one gate every command from outside passes (issue 24): the
 * Modbus commands and feed override, and CAN's command frames (override
 * included).  A peer's right to write at all ([modbus] writes, write_allow)
 * is its transport's; what it may do to one object is decided here:
 *   - writable: writable = yes in [object.NAME], or, not given, the object
 *     is fed by that transport itself (a client of the bus that feeds it);
 *   - stopping: after SIGTERM nothing is commanded any more (the objects
 *     brake to rest by the stop policy, core.h).
 */
#ifndef TRAJD_GATE_H
#define TRAJD_GATE_H

#include "core.h"

/* obj_gate's refusal for an object the transport may not command. */
#define OBJ_GATE_NOT_WRITABLE 1

/* 1 if a peer on transport via may command o (the writable rule above). */
int obj_gate_writable(const obj_t *o, const transport_t *via);

/*
 * Whether a peer on transport via may give o a command or a feed override
 * now: 0 yes; OBJ_GATE_NOT_WRITABLE (Modbus answers exception 02, CAN counts
 * a refused command); -ENGINE_ESTATE while the daemon is stopping (Modbus
 * exception 03).  The writable rule is judged first.
 */
int obj_gate(const obj_t *o, const transport_t *via);

#endif
