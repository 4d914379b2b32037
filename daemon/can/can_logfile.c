/* can_logfile.c - candump-log transport (see can_logfile.h). */
#include "can_logfile.h"

#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "candump.h"
#include "cfgload.h"
#include "log.h"
#include "regfile.h"
#include "outworker.h"
#include "spsc.h"

typedef struct {
    int64_t ts_us;
    canproto_frame_t f;
} can_logfile_rec_t;

/* Output frames queued for the writer thread (issue 28): the lines of this
 * many frames (a SYNC, STATUS and setpoints per object and tick). */
#define CAN_LOGFILE_QUEUE 4096

static void *writer(void *arg);

/* A log_in read whole: its frames, and the load's counts (lines, comments,
 * bad_lines, first_bad_line, frames_in of can_logfile_stats_t). */
struct can_logfile_input {
    can_logfile_rec_t *rec;
    size_t n, cap;
    can_logfile_stats_t st;
    char first_bad_why[64]; /* why the first bad line was refused */
};

struct can_logfile {
    can_logfile_input_t own;       /* its own frames (can_logfile_open_mode) */
    const can_logfile_input_t *in; /* &own, or a log_in read before (can_logfile_open_input) */
    size_t next;                   /* the next input frame to deliver */
    int64_t start_ns;
    int64_t now_ns;
    int64_t epoch_ns;    /* added to engine time in output stamps */
    int out_fd;          /* -1: no output */
    int out_own;         /* close it at the end (not stdout) */
    long long out_kept;  /* bytes kept in the output file at open, -1: not a regular file */
    int64_t out_last_us; /* stamp of its last line kept, INT64_MIN: none */
    char *obuf;          /* CAN_LOGFILE_OUT_BUF bytes of whole lines (the writer's) */
    size_t olen;
    int stalled; /* the writer's last write did not take everything */
    char ifname[CANDUMP_IFNAME_MAX + 1];
    can_logfile_stats_t st; /* the output's counts (the input's are in->st) */
    /* The output: the tick queues frames (can_logfile_send), publishes them
     * and wakes the writer once per cycle (can_logfile_flush); the writer
     * formats and writes them and counts its faults in these atomics,
     * which can_logfile_stats adds to st. */
    spsc_t q;
    outworker_t w;
    _Atomic uint64_t w_lost, w_errors;
    _Atomic int w_errno;
};

/* One bad line: counted; the first CAN_LOGFILE_REPORT_MAX are logged with
 * name:line and the reason, the rest summed up at the end of the load. */
static void bad_line(can_logfile_input_t *l, const char *name, uint64_t lineno, const char *why)
{
    if (!l->st.first_bad_line) {
        l->st.first_bad_line = lineno;
        snprintf(l->first_bad_why, sizeof l->first_bad_why, "%s", why);
    }
    if (l->st.bad_lines++ < CAN_LOGFILE_REPORT_MAX)
        log_msg(LOG_WARNING, "can: %s:%" PRIu64 ": %s: line not replayed", name, lineno, why);
}

static int add_frame(can_logfile_input_t *l, const candump_line_t *cl)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 256;
        can_logfile_rec_t *r = realloc(l->rec, cap * sizeof *r);
        if (!r)
            return -1;
        l->rec = r;
        l->cap = cap;
    }
    l->rec[l->n].ts_us = cl->ts_us;
    l->rec[l->n].f = cl->frame;
    l->n++;
    return 0;
}

/* One whole line (len bytes, '\n' included if present). */
static int load_line(can_logfile_input_t *l, const char *name, uint64_t lineno, const char *line,
                     size_t len)
{
    candump_line_t cl;
    l->st.lines++;
    size_t i = 0;
    while (i < len && (line[i] == ' ' || line[i] == '\t'))
        i++;
    if (i == len || line[i] == '#' || line[i] == '\n' || line[i] == '\r') {
        l->st.comments++; /* a comment of any length is still only a comment */
        return 0;
    }
    if (len > CAN_LOGFILE_LINE_MAX) {
        /* refused whole: parsing a cut-off piece could deliver a frame (a command) */
        char why[64];
        snprintf(why, sizeof why, "longer than %d bytes", CAN_LOGFILE_LINE_MAX);
        bad_line(l, name, lineno, why);
        return 0;
    }
    if (memchr(line, '\0', len)) {
        bad_line(l, name, lineno, "NUL byte (binary file?)");
        return 0;
    }
    int rc = candump_parse_line(line, &cl);
    if (rc == -CANDUMP_ESKIP) {
        l->st.comments++;
        return 0;
    }
    if (rc < 0) {
        bad_line(l, name, lineno, candump_strerror(rc));
        return 0;
    }
    return add_frame(l, &cl);
}

