/* fuzz_track_path.c - libFuzzer target for the path track format
 * (daemon/replay/track_path.c): the input is the file.  Paths whose elements
 * could expand into more than MAX_WP waypoints are skipped (fuzz_path_bound.h:
 * a path asks for up to PATH_STEPS_MAX points per element, legitimately).
 * Checks: fuzz_track_check.h. */
#include <string.h>

#include "fuzz_path_bound.h"
#include "fuzz_track_check.h"

#define MAX_WP 512
#define MAX_EL 64

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    path_elem_t el[MAX_EL];
    char line[PATH_LINE_MAX + 1];
    size_t nel = 0, pos = 0;
    while (pos < size) {
        size_t e = pos, n;
        while (e < size && data[e] != '\n')
            e++;
        n = e - pos < PATH_LINE_MAX ? e - pos : PATH_LINE_MAX;
        memcpy(line, data + pos, n);
        line[n] = '\0';
        pos = e + 1;
        if (path_parse_line(line, &el[nel]) == 0 && el[nel].kind != PATH_NONE && ++nel == MAX_EL)
            return 0;
    }
    if (!(expansion_bound(el, nel) <= MAX_WP))
        return 0;
    fuzz_track_check((const char *)data, size, TRACK_FMT_PATH, 0);
    return 0;
}
