/* fuzz_track_csv.c - libFuzzer target for the CSV track formats
 * (daemon/replay/track_csv.c): byte 0 picks t,x,y,z or t,lat,lon[,alt] and
 * the skip-bad flag, the rest is the file.  Checks: fuzz_track_check.h. */
#include "fuzz_track_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    fuzz_track_check((const char *)data + 1, size - 1,
                     (data[0] & 1) ? TRACK_FMT_LATLON : TRACK_FMT_XYZ,
                     (data[0] & 2) ? TRACK_SKIP_BAD : 0);
    return 0;
}
