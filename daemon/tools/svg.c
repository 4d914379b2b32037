/* svg.c - plan view and speed profile of a replayed track.  See svg.h. */
#include "svg.h"

#include <errno.h>
#include <stdint.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    double x_m, y_m, t_s, speed_m_s;
    int64_t now_ns;
} sample_t;

typedef struct {
    double x_m, y_m;
    int accepted;
} wpt_t;

struct svg_plot {
    int geographic;
    size_t max; /* capacity of s */
    sample_t *s;
    size_t n;      /* kept */
    size_t stride; /* keep one setpoint in stride */
    size_t seen;   /* setpoints offered (drawn ones) */
    sample_t last; /* last setpoint, always drawn */
    int have_last;
    int last_kept; /* last was also appended to s */
    wpt_t *w;
    size_t nw, capw;
    sample_t ev[SVG_UNDERRUNS_DRAWN]; /* where underruns began (never decimated) */
    size_t nev, ev_total;
    engine_state_t prev_state;
};

/* Page layout, pixels. */
#define PAGE_W 900.0
#define MARGIN_L 80.0
#define MARGIN_R 30.0
#define PLAN_TOP 50.0
#define PLAN_H 560.0
#define GAP_H 70.0
#define SPEED_H 200.0
#define MARGIN_B 60.0
#define PAGE_H (PLAN_TOP + PLAN_H + GAP_H + SPEED_H + MARGIN_B)
#define TICKS_WANTED 6

svg_plot_t *svg_plot_new(size_t max_points, int geographic)
{
    svg_plot_t *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    if (max_points == 0)
        max_points = SVG_POINTS_DEFAULT;
    if (max_points < SVG_POINTS_MIN)
        max_points = SVG_POINTS_MIN;
    p->s = malloc(max_points * sizeof *p->s);
    if (!p->s) {
        free(p);
        return NULL;
    }
    p->max = max_points;
    p->stride = 1;
    p->geographic = geographic;
    return p;
}

void svg_plot_free(svg_plot_t *p)
{
    if (!p)
        return;
    free(p->s);
    free(p->w);
    free(p);
}

int svg_plot_waypoint(svg_plot_t *p, double x_m, double y_m, int accepted)
{
    if (!isfinite(x_m) || !isfinite(y_m))
        return 0;
    if (p->nw == p->capw) {
        size_t cap = p->capw ? p->capw * 2 : 256;
        wpt_t *w = realloc(p->w, cap * sizeof *w);
        if (!w)
            return -ENOMEM;
        p->w = w;
        p->capw = cap;
    }
    p->w[p->nw].x_m = x_m;
    p->w[p->nw].y_m = y_m;
    p->w[p->nw].accepted = accepted;
    p->nw++;
    return 0;
}

int svg_plot_setpoint(svg_plot_t *p, const engine_setpoint_t *sp)
{
    engine_state_t prev = p->prev_state;
    p->prev_state = sp->state;
    if (sp->state == ENGINE_STATE_WAITING)
        return 0;
    double v = sqrt(sp->vel_m_s[0] * sp->vel_m_s[0] + sp->vel_m_s[1] * sp->vel_m_s[1] +
                    sp->vel_m_s[2] * sp->vel_m_s[2]);
    if (!isfinite(sp->pos_m[0]) || !isfinite(sp->pos_m[1]) || !isfinite(sp->t_s) || !isfinite(v))
        return 0;
    sample_t s = {sp->pos_m[0], sp->pos_m[1], sp->t_s, v, sp->now_ns};
    if (sp->state == ENGINE_STATE_UNDERRUN && prev != ENGINE_STATE_UNDERRUN) {
        if (p->nev < SVG_UNDERRUNS_DRAWN)
            p->ev[p->nev++] = s;
        p->ev_total++;
    }
    p->last = s;
    p->have_last = 1;
    p->last_kept = 0;
    if (p->seen++ % p->stride != 0)
        return 0;
    if (p->n == p->max) {
        /* Keep every other one: the kept ones stay on a stride grid. */
        size_t j = 0;
        for (size_t i = 0; i < p->n; i += 2)
            p->s[j++] = p->s[i];
        p->n = j;
        p->stride *= 2;
        /* The current setpoint (index seen-1, a multiple of the old stride)
         * stays only if it is on the new grid. */
        if ((p->seen - 1) % p->stride != 0)
            return 0;
    }
    p->s[p->n++] = s;
    p->last_kept = 1;
    return 0;
}

