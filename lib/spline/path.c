/* path.c - lines and exact arcs into waypoints; see path.h. */
#include "path.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "nurbs.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Points closer than this (m) count as the same: no joining line is added. */
#define PATH_SAME_POINT_M 1e-9
/* Step counts are capped so a typo (speed 1e-9) cannot ask for 1e18 points. */
#define PATH_STEPS_MAX 10000000.0

const char *path_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case PATH_OK: return "success";
    case PATH_ESYNTAX: return "path: unknown keyword, wrong field count or not a number";
    case PATH_ERANGE: return "path: value out of range (speed, step, radius, sweep)";
    case PATH_ENOSTART: return "path: element before 'start'";
    case PATH_EFULL: return "path: more waypoints than fit";
    case PATH_ETWICE: return "path: 'start' given twice";
    case PATH_ETIME:
        return "path: time beyond 1e9 s or not increasing (wait, start time, "
               "or a step too short for the time's resolution)";
    default: return "unknown path error";
    }
}

/* Split into at most 8 fields; returns the count, -1 if too many. */
static int split(char *buf, char **f)
{
    int n = 0;
    char *save = NULL, *tok;

    for (tok = strtok_r(buf, " \t\r\n,", &save); tok; tok = strtok_r(NULL, " \t\r\n,", &save)) {
        if (n == 8)
            return -1;
        f[n++] = tok;
    }
    return n;
}

static int num(const char *s, double *v)
{
    char *end;
    *v = strtod(s, &end);
    return (end != s && *end == '\0' && isfinite(*v)) ? 0 : -1;
}

static int nums(char **f, int n, double *v)
{
    int i;
    for (i = 0; i < n; i++)
        if (num(f[i], &v[i]) < 0)
            return -1;
    return 0;
}

int path_parse_line(const char *line, path_elem_t *el)
{
    char buf[PATH_LINE_MAX + 1], *f[8], *hash;
    double v[6];
    int n;

    memset(el, 0, sizeof *el);
    if (strlen(line) > PATH_LINE_MAX)
        return -PATH_ESYNTAX;
    strcpy(buf, line);
    hash = strchr(buf, '#');
    if (hash)
        *hash = '\0';
    n = split(buf, f);
    if (n < 0)
        return -PATH_ESYNTAX;
    if (n == 0) {
        el->kind = PATH_NONE;
        return 0;
    }
    if (!strcasecmp(f[0], "start")) {
        if ((n != 4 && n != 5) || nums(f + 1, n - 1, v) < 0)
            return -PATH_ESYNTAX;
        el->kind = PATH_START;
        memcpy(el->xyz_m, v, sizeof el->xyz_m);
        el->t_s = n == 5 ? v[3] : 0.0;
        return fabs(el->t_s) <= PATH_TIME_MAX_S ? 0 : -PATH_ETIME;
    }
    if (!strcasecmp(f[0], "speed") || !strcasecmp(f[0], "step") || !strcasecmp(f[0], "wait")) {
        if (n != 2 || nums(f + 1, 1, v) < 0)
            return -PATH_ESYNTAX;
        el->kind = f[0][1] == 'p' || f[0][1] == 'P'     ? PATH_SPEED
                   : (f[0][1] == 't' || f[0][1] == 'T') ? PATH_STEP
                                                        : PATH_WAIT;
        if (!(v[0] > 0.0))
            return -PATH_ERANGE;
        el->value = v[0];
        if (el->kind == PATH_WAIT && v[0] > PATH_TIME_MAX_S)
            return -PATH_ETIME;
        return 0;
    }
    if (!strcasecmp(f[0], "line")) {
        if (n != 4 || nums(f + 1, 3, v) < 0)
            return -PATH_ESYNTAX;
        el->kind = PATH_LINE;
        memcpy(el->xyz_m, v, sizeof el->xyz_m);
        return 0;
    }
    if (!strcasecmp(f[0], "arc") || !strcasecmp(f[0], "circle")) {
        int circle = f[0][0] == 'c' || f[0][0] == 'C';
        if (n != 6 || nums(f + 1, circle ? 4 : 5, v) < 0)
            return -PATH_ESYNTAX;
        el->kind = PATH_ARC;
        el->centre_m[0] = v[0];
        el->centre_m[1] = v[1];
        el->radius_m = v[2];
        el->start_rad = v[3] * M_PI / 180.0;
        if (circle) {
            if (!strcasecmp(f[5], "ccw"))
                el->sweep_rad = 2.0 * M_PI;
            else if (!strcasecmp(f[5], "cw"))
                el->sweep_rad = -2.0 * M_PI;
            else
                return -PATH_ESYNTAX;
        } else {
            el->sweep_rad = (v[4] - v[3]) * M_PI / 180.0;
        }
        if (!(el->radius_m > 0.0) || !(fabs(el->sweep_rad) > 0.0) ||
            fabs(el->sweep_rad) > 2.0 * M_PI * (1.0 + 1e-12))
            return -PATH_ERANGE;
        return 0;
    }
    return -PATH_ESYNTAX;
}

typedef struct {
    double pos[3], t, speed, step;
    int started;
    int bad_time; /* a waypoint's time was beyond PATH_TIME_MAX_S or not increasing */
    size_t n, cap;
    engine_waypoint_t *out;
} walker_t;