/* Every line of fp into l; 0, or -1 with why (out of memory, a read error,
 * the load cancelled: cfgload.h, a SIGTERM while a configuration is read). */
static int load_fp(can_logfile_input_t *l, FILE *fp, const char *name, char *why, size_t wl)
{
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    uint64_t lineno = 0;
    int rc = 0;
    while ((len = getline(&line, &cap, fp)) >= 0) {
        if ((++lineno & 0xffffu) == 0 && cfgload_cancelled()) {
            snprintf(why, wl, "cancelled (trajd is stopping)");
            rc = -1;
            break;
        }
        if (load_line(l, name, lineno, line, (size_t)len) < 0) {
            snprintf(why, wl, "out of memory");
            rc = -1;
            break;
        }
    }
    int read_err = ferror(fp) ? errno : 0;
    free(line);
    if (rc == 0 && read_err) {
        snprintf(why, wl, "read error: %s", strerror(read_err));
        rc = -1;
    }
    if (l->st.bad_lines > CAN_LOGFILE_REPORT_MAX)
        log_msg(LOG_WARNING,
                "can: %s: %" PRIu64 " lines not replayed in all (first at line %" PRIu64
                ", %d reported)",
                name, l->st.bad_lines, l->st.first_bad_line, CAN_LOGFILE_REPORT_MAX);
    l->st.frames_in = l->n;
    return rc;
}

/* The log_in at path, read-only, if a regular file within CAN_LOGFILE_MAX_BYTES
 * (regfile.h: a FIFO or a device is refused), else NULL with why. */
static FILE *open_in(const char *path, char *why, size_t wl)
{
    int fd = regfile_open(path, CAN_LOGFILE_MAX_BYTES, why, wl);
    FILE *fp = fd < 0 ? NULL : fdopen(fd, "r");
    if (fd >= 0 && !fp) {
        snprintf(why, wl, "%s", strerror(errno));
        close(fd);
    }
    return fp;
}

/* What a load that found no frame saw in the file, into why. */
static void no_frame_why(const can_logfile_input_t *l, char *why, size_t wl)
{
    if (!l->st.lines) {
        snprintf(why, wl, "empty: no CAN frame in it");
        return;
    }
    int n = snprintf(why, wl,
                     "no CAN frame in it (%" PRIu64 " lines: %" PRIu64
                     " comments or blank, %" PRIu64 " bad",
                     l->st.lines, l->st.comments, l->st.bad_lines);
    if (n >= 0 && (size_t)n < wl)
        snprintf(why + n, wl - (size_t)n,
                 l->st.bad_lines ? ", the first bad at line %" PRIu64 ": %s)" : ")",
                 l->st.first_bad_line, l->first_bad_why);
}

void can_logfile_input_free(can_logfile_input_t *in)
{
    if (!in)
        return;
    free(in->rec);
    free(in);
}

can_logfile_input_t *can_logfile_input_read(const char *path, char *why, size_t wl)
{
    FILE *fp = open_in(path, why, wl);
    if (!fp)
        return NULL;
    can_logfile_input_t *in = calloc(1, sizeof *in);
    int rc = in ? load_fp(in, fp, path, why, wl) : -1;
    fclose(fp);
    if (!in)
        snprintf(why, wl, "out of memory");
    else if (rc == 0 && in->n == 0) {
        no_frame_why(in, why, wl);
        rc = -1;
    }
    if (rc < 0) {
        can_logfile_input_free(in);
        return NULL;
    }
    if (in->n < in->cap) { /* kept for as long as its configuration: no slack */
        can_logfile_rec_t *r = realloc(in->rec, in->n * sizeof *r);
        if (r) {
            in->rec = r;
            in->cap = in->n;
        }
    }
    return in;
}

/* The end of the regular file at path (size bytes): *torn = the bytes
 * after its last newline (the head of a line a full disk cut; 0 if none of
 * the last CAN_LOGFILE_LINE_MAX bytes of a longer file is a newline: not a
 * candump log's tail), *last_us = the stamp of its last whole line if that
 * is a stamped frame, else INT64_MIN. */
