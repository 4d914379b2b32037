/*
 * trajctl.c - the operator's client of a running trajd, over its control
 * socket (daemon/ctl/ctl.h; the protocol: config/PROTOCOL.md "Control
 * socket"; the manual: trajctl(1)).
 *
 *   trajctl status [-w] [OBJECT]        a table of objects (-w: refreshed)
 *   trajctl stop|start|clear OBJECT     commands (the object must be writable)
 *   trajctl override N OBJECT           feed override, N percent (0 .. 200)
 *   trajctl watch [--spark] OBJECT      every setpoint, as trajd's CSV, or a sparkline
 *   trajctl reload                      re-read trajd's configuration
 *   trajctl check FILE                  trajd --check-config FILE
 *
 * Exit statuses (sysexits.h): 0; 1 trajd refused; EX_USAGE; EX_UNAVAILABLE
 * no trajd reachable; EX_IOERR setpoints lost by a watch; EX_PROTOCOL; EX_NOPERM;
 * EX_CONFIG (check: the file is invalid).
 */
#include <errno.h>
#include <getopt.h>
#include <grp.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sysexits.h>
#include <time.h>
#include <unistd.h>

#include "csv_format.h"
#include "ctl.h"
#include "version.h"

#define EXIT_REFUSED 1
#define ANSWER_TIMEOUT_MS 10000 /* a request's answer (a reload may load tracks) */

typedef struct {
    const char *socket;
    const char *instance;
    int watch;         /* status -w */
    double interval_s; /* status -w period */
    long long count;   /* watch: stop after this many setpoints (0 = never) */
    int spark;         /* watch --spark */
    int header;        /* watch: the CSV header line */
    int age;           /* watch --age: the age_s column */
    char path[108];    /* the socket used */
    int fd;
    char buf[1 << 16]; /* received, not yet consumed */
    size_t len, off;
} trajctl_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: trajctl [-s SOCKET | -i NAME] COMMAND [ARGS]\n"
            "The operator's client of a running trajd (trajctl(1)).\n"
            "Commands:\n"
            "  status [OBJECT]        a table of the objects: state, t_s, delay, speed,\n"
            "                         override, counters, health\n"
            "  stop OBJECT            bring OBJECT to rest along its path\n"
            "  start OBJECT           release OBJECT's stop (the waypoints that came\n"
            "                         meanwhile, reached by a transfer), or start a waiting\n"
            "                         OBJECT with the waypoints it holds\n"
            "  clear OBJECT           clear OBJECT (and a feed hold or safety fault)\n"
            "  override N OBJECT      feed override, N percent (0 to 200)\n"
            "  watch OBJECT           every setpoint of OBJECT as CSV, as trajd writes it\n"
            "  reload                 re-read trajd's configuration (as SIGHUP)\n"
            "  check FILE             check a configuration file (trajd --check-config)\n"
            "Options:\n"
            "  -s, --socket PATH      trajd's control socket (default: " CTL_RUN_DIR "/control,\n"
            "                         else $XDG_RUNTIME_DIR/trajd/control)\n"
            "  -i, --instance NAME    the socket of trajd@NAME (" CTL_RUN_DIR "/NAME/control)\n"
            "  -w, --watch            status: refresh the table, as watch(1) does\n"
            "  -n, --interval SECS    status --watch: seconds between refreshes (1)\n"
            "  -c, --count N          watch: stop after N setpoints\n"
            "      --spark            watch: a sparkline of the speed instead of CSV\n"
            "      --age              watch: add trajd's age_s column\n"
            "      --no-header        watch: no CSV header line\n"
            "  -V, --version          print the version\n"
            "  -h, --help             this text\n"
            "Exit status: 0; 1 trajd refused; 64 usage; 69 trajd unreachable; 74 setpoints\n"
            "lost by a watch; 76 protocol; 77 permission denied; 78 invalid config (check).\n");
}

/* ---- a flat JSON line: the value of "key" ---- */

static const char *jget(const char *line, const char *key)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\":", key);
    const char *p = strstr(line, pat);
    return p ? p + strlen(pat) : NULL;
}

