/* track_path.c - a path of lines and arcs (lib/spline/path.h text form)
 * expanded into timed waypoints.  See track.h. */
#include "track_loader.h"

#include <stdlib.h>
#include <string.h>

#include "path.h"

/*
 * Parse a path text and expand it straight into trk (no row_t stage: the
 * waypoints are metric already).  Waypoints of element k are those between
 * the expansions of elements 0..k-1 and 0..k, which gives line[].
 */
int track_path_parse(track_loader_t *L, const char *buf, size_t len, track_t *trk)
{
    path_elem_t *el = NULL;
    uint32_t *el_line = NULL;
    size_t nel = 0, cap = 0, pos = 0, nw = 0, k, prev = 0;
    unsigned long lineno = 0;
    int rc = -1;

    while (pos < len) {
        char line[PATH_LINE_MAX + 1];
        size_t e = pos, ll;
        int prc;
        while (e < len && buf[e] != '\n')
            e++;
        ll = e - pos;
        lineno++;
        if (ll > PATH_LINE_MAX) {
            track_loader_fatal(L, lineno, "line longer than %d characters", PATH_LINE_MAX);
            goto out;
        }
        memcpy(line, buf + pos, ll);
        line[ll] = '\0';
        pos = e + 1;
        if (nel == cap) {
            size_t nc = cap ? 2 * cap : 64;
            path_elem_t *ne = realloc(el, nc * sizeof *el);
            uint32_t *nl = ne ? realloc(el_line, nc * sizeof *el_line) : NULL;
            if (ne)
                el = ne;
            if (!ne || !nl) {
                track_loader_fatal(L, 0, "out of memory");
                goto out;
            }
            el_line = nl;
            cap = nc;
        }
        prc = path_parse_line(line, &el[nel]);
        if (prc < 0) {
            track_loader_fatal(L, lineno, "%s", path_strerror(prc));
            goto out;
        }
        if (el[nel].kind != PATH_NONE)
            el_line[nel++] = (uint32_t)lineno;
    }
    if ((rc = path_expand(el, nel, NULL, 0, &nw)) < 0) {
        track_loader_fatal(L, 0, "%s", path_strerror(rc));
        goto out;
    }
    rc = -1;
    if (nw == 0) {
        track_loader_fatal(L, 0, "no waypoints");
        goto out;
    }
    trk->wp = calloc(nw, sizeof *trk->wp);
    trk->line = calloc(nw, sizeof *trk->line);
    if (!trk->wp || !trk->line) {
        track_loader_fatal(L, 0, "out of memory");
        goto out;
    }
    if (path_expand(el, nel, trk->wp, nw, &nw) < 0)
        goto out;
    for (k = 1; k <= nel; k++) {
        size_t upto = 0, i;
        (void)path_expand(el, k, NULL, 0, &upto);
        for (i = prev; i < upto && i < nw; i++)
            trk->line[i] = el_line[k - 1];
        prev = upto;
    }
    trk->n = nw;
    trk->format = TRACK_FMT_PATH;
    rc = 0;
out:
    free(el);
    free(el_line);
    return rc;
}
