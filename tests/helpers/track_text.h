/*
 * track_text.h - a track held in memory, loaded as trajd loads a track file
 * (daemon/replay/track.h track_load_opts): its len bytes written to the file
 * name in a temporary directory of the program's own (made at the first
 * load, removed at exit; the file at once after the load), so that messages
 * read "<directory>/name:line: ...".  For the C track tests and the track
 * fuzz targets; a failure to write the file aborts.
 */
#ifndef TRAJD_TRACK_TEXT_H
#define TRAJD_TRACK_TEXT_H

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "track.h"

static char track_text_dir[64];

static inline void track_text_cleanup(void)
{
    rmdir(track_text_dir);
}

static inline int track_load_text(const char *name, const char *buf, size_t len, track_format_t fmt,
                                  unsigned flags, track_t *trk, char *err, size_t errlen)
{
    char path[sizeof track_text_dir + 256];
    if (!track_text_dir[0]) {
        snprintf(track_text_dir, sizeof track_text_dir, "/tmp/trajd_track_text.XXXXXX");
        if (!mkdtemp(track_text_dir))
            abort();
        atexit(track_text_cleanup);
    }
    snprintf(path, sizeof path, "%s/%s", track_text_dir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(buf, 1, len, f) != len || fclose(f) != 0)
        abort();
    int rc = track_load_opts(path, fmt, flags, trk, err, errlen);
    unlink(path);
    return rc;
}

#endif
