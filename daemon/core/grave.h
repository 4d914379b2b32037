/*
 * grave.h - engines given up in the loop freed on a thread beside it (issue
 * 28: the tick never waits on a free).  An engine is about 1.9 MB, mostly one
 * mapping of its own, and its free is an munmap: a reload that changed 256
 * moving objects freed their 256 braking predecessors on the ticks at which
 * they came to rest, in the loop (tests/e2e/test_reload_nohold.py
 * test_reload_changes_many).
 *
 * The loop hands an engine over (grave_put: a bounded ring, never blocks);
 * the thread, started at the first, frees it.  A full ring, or no thread (said
 * once), and the engine is freed in the loop as before.
 * grave_stop, at exit, frees what is left and joins the thread.
 */
#ifndef TRAJD_GRAVE_H
#define TRAJD_GRAVE_H

#include "engine.h"

/* Free e beside the loop (NULL: no-op).  Loop thread only. */
void grave_put(engine_t *e);

/* Free what is left and join the thread (at exit; a no-op if never started). */
void grave_stop(void);

#endif