static void read_tail(const char *path, long long size, long long *torn, int64_t *last_us)
{
    char buf[CAN_LOGFILE_LINE_MAX];
    size_t n = size < (long long)sizeof buf ? (size_t)size : sizeof buf, end = n;
    int fd = open(path, O_RDONLY | O_CLOEXEC); /* the output fd is write-only */
    ssize_t got = fd < 0 ? -1 : pread(fd, buf, n, (off_t)(size - (long long)n));
    *torn = 0;
    *last_us = INT64_MIN;
    if (fd >= 0)
        close(fd);
    if (n == 0 || got != (ssize_t)n)
        return;
    while (end > 0 && buf[end - 1] != '\n')
        end--;
    *torn = end > 0 ? (long long)(n - end) : (long long)n == size ? size : 0;
    if (end == 0)
        return;
    buf[end - 1] = '\0'; /* the last whole line, whole if it starts after a newline */
    char *line = memrchr(buf, '\n', end - 1);
    candump_line_t cl;
    if ((line || (long long)n == size) && candump_parse_line(line ? line + 1 : buf, &cl) == 0 &&
        (line ? line[1] : buf[0]) == '(')
        *last_us = cl.ts_us;
}

/* Open out_path ("-": stdout) for the output lines; appending, a torn last
 * line is cut off first so the next line starts on a line of its own. */
static int open_out(can_logfile_t *l, const char *out_path, int append, char *err, size_t errlen)
{
    struct stat sb;
    l->out_own = strcmp(out_path, "-") != 0;
    if (!l->out_own) {
        l->out_fd = STDOUT_FILENO;
        return 0;
    }
    /* O_APPEND always: a torn line is cut off the end (cut_torn), and the
     * next write must land there, not at an offset past it */
    int flags = O_WRONLY | O_CREAT | O_CLOEXEC | O_APPEND | (append ? 0 : O_TRUNC);
    l->out_fd = regfile_create(out_path, flags, 0644); /* the [daemon] user's if made here */
    if (l->out_fd < 0 || fstat(l->out_fd, &sb) < 0) {
        snprintf(err, errlen, "%s: %s", out_path, strerror(errno));
        return -1;
    }
    l->out_kept = S_ISREG(sb.st_mode) ? (long long)sb.st_size : -1;
    long long tail = 0;
    if (l->out_kept > 0)
        read_tail(out_path, l->out_kept, &tail, &l->out_last_us);
    if (tail > 0 && ftruncate(l->out_fd, (off_t)(l->out_kept - tail)) == 0) {
        log_msg(LOG_WARNING, "can: log_out %s: %lld bytes of a torn last line cut off", out_path,
                tail);
        l->out_kept -= tail;
    }
    return 0;
}

can_logfile_t *can_logfile_open_mode(const char *in_path, const char *out_path, const char *ifname,
                                     int64_t start_ns, int append, char *err, size_t errlen)
{
    char why[256];
    can_logfile_input_t *in = NULL;
    if (in_path && !(in = can_logfile_input_read(in_path, why, sizeof why))) {
        snprintf(err, errlen, "%s: %s", in_path, why);
        return NULL;
    }
    can_logfile_t *l = can_logfile_open_input(in, out_path, ifname, start_ns, append, err, errlen);
    if (!l) {
        can_logfile_input_free(in);
        return NULL;
    }
    if (in) { /* its own: freed with it */
        l->own = *in;
        l->in = &l->own;
        free(in);
    }
    return l;
}

