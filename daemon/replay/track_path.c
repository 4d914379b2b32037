/* track_path.c - a path of lines and arcs (lib/spline/path.h text form)
 * expanded into timed waypoints.  See track.h. */
#include "track_loader.h"

#include <stdlib.h>
#include <string.h>

#include "path.h"

typedef struct {
    path_elem_t *el;
    uint32_t *el_line; /* source line of each element */
    size_t n, cap;
} elems_t;

static int elems_grow(elems_t *E)
{
    if (E->n < E->cap)
        return 0;
    size_t nc = E->cap ? 2 * E->cap : 64;
    path_elem_t *ne = realloc(E->el, nc * sizeof *E->el);
    if (!ne)
        return -1;
    E->el = ne;
    uint32_t *nl = realloc(E->el_line, nc * sizeof *E->el_line);
    if (!nl)
        return -1;
    E->el_line = nl;
    E->cap = nc;
    return 0;
}

/* Every line into an element; a bad line is an error with its line number
 * (never skipped: a path is a program, not a log). */
static int read_elems(track_loader_t *L, const char *buf, size_t len, elems_t *E)
{
    size_t pos = 0;
    unsigned long lineno = 0;
    while (pos < len) {
        char line[PATH_LINE_MAX + 1];
        size_t e = pos;
        while (e < len && buf[e] != '\n')
            e++;
        size_t ll = e - pos;
        lineno++;
        if (ll > PATH_LINE_MAX) {
            track_loader_fatal(L, lineno, "line longer than %d characters", PATH_LINE_MAX);
            return -1;
        }
        if (memchr(buf + pos, '\0', ll)) {
            track_loader_fatal(L, lineno, "NUL byte (binary file?)");
            return -1;
        }
        memcpy(line, buf + pos, ll);
        line[ll] = '\0';
        pos = e + 1;
        if (elems_grow(E) < 0) {
            track_loader_fatal(L, 0, "out of memory");
            return -1;
        }
        int prc = path_parse_line(line, &E->el[E->n]);
        if (prc < 0) {
            track_loader_fatal(L, lineno, "%s", path_strerror(prc));
            return -1;
        }
        if (E->el[E->n].kind != PATH_NONE)
            E->el_line[E->n++] = lineno > UINT32_MAX ? UINT32_MAX : (uint32_t)lineno;
    }
    return 0;
}

/* Expand (counting first), with an expansion error at its element's line. */
static int expand(track_loader_t *L, const elems_t *E, size_t *el_end, track_t *trk)
{
    size_t nw = 0, bad = 0;
    int rc = path_expand_ex(E->el, E->n, NULL, TRACK_PATH_WAYPOINTS_MAX, &nw, el_end, &bad);
    if (rc == -PATH_EFULL) {
        track_loader_fatal(L, E->el_line[bad],
                           "the path would expand to more than %lu waypoints (a smaller step, "
                           "or longer lines; the limit is TRACK_PATH_WAYPOINTS_MAX)",
                           (unsigned long)TRACK_PATH_WAYPOINTS_MAX);
        return -1;
    }
    if (rc < 0) {
        track_loader_fatal(L, E->el_line[bad], "%s", path_strerror(rc));
        return -1;
    }
    if (nw == 0) {
        track_loader_fatal(L, 0, "no waypoints");
        return -1;
    }
    trk->wp = calloc(nw, sizeof *trk->wp);
    trk->line = calloc(nw, sizeof *trk->line);
    if (!trk->wp || !trk->line) {
        track_loader_fatal(L, 0, "out of memory");
        return -1;
    }
    if (path_expand(E->el, E->n, trk->wp, nw, &nw) < 0) {
        track_loader_fatal(L, 0, "path expansion changed between count and fill");
        return -1;
    }
    trk->n = nw;
    return 0;
}

/*
 * Parse a path text and expand it straight into trk (no row stage: the
 * waypoints are metric already).  Element i made waypoints el_end[i-1] ..
 * el_end[i]-1, which gives line[].
 */
int track_path_parse(track_loader_t *L, const char *buf, size_t len, track_t *trk)
{
    elems_t E = {0};
    size_t *el_end = NULL;
    int rc = -1;
    if (read_elems(L, buf, len, &E) < 0)
        goto out;
    el_end = calloc(E.n ? E.n : 1, sizeof *el_end);
    if (!el_end) {
        track_loader_fatal(L, 0, "out of memory");
        goto out;
    }
    if (expand(L, &E, el_end, trk) < 0)
        goto out;
    for (size_t k = 0, i = 0; k < E.n; k++)
        for (; i < el_end[k] && i < trk->n; i++)
            trk->line[i] = E.el_line[k];
    trk->format = TRACK_FMT_PATH;
    rc = 0;
out:
    free(E.el);
    free(E.el_line);
    free(el_end);
    return rc;
}
