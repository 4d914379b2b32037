/*
 * path.h - a waypoint path from lines and exact circular arcs.
 *
 * A path is a small program of elements, usually parsed from text, one per
 * line ('#' starts a comment; angles in degrees, lengths in metres,
 * times in seconds):
 *
 *   start X Y Z [T]        first waypoint (time T, default 0); exactly once
 *   speed V                speed for the elements that follow (m/s, > 0; default 1)
 *   step S                 waypoint spacing in time (s, > 0; default 1)
 *   line X Y Z             straight line to (X, Y, Z)
 *   arc CX CY R A0 A1      arc of the circle centre (CX, CY), radius R, in the
 *                          plane z = current z, from angle A0 to A1 (A1 < A0:
 *                          clockwise; |A1 - A0| <= 360).  If the current
 *                          point is not the arc's start, a line joins them.
 *   circle CX CY R A0 DIR  a full turn from angle A0, DIR = ccw or cw
 *   wait S                 stay S seconds (one waypoint at the end)
 *
 * Times (start T, wait S, and every waypoint's time) stay within
 * |t| <= PATH_TIME_MAX_S and strictly increase from one waypoint to the
 * next: "wait 1e300" or a step too short for the resolution of double at
 * that time would otherwise give waypoints all at one time, which a
 * consumer rejects as duplicates, losing the rest of the path silently.
 *
 * Each moving element of length L becomes ceil(L / (V S)) equal steps
 * (at least one), so waypoints are at most S apart in time and the speed is
 * exactly V along the element.  Arc waypoints are points of a NURBS circle
 * (lib/spline/nurbs) evaluated at the parameter of exactly the intended angle: they
 * lie on the circle to rounding (not on a cubic approximation of it), at
 * equal angular steps, hence equal arc length.
 *
 * Pure: parsing works on strings, expansion writes caller memory.
 */
#ifndef TRAJD_PATH_H
#define TRAJD_PATH_H
/* trajd public API: installed as <trajd/path.h> (make install; pkg-config trajd). */

#include <stddef.h>

#include "motion.h"

enum path_error {
    PATH_OK = 0,
    PATH_ESYNTAX = 1,  /* unknown keyword, wrong number of fields, not a number */
    PATH_ERANGE = 2,   /* speed/step/radius <= 0, sweep 0 or above 360, not finite */
    PATH_ENOSTART = 3, /* a moving element before any 'start' */
    PATH_EFULL = 4,    /* more waypoints than the caller's capacity */
    PATH_ETWICE = 5,   /* a second 'start' (time would run backwards) */
    PATH_ETIME = 6,    /* a time beyond PATH_TIME_MAX_S, or not increasing */
};

/* Largest |time| in a path, s (about 31.7 years).  Double resolution there
 * is 1.2e-7 s, so steps down to a microsecond still increase exactly. */
#define PATH_TIME_MAX_S 1e9

/* Longest line path_parse_line accepts (characters). */
#define PATH_LINE_MAX 256

const char *path_strerror(int err);

typedef enum {
    PATH_NONE = 0, /* blank or comment line */
    PATH_START,
    PATH_SPEED,
    PATH_STEP,
    PATH_LINE,
    PATH_ARC,
    PATH_WAIT,
} path_kind_t;

typedef struct {
    path_kind_t kind;
    double xyz_m[3];    /* START, LINE: the point */
    double t_s;         /* START: its time */
    double value;       /* SPEED m/s, STEP s, WAIT s */
    double centre_m[2]; /* ARC */
    double radius_m;    /* ARC */
    double start_rad;   /* ARC */
    double sweep_rad;   /* ARC: signed, |sweep| <= 2 pi */
} path_elem_t;

/*
 * Parse one line of the text form into el (PATH_NONE for blank/comment).
 * Returns 0, -PATH_ESYNTAX, -PATH_ERANGE, -PATH_ETIME (start T or wait S
 * beyond PATH_TIME_MAX_S).
 */
int path_parse_line(const char *line, path_elem_t *el);

/*
 * Expand elements into waypoints (seq = 1, 2, ...).  With out == NULL only
 * counts, and cap > 0 bounds the count: a line or arc that would take it
 * above cap is refused with -PATH_EFULL before it is walked (a step of 1e-6
 * m cannot make 1e7 points to count), *n_out then the count before it.
 * Otherwise *n_out receives the number of waypoints (also on -PATH_EFULL:
 * the number that would be needed).
 * Returns 0, -PATH_ENOSTART, -PATH_ETWICE, -PATH_ERANGE, -PATH_ETIME,
 * -PATH_EFULL.
 */
int path_expand(const path_elem_t *el, size_t nel, engine_waypoint_t *out, size_t cap,
                size_t *n_out);

/*
 * As path_expand, and also: el_end (NULL or nel entries) receives for each
 * element the number of waypoints made up to and including it (so element
 * i made waypoints el_end[i-1] .. el_end[i]-1); on an error *bad_el (may be
 * NULL) is the index of the element that failed (for a message with its
 * line), and el_end is filled up to it.
 */
int path_expand_ex(const path_elem_t *el, size_t nel, engine_waypoint_t *out, size_t cap,
                   size_t *n_out, size_t *el_end, size_t *bad_el);

#endif
