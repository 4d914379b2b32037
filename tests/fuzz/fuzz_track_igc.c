/* fuzz_track_igc.c - libFuzzer target for the track format of IGC flight log B records (daemon/replay/track_igc.c):
 * byte 0 sets the skip-bad flag, the rest is the file.  Checks: fuzz_track_check.h. */
#include "fuzz_track_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    fuzz_track_check((const char *)data + 1, size - 1, TRACK_FMT_IGC,
                     (data[0] & 1) ? TRACK_SKIP_BAD : 0);
    return 0;
}
