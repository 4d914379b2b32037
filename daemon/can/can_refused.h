/*
 * can_refused.h - why a CAN command frame was refused, in words for the log
 * (can_transport's rate-limited "command frame(s) refused" line), and the
 * files and descriptors the CAN transport reads, writes and holds (cfg_files.h,
 * fdlimit.h).
 */
#ifndef TRAJD_CAN_REFUSED_H
#define TRAJD_CAN_REFUSED_H

#include <stddef.h>

#include "cfg_files.h"

/* The reason of a refusal of command cmd (CANPROTO_CMD_*) to object name:
 * err 0 (not writable, the gate's cmd_mask), -ENGINE_ERANGE (an override
 * above 200 %), -ENGINE_ESTATE (stopping if stopping, else the feed hold),
 * else the engine's text. */
void can_refused_why(char *buf, size_t len, int err, unsigned cmd, int stopping, const char *name);

/* transport_t.files of the CAN transport: [can] log_in read, log_out written. */
void can_transport_files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx);

/* transport_t.fds of the CAN transport: its socket, log_in, log_out. */
unsigned can_transport_fds(const cfg_t *cfg, unsigned *clients);

#endif
