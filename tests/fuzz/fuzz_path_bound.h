/* fuzz_path_bound.h - keeps the path fuzz targets fast (fuzz_path.c,
 * fuzz_track_path.c): they skip paths that could expand into many points. */
#ifndef FUZZ_PATH_BOUND_H
#define FUZZ_PATH_BOUND_H

#include <math.h>
#include <stddef.h>

#include "path.h"

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
static inline double expansion_bound(const path_elem_t *el, size_t nel)
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
        case PATH_ARC:
            n += ceil(line) + 1 + ceil(fabs(e->radius_m * e->sweep_rad) / (speed * step)) + 1;
            break;
        default: n += 1; break;
        }
        if (!(speed > 0) || !(step > 0))
            return n; /* path_expand stops here: -PATH_ERANGE */
    }
    return isfinite(n) ? n : INFINITY;
}

#endif
