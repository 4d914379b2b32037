/*
 * trajd.c - the daemon's main: command line, signals, systemd notify,
 * reload.  Everything else is in core.c and the transports; this file only
 * wires them together.
 *
 * Signals (signalfd, in the loop):
 *   SIGHUP           re-read the config on a worker thread (cfgload.h) while the
 *                    old one ticks on; a bad one is refused, the old keeps running
 *                    (reload.h: what happens to each object); objects it removes
 *                    brake to rest first, and SIGHUPs arriving meanwhile (or while
 *                    it is read, or in one batch) are coalesced into one more
 *                    reload after it; the clock keeps its phase across the swap
 *   SIGUSR1, SIGUSR2, SIGALRM  logged and ignored (their default would end
 *                    trajd with its objects moving)
 *   SIGTERM, SIGINT  stop policy of core.h (bring objects to rest, exit 0), a reload
 *                    being read dropped; a second one exits at once (0); while
 *                    the config is first read: its parse cancelled, exit 0
 * Exit status: 0; EX_USAGE, EX_CONFIG, EX_UNAVAILABLE (cannot start), EX_OSERR,
 * EX_SOFTWARE; CORE_EXIT_OUTPUT_LOST (74) if any setpoint line was lost by an
 * output or a setpoint cycle with a position not sent on the CAN bus;
 * CORE_EXIT_EPIPE (141) when stdout's reader went away; CORE_EXIT_NO_INPUT
 * (65) if a replayed track or log_in had no usable waypoint; CORE_EXIT_HELD (75)
 * if an object ended held (safety fault, drive fault, lost heartbeat, or stopped
 * and latched by the per-axis limits: axis_lag_stops, axis_beyond).
 * Control socket (daemon/ctl/ctl.h, for trajctl): opened before privileges
 * drop, kept across reloads (each new core is handed to it), closed last.
 * systemd (sd_notify; no-ops without NOTIFY_SOCKET):
 *   READY=1 once every input and output is open and the clock runs;
 *   RELOADING=1 ... READY=1 around a reload; STOPPING=1 at SIGTERM;
 *   WATCHDOG=1 from a loop timer at half of WATCHDOG_USEC;
 *   STATUS=<the status line> every [daemon] status_interval_s.
 */
#include <errno.h>
#include <math.h>
#include <getopt.h>
#include <grp.h>
#include <poll.h>
#include <pwd.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/signalfd.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <sysexits.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include "cfg.h"
#include "cfgload.h"
#include "core.h"
#include "ctl.h"
#include "fdlimit.h"
#include "grave.h"
#include "log.h"
#include "loop.h"
#include "regfile.h"
#include "reload.h"
#include "rt.h"
#include "stdfds.h"
#include "version.h"

#define TRAJD_DEFAULT_CONF "/etc/trajd/trajd.conf"

typedef struct {
    const char *conf_path;
    loop_t *loop;
    cfg_t *cfg;
    core_t *core;
    stats_t stats;
    int sig_fd;
    int status_fd; /* 1 s housekeeping timer */
    int watchdog_fd;
    uint64_t seconds;            /* housekeeping ticks */
    int signals_seen;            /* SIGTERM/SIGINT count */
    uint64_t lost_said;          /* output lines lost as the exit line counted them */
    int ready_fd;                /* background mode: pipe to the waiting parent, else -1 */
    cfg_t *pending;              /* a reload waiting for the objects it removes to rest */
    int pending_fd;              /* its timer (-1: none) */
    int64_t pending_deadline_ns; /* CLOCK_MONOTONIC: swap anyway after stop_timeout_s */
    int hup_again;               /* SIGHUP while loading or pending: read the config again after */
    cfgload_t *load;             /* a reload being read and checked on its worker, or NULL */
    uint64_t reloads;            /* SIGHUPs acted on */
    uint64_t reloads_failed;     /* of those, refused (bad config, cannot open) */
    ctl_t *ctl;                  /* the control socket (trajctl), NULL if it could not open */
} trajd_t;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: trajd [-f] [-c FILE]\n"
            "       trajd --check-config [FILE]   (or: trajd -c FILE --check-config)\n"
            "Real-time trajectory interpolation daemon.\n"
            "  -c, --config FILE     configuration (default " TRAJD_DEFAULT_CONF ")\n"
            "  -f, --foreground      stay in the foreground (as under systemd);\n"
            "                        without it trajd detaches once it is ready\n"
            "      --check-config [FILE]  check FILE (none: the -c one), print the first\n"
            "                        error as file:line, exit\n"
            "  -V, --version         print the version\n"
            "  -h, --help            this text\n"
            "Signals: SIGHUP reloads the config, SIGTERM/SIGINT bring objects to rest and exit.\n");
}

/* The status line: core_summary, then the reload counts. */
static void status_line(const trajd_t *d, char *line, size_t len)
{
    int n = core_summary(d->core, line, len);
    if (n >= 0 && (size_t)n < len && d->reloads)
        snprintf(line + n, len - (size_t)n, ", reloads %llu (%llu failed)",
                 (unsigned long long)d->reloads, (unsigned long long)d->reloads_failed);
}

