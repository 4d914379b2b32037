/* keep.c - what a transport keeps of its objects over a reload (see keep.h). */
#include "keep.h"

#include <stdlib.h>
#include <string.h>

typedef struct rec {
    struct rec *next;
    char *kind, *name;
    size_t size;
    unsigned char data[];
} rec_t;

static rec_t *recs;

static void drop_all(void)
{
    while (recs) {
        rec_t *r = recs;
        recs = r->next;
        free(r->kind);
        free(r->name);
        free(r);
    }
}

static rec_t **find(const char *kind, const char *name)
{
    rec_t **p = &recs;
    for (; *p; p = &(*p)->next)
        if (!strcmp((*p)->kind, kind) && !strcmp((*p)->name, name))
            break;
    return p;
}

static void unlink_free(rec_t **p)
{
    rec_t *r = *p;
    *p = r->next;
    free(r->kind);
    free(r->name);
    free(r);
}

int keep_put(const char *kind, const char *name, const void *data, size_t size)
{
    static int registered;
    if (!registered && atexit(drop_all) == 0) /* what the exit leaves: freed */
        registered = 1;
    rec_t **p = find(kind, name);
    if (*p)
        unlink_free(p);
    rec_t *r = malloc(sizeof *r + size);
    if (!r)
        return -1;
    r->kind = strdup(kind);
    r->name = strdup(name);
    if (!r->kind || !r->name) {
        free(r->kind);
        free(r->name);
        free(r);
        return -1;
    }
    r->size = size;
    memcpy(r->data, data, size);
    r->next = recs;
    recs = r;
    return 0;
}

int keep_take(const char *kind, const char *name, void *data, size_t size)
{
    rec_t **p = find(kind, name);
    if (!*p || (*p)->size != size)
        return 0;
    memcpy(data, (*p)->data, size);
    unlink_free(p);
    return 1;
}

void keep_drop(const char *kind)
{
    for (rec_t **p = &recs; *p;)
        if (!strcmp((*p)->kind, kind))
            unlink_free(p);
        else
            p = &(*p)->next;
}
