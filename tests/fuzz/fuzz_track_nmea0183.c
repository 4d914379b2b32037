/* fuzz_track_nmea0183.c - libFuzzer target for the track format of NMEA 0183 GGA/RMC sentences (daemon/replay/track_nmea0183.c):
 * byte 0 sets the skip-bad flag, the rest is the file.  Checks: fuzz_track_check.h. */
#include "fuzz_track_check.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    fuzz_track_check((const char *)data + 1, size - 1, TRACK_FMT_NMEA0183,
                     (data[0] & 1) ? TRACK_SKIP_BAD : 0);
    return 0;
}