static void notify_status(trajd_t *d)
{
    char line[1024];
    status_line(d, line, sizeof line);
    sd_notifyf(0, "STATUS=%s", line);
}

static void on_second(loop_t *l, uint64_t exp, void *ctx)
{
    trajd_t *d = ctx;
    (void)l;
    if (!d->core)
        return; /* a failed reload is ending the loop */
    d->seconds += exp;
    core_stats_roll(d->core);
    ctl_housekeeping(d->ctl);
    double iv = d->cfg->daemon.status_interval_s;
    if (iv > 0) {
        uint64_t every = iv < 1 ? 1 : (uint64_t)iv;
        if (d->seconds % every < exp) {
            char line[1024];
            status_line(d, line, sizeof line);
            log_msg(LOG_INFO, "status: %s", line);
            sd_notifyf(0, "STATUS=%s", line);
        }
    }
    if (d->core->stopping && core_done(d->core))
        loop_stop(d->loop, 0); /* stop timeout passed while no tick ran */
}

static void on_watchdog(loop_t *l, uint64_t exp, void *ctx)
{
    (void)l;
    (void)exp;
    (void)ctx;
    sd_notify(0, "WATCHDOG=1");
}

/* Open cfg (replacing d->core if there is one, see core_open) and start its clock. */
/* The output clock of d's core (core_start): at once for a reload (start_core's
 * clock), last of all at the first start (run), as start-up work that grows with
 * the objects (a line each) would pass its first deadlines.  On failure the core goes. */
static int start_clock(trajd_t *d, char *why, size_t wl)
{
    int rc = core_start(d->core);
    if (rc < 0) {
        snprintf(why, wl, "output clock: %s", strerror(-rc));
        core_close(d->core);
        d->core = NULL;
        if (d->ctl)
            ctl_set_core(d->ctl, NULL);
    }
    return rc;
}

static int start_core(trajd_t *d, cfg_t *cfg, char *why, size_t wl, int clock)
{
    char rtwhy[256];
    core_t *nc = NULL;
    const cfg_rt_t *was = d->core ? &d->cfg->rt : NULL; /* a reload: the running one's */
    int rt_same = was && was->fifo_priority == cfg->rt.fifo_priority &&
                  was->mlockall == cfg->rt.mlockall && was->affinity_set == cfg->rt.affinity_set &&
                  CPU_EQUAL(&was->affinity, &cfg->rt.affinity);
    fdlimit_t f;
    char fdwhy[320];
    fdlimit_of(cfg, &f);
    int fit = fdlimit_fit(&f, fdwhy, sizeof fdwhy);
    if (fit)
        log_msg(fit < 0 ? LOG_ERR : LOG_WARNING, "%s", fdwhy);
    int rc = core_open(d->loop, cfg, &d->stats, &d->core, &nc, why, wl);
    if (rc < 0) {
        if (d->ctl && !d->core) /* the old core was closed: none runs now */
            ctl_set_core(d->ctl, NULL);
        return rc;
    }
    d->core = nc;
    if (d->ctl)
        ctl_set_core(d->ctl, d->core);
    /* before the clock starts: mlockall faults every page in (seconds for
     * 1024 objects), which must not count as ticks missed.  A reload keeps
     * the clock's phase (core_start): applied again only if [realtime] changed */
    if (!rt_same && rt_apply(&cfg->rt, rtwhy, sizeof rtwhy) < 0)
        log_msg(LOG_WARNING, "realtime settings not applied (running without them): %s", rtwhy);
    if (clock && (rc = start_clock(d, why, wl)) < 0)
        return rc;
    log_set_level(cfg->daemon.log_level);
    return 0;
}

/*
 * Started as root: once every socket and file is open, become [daemon] user
 * (its groups, then its gid, then its uid; checked: root cannot be regained).
 * Without a user, warn loudly unless systemd started us (its unit decides
 * the user: User=, DynamicUser=).  Returns 0, or -1 with why (then trajd
 * does not go on as root against its configuration).
 */
static int drop_privileges(const cfg_t *cfg, char *why, size_t wl)
{
    if (geteuid() != 0)
        return 0;
    if (!cfg->daemon.user[0]) {
        if (!getenv("INVOCATION_ID"))
            log_msg(LOG_WARNING,
                    "RUNNING AS ROOT: every Modbus/CAN peer talks to a root process; set "
                    "[daemon] user = <name> to drop to it once the sockets are open");
        return 0;
    }
    errno = 0;
    struct passwd *pw = getpwnam(cfg->daemon.user);
    if (!pw) {
        snprintf(why, wl, "[daemon] user %s: %s", cfg->daemon.user,
                 errno ? strerror(errno) : "no such user");
        return -1;
    }
    if (initgroups(pw->pw_name, pw->pw_gid) < 0 || setgid(pw->pw_gid) < 0 ||
        setuid(pw->pw_uid) < 0) {
        snprintf(why, wl, "[daemon] user %s: %s", cfg->daemon.user, strerror(errno));
        return -1;
    }
    if (pw->pw_uid != 0 && (setuid(0) == 0 || geteuid() == 0)) {
        snprintf(why, wl, "[daemon] user %s: root could be regained", cfg->daemon.user);
        return -1;
    }
    log_msg(LOG_NOTICE, "dropped privileges to user %s (uid %u, gid %u)", pw->pw_name,
            (unsigned)pw->pw_uid, (unsigned)pw->pw_gid);
    return 0;
}

