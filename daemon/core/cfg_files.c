/* cfg_files.c - files compared by identity (see cfg_files.h). */
#include "cfg_files.h"

#include <errno.h>
#include <libgen.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "transport.h"

/* One file as its identity: device and inode if it exists, else the
 * canonical path it would be made at. */
typedef struct {
    int exists, chr;
    dev_t dev;
    ino_t ino;
    char real[2 * PATH_MAX + 2];
} ident_t;

static void ident(const char *path, ident_t *id)
{
    struct stat sb;
    memset(id, 0, sizeof *id);
    if (stat(path, &sb) == 0) {
        id->exists = 1;
        id->chr = S_ISCHR(sb.st_mode);
        id->dev = sb.st_dev;
        id->ino = sb.st_ino;
        return;
    }
    /* not made yet: its directory resolved (symlinks, "..", "."), then its name */
    char d[PATH_MAX], b[PATH_MAX], rd[PATH_MAX];
    snprintf(d, sizeof d, "%s", path);
    snprintf(b, sizeof b, "%s", path);
    const char *dir = dirname(d), *base = basename(b);
    if (!realpath(dir, rd))
        snprintf(rd, sizeof rd, "%s", dir);
    snprintf(id->real, sizeof id->real, "%s/%s", strcmp(rd, "/") ? rd : "", base);
}

static int same_ident(const ident_t *a, const ident_t *b)
{
    if (a->chr || b->chr)
        return 0;
    if (a->exists != b->exists)
        return 0;
    return a->exists ? a->dev == b->dev && a->ino == b->ino : !strcmp(a->real, b->real);
}

static int ignored(const char *p)
{
    return !p || !p[0] || !strcmp(p, "-");
}

int cfg_same_file(const char *a, const char *b)
{
    if (ignored(a) || ignored(b))
        return 0;
    ident_t x, y;
    ident(a, &x);
    ident(b, &y);
    return same_ident(&x, &y);
}

typedef struct {
    ident_t id;
    int output, line;
    char what[64];
    const char *path;
} file_t;

typedef struct {
    file_t *f;
    size_t n, cap;
    int nomem;
} files_t;

static void add(void *ctx, const char *path, int output, int line, const char *what)
{
    files_t *F = ctx;
    if (ignored(path) || F->nomem)
        return;
    if (F->n == F->cap) {
        size_t nc = F->cap ? 2 * F->cap : 16;
        file_t *nf = realloc(F->f, nc * sizeof *nf);
        if (!nf) {
            F->nomem = 1;
            return;
        }
        F->f = nf;
        F->cap = nc;
    }
    file_t *f = &F->f[F->n++];
    ident(path, &f->id);
    f->output = output;
    f->line = line;
    f->path = path;
    snprintf(f->what, sizeof f->what, "%s", what);
}

int cfg_files_check(const cfg_t *c, int *line, char *why, size_t wl)
{
    files_t F = {NULL, 0, 0, 0};
    for (unsigned t = 0; transport_table[t]; t++)
        if (transport_table[t]->files && cfg_uses(c, transport_table[t]))
            transport_table[t]->files(c, add, &F);
    int rc = F.nomem ? -CFG_ENOMEM : 0;
    if (F.nomem)
        snprintf(why, wl, "out of memory");
    for (size_t i = 0; i < F.n && !rc; i++)
        for (size_t j = 0; j < i && !rc; j++) {
            const file_t *a = &F.f[j], *b = &F.f[i];
            if (!(a->output || b->output) || !same_ident(&a->id, &b->id))
                continue;
            *line = a->line > b->line ? a->line : b->line;
            snprintf(why, wl, "%s %s and %s %s are one file: %s", a->what, a->path, b->what,
                     b->path,
                     a->output && b->output ? "two outputs would write it"
                                            : "an output would overwrite an input");
            rc = -CFG_EVALUE;
        }
    free(F.f);
    return rc;
}