static double jnum(const char *line, const char *key)
{
    const char *v = jget(line, key);
    return v && strncmp(v, "null", 4) != 0 ? strtod(v, NULL) : NAN;
}

static long long jint(const char *line, const char *key)
{
    const char *v = jget(line, key);
    return v ? strtoll(v, NULL, 10) : 0;
}

/* A string value, unescaped (\" \\ \uXXXX below 0x80), into out; "" if absent. */
static const char *jstr(const char *line, const char *key, char *out, size_t len)
{
    const char *v = jget(line, key);
    size_t n = 0;
    out[0] = 0;
    if (!v || *v != '"')
        return out;
    for (v++; *v && *v != '"' && n + 1 < len; v++) {
        if (*v == '\\' && v[1] == 'u' && strlen(v) >= 6) {
            out[n++] = (char)strtol((char[]){v[4], v[5], 0}, NULL, 16);
            v += 5;
            continue;
        }
        if (*v == '\\' && v[1])
            v++;
        out[n++] = *v;
    }
    out[n] = 0;
    return out;
}

/* [a,b,c] into x[3] (null: NaN); 0, or -1 if malformed. */
static int jarr3(const char *line, const char *key, double x[3])
{
    const char *v = jget(line, key);
    if (!v || *v != '[')
        return -1;
    v++;
    for (int a = 0; a < 3; a++) {
        char *end;
        if (strncmp(v, "null", 4) == 0) {
            x[a] = NAN;
            end = (char *)v + 4;
        } else {
            x[a] = strtod(v, &end);
            if (end == v)
                return -1;
        }
        v = end + (*end == ',' || *end == ']');
    }
    return 0;
}

/* ---- the connection ---- */

/* The socket: -s, -i, $TRAJCTL_SOCKET, then where trajd puts it by default. */
static void pick_socket(trajctl_t *c)
{
    const char *xdg = getenv("XDG_RUNTIME_DIR"), *env = getenv("TRAJCTL_SOCKET");
    struct stat st;
    if (c->socket)
        snprintf(c->path, sizeof c->path, "%s", c->socket);
    else if (c->instance)
        snprintf(c->path, sizeof c->path, CTL_RUN_DIR "/%s/" CTL_SOCKET_NAME, c->instance);
    else if (env && env[0])
        snprintf(c->path, sizeof c->path, "%s", env);
    else if (stat(CTL_RUN_DIR "/" CTL_SOCKET_NAME, &st) == 0 || !xdg || xdg[0] != '/')
        snprintf(c->path, sizeof c->path, CTL_RUN_DIR "/" CTL_SOCKET_NAME);
    else
        snprintf(c->path, sizeof c->path, "%.80s/trajd/" CTL_SOCKET_NAME, xdg);
}

/* The next line (without '\n'), waiting at most timeout_ms (-1: for ever);
 * NULL at the end of the connection or on time-out (errno ETIMEDOUT). */
static char *read_line(trajctl_t *c, int timeout_ms)
{
    for (;;) {
        char *nl = memchr(c->buf + c->off, '\n', c->len - c->off);
        if (nl) {
            char *line = c->buf + c->off;
            *nl = 0;
            c->off = (size_t)(nl + 1 - c->buf);
            return line;
        }
        if (c->off) {
            memmove(c->buf, c->buf + c->off, c->len - c->off);
            c->len -= c->off;
            c->off = 0;
        }
        if (c->len == sizeof c->buf - 1) {
            errno = EPROTO;
            return NULL;
        }
        struct pollfd p = {c->fd, POLLIN, 0};
        int rc = poll(&p, 1, timeout_ms);
        if (rc == 0) {
            errno = ETIMEDOUT;
            return NULL;
        }
        if (rc < 0 && errno == EINTR)
            continue;
        ssize_t r = rc < 0 ? -1 : read(c->fd, c->buf + c->len, sizeof c->buf - 1 - c->len);
        if (r <= 0) {
            errno = r == 0 ? ECONNRESET : errno;
            return NULL;
        }
        c->len += (size_t)r;
    }
}