static int reload(trajd_t *d, const char *from, char *err, size_t errlen);

/* At exit: the thread freeing the last old configuration, and the one freeing
 * the engines the last cores gave up (grave.h). */
static void join_workers(void)
{
    cfgload_retire_join();
    grave_stop();
}

/* A reload refused: counted, logged, told to systemd; the old configuration runs on. */
static void reload_refused(trajd_t *d, const char *what, const char *err)
{
    d->reloads_failed++;
    log_msg(LOG_ERR,
            "reload refused%s, still running the old configuration (every object as it "
            "was): %s",
            what, err);
    sd_notifyf(0, "READY=1\nSTATUS=reload refused: %s", err);
}

/* SIGHUPs were coalesced while a reload was under way: read the config again. */
static void reload_again(trajd_t *d)
{
    if (d->hup_again && d->core && !d->core->stopping && !d->load && !d->pending) {
        char err[1024];
        d->hup_again = 0;
        (void)reload(d, "SIGHUP", err, sizeof err); /* logged there */
    }
}

/* Swap in nc (checked), then read the config again if SIGHUPs were coalesced.
 * 0, or -1 with the reason in err. */
static int reload_swap(trajd_t *d, cfg_t *nc, char *err, size_t errlen)
{
    int rc = 0;
    /* core_open carries unchanged objects over, closes the old transports
     * (they may hold a TCP port the new ones need), then opens the new ones.
     * If that fails, the old core reopens its transports and runs on (one
     * that does not reopen left closed, its outputs counted lost); the old
     * configuration opened from scratch is a last resort with no old core. */
    if (start_core(d, nc, err, errlen, 1) < 0) {
        char err2[1024];
        rc = -1;
        if (d->core)
            reload_release_removed(d->core, nc); /* braked for nothing: inputs resume */
        cfg_free(nc);
        if (d->core) {
            reload_refused(d, " (cannot open)", err);
        } else {
            d->reloads_failed++;
            log_msg(LOG_CRIT,
                    "reload refused (cannot open): %s; and the old configuration's "
                    "transports did not reopen: opening it from scratch",
                    err);
            if (start_core(d, d->cfg, err2, sizeof err2, 1) < 0) {
                log_msg(LOG_CRIT, "cannot reopen the old configuration either: %s", err2);
                loop_stop(d->loop, EX_SOFTWARE);
                return -1;
            }
            sd_notifyf(0, "READY=1\nSTATUS=reload refused: %s", err);
        }
    } else {
        cfgload_retire(d->cfg); /* freed on a thread: its tracks may be large */
        d->cfg = nc;
        unsigned kept = 0;
        for (unsigned i = 0; i < d->core->nobj; i++)
            kept += (unsigned)d->core->obj[i].carried;
        log_msg(LOG_NOTICE, "reloaded: %u object(s), %u carried over without interruption",
                nc->nobj, kept);
        sd_notify(0, "READY=1");
        notify_status(d);
    }
    reload_again(d);
    return rc;
}

/* Drop a pending reload (SIGTERM, or it swapped). */
static cfg_t *pending_take(trajd_t *d)
{
    cfg_t *nc = d->pending;
    if (d->pending_fd >= 0)
        loop_timer_del(d->loop, d->pending_fd);
    d->pending_fd = -1;
    d->pending = NULL;
    return nc;
}

/* While a reload waits: swap once the objects it removes rest. */
static void on_pending(loop_t *l, uint64_t exp, void *ctx)
{
    trajd_t *d = ctx;
    (void)l;
    (void)exp;
    if (!d->pending || !d->core)
        return;
    int rest = reload_removed_at_rest(d->core, d->pending);
    if (!rest && core_mono_ns() < d->pending_deadline_ns)
        return;
    if (!rest)
        log_msg(LOG_WARNING,
                "reload: removed objects not at rest after %.1f s "
                "(stop_timeout_s): reloading anyway",
                d->cfg->daemon.stop_timeout_s);
    char err[1024];
    (void)reload_swap(d, pending_take(d), err, sizeof err); /* logged there */
}

/* The new configuration read and checked (rc 0, nc), or refused (rc < 0, err):
 * swapped in now, or once the objects it removes rest (on_pending).  0 when
 * taken, or -1 with the reason in err. */
static int reload_loaded(trajd_t *d, cfg_t *nc, int rc, char *err, size_t errlen)
{
    if (rc == 0)
        rc = reload_rate_check(d->core, nc, err, errlen);
    if (rc < 0) {
        reload_refused(d, "", err);
        cfg_free(nc);
        reload_again(d);
        return -1;
    }
    if (reload_brake_removed(d->core, nc) > 0) {
        int64_t tick = (int64_t)((double)d->cfg->daemon.period_ns / d->cfg->daemon.speed);
        d->pending_fd = loop_timer_add(d->loop, tick > 1000000 ? tick : 1000000, on_pending, d);
        if (d->pending_fd >= 0) {
            d->pending = nc;
            d->pending_deadline_ns = core_mono_ns() +
                                     (int64_t)(d->cfg->daemon.stop_timeout_s * 1e9);
            return 0; /* swapped by on_pending once they rest */
        }
        log_msg(LOG_WARNING,
                "reload: no timer to wait for removed objects to rest (%s): "
                "reloading now",
                strerror(-d->pending_fd));
    }
    return reload_swap(d, nc, err, errlen);
}

