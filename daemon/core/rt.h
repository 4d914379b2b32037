/*
 * rt.h - apply the [realtime] settings to the process: CPU affinity,
 * mlockall(MCL_CURRENT | MCL_FUTURE), SCHED_FIFO priority.  All off by default.
 *
 * Policy: a setting that cannot be applied (typically EPERM without
 * CAP_SYS_NICE / CAP_IPC_LOCK, or a CPU that does not exist) is reported in
 * why and the caller logs a warning and runs on without it: the daemon still
 * works, only with more jitter, and the status line shows the lateness.
 */
#ifndef TRAJD_RT_H
#define TRAJD_RT_H

#include <stddef.h>

#include "cfg.h"

/* Apply rt.  Returns 0, or -errno of the first failure with a message in why
 * (the remaining settings are still tried). */
int rt_apply(const cfg_rt_t *rt, char *why, size_t whylen);

#endif
