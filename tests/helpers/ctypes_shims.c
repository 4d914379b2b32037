/* ctypes_shims.c - see ctypes_shims.h. */
#include "ctypes_shims.h"

#include <stdlib.h>

#include "engine.h"

unsigned engine_pick_flat(int method, int param, double accuracy, unsigned max_lookahead,
                          unsigned *fragment, unsigned *overlap)
{
    engine_config_t c, r;

    engine_config_default(&c);
    c.method = (engine_method_t)method;
    c.param = (engine_param_t)param;
    if (accuracy > 0)
        c.accuracy = accuracy;
    if (max_lookahead > 0)
        c.max_lookahead = max_lookahead;
    if (engine_config_resolve(&c, &r) < 0 || r.method != c.method)
        return 0; /* no fragment fits (a local method may: engine_method_flat) */
    *fragment = r.fragment;
    *overlap = r.overlap;
    return engine_lookahead(&r);
}

static long curve_flat(int method, int param, int ends, unsigned fragment, unsigned overlap,
                       size_t n, const double *t_s, const double *xyz, const double *vel,
                       double *seg_out, size_t max_seg);

long engine_curve_flat(int method, int param, int ends, unsigned fragment, unsigned overlap,
                       size_t n, const double *t_s, const double *xyz, double *seg_out,
                       size_t max_seg)
{
    return curve_flat(method, param, ends, fragment, overlap, n, t_s, xyz, NULL, seg_out, max_seg);
}

long engine_curve_vel_flat(int method, int ends, size_t n, const double *t_s, const double *xyz,
                           const double *vel, double *seg_out, size_t max_seg)
{
    return curve_flat(method, ENGINE_PARAM_TIME, ends, 0, 0, n, t_s, xyz, vel, seg_out, max_seg);
}

int engine_method_flat(unsigned max_lookahead, int ends, unsigned *lookahead)
{
    engine_config_t c, r;

    engine_config_default(&c);
    c.max_lookahead = max_lookahead;
    c.ends = (engine_ends_t)ends;
    if (engine_config_check(&c, NULL) < 0 || engine_config_resolve(&c, &r) < 0)
        return -1;
    *lookahead = engine_lookahead(&r);
    return (int)r.method;
}

static long curve_flat(int method, int param, int ends, unsigned fragment, unsigned overlap,
                       size_t n, const double *t_s, const double *xyz, const double *vel,
                       double *seg_out, size_t max_seg)
{
    engine_config_t cfg;
    engine_waypoint_t *wp;
    fdiff_seg_t *segs;
    size_t i, nseg = 0;
    int rc;

    engine_config_default(&cfg);
    cfg.method = (engine_method_t)method;
    cfg.param = (engine_param_t)param;
    cfg.ends = (engine_ends_t)ends;
    if (fragment)
        cfg.fragment = fragment;
    if (overlap)
        cfg.overlap = overlap;
    cfg.profile = ENGINE_PROFILE_NONE;
    cfg.max_gap_s = 1e9;
    wp = calloc(n ? n : 1, sizeof(*wp));
    segs = calloc(max_seg ? max_seg : 1, sizeof(*segs));
    if (!wp || !segs) {
        free(wp);
        free(segs);
        return -ENGINE_ENOMEM;
    }
    for (i = 0; i < n; i++) {
        wp[i].t_s = t_s[i];
        for (int k = 0; k < ENGINE_AXES; k++)
            wp[i].pos_m[k] = xyz[i * ENGINE_AXES + k];
        if (vel) {
            wp[i].has_vel = 1;
            for (int k = 0; k < ENGINE_AXES; k++)
                wp[i].vel_m_s[k] = vel[i * ENGINE_AXES + k];
        }
    }
    rc = engine_curve(&cfg, wp, n, segs, max_seg, &nseg);
    for (i = 0; i < nseg; i++) {
        double *o = seg_out + i * 14;
        o[0] = segs[i].t0_s;
        o[1] = segs[i].dur_s;
        for (int k = 0; k < ENGINE_AXES; k++)
            for (int m = 0; m < 4; m++)
                o[2 + k * 4 + m] = segs[i].c[k][m];
    }
    free(wp);
    free(segs);
    return rc < 0 ? rc : (long)nseg;
}