/* The reload's worker is done (its eventfd): take its result, between two ticks. */
static void on_loaded(loop_t *l, int fd, uint32_t events, void *ctx)
{
    trajd_t *d = ctx;
    char err[1024] = "";
    cfg_t *nc = NULL;
    (void)events;
    loop_del(l, fd);
    int rc = cfgload_finish(d->load, &nc, err, sizeof err);
    d->load = NULL;
    rc = reload_loaded(d, nc, rc, err, sizeof err);
    ctl_reload_done(d->ctl, rc, err);
}

/* SIGTERM while a reload is read: its parse is cancelled, its result dropped (counted). */
static void load_drop(trajd_t *d, const char *why)
{
    if (!d->load)
        return;
    if (d->loop)
        loop_del(d->loop, cfgload_fd(d->load));
    cfgload_drop(d->load);
    d->load = NULL;
    d->reloads_failed++;
    log_msg(LOG_NOTICE, "the reload being read is dropped (its parse cancelled): %s", why);
    ctl_reload_done(d->ctl, -1, why);
}

/* SIGHUP, or trajctl reload (from): 0 when taken (done, or waiting for removed
 * objects to rest), 1 when being read on the reload's worker (on_loaded takes
 * it), or -1 with the reason in err. */
static int reload(trajd_t *d, const char *from, char *err, size_t errlen)
{
    cfg_t *nc = NULL;
    if (!d->core || d->core->stopping) {
        snprintf(err, errlen, "trajd is stopping");
        return -1;
    }
    if (d->load || d->pending) {
        d->hup_again = 1;
        log_msg(LOG_NOTICE,
                "%s while a reload is %s: coalesced, %s is read again once that reload is "
                "done",
                from, d->load ? "being read" : "waiting for removed objects to rest", d->conf_path);
        return 0;
    }
    d->reloads++;
    sd_notifyf(0, "RELOADING=1\nMONOTONIC_USEC=%llu", (unsigned long long)(core_mono_ns() / 1000));
    log_msg(LOG_NOTICE, "%s: reloading %s", from, d->conf_path);
    /* read, parsed and checked on a worker beside the running configuration
     * (cfgload.h): the ticks go on meanwhile */
    int e = 0;
    d->load = cfgload_start(d->conf_path, d->cfg, &e);
    if (d->load && (e = loop_add(d->loop, cfgload_fd(d->load), EPOLLIN, on_loaded, d)) == 0)
        return 1;
    if (d->load) {
        cfgload_drop(d->load);
        d->load = NULL;
    }
    log_msg(LOG_WARNING,
            "reload: no worker thread (%s): the configuration is read in the loop, "
            "ticks wait for it",
            strerror(-e));
    int rc = cfg_load(d->conf_path, &nc, err, errlen);
    if (rc == 0)
        rc = cfg_reload_check(d->cfg, nc, err, errlen);
    return reload_loaded(d, nc, rc, err, errlen);
}

static int ctl_reload(void *ctx, char *why, size_t wl)
{
    return reload(ctx, "trajctl", why, wl);
}

/* A signal trajd does not act on (trajd_signals, its default would end trajd
 * at once with the objects moving): 1, logged, ignored. */
static int stray_signal(const struct signalfd_siginfo *si)
{
    if (si->ssi_signo != SIGUSR1 && si->ssi_signo != SIGUSR2 && si->ssi_signo != SIGALRM)
        return 0;
    log_msg(LOG_WARNING, "%s (from pid %u): ignored (trajd acts on SIGHUP, SIGTERM and SIGINT)",
            strsignal((int)si->ssi_signo), (unsigned)si->ssi_pid);
    return 1;
}

static void on_signal(loop_t *l, int fd, uint32_t events, void *ctx)
{
    trajd_t *d = ctx;
    struct signalfd_siginfo si;
    int hup = 0;
    (void)events;
    while (read(fd, &si, sizeof si) == (ssize_t)sizeof si) {
        if (!d->core)
            return; /* a failed reload is ending the loop */
        switch (si.ssi_signo) {
        case SIGHUP: hup++; break; /* one reload for the batch, after it */
        case SIGTERM:
        case SIGINT:
            if (++d->signals_seen > 1) {
                log_msg(LOG_NOTICE, "second %s: exiting now", strsignal((int)si.ssi_signo));
                loop_stop(l, 0);
                return;
            }
            log_msg(LOG_NOTICE, "%s: bringing objects to rest (at most %.1f s)",
                    strsignal((int)si.ssi_signo), d->cfg->daemon.stop_timeout_s);
            sd_notify(0, "STOPPING=1");
            if (d->pending) {
                log_msg(LOG_NOTICE, "the pending reload is dropped");
                cfg_free(pending_take(d));
            }
            load_drop(d, "trajd is stopping");
            core_stop(d->core);
            break;
        default: (void)stray_signal(&si); break;
        }
    }
    if (hup > 1)
        log_msg(LOG_NOTICE, "%d SIGHUPs at once: one reload", hup);
    if (hup) {
        char err[1024];
        (void)reload(d, "SIGHUP", err, sizeof err); /* logged there */
    }
}