size_t svg_plot_kept(const svg_plot_t *p)
{
    return p->n;
}

size_t svg_plot_stride(const svg_plot_t *p)
{
    return p->stride;
}

/* ---- drawing helpers ------------------------------------------------------ */

typedef struct {
    double lo, hi; /* data range */
    double p0, p1; /* pixel range (p0 for lo) */
} axis_t;

static double ax_map(const axis_t *a, double v)
{
    /* hi > lo always (widened in range_fix), so no division by zero. */
    return a->p0 + (v - a->lo) / (a->hi - a->lo) * (a->p1 - a->p0);
}

/* Widen a degenerate or empty range so the mapping is defined. */
static void range_fix(double *lo, double *hi)
{
    if (!(*lo <= *hi)) { /* empty (lo = +inf, hi = -inf) */
        *lo = 0;
        *hi = 1;
    }
    double span = *hi - *lo;
    double mag = fmax(fabs(*lo), fabs(*hi));
    if (span < 1e-9 * fmax(mag, 1.0)) {
        double pad = fmax(mag * 1e-3, 0.5);
        *lo -= pad;
        *hi += pad;
    }
}

/* 1, 2 or 5 times a power of ten, giving about TICKS_WANTED ticks. */
static double nice_step(double span)
{
    double raw = span / TICKS_WANTED;
    double p10 = pow(10.0, floor(log10(raw)));
    double m = raw / p10;
    return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p10;
}

static void fmt_tick(char *buf, size_t len, double v, double step)
{
    int dec = step >= 1 ? 0 : (int)ceil(-log10(step) - 1e-9);
    if (dec > 6)
        dec = 6;
    if (fabs(v) < step * 1e-6)
        v = 0; /* no "-0" */
    snprintf(buf, len, "%.*f", dec, v);
}

static void xml_escape(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        default:
            /* Control characters are not allowed in XML 1.0 text. */
            if ((unsigned char)*s >= 0x20 || *s == '\t')
                fputc(*s, f);
        }
    }
}

/* Frame, grid, ticks and labels of one panel. */
static void draw_axes(FILE *f, const axis_t *ax, const axis_t *ay, const char *xlabel,
                      const char *ylabel, const char *id)
{
    double x0 = ax->p0, x1 = ax->p1, y0 = ay->p0, y1 = ay->p1; /* y0 bottom, y1 top */
    fprintf(f, "<g id=\"%s-axes\" font-family=\"sans-serif\" font-size=\"12\">\n", id);
    fprintf(f,
            "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"white\" "
            "stroke=\"black\"/>\n",
            x0, y1, x1 - x0, y0 - y1);
    double step = nice_step(ax->hi - ax->lo);
    char buf[64];
    for (double v = ceil(ax->lo / step) * step; v <= ax->hi + step * 1e-9; v += step) {
        double px = ax_map(ax, v);
        fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>", px,
                y0, px, y1);
        fmt_tick(buf, sizeof buf, v, step);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", px, y0 + 16,
                buf);
    }
    step = nice_step(ay->hi - ay->lo);
    for (double v = ceil(ay->lo / step) * step; v <= ay->hi + step * 1e-9; v += step) {
        double py = ax_map(ay, v);
        fprintf(f, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>", x0,
                py, x1, py);
        fmt_tick(buf, sizeof buf, v, step);
        fprintf(f, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", x0 - 6, py + 4,
                buf);
    }
    fprintf(f, "<text class=\"xlabel\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n",
            (x0 + x1) / 2, y0 + 36, xlabel);
    fprintf(f,
            "<text class=\"ylabel\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" "
            "transform=\"rotate(-90 %.1f %.1f)\">%s</text>\n",
            x0 - 58, (y0 + y1) / 2, x0 - 58, (y0 + y1) / 2, ylabel);
    fputs("</g>\n", f);
}

/* The kept samples plus the last one if it was not kept. */
static size_t nsamples(const svg_plot_t *p)
{
    return p->n + (p->have_last && !p->last_kept);
}

static const sample_t *sample(const svg_plot_t *p, size_t i)
{
    return i < p->n ? &p->s[i] : &p->last;
}