static int unreachable(const trajctl_t *c, const char *why)
{
    fprintf(stderr,
            "trajctl: cannot reach trajd at %s: %s\n"
            "trajctl: is trajd running? (-s PATH or -i NAME name another socket)\n",
            c->path, why);
    return EX_UNAVAILABLE;
}

static int denied(const trajctl_t *c)
{
    struct stat st;
    char grp[64] = "its group";
    if (stat(c->path, &st) == 0) {
        const struct group *g = getgrgid(st.st_gid);
        if (g)
            snprintf(grp, sizeof grp, "group '%s'", g->gr_name);
        else
            snprintf(grp, sizeof grp, "group %u", (unsigned)st.st_gid);
    }
    fprintf(stderr,
            "trajctl: permission denied on %s: trajd's control socket admits its owner and "
            "%s (mode 0660, [daemon] control_group); ask to be added to it, or run as root\n",
            c->path, grp);
    return EX_NOPERM;
}

/* Connect and read the greeting: 0 or the exit status (its message printed). */
static int connect_ctl(trajctl_t *c)
{
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    pick_socket(c);
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", c->path);
    c->fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (c->fd < 0)
        return unreachable(c, strerror(errno));
    if (connect(c->fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        if (errno == EACCES || errno == EPERM)
            return denied(c);
        return unreachable(c, errno == ECONNREFUSED ? "nobody listens there (a stale socket)"
                                                    : strerror(errno));
    }
    char *line = read_line(c, ANSWER_TIMEOUT_MS);
    if (!line)
        return unreachable(c, errno == ETIMEDOUT ? "no answer" : "it closed the connection");
    char v[256];
    if (strcmp(jstr(line, "reply", v, sizeof v), "hello") != 0) {
        return unreachable(c, strcmp(v, "error") == 0 ? jstr(line, "message", v, sizeof v)
                                                      : "not trajd's greeting");
    }
    return 0;
}

static int send_line(trajctl_t *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int send_line(trajctl_t *c, const char *fmt, ...)
{
    char req[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(req, sizeof req - 1, fmt, ap);
    va_end(ap);
    if (n < 0 || n >= (int)sizeof req - 1)
        return -1;
    req[n++] = '\n';
    return send(c->fd, req, (size_t)n, MSG_NOSIGNAL) == n ? 0 : -1;
}

/* The answer to a request: a line, or NULL with the exit status in *rc (printed). */
static char *answer(trajctl_t *c, int *rc)
{
    char *line = read_line(c, ANSWER_TIMEOUT_MS);
    if (!line) {
        *rc = unreachable(c, errno == ETIMEDOUT ? "no answer" : "the connection was lost");
        return NULL;
    }
    return line;
}

/* An error reply: its message printed; EXIT_REFUSED, or 0 if the line is not one. */
static int refused(const char *line)
{
    char v[600], code[32];
    if (strcmp(jstr(line, "reply", v, sizeof v), "error") != 0)
        return 0;
    fprintf(stderr, "trajctl: trajd refused (%s): %s\n", jstr(line, "error", code, sizeof code),
            jstr(line, "message", v, sizeof v));
    return EXIT_REFUSED;
}

/* The next answer if it is "ok", else NULL with *rc the exit status (unreachable,
 * refused, or an answer not understood). */
static char *answer_ok(trajctl_t *c, int *rc)
{
    char v[64];
    char *line = answer(c, rc);
    if (!line)
        return NULL;
    if ((*rc = refused(line)) != 0)
        return NULL;
    if (strcmp(jstr(line, "reply", v, sizeof v), "ok") != 0) {
        fprintf(stderr, "trajctl: unexpected answer: %.200s\n", line);
        *rc = EX_PROTOCOL;
        return NULL;
    }
    return line;
}

/* ---- commands ---- */

static int cmd_simple(trajctl_t *c, char **argv, int argc)
{
    int rc = 0;
    if (argc == 3)
        rc = send_line(c, "%s %s %s", argv[0], argv[1], argv[2]);
    else if (argc == 2)
        rc = send_line(c, "%s %s", argv[0], argv[1]);
    else
        rc = send_line(c, "%s", argv[0]);
    if (rc < 0)
        return unreachable(c, "the connection was lost");
    char *line = answer_ok(c, &rc);
    if (!line)
        return rc;
    return 0;
}

static void fmt_s(char *out, size_t len, double x, const char *unit)
{
    if (isnan(x))
        snprintf(out, len, "-");
    else
        snprintf(out, len, "%.3f%s", x, unit);
}

static void print_head(const char *l)
{
    char v[128], cfgp[256];
    printf("trajd %s pid %lld, up %.1f s, %g Hz, %lld objects%s; config %s\n",
           jstr(l, "trajd", v, sizeof v), jint(l, "pid"), jnum(l, "uptime_s"), jnum(l, "rate_hz"),
           jint(l, "objects"),
           strncmp(jget(l, "stopping") ? jget(l, "stopping") : "f", "true", 4) == 0 ? ", STOPPING"
                                                                                    : "",
           jstr(l, "config", cfgp, sizeof cfgp));
    printf("ticks %lld, missed %lld, overruns %lld, late p99 %lld us (max %lld), lines lost %lld, "
           "%lld clients, watch setpoints lost %lld, log lines dropped %lld\n",
           jint(l, "ticks"), jint(l, "missed_ticks"), jint(l, "overruns"), jint(l, "late_p99_us"),
           jint(l, "late_max_us"), jint(l, "out_lost"), jint(l, "clients"), jint(l, "watch_lost"),
           jint(l, "log_dropped"));
    printf("%-12s %4s %-9s %10s %9s %8s %8s %8s %8s %4s %4s %7s %5s %5s %5s  %s\n", "OBJECT", "ID",
           "STATE", "T_S", "SPEED", "AGE", "DELAY", "LAG", "AHEAD", "OVR%", "BUF", "ACCEPT", "REJ",
           "UNDR", "LOST", "HEALTH");
}

static void print_obj(const char *l)
{
    char name[64], state[16], lc[16], hl[128], t[32], sp[32], age[32], d[32], lag[32], ah[32];
    /* the owner's state where the engine's does not tell it (a latched stop
     * reads "finished" there, a hold "streaming": lib/engine/LIFECYCLE.md) */
    jstr(l, "state", state, sizeof state);
    jstr(l, "lifecycle", lc, sizeof lc);
    if (!strcmp(lc, "stopping") || !strcmp(lc, "stopped") || !strcmp(lc, "held") ||
        !strcmp(lc, "transfer"))
        snprintf(state, sizeof state, "%s", lc);
    fmt_s(t, sizeof t, jnum(l, "t_s"), "");
    fmt_s(sp, sizeof sp, jnum(l, "speed"), "");
    fmt_s(age, sizeof age, jnum(l, "age_s"), "");
    fmt_s(d, sizeof d, jnum(l, "delay_s"), "");
    fmt_s(lag, sizeof lag, jnum(l, "lag_s"), "");
    fmt_s(ah, sizeof ah, jnum(l, "ahead_s"), "");
    jstr(l, "health", hl, sizeof hl);
    printf("%-12s %4lld %-9s %10s %9s %8s %8s %8s %8s %4.0f %4lld %7lld %5lld %5lld %5lld  %s%s\n",
           jstr(l, "object", name, sizeof name), jint(l, "id"), state, t, sp, age, d, lag, ah,
           jnum(l, "override") * 100, jint(l, "buffered"), jint(l, "accepted"), jint(l, "rejected"),
           jint(l, "underruns"), jint(l, "out_lost"), hl[0] ? hl : "ok",
           strncmp(jget(l, "writable") ? jget(l, "writable") : "f", "true", 4) == 0
               ? ""
               : " (read-only)");
}

/* One status table: 0 or the exit status. */
static int status_once(trajctl_t *c, const char *object)
{
    int rc = object ? send_line(c, "status %s", object) : send_line(c, "status");
    char v[32];
    if (rc < 0)
        return unreachable(c, "the connection was lost");
    for (int first = 1;; first = 0) {
        char *line = answer(c, &rc);
        if (!line)
            return rc;
        if ((rc = refused(line)) != 0)
            return rc;
        jstr(line, "reply", v, sizeof v);
        if (first && strcmp(v, "status") != 0) {
            fprintf(stderr, "trajctl: unexpected answer: %.200s\n", line);
            return EX_PROTOCOL;
        }
        if (strcmp(v, "end") == 0)
            return 0;
        if (first)
            print_head(line);
        else
            print_obj(line);
    }
}

static int cmd_status(trajctl_t *c, const char *object)
{
    if (!c->watch)
        return status_once(c, object);
    for (;;) {
        printf("\033[H\033[2J");
        int rc = status_once(c, object);
        fflush(stdout);
        if (rc)
            return rc;
        struct timespec ts = {(time_t)c->interval_s,
                              (long)((c->interval_s - floor(c->interval_s)) * 1e9)};
        nanosleep(&ts, NULL);
    }
}

/* A setpoint line into sp; 0, or -1 if malformed. */
static int parse_sp(const char *l, engine_setpoint_t *sp)
{
    static const char *const states[] = {"waiting", "streaming", "underrun", "finished"};
    char st[16];
    memset(sp, 0, sizeof *sp);
    sp->now_ns = jint(l, "now_ns");
    sp->t_s = jnum(l, "t_s");
    if (jarr3(l, "pos", sp->pos_m) < 0 || jarr3(l, "vel", sp->vel_m_s) < 0 ||
        jarr3(l, "acc", sp->acc_m_s2) < 0)
        return -1;
    jstr(l, "state", st, sizeof st);
    for (unsigned k = 0; k < 4; k++)
        if (strcmp(st, states[k]) == 0)
            sp->state = (engine_state_t)k;
    sp->flags = (uint32_t)jint(l, "flags");
    sp->cycle = (uint32_t)jint(l, "cycle");
    sp->track = (uint32_t)jint(l, "track");
    sp->age_s = jnum(l, "age_s");
    return 0;
}

/* --spark: one character per tenth of a second (the fastest speed in it),
 * scaled to the fastest in view, redrawn on one line. */
typedef struct {
    char cols[200];
    unsigned ncols, width, per, n;
    double bucket, vals[200], top;
} spark_t;

static void spark_add(spark_t *s, const char *name, const engine_setpoint_t *sp)
{
    static const char *const bars[] = {"▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"};
    double v = sqrt(sp->vel_m_s[0] * sp->vel_m_s[0] + sp->vel_m_s[1] * sp->vel_m_s[1] +
                    sp->vel_m_s[2] * sp->vel_m_s[2]);
    if (isfinite(v) && v > s->bucket)
        s->bucket = v;
    if (++s->n < s->per)
        return;
    if (s->ncols == s->width) {
        memmove(s->vals, s->vals + 1, (s->width - 1) * sizeof *s->vals);
        s->ncols--;
    }
    s->vals[s->ncols++] = s->bucket;
    s->n = 0;
    s->bucket = 0;
    s->top = 0;
    for (unsigned i = 0; i < s->ncols; i++)
        s->top = fmax(s->top, s->vals[i]);
    printf("\r%s ", name);
    for (unsigned i = 0; i < s->ncols; i++)
        fputs(bars[s->top > 0 ? (int)fmin(7, s->vals[i] / s->top * 7.999) : 0], stdout);
    printf(" %.2f m/s (top %.2f) ", s->vals[s->ncols - 1], s->top);
    fflush(stdout);
}

/* The lines of a watch after its "ok"; the exit status. */
static int watch_loop(trajctl_t *c, const char *name, double rate_hz)
{
    char row[CSV_FORMAT_LINE_MAX + 64], v[64];
    unsigned long long lost = 0;
    long long n = 0;
    spark_t sk = {.width = 60, .per = rate_hz >= 10 ? (unsigned)(rate_hz / 10) : 1};
    if (!c->spark && c->header) {
        int k = csv_format_header(row, sizeof row);
        if (c->age)
            k = csv_format_add_age(row, sizeof row, k, NULL);
        fwrite(row, 1, (size_t)k, stdout);
    }
    while (!c->count || n < c->count) {
        char *l = read_line(c, -1);
        if (!l) {
            fflush(stdout);
            fprintf(stderr, "trajctl: trajd closed the connection after %lld setpoints\n", n);
            return EX_UNAVAILABLE;
        }
        if (jget(l, "overflow")) {
            lost += (unsigned long long)jint(l, "lost");
            fprintf(stderr,
                    "trajctl: %lld setpoints of '%s' lost here (%llu in all): read too slowly, "
                    "trajd's ring of %lld for this watch was full\n",
                    jint(l, "lost"), name, lost, jint(l, "ring"));
            continue;
        }
        if (!jget(l, "sp")) {
            fflush(stdout);
            jstr(l, "reply", v, sizeof v);
            if (strcmp(v, "bye") == 0 || strcmp(v, "end") == 0) {
                fprintf(stderr, "trajctl: watch of '%s' ended: %s\n", name,
                        jstr(l, "why", row, sizeof row));
                return lost ? EX_IOERR : 0;
            }
            fprintf(stderr, "trajctl: unexpected line: %.200s\n", l);
            return EX_PROTOCOL;
        }
        engine_setpoint_t sp;
        if (parse_sp(l, &sp) < 0) {
            fprintf(stderr, "trajctl: malformed setpoint: %.200s\n", l);
            return EX_PROTOCOL;
        }
        n++;
        if (c->spark) {
            spark_add(&sk, name, &sp);
            continue;
        }
        int k = csv_format_format(row, sizeof row, name, &sp);
        if (k > 0 && c->age)
            k = csv_format_add_age(row, sizeof row, k, &sp);
        if (k > 0)
            fwrite(row, 1, (size_t)k, stdout);
        if (c->off == c->len)
            fflush(stdout); /* nothing more received yet: show what we have */
    }
    fflush(stdout);
    return lost ? EX_IOERR : 0;
}

static int cmd_watch(trajctl_t *c, const char *object)
{
    int rc;
    char v[64];
    if (send_line(c, "watch %s", object) < 0)
        return unreachable(c, "the connection was lost");
    char *line = answer_ok(c, &rc);
    if (!line)
        return rc;
    return watch_loop(c, jstr(line, "object", v, sizeof v), jnum(line, "rate_hz"));
}

/* check FILE: the trajd beside this program (else on PATH) checks it. */
static int cmd_check(const char *file)
{
    char self[PATH_MAX], trajd[PATH_MAX + 8];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    fflush(stdout);
    if (n > 0) {
        self[n] = 0;
        char *slash = strrchr(self, '/');
        if (slash) {
            *slash = 0;
            snprintf(trajd, sizeof trajd, "%s/trajd", self);
            if (access(trajd, X_OK) == 0)
                execl(trajd, "trajd", "--check-config", file, (char *)NULL);
        }
    }
    execlp("trajd", "trajd", "--check-config", file, (char *)NULL);
    fprintf(stderr, "trajctl: cannot run trajd --check-config: %s\n", strerror(errno));
    return EX_UNAVAILABLE;
}

/* Options into c; the index of the command word, or -(exit status + 1). */
static int parse_args(int argc, char **argv, trajctl_t *c)
{
    enum { O_SPARK = 256, O_AGE, O_NOHEADER };
    static const struct option opts[] = {
        {"socket", required_argument, NULL, 's'},
        {"instance", required_argument, NULL, 'i'},
        {"watch", no_argument, NULL, 'w'},
        {"interval", required_argument, NULL, 'n'},
        {"count", required_argument, NULL, 'c'},
        {"spark", no_argument, NULL, O_SPARK},
        {"age", no_argument, NULL, O_AGE},
        {"no-header", no_argument, NULL, O_NOHEADER},
        {"version", no_argument, NULL, 'V'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    int o;
    char *end;
    while ((o = getopt_long(argc, argv, "s:i:wn:c:Vh", opts, NULL)) != -1) {
        switch (o) {
        case 's': c->socket = optarg; break;
        case 'i': c->instance = optarg; break;
        case 'w': c->watch = 1; break;
        case 'n':
            c->interval_s = strtod(optarg, &end);
            if (*end || !(c->interval_s >= 0.1 && c->interval_s <= 3600)) {
                fprintf(stderr, "trajctl: --interval: seconds, 0.1 to 3600\n");
                return -(EX_USAGE + 1);
            }
            break;
        case 'c':
            c->count = strtoll(optarg, &end, 10);
            if (*end || c->count < 1) {
                fprintf(stderr, "trajctl: --count: a number of setpoints, at least 1\n");
                return -(EX_USAGE + 1);
            }
            break;
        case O_SPARK: c->spark = 1; break;
        case O_AGE: c->age = 1; break;
        case O_NOHEADER: c->header = 0; break;
        case 'V': printf("trajctl %s\n", TRAJD_VERSION); return -1;
        case 'h': usage(stdout); return -1;
        default: usage(stderr); return -(EX_USAGE + 1);
        }
    }
    return optind;
}

/* 1 if text is a whole percent 0 .. 200 (override's N) */
static int percent_ok(const char *text)
{
    char *end;
    long v = strtol(text, &end, 10);
    return *text && !*end && text[0] != '+' && text[0] != ' ' && v >= 0 && v <= 200;
}

/* An override's N that is not a whole percent 0 .. 200: said, EX_USAGE. */
static int bad_percent(const char *text)
{
    fprintf(stderr, "trajctl: override N OBJECT: N is a whole percent, 0 to 200, got '%s'\n", text);
    return EX_USAGE;
}

/* The command's words: the exit status. */
static int run(trajctl_t *c, char **w, int n)
{
    static const struct {
        const char *name;
        int words; /* with the command */
    } cmds[] = {{"status", 1},   {"stop", 2},  {"start", 2}, {"clear", 2},
                {"override", 3}, {"watch", 2}, {"reload", 1}};
    if (n == 2 && strcmp(w[0], "check") == 0)
        return cmd_check(w[1]);
    for (unsigned k = 0; k < sizeof cmds / sizeof *cmds; k++) {
        if (strcmp(w[0], cmds[k].name) != 0)
            continue;
        if (n != cmds[k].words && !(k == 0 && n == 2))
            break;
        if (strcmp(w[0], "override") == 0 && !percent_ok(w[1]))
            return bad_percent(w[1]);
        int rc = connect_ctl(c);
        if (rc)
            return rc;
        if (k == 0)
            return cmd_status(c, n == 2 ? w[1] : NULL);
        if (strcmp(w[0], "watch") == 0)
            return cmd_watch(c, w[1]);
        return cmd_simple(c, w, n);
    }
    fprintf(stderr, "trajctl: bad command line: '%s'%s\n", w[0],
            n > 1 ? " (or its arguments)" : "");
    usage(stderr);
    return EX_USAGE;
}

int main(int argc, char **argv)
{
    static trajctl_t c = {.fd = -1, .interval_s = 1, .header = 1};
    /* override -1 OBJECT: a value, not an option (getopt would take it for one) */
    for (int k = 1; k + 1 < argc; k++)
        if (strcmp(argv[k], "override") == 0 && argv[k + 1][0] == '-' && argv[k + 1][1] &&
            strchr("0123456789.", argv[k + 1][1]))
            return bad_percent(argv[k + 1]);
    int i = parse_args(argc, argv, &c);
    if (i < 0)
        return -i - 1;
    if (i >= argc) {
        fprintf(stderr, "trajctl: a command is needed\n");
        usage(stderr);
        return EX_USAGE;
    }
    signal(SIGPIPE, SIG_DFL);
    int rc = run(&c, argv + i, argc - i);
    if (c.fd >= 0)
        close(c.fd);
    return rc;
}
