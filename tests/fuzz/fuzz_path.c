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

#include "path.h"

#define MAX_EL 16
#define MAX_WP 512

/*
 * An upper bound on the waypoints path_expand would produce, from the elements
 * alone, without walking them (counting walks every point: a path of up to
 * PATH_STEPS_MAX points per element made this target run at 1.5 k/s).  Every
 * point lies within M of the origin (M: the largest |coordinate| of a start or
 * line point, |centre| + radius of an arc), so a line is at most 2 sqrt(3) M
 * long; an arc is r |sweep| long and may add a joining line; each moving
 * element gives ceil(length / (speed step)) points at the speed and step in
 * force (at least one).  NaN or infinite: no bound.
 */
static double expansion_bound(const path_elem_t *el, size_t nel)
{
    double m = 0, speed = 1, step = 1, n = 0;
    size_t i;
    for (i = 0; i < nel; i++) {
        const path_elem_t *e = &el[i];
        double c = 0;
        if (e->kind == PATH_START || e->kind == PATH_LINE)
            c = fmax(fabs(e->xyz_m[0]), fmax(fabs(e->xyz_m[1]), fabs(e->xyz_m[2])));
        else if (e->kind == PATH_ARC)
            c = fmax(fabs(e->centre_m[0]), fabs(e->centre_m[1])) + fabs(e->radius_m);
        m = fmax(m, c);
    }
    for (i = 0; i < nel; i++) {
        const path_elem_t *e = &el[i];
        double line = 2 * sqrt(3.0) * m / (speed * step);
        switch (e->kind) {
        case PATH_SPEED: speed = e->value; break;
        case PATH_STEP: step = e->value; break;
        case PATH_LINE: n += ceil(line) + 1; break;
        case PATH_ARC: n += ceil(line) + 1 + ceil(fabs(e->radius_m * e->sweep_rad) / (speed * step)) + 1; break;
        default: n += 1; break;
        }
        if (!(speed > 0) || !(step > 0))
            return n; /* path_expand stops here: -PATH_ERANGE */
    }
    return isfinite(n) ? n : INFINITY;
}

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
        if (!isfinite(wp[i].t_s) || !isfinite(wp[i].pos_m[0]) ||
            !isfinite(wp[i].pos_m[1]) || !isfinite(wp[i].pos_m[2]))
            abort();
        if (i && wp[i].t_s < wp[i - 1].t_s)
            abort();
    }
    return 0;
}