/* Where the speed line must not join two samples: track time went back, or
 * ran ahead faster than the clock (the start of a new trajectory after a
 * gap: the time in between is not motion).  Track time standing still
 * (a hold, a transfer) is drawn: it shows as a vertical stroke at that time.
 * The plan view is never broken: the setpoints are continuous motion (the
 * engine moves to a new trajectory's start by a transfer, it never jumps),
 * and it draws exactly what was streamed. */
#define SPEED_BREAK_FACTOR 1.5
static int speed_break(const sample_t *a, const sample_t *b)
{
    double dt_s = b->t_s - a->t_s;
    double dnow_s = (double)(b->now_ns - a->now_ns) * 1e-9;
    return dt_s < 0 || dt_s > SPEED_BREAK_FACTOR * dnow_s + 1e-9;
}

static void draw_path(FILE *f, const svg_plot_t *p, const axis_t *ax, const axis_t *ay, int speed,
                      const char *id, const char *color)
{
    size_t n = nsamples(p);
    fprintf(f,
            "<path id=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" "
            "stroke-linejoin=\"round\" d=\"",
            id, color);
    for (size_t i = 0; i < n; i++) {
        const sample_t *s = sample(p, i);
        int move = i == 0 || (speed && speed_break(sample(p, i - 1), s));
        double px = ax_map(ax, speed ? s->t_s : s->x_m);
        double py = ax_map(ay, speed ? s->speed_m_s : s->y_m);
        fprintf(f, "%s%.1f %.1f", move ? (i ? " M" : "M") : " L", px, py);
    }
    fputs("\"/>\n", f);
}

/* A triangle where each underrun began (plan: at the held position;
 * speed panel: on the time axis). */
static void draw_events(FILE *f, const svg_plot_t *p, const axis_t *ax, const axis_t *ay, int speed)
{
    fprintf(f, "<g id=\"%s\" fill=\"#9467bd\">", speed ? "underruns-t" : "underruns");
    for (size_t i = 0; i < p->nev; i++) {
        double x = ax_map(ax, speed ? p->ev[i].t_s : p->ev[i].x_m);
        double y = speed ? ay->p0 : ax_map(ay, p->ev[i].y_m);
        fprintf(f, "<path d=\"M%.1f %.1f l5 10 h-10 z\"/>", x, y - (speed ? 10 : 5));
    }
    fputs("</g>\n", f);
}

/* The page, its title and the legend. */
static void draw_header(FILE *f, const svg_plot_t *p, const char *title)
{
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"0 0 %.0f %.0f\">\n",
            PAGE_W, PAGE_H, PAGE_W, PAGE_H);
    fputs("<title>", f);
    xml_escape(f, title ? title : "trajreplay");
    fputs("</title>\n<rect width=\"100%\" height=\"100%\" fill=\"#f8f8f8\"/>\n", f);
    fprintf(f,
            "<text id=\"title\" x=\"%.1f\" y=\"22\" font-family=\"sans-serif\" "
            "font-size=\"15\">",
            MARGIN_L);
    xml_escape(f, title ? title : "trajreplay");
    fputs("</text>\n", f);

    /* Legend. */
    fprintf(
        f,
        "<g id=\"legend\" font-family=\"sans-serif\" font-size=\"12\">"
        "<circle cx=\"%.1f\" cy=\"38\" r=\"3\" fill=\"#1f5fbf\"/>"
        "<text x=\"%.1f\" y=\"42\">waypoints (%zu)</text>"
        "<line x1=\"%.1f\" y1=\"38\" x2=\"%.1f\" y2=\"38\" stroke=\"#d62728\" stroke-width=\"2\"/>"
        "<text x=\"%.1f\" y=\"42\">setpoints</text>"
        "<path d=\"M%.1f 35 l6 6 m0 -6 l-6 6\" stroke=\"#ff7f0e\" stroke-width=\"2\"/>"
        "<text x=\"%.1f\" y=\"42\">rejected</text>"
        "<path d=\"M%.1f 34 l4 8 h-8 z\" fill=\"#9467bd\"/>"
        "<text x=\"%.1f\" y=\"42\">underrun (%zu)</text></g>\n",
        MARGIN_L + 4, MARGIN_L + 12, p->nw, MARGIN_L + 160, MARGIN_L + 180, MARGIN_L + 186,
        MARGIN_L + 270, MARGIN_L + 282, MARGIN_L + 360, MARGIN_L + 370, p->ev_total);
}

/* Accepted waypoints as dots (at most about SVG_WAYPOINTS_DRAWN of them),
 * every rejected one as a cross. */
