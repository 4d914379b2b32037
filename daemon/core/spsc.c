/* spsc.c - single-producer single-consumer ring (see spsc.h). */
#include "spsc.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int spsc_init(spsc_t *r, size_t rec, size_t cap)
{
    size_t n = 1;
    while (n < cap)
        n *= 2;
    memset(r, 0, sizeof *r);
    atomic_init(&r->head, 0);
    atomic_init(&r->tail, 0);
    r->mask = n - 1;
    r->rec = rec;
    r->buf = calloc(n, rec);
    return r->buf ? 0 : -ENOMEM;
}

void spsc_fini(spsc_t *r)
{
    free(r->buf);
    r->buf = NULL;
}
