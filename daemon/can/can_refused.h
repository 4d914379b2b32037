/*
 * can_refused.h - why a CAN command frame was refused, in words for the log
 * (can_transport's rate-limited "command frame(s) refused" line), and the
 * files and descriptors the CAN transport reads, writes and holds (cfg_files.h,
 * fdlimit.h).
 */
#ifndef TRAJD_CAN_REFUSED_H
#define TRAJD_CAN_REFUSED_H

#include <stddef.h>

#include "can_port.h"
#include "cfg_files.h"

/* The reason of a refusal of command cmd (CANPROTO_CMD_*) to object name:
 * err 0 (not writable, the gate's cmd_mask), -ENGINE_ERANGE (an override
 * above 200 %), -ENGINE_ESTATE (stopping if stopping, else the feed hold),
 * else the engine's text. */
void can_refused_why(char *buf, size_t len, int err, unsigned cmd, int stopping, const char *name);

/* transport_t.files of the CAN transport: [can] log_in read, log_out written. */
void can_transport_files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx);

/* Object name's input refused and output dropped since the last call
 * (*logged: the counters then, updated), one line per kind, with the id
 * the waypoints come on (wp_id): waypoints lost (sequence gaps), malformed
 * frames (by reason), frames out of order (behind the last waypoint taken and
 * not later in time), resyncs (a sender that restarted its numbering: a
 * waypoint behind but later in time, taken; at notice level, with the last
 * one's numbers), setpoint cycles dropped (late, queue full, down, error).  Counters
 * that went back (reset counters) are taken as they are.  Returns the lines
 * logged.  Not from the tick: the CAN transport's housekeeping, once a second
 * at most. */
int can_log_traffic(const char *name, unsigned wp_id, const can_port_obj_stats_t *now,
                    can_port_obj_stats_t *logged);

/* transport_t.fds of the CAN transport: its socket, log_in, log_out. */
unsigned can_transport_fds(const cfg_t *cfg, unsigned *clients);

#endif