can_logfile_t *can_logfile_open_input(const can_logfile_input_t *in, const char *out_path,
                                      const char *ifname, int64_t start_ns, int append, char *err,
                                      size_t errlen)
{
    /* its queue's counters are _Alignas(64) (spsc.h): more than malloc gives */
    can_logfile_t *l = aligned_alloc(_Alignof(can_logfile_t), sizeof *l);
    if (l)
        memset(l, 0, sizeof *l);
    if (!l) {
        snprintf(err, errlen, "out of memory");
        return NULL;
    }
    l->in = in ? in : &l->own;
    l->start_ns = start_ns;
    l->out_fd = -1;
    l->out_kept = -1;
    l->out_last_us = INT64_MIN;
    snprintf(l->ifname, sizeof l->ifname, "%s", ifname && *ifname ? ifname : "can0");
    if (out_path) {
        if (!(l->obuf = malloc(CAN_LOGFILE_OUT_BUF))) {
            snprintf(err, errlen, "out of memory");
            goto fail;
        }
        if (open_out(l, out_path, append, err, errlen) < 0)
            goto fail;
        int rc = spsc_init(&l->q, sizeof(can_logfile_rec_t), CAN_LOGFILE_QUEUE);
        if (rc == 0)
            rc = outworker_start(&l->w, writer, l, "trajd-canout");
        if (rc < 0) {
            snprintf(err, errlen, "%s: writer thread: %s", out_path, strerror(-rc));
            goto fail;
        }
    }
    return l;
fail:
    can_logfile_close(l);
    return NULL;
}

long long can_logfile_out_kept(const can_logfile_t *l)
{
    return l->out_kept;
}

int64_t can_logfile_out_last_us(const can_logfile_t *l)
{
    return l->out_last_us;
}

void can_logfile_finish(can_logfile_t *l)
{
    if (!l || !l->w.started)
        return;
    spsc_publish(&l->q);
    outworker_stop(&l->w); /* it takes every frame published, writes, then returns */
}

void can_logfile_close(can_logfile_t *l)
{
    if (!l)
        return;
    can_logfile_finish(l);
    spsc_fini(&l->q);
    if (l->out_own && l->out_fd >= 0)
        close(l->out_fd);
    free(l->obuf);
    free(l->own.rec);
    free(l);
}

int can_logfile_recv(can_logfile_t *l, int64_t now_ns, canproto_frame_t *f)
{
    const can_logfile_input_t *in = l->in;
    l->now_ns = now_ns;
    if (l->next >= in->n)
        return 0;
    /* due = start + (ts_k - ts_0) us; candump_parse_line bounds ts_us below
     * 1e18, so the difference fits, and the product is checked */
    int64_t d_us = in->rec[l->next].ts_us - in->rec[0].ts_us;
    int64_t due = d_us <= 0 ? l->start_ns /* stamped before the first: due with it */
                  : d_us > (INT64_MAX / 2 - l->start_ns) / 1000 ? INT64_MAX
                                                                : l->start_ns + d_us * 1000;
    if (due > now_ns)
        return 0;
    *f = in->rec[l->next++].f;
    return 1;
}

/* Where the input last kept stopped (one daemon per process). */
static struct {
    int set;
    size_t pos;
    char path[PATH_MAX];
} kept;

void can_logfile_keep_pos(const can_logfile_t *l, const char *path)
{
    kept.set = 1;
    kept.pos = l->next;
    snprintf(kept.path, sizeof kept.path, "%s", path);
}

size_t can_logfile_resume(can_logfile_t *l, const char *path)
{
    size_t pos = 0;
    if (kept.set && path && !strcmp(kept.path, path)) {
        pos = kept.pos < l->in->n ? kept.pos : l->in->n;
        l->next = pos;
    }
    kept.set = 0;
    return pos;
}

void can_logfile_set_time(can_logfile_t *l, int64_t now_ns)
{
    l->now_ns = now_ns;
}

void can_logfile_set_epoch(can_logfile_t *l, int64_t epoch_ns)
{
    l->epoch_ns = epoch_ns;
}

int can_logfile_send(can_logfile_t *l, const canproto_frame_t *f)
{
    if (l->out_fd < 0)
        return 0;
    can_logfile_rec_t *r = l->w.started ? spsc_slot(&l->q) : NULL;
    if (!r) { /* the writer is behind: the queue is full */
        l->st.frames_lost++;
        return -EIO;
    }
    r->ts_us = (l->now_ns + l->epoch_ns) / 1000;
    r->f = *f;
    spsc_push(&l->q);
    l->st.frames_out++;
    return 0;
}

int can_logfile_done(const can_logfile_t *l)
{
    return l->next >= l->in->n;
}

/* Lines (newlines) in buf[0..n). */
static uint64_t count_lines(const char *buf, size_t n)
{
    uint64_t k = 0;
    for (const char *p = buf, *end = buf + n; (p = memchr(p, '\n', (size_t)(end - p))); p++)
        k++;
    return k;
}

/* After a failed write: the head of the line a short write left in a
 * regular file (obuf[0..off) was written) is cut off again, so the file
 * ends with a whole line (opened O_APPEND: the next write lands there). */