static void emit(walker_t *w, const double *p, double t)
{
    if (!(fabs(t) <= PATH_TIME_MAX_S) || (w->n > 0 && !(t > w->t)))
        w->bad_time = 1;
    if (w->out && w->n < w->cap) {
        engine_waypoint_t *o = &w->out[w->n];
        o->t_s = t;
        o->pos_m[0] = p[0];
        o->pos_m[1] = p[1];
        o->pos_m[2] = p[2];
        o->seq = (uint32_t)(w->n + 1);
    }
    w->n++;
    memcpy(w->pos, p, sizeof w->pos);
    w->t = t;
}

static int steps_for(const walker_t *w, double len, double *dur, unsigned long *k)
{
    double s;
    *dur = len / w->speed;
    s = ceil(*dur / w->step - 1e-9);
    if (!isfinite(s) || s > PATH_STEPS_MAX)
        return -PATH_ERANGE;
    *k = s < 1.0 ? 1ul : (unsigned long)s;
    /* counting with a bound: refused before the walk (path_expand) */
    if (!w->out && w->cap && *k > w->cap - (w->n < w->cap ? w->n : w->cap))
        return -PATH_EFULL;
    return 0;
}

static int do_line(walker_t *w, const double *to)
{
    double a[3], len, dur;
    unsigned long k, i;
    int c, rc;

    memcpy(a, w->pos, sizeof a);
    len = sqrt((to[0] - a[0]) * (to[0] - a[0]) + (to[1] - a[1]) * (to[1] - a[1]) +
               (to[2] - a[2]) * (to[2] - a[2]));
    if (len < PATH_SAME_POINT_M)
        return 0;
    rc = steps_for(w, len, &dur, &k);
    if (rc < 0)
        return rc;
    {
        double t0 = w->t;
        for (i = 1; i <= k; i++) {
            double p[3], f = (double)i / (double)k;
            for (c = 0; c < 3; c++)
                p[c] = i == k ? to[c] : a[c] + f * (to[c] - a[c]);
            emit(w, p, t0 + f * dur);
        }
    }
    return 0;
}

static int do_arc(walker_t *w, const path_elem_t *el)
{
    double knots[NURBS_ARC_KNOTS_MAX], ctrl[NURBS_ARC_CTRL_MAX * 3], wt[NURBS_ARC_CTRL_MAX];
    double p0[3], len, dur, t0;
    unsigned long k, i;
    nurbs_t arc;
    int rc;

    rc = nurbs_arc(el->centre_m[0], el->centre_m[1], w->pos[2], 3, el->radius_m, el->start_rad,
                   el->sweep_rad, knots, ctrl, wt, &arc);
    if (rc < 0)
        return -PATH_ERANGE;
    /* The arc's first pole is its start point: join it by a line if needed. */
    memcpy(p0, ctrl, sizeof p0);
    rc = do_line(w, p0);
    if (rc < 0)
        return rc;
    len = el->radius_m * fabs(el->sweep_rad);
    rc = steps_for(w, len, &dur, &k);
    if (rc < 0)
        return rc;
    t0 = w->t;
    for (i = 1; i <= k; i++) {
        double p[3], f = (double)i / (double)k;
        if (nurbs_eval(&arc, nurbs_arc_param(el->sweep_rad, f), p) < 0)
            return -PATH_ERANGE;
        emit(w, p, t0 + f * dur);
    }
    return 0;
}

int path_expand(const path_elem_t *el, size_t nel, engine_waypoint_t *out, size_t cap,
                size_t *n_out)
{
    return path_expand_ex(el, nel, out, cap, n_out, NULL, NULL);
}

int path_expand_ex(const path_elem_t *el, size_t nel, engine_waypoint_t *out, size_t cap,
                   size_t *n_out, size_t *el_end, size_t *bad_el)
{
    walker_t w;
    size_t i;
    int rc = 0;

    memset(&w, 0, sizeof w);
    w.speed = 1.0;
    w.step = 1.0;
    w.out = out;
    w.cap = cap;
    for (i = 0; i < nel && rc == 0; i++) {
        switch (el[i].kind) {
        case PATH_NONE: break;
        case PATH_START:
            if (w.started) {
                rc = -PATH_ETWICE;
                break;
            }
            w.started = 1;
            emit(&w, el[i].xyz_m, el[i].t_s);
            break;
        case PATH_SPEED:
        case PATH_STEP:
            if (!(el[i].value > 0.0) || !isfinite(el[i].value)) {
                rc = -PATH_ERANGE;
                break;
            }
            if (el[i].kind == PATH_SPEED)
                w.speed = el[i].value;
            else
                w.step = el[i].value;
            break;
        case PATH_LINE: rc = w.started ? do_line(&w, el[i].xyz_m) : -PATH_ENOSTART; break;
        case PATH_ARC: rc = w.started ? do_arc(&w, &el[i]) : -PATH_ENOSTART; break;
        case PATH_WAIT:
            if (!w.started)
                rc = -PATH_ENOSTART;
            else if (!(el[i].value > 0.0) || !isfinite(el[i].value))
                rc = -PATH_ERANGE;
            else
                emit(&w, w.pos, w.t + el[i].value);
            break;
        default: rc = -PATH_ERANGE; break;
        }
        if (rc == 0 && w.bad_time)
            rc = -PATH_ETIME;
        if (rc < 0 && bad_el)
            *bad_el = i;
        if (rc == 0 && el_end)
            el_end[i] = w.n;
    }
    if (n_out)
        *n_out = w.n;
    if (rc < 0)
        return rc;
    if (out && w.n > cap)
        return -PATH_EFULL;
    return 0;
}
