/*
 * svg.h - draw a replayed track as a small stand-alone SVG for a person to
 * look at: a plan view (x/east against y/north, equal scale) with the
 * waypoints as dots (rejected ones as crosses) and the streamed curve as a
 * line, and under it the speed |v| against track time.  Axes carry ticks,
 * labels and units.
 *
 * Memory stays bounded for any track length: setpoints are decimated for
 * drawing only (every stride-th is kept; when max_points are held, every
 * other one is dropped and the stride doubles), so a long track draws with
 * at most max_points curve vertices.  Limit: a speed spike shorter than the
 * stride can fall between kept samples; the CSV output has every setpoint.
 * The very last setpoint is always drawn.  Setpoints in state WAITING (no
 * motion yet) are not drawn.  The plan view draws the setpoints as one
 * unbroken line (what was streamed, transfers between trajectories
 * included); the speed line is broken where track time jumps ahead of the
 * clock (a new trajectory after a gap) or goes back.  Where an underrun
 * began (waypoints late: the output holds) a purple triangle marks the
 * place in the plan view and the time on the speed axis.  Waypoints are all kept; above
 * SVG_WAYPOINTS_DRAWN only every k-th is drawn.
 */
#ifndef TRAJD_SVG_H
#define TRAJD_SVG_H

#include <stddef.h>
#include <stdio.h>
#include "engine.h"

#define SVG_POINTS_DEFAULT 4000 /* curve vertices kept (the size does not grow with the track) */
#define SVG_POINTS_MIN 16
#define SVG_WAYPOINTS_DRAWN 5000 /* at most this many waypoint dots */
#define SVG_UNDERRUNS_DRAWN 256  /* underrun marks drawn (all are counted in the legend) */

typedef struct svg_plot svg_plot_t;

/* New plot keeping at most max_points setpoints (at least SVG_POINTS_MIN;
 * 0 = SVG_POINTS_DEFAULT).  geographic selects the axis names (east/north
 * rather than x/y).  Returns NULL if out of memory. */
svg_plot_t *svg_plot_new(size_t max_points, int geographic);

/* Free; NULL is a no-op. */
void svg_plot_free(svg_plot_t *p);

/* Add a waypoint (accepted: 1 if the engine took it, 0 if it rejected it).
 * Non-finite coordinates are ignored.  Returns 0 or -ENOMEM. */
int svg_plot_waypoint(svg_plot_t *p, double x_m, double y_m, int accepted);

/* Add a setpoint (decimated as described above).  Non-finite values are
 * ignored.  Returns 0 (never fails: the storage was sized at svg_plot_new). */
int svg_plot_setpoint(svg_plot_t *p, const engine_setpoint_t *sp);

/*
 * Write the SVG document to f.  title (may be NULL) is escaped for XML.
 * Returns 0, or -EIO if writing failed (the caller reports errno/ferror).
 */
int svg_plot_write(const svg_plot_t *p, FILE *f, const char *title);

/* Setpoints currently kept, and the decimation stride (trajreplay's title
 * says them: the drawing is not the CSV). */
size_t svg_plot_kept(const svg_plot_t *p);
size_t svg_plot_stride(const svg_plot_t *p);

#endif