static void draw_waypoints(FILE *f, const svg_plot_t *p, const axis_t *ax, const axis_t *ay)
{
    size_t every = p->nw > SVG_WAYPOINTS_DRAWN
                       ? (p->nw + SVG_WAYPOINTS_DRAWN - 1) / SVG_WAYPOINTS_DRAWN
                       : 1;
    fputs("<g id=\"waypoints\" fill=\"#1f5fbf\">", f);
    for (size_t i = 0; i < p->nw; i += every)
        if (p->w[i].accepted)
            fprintf(f, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"2.5\"/>", ax_map(ax, p->w[i].x_m),
                    ax_map(ay, p->w[i].y_m));
    fputs("</g>\n<g id=\"rejected\" stroke=\"#ff7f0e\" stroke-width=\"1.5\">", f);
    for (size_t i = 0; i < p->nw; i++)
        if (!p->w[i].accepted)
            fprintf(f, "<path d=\"M%.1f %.1f l6 6 m0 -6 l-6 6\"/>", ax_map(ax, p->w[i].x_m) - 3,
                    ax_map(ay, p->w[i].y_m) - 3);
    fputs("</g>\n", f);
}

int svg_plot_write(const svg_plot_t *p, FILE *f, const char *title)
{
    size_t n = nsamples(p);
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    double tlo = INFINITY, thi = -INFINITY, vhi = 0;
    for (size_t i = 0; i < p->nw; i++) {
        xlo = fmin(xlo, p->w[i].x_m);
        xhi = fmax(xhi, p->w[i].x_m);
        ylo = fmin(ylo, p->w[i].y_m);
        yhi = fmax(yhi, p->w[i].y_m);
    }
    for (size_t i = 0; i < n; i++) {
        const sample_t *s = sample(p, i);
        xlo = fmin(xlo, s->x_m);
        xhi = fmax(xhi, s->x_m);
        ylo = fmin(ylo, s->y_m);
        yhi = fmax(yhi, s->y_m);
        tlo = fmin(tlo, s->t_s);
        thi = fmax(thi, s->t_s);
        vhi = fmax(vhi, s->speed_m_s);
    }
    range_fix(&xlo, &xhi);
    range_fix(&ylo, &yhi);
    range_fix(&tlo, &thi);
    double vlo = 0;
    vhi *= 1.05;
    range_fix(&vlo, &vhi);

    /* Plan view: equal scale in x and y, centred in its box. */
    double bw = PAGE_W - MARGIN_L - MARGIN_R, bh = PLAN_H;
    double scale = fmin(bw / (xhi - xlo), bh / (yhi - ylo)); /* px per metre */
    double cx = (xlo + xhi) / 2, cy = (ylo + yhi) / 2;
    axis_t px = {cx - bw / 2 / scale, cx + bw / 2 / scale, MARGIN_L, MARGIN_L + bw};
    axis_t py = {cy - bh / 2 / scale, cy + bh / 2 / scale, PLAN_TOP + bh, PLAN_TOP};
    double sp_top = PLAN_TOP + PLAN_H + GAP_H;
    axis_t st = {tlo, thi, MARGIN_L, MARGIN_L + bw};
    axis_t sv = {vlo, vhi, sp_top + SPEED_H, sp_top};

    draw_header(f, p, title);

    char lx[64], ly[64];
    snprintf(lx, sizeof lx, "%s (m)", p->geographic ? "east" : "x");
    snprintf(ly, sizeof ly, "%s (m)", p->geographic ? "north" : "y");
    draw_axes(f, &px, &py, lx, ly, "plan");
    fprintf(f,
            "<clipPath id=\"plan-clip\"><rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" "
            "height=\"%.1f\"/></clipPath>\n",
            px.p0, py.p1, bw, bh);
    fputs("<g clip-path=\"url(#plan-clip)\">\n", f);
    draw_waypoints(f, p, &px, &py);
    draw_path(f, p, &px, &py, 0, "curve", "#d62728");
    draw_events(f, p, &px, &py, 0);
    fputs("</g>\n", f);

    draw_axes(f, &st, &sv, "track time t (s)", "speed |v| (m/s)", "speed");
    draw_path(f, p, &st, &sv, 1, "speed", "#2ca02c");
    draw_events(f, p, &st, &sv, 1);
    fputs("</svg>\n", f);
    return ferror(f) ? -EIO : 0;
}