static void cut_torn(can_logfile_t *l, size_t off)
{
    size_t head = 0;
    struct stat sb;
    while (head < off && l->obuf[off - head - 1] != '\n')
        head++;
    if (head && l->out_kept >= 0 && fstat(l->out_fd, &sb) == 0 && sb.st_size >= (off_t)head &&
        ftruncate(l->out_fd, sb.st_size - (off_t)head) < 0)
        atomic_store_explicit(&l->w_errno, errno, memory_order_relaxed);
}

/* The writer: what the buffer holds, without waiting for a slow reader
 * (EAGAIN: later); a failed write counts and its frames are lost. */
static void out_write(can_logfile_t *l)
{
    size_t off = 0;
    l->stalled = 0;
    while (l->out_fd >= 0 && off < l->olen) {
        ssize_t w = write(l->out_fd, l->obuf + off, l->olen - off);
        if (w > 0) {
            off += (size_t)w;
            continue;
        }
        if (w < 0 && errno == EINTR)
            continue;
        l->stalled = 1;
        if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            break; /* later; new frames are lost (counted) once the buffer is full */
        int e = w < 0 ? errno : EIO;
        atomic_store_explicit(&l->w_errno, e, memory_order_relaxed);
        cut_torn(l, off);
        atomic_fetch_add_explicit(&l->w_lost, count_lines(l->obuf + off, l->olen - off),
                                  memory_order_relaxed);
        atomic_fetch_add_explicit(&l->w_errors, 1, memory_order_relaxed);
        off = l->olen;
    }
    if (off) {
        memmove(l->obuf, l->obuf + off, l->olen - off);
        l->olen -= off;
    }
}

/* The writer: one queued frame as a line into the buffer (written first
 * when full, unless the last write stalled: then the frame is lost). */
static void out_line(can_logfile_t *l, const can_logfile_rec_t *r)
{
    char buf[256];
    int n = candump_format_line(buf, sizeof buf, r->ts_us, l->ifname, &r->f);
    if (n >= 0 && (size_t)n > CAN_LOGFILE_OUT_BUF - l->olen && !l->stalled)
        out_write(l);
    if (n < 0 || (size_t)n > CAN_LOGFILE_OUT_BUF - l->olen) {
        atomic_fetch_add_explicit(&l->w_lost, 1, memory_order_relaxed);
        return;
    }
    memcpy(l->obuf + l->olen, buf, (size_t)n);
    l->olen += (size_t)n;
}

static int queue_idle(void *arg)
{
    can_logfile_t *l = arg;
    return spsc_avail(&l->q) == 0;
}

static void *writer(void *arg)
{
    can_logfile_t *l = arg;
    for (;;) {
        int stop = outworker_stopping(&l->w);
        size_t n = spsc_avail(&l->q);
        for (size_t i = 0; i < n; i++)
            out_line(l, spsc_at(&l->q, i));
        spsc_release(&l->q, n);
        if (n || stop)
            out_write(l);
        if (stop)
            break;
        if (!n)
            outworker_wait(&l->w, queue_idle, l);
    }
    if (l->olen) { /* left unwritten at the end (a reader that stopped reading) */
        atomic_fetch_add_explicit(&l->w_lost, count_lines(l->obuf, l->olen), memory_order_relaxed);
        l->olen = 0;
    }
    return NULL;
}

void can_logfile_flush(can_logfile_t *l)
{
    if (!l->w.started)
        return;
    spsc_publish(&l->q);
    outworker_wake(&l->w);
}

void can_logfile_stats(const can_logfile_t *l, can_logfile_stats_t *st)
{
    can_logfile_t *m = (can_logfile_t *)l; /* atomic loads take a non-const pointer */
    *st = l->st;
    st->lines = l->in->st.lines;
    st->comments = l->in->st.comments;
    st->bad_lines = l->in->st.bad_lines;
    st->first_bad_line = l->in->st.first_bad_line;
    st->frames_in = l->in->st.frames_in;
    st->frames_lost += atomic_load_explicit(&m->w_lost, memory_order_relaxed);
    st->write_errors = atomic_load_explicit(&m->w_errors, memory_order_relaxed);
    st->last_errno = atomic_load_explicit(&m->w_errno, memory_order_relaxed);
}