/* Background mode: the parent waits until the child is ready (or failed). */
static int detach(trajd_t *d)
{
    int fds[2];
    if (pipe(fds) < 0)
        return -errno;
    pid_t pid = fork();
    if (pid < 0)
        return -errno;
    if (pid > 0) {
        char code = 1;
        close(fds[1]);
        if (read(fds[0], &code, 1) != 1) {
            int st;
            waitpid(pid, &st, 0);
            _exit(WIFEXITED(st) ? WEXITSTATUS(st) : 1);
        }
        _exit(code);
    }
    close(fds[0]);
    setsid();
    d->ready_fd = fds[1];
    return 0;
}

static void report_ready(trajd_t *d, char code)
{
    if (d->ready_fd >= 0) {
        ssize_t w = write(d->ready_fd, &code, 1);
        (void)w;
        close(d->ready_fd);
        d->ready_fd = -1;
        /* Detached and running: the terminal that started us is not watching. */
        if (code == 0)
            log_set_mode(LOG_MODE_SYSLOG);
    }
}

/* The command line into d, *foreground and *check; -1 to go on, else the exit code. */
static int parse_args(int argc, char **argv, trajd_t *d, int *foreground, const char **check)
{
    static const struct option opts[] = {
        {"config", required_argument, NULL, 'c'},
        {"foreground", no_argument, NULL, 'f'},
        {"check-config", optional_argument, NULL, 'C'},
        {"version", no_argument, NULL, 'V'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "c:fVh", opts, NULL)) != -1) {
        switch (c) {
        case 'c': d->conf_path = optarg; break;
        case 'f': *foreground = 1; break;
        case 'C': /* FILE, or -c's (trajd -c FILE --check-config) */
            *check = optarg ? optarg : "";
            break;
        case 'V': printf("trajd %s\n", TRAJD_VERSION); return 0;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return EX_USAGE;
        }
    }
    if (*check && !(*check)[0]) /* --check-config FILE, or with no FILE the -c one */
        *check = optind < argc ? argv[optind++] : d->conf_path;
    if (optind < argc) {
        fprintf(stderr, "trajd: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return EX_USAGE;
    }
    return -1;
}

/* Started as root with [daemon] user: the files trajd makes are that user's
 * (regfile.h), so that a reload after the drop opens them again. */
static void files_owner(const cfg_t *cfg)
{
    if (geteuid() != 0 || !cfg->daemon.user[0])
        return;
    struct passwd *pw = getpwnam(cfg->daemon.user);
    if (pw)
        regfile_owner(pw->pw_uid, pw->pw_gid);
}

/* --check-config FILE: the exit code. */
/* " (no configuration there: ...)" where path is the default one and absent, else "". */
static const char *no_conf_hint(const char *path)
{
    struct stat sb;
    if (strcmp(path, TRAJD_DEFAULT_CONF) == 0 && stat(path, &sb) < 0)
        return " (no configuration there: give one with -c FILE; `make install` puts the "
               "example there; config/demo.conf runs with no hardware)";
    return "";
}

static int check_config(const char *path)
{
    char err[1024];
    cfg_t *cfg;
    if (cfg_load(path, &cfg, err, sizeof err) < 0) {
        fprintf(stderr, "%s%s\n", err, no_conf_hint(path));
        return EX_CONFIG;
    }
    fdlimit_t f;
    fdlimit_of(cfg, &f);
    if (fdlimit_check(&f, err, sizeof err) < 0) {
        fprintf(stderr, "%s: %s\n", path, err);
        cfg_free(cfg);
        return EX_CONFIG;
    }
    if ((unsigned long long)f.need + f.clients > f.soft)
        fprintf(stderr,
                "%s: note: about %u file descriptors (%u more for clients at most), above the "
                "soft limit of %llu: trajd raises it at start, up to the hard limit of %llu\n",
                path, f.need, f.clients, f.soft, f.hard);
    printf("%s: ok, %u object(s):", path, cfg->nobj);
    for (unsigned i = 0; i < cfg->nobj; i++)
        printf(" %s", cfg->obj[i].name);
    printf("\n");
    cfg_free(cfg);
    return 0;
}

/* The signals trajd takes from a signalfd (blocked from the first read of
 * the configuration on). */
static void trajd_signals(sigset_t *mask)
{
    sigemptyset(mask);
    sigaddset(mask, SIGHUP);
    sigaddset(mask, SIGTERM);
    sigaddset(mask, SIGINT);
    /* whose default ends the process at once, objects moving: logged, ignored */
    sigaddset(mask, SIGUSR1);
    sigaddset(mask, SIGUSR2);
    sigaddset(mask, SIGALRM);
}

/* Signals while the configuration is first read: SIGTERM/SIGINT cancel the
 * parse (1), a SIGHUP is ignored (the file is being read now), logged. */
