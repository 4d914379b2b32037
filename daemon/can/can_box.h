/*
 * can_box.h - what the CAN output's fields can hold, at config time (issue
 * 24: values are never silently clipped to their field).
 *
 * Positions: an object with CAN output sends them as int32 (its own
 * SETPOINT frames, 0.1 mm: +-214 748.3647 m; a CiA 402 target, increments =
 * offset +- round(pos x counts_per_m)).  Its position box (cfg_box.h) must fit
 * every such field: a given box that does not is refused with the object's
 * line; without one, the box is derived from the fields (the safety monitor
 * then holds the object at the edge instead of a clipped value going out).
 *
 * Speed: the classic SETPOINT frame's velocity is int16 mm/s (+-32.767 m/s).
 * Whether a track goes faster is not known at config time: an object whose
 * speed limit in force, times ENGINE_SPEED_CAP, exceeds it (or that has no
 * limit) gets a warning line naming the remedies (can.fd = yes: int32 um/s, or
 * max_speed_m_s); a clipped value is then counted (tx_clamped), flagged in
 * STATUS (bit 3) and on Modbus (diagnostics tx_clamped), and logged.
 */
#ifndef TRAJD_CAN_BOX_H
#define TRAJD_CAN_BOX_H

#include "cfg.h"

/* The rules above for every object with CAN output of cfg (the CAN
 * transport's check).  0, or -CFG_EVALUE with *line and why. */
int can_box_check(cfg_t *cfg, int *line, char *why, size_t wl);

#endif
