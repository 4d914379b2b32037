/*
 * fuzz_path.c - libFuzzer target for the path text form (lib/spline/path.h):
 * arbitrary lines are parsed, the accepted elements expanded; the oracle is
 * that nothing crashes, counting and filling agree, times never decrease
 * and every waypoint is finite.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_path_bound.h"
#include "path.h"

#define MAX_EL 16
#define MAX_WP 512

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static engine_waypoint_t wp[MAX_WP];
    path_elem_t el[MAX_EL];
    char line[PATH_LINE_MAX + 1];
    size_t nel = 0, pos = 0, need = 0, got = 0, i;

    while (pos < size && nel < MAX_EL) {
        size_t e = pos, n;
        while (e < size && data[e] != '\n')
            e++;
        n = e - pos < PATH_LINE_MAX ? e - pos : PATH_LINE_MAX;
        memcpy(line, data + pos, n);
        line[n] = '\0';
        pos = e + 1;
        if (path_parse_line(line, &el[nel]) == 0 && el[nel].kind != PATH_NONE)
            nel++;
    }
    /* keep fuzz runs fast: skip paths that could expand into many points */
    if (!(expansion_bound(el, nel) <= MAX_WP))
        return 0;
    if (path_expand(el, nel, NULL, 0, &need) < 0)
        return 0;
    if (need > MAX_WP)
        abort(); /* beyond the bound above */
    if (path_expand(el, nel, wp, MAX_WP, &got) != 0 || got != need)
        abort();
    for (i = 0; i < got; i++) {
        if (!isfinite(wp[i].t_s) || !isfinite(wp[i].pos_m[0]) || !isfinite(wp[i].pos_m[1]) ||
            !isfinite(wp[i].pos_m[2]))
            abort();
        if (i && wp[i].t_s < wp[i - 1].t_s)
            abort();
    }
    return 0;
}