static int start_signals(int sfd)
{
    struct signalfd_siginfo si;
    while (read(sfd, &si, sizeof si) == (ssize_t)sizeof si) {
        if (si.ssi_signo == SIGHUP) {
            log_msg(LOG_NOTICE, "SIGHUP while the configuration is first read: ignored (it is "
                                "being read now)");
            continue;
        }
        if (stray_signal(&si))
            continue;
        log_msg(LOG_NOTICE,
                "%s while the configuration is first read: its parse cancelled, "
                "exiting",
                strsignal((int)si.ssi_signo));
        return 1;
    }
    return 0;
}

/*
 * The configuration at start, read and its tracks parsed on the reload's
 * worker (cfgload.h) while this thread waits for it or for a signal:
 * SIGTERM/SIGINT cancel the parse and trajd exits 0 (-1), as in every later
 * state.  0 with d->cfg, -1 (stopped), or EX_CONFIG (logged).
 */
static int load_at_start(trajd_t *d)
{
    char err[1024] = "";
    sigset_t mask;
    trajd_signals(&mask);
    sigprocmask(SIG_BLOCK, &mask, NULL); /* open_loop's signalfd takes them from here on */
    int e = 0, rc = 1, sfd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    cfgload_t *l = sfd >= 0 ? cfgload_start(d->conf_path, NULL, &e) : NULL;
    if (!l) /* no worker: read here (a SIGTERM waits for the loop) */
        rc = cfg_load(d->conf_path, &d->cfg, err, sizeof err);
    while (rc == 1) {
        struct pollfd p[2] = {{cfgload_fd(l), POLLIN, 0}, {sfd, POLLIN, 0}};
        if (poll(p, 2, -1) < 0)
            continue; /* EINTR */
        if (p[0].revents) {
            rc = cfgload_finish(l, &d->cfg, err, sizeof err);
        } else if (start_signals(sfd)) {
            cfgload_drop(l);
            close(sfd);
            return -1;
        }
    }
    if (sfd >= 0)
        close(sfd);
    if (rc < 0) {
        log_msg(LOG_ERR, "%s%s", err, no_conf_hint(d->conf_path));
        return EX_CONFIG;
    }
    return 0;
}

/* The event loop, with SIGHUP/SIGTERM/SIGINT delivered to it by a signalfd:
 * 0 or an exit code (logged). */
static int open_loop(trajd_t *d)
{
    /* A reader that goes away must not kill us mid-write: EPIPE on stdout
     * ends the daemon cleanly with CORE_EXIT_EPIPE (csv_transport.h). */
    signal(SIGPIPE, SIG_IGN);
    sigset_t mask;
    trajd_signals(&mask);
    sigprocmask(SIG_BLOCK, &mask, NULL);

    int e = 0;
    d->loop = loop_new(&e);
    if (!d->loop) {
        log_msg(LOG_ERR, "event loop: %s", strerror(-e));
        return EX_OSERR;
    }
    d->sig_fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (d->sig_fd < 0 || loop_add(d->loop, d->sig_fd, EPOLLIN, on_signal, d) < 0) {
        log_msg(LOG_ERR, "signalfd: %s", strerror(errno));
        return EX_OSERR;
    }
    return 0;
}

/*
 * The control socket (daemon/ctl/ctl.h), opened before privileges drop (it
 * may be under /run).  Set in the config ([daemon] control_socket): it must
 * open, or trajd does not start.  Left to its default place: if there is
 * none, or another trajd answers there, trajd runs without one and says so.
 */
static int open_control(trajd_t *d)
{
    char why[512], path[PATH_MAX];
    int configured = ctl_socket_path(&d->cfg->daemon, path, sizeof path, why, sizeof why) > 0;
    int rc = ctl_open(&d->ctl, d->loop, d->cfg, ctl_reload, d, why, sizeof why);
    if (rc == 0)
        return 0; /* start_core hands it the core */
    if (configured) {
        log_msg(LOG_ERR, "cannot start: control socket: %s", why);
        return -1;
    }
    log_msg(LOG_WARNING, "running WITHOUT a control socket (trajctl cannot reach this trajd): %s",
            why);
    return 0;
}

/* Start the core and the housekeeping timers, tell systemd and the waiting
 * parent, run until the stop policy ends the loop: the exit code. */
