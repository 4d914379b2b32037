/*
 * fuzz_can_logfile.c - libFuzzer target for the candump log reader
 * (daemon/can/can_logfile.c): the input is the log_in file, lines of any
 * length, opened as trajd opens it (can_logfile_open_mode; one temporary file,
 * rewritten for each input).
 *
 * Oracle, a model of the reader built here independently: split the input at
 * '\n'; a line becomes a frame only if, whole, it is no longer than
 * CAN_LOGFILE_LINE_MAX, holds no NUL byte, and candump_parse_line accepts it.
 * A log with no such frame is refused.  The frames replayed (all of them, at a
 * time far ahead) must be exactly these,
 * in file order: no piece of a line is ever parsed as a frame (a 511-byte
 * split once turned the tail of a long line into a command).  Every line is
 * counted once: lines = comments + bad lines + frames.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <syslog.h>
#include <unistd.h>

#include "can_logfile.h"
#include "candump.h"
#include "log.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_FRAMES 4096

static char in_path[64];

static void remove_in(void)
{
    unlink(in_path);
}

/* The input as the log_in file: the temporary file, made at the first call
 * (removed at exit), now holding data alone. */
static const char *write_in(const uint8_t *data, size_t size)
{
    if (!in_path[0]) {
        snprintf(in_path, sizeof in_path, "/tmp/fuzz_can_logfile.XXXXXX");
        int fd = mkstemp(in_path);
        if (fd < 0)
            abort();
        close(fd);
        atexit(remove_in);
    }
    FILE *fp = fopen(in_path, "wb");
    if (!fp || fwrite(data, 1, size, fp) != size || fclose(fp) != 0)
        abort();
    return in_path;
}

static int same_frame(const canproto_frame_t *a, const canproto_frame_t *b)
{
    return a->id == b->id && a->len == b->len && a->flags == b->flags &&
           !memcmp(a->data, b->data, a->len);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static canproto_frame_t want[MAX_FRAMES];
    static char line[CAN_LOGFILE_LINE_MAX + 1];
    size_t nwant = 0, nlines = 0, pos = 0;
    char err[256];

    if (size == 0)
        return 0;
    log_set_level(LOG_ERR); /* bad lines are logged as warnings: not here */
    /* the model */
    while (pos < size) {
        const uint8_t *nl = memchr(data + pos, '\n', size - pos);
        size_t len = nl ? (size_t)(nl - (data + pos)) + 1 : size - pos;
        candump_line_t cl;
        nlines++;
        if (len <= CAN_LOGFILE_LINE_MAX && !memchr(data + pos, '\0', len)) {
            memcpy(line, data + pos, len);
            line[len] = '\0';
            if (candump_parse_line(line, &cl) == 0) {
                if (nwant == MAX_FRAMES)
                    return 0;
                want[nwant++] = cl.frame;
            }
        }
        pos += len;
    }

    can_logfile_t *l = can_logfile_open_mode(write_in(data, size), NULL, "vcan0", 0, 0, err,
                                             sizeof err);
    /* a log with no frame is refused, as its config check refuses it
     * (can_logfile_input_read: "empty" or "no CAN frame in it"); one with a
     * frame opens */
    if (!l != !nwant)
        abort();
    if (!l)
        return 0;

    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    if (st.lines != nlines || st.lines != st.comments + st.bad_lines + st.frames_in ||
        st.frames_in != nwant)
        abort();
    canproto_frame_t f;
    size_t got = 0;
    while (can_logfile_recv(l, INT64_MAX, &f) == 1) {
        if (got >= nwant || !same_frame(&f, &want[got]))
            abort();
        got++;
    }
    if (got != nwant || !can_logfile_done(l))
        abort();
    can_logfile_close(l);
    return 0;
}
