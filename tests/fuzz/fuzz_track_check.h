/* fuzz_track_check.h - what every track format's fuzz target checks on a
 * parse (tests/fuzz/fuzz_track_<format>.c): no crash, no leak, and the
 * loader's promises: a successful load holds at least one waypoint, all
 * finite, the format asked for, source line numbers that never decrease, and
 * skipped lines only when skipping was asked for, at most TRACK_REPORT_MAX of
 * them reported. */
#ifndef FUZZ_TRACK_CHECK_H
#define FUZZ_TRACK_CHECK_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "track.h"
#include "track_text.h"

static inline void fuzz_track_check(const char *buf, size_t len, track_format_t fmt, unsigned flags)
{
    track_t t;
    char err[256];
    if (track_load_text("fuzz", buf, len, fmt, flags, &t, err, sizeof err) != 0)
        return;
    if (t.n == 0 || t.format != fmt)
        abort();
    for (size_t i = 0; i < t.n; i++) {
        if (!isfinite(t.wp[i].t_s) || !isfinite(t.wp[i].pos_m[0]) || !isfinite(t.wp[i].pos_m[1]) ||
            !isfinite(t.wp[i].pos_m[2]))
            abort();
        if (i && t.line && t.line[i] < t.line[i - 1])
            abort();
    }
    if ((!(flags & TRACK_SKIP_BAD) && t.skipped) || t.nreports > TRACK_REPORT_MAX ||
        t.nreports > t.skipped)
        abort();
    track_free(&t);
}

#endif
