/*
 * cfgload.h - a reload's configuration built beside the running one (issue
 * 28 item 2): cfg_load (the file read, every replay track opened and parsed,
 * every check), cfg_reload_check against the running configuration and the
 * engines of the objects it adds or changes (cfg_t prebuilt) run
 * on a worker thread at SCHED_OTHER (whatever the loop's policy), niced
 * (CFGLOAD_NICE), with every signal blocked.  Its completion is an eventfd the loop polls (cfgload_fd);
 * the loop then takes the result (cfgload_finish) and swaps it in between
 * two ticks.  The tick never waits on it; the running configuration runs on
 * meanwhile and is only read (never freed) until the result is taken.
 *
 * One load at a time.  cfgload_drop (SIGTERM) asks the parse to stop
 * (cfgload_cancelled: a track load gives up within 65536 rows), joins the
 * worker and frees what it built.
 */
#ifndef TRAJD_CFGLOAD_H
#define TRAJD_CFGLOAD_H

#include <stddef.h>

#include "cfg.h"

typedef struct cfgload cfgload_t;

/* The workers' nice, above trajd's own (at most 19; SCHED_OTHER): the loop,
 * at the nice trajd was started with or at SCHED_FIFO, wins the CPU they share. */
#define CFGLOAD_NICE 10

/* Start loading path, to be checked against running (read by the worker
 * until cfgload_finish or cfgload_drop).  NULL with *err (-errno) if no
 * thread could start. */
cfgload_t *cfgload_start(const char *path, const cfg_t *running, int *err);

/* Readable (EPOLLIN) once the worker is done. */
int cfgload_fd(const cfgload_t *l);

/* Once cfgload_fd is readable: joins the worker, frees l.  0 with *out (the
 * new configuration, checked), or a negated cfg_error with err set. */
int cfgload_finish(cfgload_t *l, cfg_t **out, char *err, size_t errlen);

/* Drop a load under way (NULL: no-op): the parse is cancelled, the worker
 * joined, what it built freed. */
void cfgload_drop(cfgload_t *l);

/* The old configuration after a swap: freed on a thread (its tracks are
 * up to TRACK_FILE_MAX_BYTES of memory: milliseconds the tick must not wait
 * on).  Only the loop calls it; it joins the previous one first. */
void cfgload_retire(cfg_t *old);

/* Wait for the last cfgload_retire (at exit, before the process ends). */
void cfgload_retire_join(void);

/* c's object array built beside the running core (cfg_t prebuilt_objs: nobj
 * obj_t, zeroed), now the caller's to free; NULL if none was built. */
void *cfgload_take_objs(const cfg_t *c);

/* 1 while a drop cancels the load under way (polled by the track parsers). */
int cfgload_cancelled(void);

#endif