static int run(trajd_t *d)
{
    char err[1024];
    d->stats.start_mono_ns = core_mono_ns();
    if (open_control(d) < 0) /* first: the clock starts with nothing left to open */
        return EX_UNAVAILABLE;
    /* from here (detached: after the fork) lines go through the log thread */
    if (log_async_start() < 0)
        log_msg(LOG_WARNING, "log thread not started: lines are written by the loop");
    if (start_core(d, d->cfg, err, sizeof err, 0) < 0) {
        log_msg(LOG_ERR, "cannot start: %s", err);
        return EX_UNAVAILABLE;
    }
    if (drop_privileges(d->cfg, err, sizeof err) < 0) {
        log_msg(LOG_ERR, "cannot start: %s", err);
        return EX_NOPERM;
    }
    d->status_fd = loop_timer_add(d->loop, 1000000000, on_second, d);
    uint64_t wd_usec = 0;
    if (sd_watchdog_enabled(0, &wd_usec) > 0 && wd_usec > 0)
        d->watchdog_fd = loop_timer_add(d->loop, (int64_t)wd_usec * 1000 / 2, on_watchdog, d);
    log_msg(LOG_INFO, "started: %u object(s) at %.6g Hz, speed %.6g, config %s", d->cfg->nobj,
            d->cfg->daemon.rate_hz, d->cfg->daemon.speed, d->conf_path);
    objlog_first_seconds(d->cfg);
    if (start_clock(d, err, sizeof err) < 0) {
        log_msg(LOG_ERR, "cannot start: %s", err);
        return EX_UNAVAILABLE;
    }
    sd_notify(0, "READY=1");
    notify_status(d);
    report_ready(d, 0);

    int rc = loop_run(d->loop);
    if (rc < 0) {
        log_msg(LOG_ERR, "event loop: %s", strerror(-rc));
        rc = EX_OSERR;
    }
    if (d->core) {
        char line[1024];
        core_stats_roll(d->core);
        status_line(d, line, sizeof line);
        log_msg(LOG_INFO, "exit: %s", line);
        d->lost_said = d->stats.out_lost;
    }
    return rc;
}

/* Numeric refusals (a solver refused finite data), which the engine documents
 * cannot happen, summed over the objects: an exit status of their own.  Hard
 * stops (a moving output's curve ended) do happen (a starved daemon; one on
 * gpxpy_cerknicko-jezero.csv with bspline uniform): logged at error level. */
static uint64_t engine_faults(const core_t *c, const stats_t *st)
{
    uint64_t n = 0, hard = 0;
    for (unsigned i = 0; c && i < c->nobj; i++) {
        n += c->obj[i].status.rejected_by[ENGINE_ENUMERIC];
        hard += c->obj[i].status.hard_stops;
    }
    if (hard) /* known to happen (starved of CPU; and see trajreplay): loud, not fatal */
        log_msg(LOG_ERR, "%llu hard stops (velocity to 0 in one tick), %llu deadlines missed",
                (unsigned long long)hard, (unsigned long long)st->missed_ticks);
    return n;
}

/* Objects that end the run held: a safety fault, a feed hold (a drive's
 * heartbeat lost), no position after waypoints were accepted (a CiA 402
 * drive left Operation Enabled: obj_drive_event), latched after the
 * per-axis limits stopped it on its path (issue 32), or latched by a stop
 * command with waypoints it never played; each named in a log line.
 * Their count (issue 24: the run exits CORE_EXIT_HELD). */
static unsigned held_objects(const core_t *c)
{
    unsigned n = 0;
    for (unsigned i = 0; c && i < c->nobj; i++) {
        const obj_t *o = &c->obj[i];
        unsigned hold = o->lc.hold; /* the lifecycle's (lib/engine/lifecycle.h) */
        const engine_status_t *st = &o->status;
        int axis = o->lc.latched && (st->axis_lag_stops || st->axis_beyond); /* issue 32 */
        /* stopped by a command, with waypoints it never played: not delivered */
        int stopped = o->lc.latched && !axis && o->lc.len > 0;
        if (!safety_fault(&o->safety) && !hold && !o->held && !axis && !stopped)
            continue;
        n++;
        if (stopped && !safety_fault(&o->safety) && !hold && !o->held) {
            log_msg(LOG_ERR,
                    "object '%s' ended held: a stop command latched it with %zu waypoints it "
                    "never played%s (start releases it)",
                    o->name, (size_t)o->lc.len,
                    lc_free_room(&o->lc, 1) ? ""
                                            : ", its buffer full, and more its input still held");
            continue;
        }
        if (axis && !safety_fault(&o->safety) && !hold && !o->held) {
            log_msg(LOG_ERR,
                    "object '%s' ended held: stopped on its path by the per-axis limits "
                    "(axis_lag_stops %llu, axis_beyond %llu), latched",
                    o->name, (unsigned long long)st->axis_lag_stops,
                    (unsigned long long)st->axis_beyond);
            continue;
        }
        log_msg(LOG_ERR, "object '%s' ended held: %s", o->name,
                safety_fault(&o->safety) ? safety_strerror(safety_fault(&o->safety))
                : (hold & LC_HOLD_DRIVE) ? "its drives left Operation Enabled"
                                         : "feed hold (a drive's heartbeat was lost)");
    }
    return n;
}

/* Objects whose last setpoint still moved when trajd exited (a second
 * SIGTERM, stop_timeout_s run out): their motion was cut short, each named
 * in a log line.  Their count (the run exits CORE_EXIT_HELD). */
static unsigned moving_objects(const core_t *c)
{
    unsigned n = 0;
    for (unsigned i = 0; c && i < c->nobj; i++) {
        const obj_t *o = &c->obj[i];
        const double *v = o->sp.vel_m_s;
        double speed = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(o->sp.flags & ENGINE_SP_NO_POSITION) && speed > 0) {
            log_msg(LOG_ERR,
                    "object '%s' still moving (%.3f m/s) when trajd exited: its motion was "
                    "cut short",
                    o->name, speed);
            n++;
        }
    }
    return n;
}

