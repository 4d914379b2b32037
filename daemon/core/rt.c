/* rt.c - real-time process settings (see rt.h). */
#include "rt.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>

int rt_apply(const cfg_rt_t *rt, char *why, size_t whylen)
{
    int rc = 0;
    size_t n = 0;
    why[0] = 0;
#define RT_FAIL(what)                                                                              \
    do {                                                                                           \
        int e = errno;                                                                             \
        if (!rc)                                                                                   \
            rc = -e;                                                                               \
        int m = snprintf(why + n, whylen - n, "%s%s: %s", n ? "; " : "", what, strerror(e));       \
        if (m > 0)                                                                                 \
            n = (size_t)m < whylen - n ? n + (size_t)m : whylen - 1;                               \
    } while (0)
    /* the CPUs allowed at start: what a reload without cpu_affinity goes back to */
    static cpu_set_t initial;
    static int have_initial;
    if (!have_initial)
        have_initial = sched_getaffinity(0, sizeof initial, &initial) == 0 ? 1 : -1;
    if (rt->affinity_set && sched_setaffinity(0, sizeof rt->affinity, &rt->affinity) < 0)
        RT_FAIL("cpu_affinity");
    if (!rt->affinity_set && have_initial > 0)
        sched_setaffinity(0, sizeof initial, &initial);
    if (rt->mlockall && mlockall(MCL_CURRENT | MCL_FUTURE) < 0)
        RT_FAIL("mlockall");
    if (!rt->mlockall)
        munlockall(); /* a reload that turns it off; a no-op if never locked */
    struct sched_param sp = {.sched_priority = rt->fifo_priority};
    if (rt->fifo_priority > 0) {
        if (sched_setscheduler(0, SCHED_FIFO | SCHED_RESET_ON_FORK, &sp) < 0)
            RT_FAIL("fifo_priority");
    } else {
        int pol = sched_getscheduler(0);
        sp.sched_priority = 0;
        /* a reload that turns SCHED_FIFO off goes back to SCHED_OTHER */
        if (pol == SCHED_FIFO && sched_setscheduler(0, SCHED_OTHER, &sp) < 0)
            RT_FAIL("fifo_priority");
    }
#undef RT_FAIL
    return rc;
}
