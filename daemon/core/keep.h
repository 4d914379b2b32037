/*
 * keep.h - what a transport keeps of its objects over a reload.  A reload
 * closes the running configuration's transports before it opens the new
 * ones (a TCP port may have to be released), so a transport whose objects
 * go on (carried over: the same engine) hands what it knew of each to the
 * transport the reload opens, by the object's name: the CAN drives' state,
 * the Modbus sequence numbering and counters, a replay's position.
 *
 * Each transport puts its objects' records at close (not at the exit) and
 * takes them at open; keep_drop then forgets what was not taken (the next
 * reload starts afresh).  Records are copied; whatever is left at the exit
 * is freed then.  Not in the tick.
 */
#ifndef TRAJD_KEEP_H
#define TRAJD_KEEP_H

#include <stddef.h>

/* Keep size bytes of data for the object name under kind (the transport's
 * name), replacing a record kept before; 0, or -1 out of memory (then
 * nothing is kept: the object starts afresh, as before a reload kept it). */
int keep_put(const char *kind, const char *name, const void *data, size_t size);

/* Copy the record kept for name under kind into data (size bytes): 1, or 0
 * if none of that size. */
int keep_take(const char *kind, const char *name, void *data, size_t size);

/* Forget every record kept under kind. */
void keep_drop(const char *kind);

#endif