/* Setpoint lines the outputs lost and setpoint cycles a bus did not take:
 * said, with the lines lost after the exit line apart (the exit line counted
 * the lines lost before the outputs drained; those still queued to a failing
 * writer then were lost too); the exit status. */
static int lost_said(const trajd_t *d)
{
    char more[96] = "";
    if (d->stats.out_lost > d->lost_said)
        snprintf(more, sizeof more, " (%llu after the exit line: queued as the outputs drained)",
                 (unsigned long long)(d->stats.out_lost - d->lost_said));
    if (d->stats.out_lost)
        log_msg(LOG_ERR, "%llu setpoint lines were lost by the outputs%s%s%s: exit status %d",
                (unsigned long long)d->stats.out_lost, more,
                d->stats.out_fault ? ", last write error: " : "",
                d->stats.out_fault ? strerror(d->stats.out_errno) : "", CORE_EXIT_OUTPUT_LOST);
    if (d->stats.out_cycles_lost)
        log_msg(LOG_ERR,
                "%llu setpoint cycles with a position were not sent on the CAN bus (late, its "
                "transmit queue full, the interface down or a write error; each logged as it "
                "came): exit status %d",
                (unsigned long long)d->stats.out_cycles_lost, CORE_EXIT_OUTPUT_LOST);
    return CORE_EXIT_OUTPUT_LOST;
}

int main(int argc, char **argv)
{
    trajd_t d = {.conf_path = TRAJD_DEFAULT_CONF,
                 .sig_fd = -1,
                 .status_fd = -1,
                 .watchdog_fd = -1,
                 .ready_fd = -1,
                 .pending_fd = -1};
    int foreground = 0, rc;
    const char *check = NULL;

    if (stdfds_open() < 0)
        return 71; /* EX_OSERR: no /dev/null */
    if ((rc = parse_args(argc, argv, &d, &foreground, &check)) >= 0)
        return rc;
    if (check)
        return check_config(check);

    if ((rc = load_at_start(&d)) != 0)
        return rc < 0 ? 0 : rc; /* < 0: SIGTERM while it was read */
    log_set_level(d.cfg->daemon.log_level);
    if (!foreground && detach(&d) < 0) {
        log_msg(LOG_ERR, "cannot detach: %s", strerror(errno));
        return EX_OSERR;
    }
    files_owner(d.cfg);
    rc = open_loop(&d);
    if (rc == 0)
        rc = run(&d);
    report_ready(&d, (char)(rc ? rc : EX_SOFTWARE));
    load_drop(&d, "trajd is exiting"); /* before the control socket and d.cfg go */
    uint64_t faults = engine_faults(d.core, &d.stats);
    unsigned held = held_objects(d.core), moving = 0;
    /* cut short by a second signal or the stop timeout (stop_timeout_s = 0
     * asks for no stop: nothing cut short it did not ask for) */
    if (d.signals_seen > 1 || (d.cfg && d.cfg->daemon.stop_timeout_s > 0))
        moving = moving_objects(d.core);
    ctl_close(d.ctl);   /* watchers get what is queued, then a goodbye */
    core_close(d.core); /* outputs drain here: lines left over count as lost */
    if (d.stats.exit_code == CORE_EXIT_EPIPE) {
        log_msg(LOG_NOTICE, "stdout: the reader went away, exiting with status %d",
                CORE_EXIT_EPIPE);
        rc = CORE_EXIT_EPIPE;
    } else if (d.stats.exit_code) {
        rc = d.stats.exit_code;
    } else if (rc == 0 && (d.stats.out_lost || d.stats.out_cycles_lost)) {
        rc = lost_said(&d);
    } else if (rc == 0 && faults) {
        log_msg(LOG_ERR,
                "internal fault: the engines counted %llu numeric refusals of finite data, which "
                "they document cannot happen: a defect of trajd, please report it: exit status %d",
                (unsigned long long)faults, EX_SOFTWARE);
        rc = EX_SOFTWARE;
    } else if (rc == 0 && d.stats.no_input) {
        log_msg(LOG_ERR,
                "a replayed track or candump log ended %llu time(s) with no usable waypoint for "
                "an object: exit status %d",
                (unsigned long long)d.stats.no_input, CORE_EXIT_NO_INPUT);
        rc = CORE_EXIT_NO_INPUT;
    } else if (rc == 0 && (held || moving)) {
        /* (an object still moving was not held: said as what it was) */
        if (held && moving)
            log_msg(LOG_ERR, "%u object(s) ended held and %u still moving: exit status %d", held,
                    moving, CORE_EXIT_HELD);
        else if (held)
            log_msg(LOG_ERR, "%u object(s) ended held: exit status %d", held, CORE_EXIT_HELD);
        else
            log_msg(LOG_ERR, "%u object(s) ended still moving: exit status %d", moving,
                    CORE_EXIT_HELD);
        rc = CORE_EXIT_HELD;
    }
    cfg_free(pending_take(&d));
    if (d.sig_fd >= 0)
        close(d.sig_fd);
    loop_free(d.loop);
    cfg_free(d.cfg);
    join_workers();
    log_async_stop(); /* every line queued is written before the exit */
    return rc;
}
