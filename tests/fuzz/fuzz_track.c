/* fuzz_track.c - libFuzzer target for the track loader (CSV and GPX).
 * The first byte picks the format and the skip-bad flag; the rest is the
 * file.  Checks: no crash, no leak, and a successful load holds only finite
 * waypoints (the loader's promise to the engine). */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "track.h"
#include "track_text.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    track_format_t fmt = (track_format_t)(data[0] % 4);
    unsigned flags = (data[0] & 0x10) ? TRACK_SKIP_BAD : 0;
    track_t t;
    char err[256];
    if (track_load_text("fuzz", (const char *)data + 1, size - 1, fmt, flags, &t, err,
                        sizeof err) == 0) {
        for (size_t i = 0; i < t.n; i++)
            if (!isfinite(t.wp[i].t_s) || !isfinite(t.wp[i].pos_m[0]) ||
                !isfinite(t.wp[i].pos_m[1]) || !isfinite(t.wp[i].pos_m[2]))
                abort();
        track_free(&t);
    }
    return 0;
}
