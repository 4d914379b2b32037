/* ctl.c - the control socket: its place, its peers, their I/O (see ctl.h). */
#include "ctl.h"

#include <errno.h>
#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include "ctl_priv.h"
#include "log.h"

static int dir_usable(const char *dir)
{
    struct stat st;
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode) && access(dir, W_OK | X_OK) == 0;
}

static int path_in(char *out, size_t len, const char *dir, const char *name, char *why, size_t wl)
{
    int n = snprintf(out, len, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= len || (size_t)n >= sizeof(struct sockaddr_un){0}.sun_path) {
        snprintf(why, wl, "%s/%s: too long for a Unix socket", dir, name);
        return -1;
    }
    return 0;
}

int ctl_socket_path(const cfg_daemon_t *d, char *out, size_t len, char *why, size_t wl)
{
    char dir[PATH_MAX];
    if (d->control_socket[0]) {
        size_t n = strlen(d->control_socket);
        if (n >= len) {
            snprintf(why, wl, "[daemon] control_socket: too long");
            return -1;
        }
        memcpy(out, d->control_socket, n + 1);
        return 1;
    }
    const char *rd = getenv("RUNTIME_DIRECTORY"); /* systemd: RuntimeDirectory=, ':'-separated */
    if (rd && rd[0] == '/') {
        snprintf(dir, sizeof dir, "%.*s", (int)strcspn(rd, ":"), rd);
        return path_in(out, len, dir, CTL_SOCKET_NAME, why, wl);
    }
    if (dir_usable(CTL_RUN_DIR) || (mkdir(CTL_RUN_DIR, 0755) == 0 && dir_usable(CTL_RUN_DIR)))
        return path_in(out, len, CTL_RUN_DIR, CTL_SOCKET_NAME, why, wl);
    const char *xdg = getenv("XDG_RUNTIME_DIR");
    if (xdg && xdg[0] == '/') {
        snprintf(dir, sizeof dir, "%s/trajd", xdg);
        if (mkdir(dir, 0700) < 0 && errno != EEXIST) {
            snprintf(why, wl, "%s: %s", dir, strerror(errno));
            return -1;
        }
        return path_in(out, len, dir, CTL_SOCKET_NAME, why, wl);
    }
    snprintf(why, wl,
             "no place for it: not under systemd ($RUNTIME_DIRECTORY), " CTL_RUN_DIR
             " not writable, no $XDG_RUNTIME_DIR; set [daemon] control_socket");
    return -1;
}

/* A socket file at path: replaced if no one answers (a dead trajd's); an
 * error if a live one does, or if it is something else. */
static int clear_stale(const char *path, char *why, size_t wl)
{
    struct stat st;
    if (lstat(path, &st) < 0)
        return errno == ENOENT ? 0 : (snprintf(why, wl, "%s: %s", path, strerror(errno)), -errno);
    if (!S_ISSOCK(st.st_mode)) {
        snprintf(why, wl, "%s exists and is not a socket", path);
        return -EEXIST;
    }
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", path);
    int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0)
        return -errno;
    int rc = connect(fd, (struct sockaddr *)&sa, sizeof sa);
    int e = errno;
    close(fd);
    if (rc == 0 || e == EAGAIN) {
        snprintf(why, wl, "%s: another trajd answers on it (set [daemon] control_socket)", path);
        return -EADDRINUSE;
    }
    if (unlink(path) < 0) {
        snprintf(why, wl, "%s: stale socket: %s", path, strerror(errno));
        return -errno;
    }
    log_msg(LOG_NOTICE, "control: replaced the stale socket %s", path);
    return 0;
}

/* Mode 0660, group control_group, owner [daemon] user (a root trajd drops to it). */
static int set_owner(const ctl_t *t, char *why, size_t wl)
{
    const cfg_daemon_t *d = &t->cfg->daemon;
    uid_t uid = (uid_t)-1;
    gid_t gid = (gid_t)-1;
    if (chmod(t->path, 0660) < 0) {
        snprintf(why, wl, "chmod 0660 %s: %s", t->path, strerror(errno));
        return -errno;
    }
    if (d->control_group[0]) {
        errno = 0;
        const struct group *gr = getgrnam(d->control_group);
        if (!gr) {
            snprintf(why, wl, "[daemon] control_group %s: %s", d->control_group,
                     errno ? strerror(errno) : "no such group");
            return -ENOENT;
        }
        gid = gr->gr_gid;
    }
    if (geteuid() == 0 && d->user[0]) {
        const struct passwd *pw = getpwnam(d->user);
        if (pw)
            uid = pw->pw_uid;
    }
    if ((uid != (uid_t)-1 || gid != (gid_t)-1) && chown(t->path, uid, gid) < 0) {
        snprintf(why, wl, "chown %s to group %s: %s (trajd must be root or in that group)", t->path,
                 d->control_group[0] ? d->control_group : "-", strerror(errno));
        return -errno;
    }
    return 0;
}

static void on_listen(loop_t *l, int fd, uint32_t events, void *ctx);

/* ---- out of file descriptors (daemon/core/acceptguard.h, as the Modbus
 * listener): the clients that wait are told why and closed, the listener
 * paused; without the guard (no fd for it at open) the loop would spin on a
 * listener that stays readable ---- */

static void tell_no_fd(int fd, int err, void *ctx)
{
    ctl_t *t = ctx;
    char line[256];
    int len = snprintf(line, sizeof line,
                       "{\"reply\":\"error\",\"error\":\"busy\",\"message\":\"trajd is out of "
                       "file descriptors: %s\"}\n",
                       strerror(err));
    ssize_t w = send(fd, line, (size_t)len, MSG_NOSIGNAL | MSG_DONTWAIT);
    (void)w;
    t->busy_refused++;
}

static void on_pause_end(loop_t *l, int fd, uint32_t events, void *ctx)
{
    ctl_t *t = ctx;
    (void)fd;
    (void)events;
    if (ag_resume(&t->ag))
        loop_add(l, t->fd, EPOLLIN, on_listen, t);
}

static void guard_open(ctl_t *t)
{
    if (ag_init(&t->ag, "control", "told why and closed") < 0)
        return;
    if (loop_add(t->loop, t->ag.timer_fd, EPOLLIN, on_pause_end, t) < 0)
        ag_fini(&t->ag);
}

static void guard_close(ctl_t *t)
{
    if (t->ag.open)
        loop_del(t->loop, t->ag.timer_fd);
    ag_fini(&t->ag);
}

static int listen_on(ctl_t *t, char *why, size_t wl)
{
    struct sockaddr_un sa = {.sun_family = AF_UNIX};
    snprintf(sa.sun_path, sizeof sa.sun_path, "%s", t->path);
    int rc = clear_stale(t->path, why, wl);
    if (rc < 0)
        return rc;
    t->fd = socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (t->fd < 0 || bind(t->fd, (struct sockaddr *)&sa, sizeof sa) < 0) {
        snprintf(why, wl, "%s: %s", t->path, strerror(errno));
        return -errno;
    }
    struct stat st;
    if (stat(t->path, &st) == 0) {
        t->dev = st.st_dev;
        t->ino = st.st_ino;
    }
    if ((rc = set_owner(t, why, wl)) < 0)
        return rc;
    if (listen(t->fd, CTL_CLIENTS_MAX) < 0) {
        snprintf(why, wl, "listen %s: %s", t->path, strerror(errno));
        return -errno;
    }
    rc = loop_add(t->loop, t->fd, EPOLLIN, on_listen, t);
    if (rc < 0)
        snprintf(why, wl, "%s: %s", t->path, strerror(-rc));
    return rc;
}

int ctl_open(ctl_t **out, loop_t *loop, const cfg_t *cfg, ctl_reload_fn reload, void *reload_ctx,
             char *why, size_t wl)
{
    ctl_t *t = calloc(1, sizeof *t);
    *out = NULL;
    if (!t) {
        snprintf(why, wl, "out of memory");
        return -ENOMEM;
    }
    t->loop = loop;
    t->cfg = cfg;
    t->fd = -1;
    t->flush_fd = -1;
    t->reload = reload;
    t->reload_ctx = reload_ctx;
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++)
        t->cl[i].fd = -1;
    int rc = ctl_socket_path(&cfg->daemon, t->path, sizeof t->path, why, wl);
    if (rc >= 0)
        rc = listen_on(t, why, wl);
    if (rc < 0) {
        if (t->fd >= 0) {
            close(t->fd);
            t->fd = -1;
            if (t->ino)
                unlink(t->path);
        }
        free(t);
        return rc < -1 ? rc : -ENOENT;
    }
    guard_open(t);
    log_msg(LOG_INFO, "control: listening on %s (mode 0660, group %s)", t->path,
            cfg->daemon.control_group[0] ? cfg->daemon.control_group : "trajd's own");
    *out = t;
    return 0;
}

/* ---- the tick's part: copy, nothing else ---- */

static void tap(void *ctx, const core_t *c)
{
    ctl_t *t = ctx;
    if (!t->watchers)
        return;
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++) {
        ctl_client_t *cl = &t->cl[i];
        if (cl->fd < 0 || cl->sub_obj < 0 || (unsigned)cl->sub_obj >= c->nobj)
            continue;
        if (cl->head - cl->tail >= CTL_RING) {
            cl->pending_lost++; /* keep what is queued: the newest is dropped */
            cl->lost++;
            t->watch_lost++;
            continue;
        }
        ctl_sp_t *e = &cl->ring[cl->head % CTL_RING];
        e->sp = c->obj[cl->sub_obj].sp;
        e->period_ns = c->period_ns;
        e->lost_before = cl->pending_lost;
        cl->pending_lost = 0;
        cl->head++;
    }
}

/* ---- clients ---- */

static void ctl_sub_end(ctl_t *t, ctl_client_t *cl);

static void client_close(ctl_t *t, ctl_client_t *cl, const char *why)
{
    if (cl->fd < 0)
        return;
    ctl_sub_end(t, cl);
    loop_del(t->loop, cl->fd);
    close(cl->fd);
    cl->fd = -1;
    free(cl->out);
    cl->out = NULL;
    log_peer(LOG_INFO, cl->peer, "control: client #%llu (%s) %s", (unsigned long long)cl->id,
             cl->peer, why);
}

static void set_events(ctl_t *t, ctl_client_t *cl, uint32_t ev)
{
    if (ev != cl->events && loop_mod(t->loop, cl->fd, ev) == 0)
        cl->events = ev;
}

/* Write what is queued, refill from a status reply or the ring, within a
 * bound (CTL_PUMP_ROUNDS buffers); then watch for what comes next. */
#define CTL_PUMP_ROUNDS 4
static void pump(ctl_t *t, ctl_client_t *cl)
{
    for (int round = 0; round < CTL_PUMP_ROUNDS && cl->fd >= 0; round++) {
        if (cl->status_next >= 0)
            ctl_status_more(t, cl);
        else if (cl->sub_obj >= 0 && cl->head != cl->tail)
            ctl_sub_more(t, cl);
        if (cl->outoff == cl->outlen)
            break;
        ssize_t w = send(cl->fd, cl->out + cl->outoff, cl->outlen - cl->outoff,
                         MSG_NOSIGNAL | MSG_DONTWAIT);
        if (w < 0) {
            if (errno == EAGAIN || errno == EINTR)
                break;
            client_close(t, cl, errno == EPIPE ? "left" : strerror(errno));
            return;
        }
        cl->outoff += (size_t)w;
        if (cl->outoff == cl->outlen)
            cl->outoff = cl->outlen = 0;
    }
    if (cl->fd < 0)
        return;
    if (cl->closing && cl->outlen == 0 && cl->status_next < 0 && t->reload_waiter != cl->id) {
        client_close(t, cl, "closed");
        return;
    }
    int more = cl->outlen > 0 || cl->status_next >= 0;
    /* read requests only when a reply has room (a watcher's ring is written
     * by the flush timer, so its reads go on) */
    int room = cl->outlen + CTL_REPLY_MAX <= CTL_OUT_BYTES && cl->status_next < 0 && !cl->closing &&
               !cl->eof;
    set_events(t, cl, (room ? EPOLLIN : 0u) | (more ? EPOLLOUT : 0u));
}

void ctl_client_pump(ctl_t *t, ctl_client_t *cl)
{
    pump(t, cl);
}

/* Complete lines in cl->in, while replies have room. */
static void serve_lines(ctl_t *t, ctl_client_t *cl)
{
    while (cl->fd >= 0 && !cl->closing && cl->status_next < 0 &&
           cl->outlen + CTL_REPLY_MAX <= CTL_OUT_BYTES) {
        char *nl = memchr(cl->in, '\n', cl->inlen);
        if (!nl)
            break;
        *nl = 0;
        if (nl > cl->in && nl[-1] == '\r')
            nl[-1] = 0;
        ctl_request(t, cl, cl->in);
        size_t used = (size_t)(nl + 1 - cl->in);
        memmove(cl->in, nl + 1, cl->inlen - used);
        cl->inlen -= used;
    }
}

static void on_client(loop_t *l, int fd, uint32_t events, void *ctx)
{
    ctl_client_t *cl = ctx;
    ctl_t *t = cl->owner;
    (void)l;
    (void)fd;
    if (events & EPOLLIN) {
        /* (a full buffer of whole lines waits for room in the replies: no
         * read, which would return 0 and be taken for the client's end) */
        ssize_t r = -1;
        errno = EAGAIN;
        if (cl->inlen < sizeof cl->in)
            r = read(cl->fd, cl->in + cl->inlen, sizeof cl->in - cl->inlen);
        if (r < 0 && errno != EAGAIN && errno != EINTR) {
            client_close(t, cl, strerror(errno));
            return;
        }
        if (r > 0)
            cl->inlen += (size_t)r;
        serve_lines(t, cl);
        if (r == 0) { /* its side shut: the replies still go out, a watch goes on */
            cl->eof = 1;
            if (cl->sub_obj < 0)
                cl->closing = 1;
        }
        if (cl->inlen == sizeof cl->in && !memchr(cl->in, '\n', cl->inlen)) {
            /* a line longer than any request (not whole lines waiting) */
            ctl_sb_t sb = ctl_out_sb(cl);
            ctl_sb_printf(&sb,
                          "{\"reply\":\"error\",\"error\":\"usage\",\"message\":\"request "
                          "line longer than %d bytes\"}\n",
                          CTL_IN_BYTES - 1);
            ctl_out_commit(cl, &sb);
            cl->closing = 1;
            cl->inlen = 0;
        }
    } else if (events & (EPOLLHUP | EPOLLERR)) {
        client_close(t, cl, "hung up");
        return;
    }
    pump(t, cl);
    /* lines held back while the replies had no room: served as room comes,
     * and their replies sent (and watched for) at once */
    while (cl->fd >= 0 && cl->inlen && !cl->closing && cl->status_next < 0) {
        size_t before = cl->inlen;
        serve_lines(t, cl);
        pump(t, cl);
        if (cl->inlen == before)
            break;
    }
}

static void on_listen(loop_t *l, int fd, uint32_t events, void *ctx)
{
    ctl_t *t = ctx;
    (void)l;
    (void)events;
    for (int n = 0; n < CTL_CLIENTS_MAX; n++) { /* bounded per callback */
        int cfd = accept4(fd, NULL, NULL, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (cfd < 0) {
            if (ag_is_shortage(errno)) {
                ag_shortage(&t->ag, fd, errno, tell_no_fd, t);
                if (t->ag.paused) /* not polled until the back-off timer fires */
                    loop_del(t->loop, fd);
            } /* else EAGAIN: none waits */
            return;
        }
        ag_accepted(&t->ag);
        struct ucred uc = {0};
        socklen_t ul = sizeof uc;
        char peer[CTL_PEER_MAX];
        if (getsockopt(cfd, SOL_SOCKET, SO_PEERCRED, &uc, &ul) < 0)
            uc.pid = 0, uc.uid = (uid_t)-1, uc.gid = (gid_t)-1;
        snprintf(peer, sizeof peer, "pid %ld uid %ld gid %ld", (long)uc.pid, (long)(int)uc.uid,
                 (long)(int)uc.gid);
        uint64_t id = ++t->next_id;
        ctl_client_t *cl = NULL;
        for (unsigned i = 0; i < CTL_CLIENTS_MAX && !cl; i++)
            if (t->cl[i].fd < 0)
                cl = &t->cl[i];
        char *out = cl ? malloc(CTL_OUT_BYTES) : NULL;
        if (!out || loop_add(t->loop, cfd, EPOLLIN, on_client, cl) < 0) {
            static const char busy[] = "{\"reply\":\"error\",\"error\":\"busy\",\"message\":"
                                       "\"too many control clients\"}\n";
            ssize_t w = send(cfd, busy, sizeof busy - 1, MSG_NOSIGNAL | MSG_DONTWAIT);
            (void)w;
            close(cfd);
            free(out);
            t->busy_refused++;
            log_peer(LOG_WARNING, peer, "control: refused %s: %u clients already", peer,
                     CTL_CLIENTS_MAX);
            continue;
        }
        memset(cl, 0, sizeof *cl);
        cl->owner = t;
        cl->fd = cfd;
        cl->id = id;
        cl->pid = uc.pid;
        cl->uid = uc.uid;
        cl->gid = uc.gid;
        cl->out = out;
        cl->events = EPOLLIN;
        cl->status_next = -1;
        cl->sub_obj = -1;
        snprintf(cl->peer, sizeof cl->peer, "%s", peer);
        log_peer(LOG_INFO, peer, "control: client #%llu connected: %s", (unsigned long long)id,
                 peer);
        ctl_request(t, cl, NULL); /* the greeting */
        pump(t, cl);
    }
}

/* ---- subscriptions: the flush timer ---- */

static void on_flush(loop_t *l, uint64_t exp, void *ctx)
{
    ctl_t *t = ctx;
    (void)l;
    (void)exp;
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++)
        if (t->cl[i].fd >= 0 && t->cl[i].sub_obj >= 0)
            pump(t, &t->cl[i]);
}

int ctl_sub_start(ctl_t *t, ctl_client_t *cl, int obj_index, const char *name)
{
    if (!cl->ring && !(cl->ring = malloc(CTL_RING * sizeof *cl->ring)))
        return -ENOMEM;
    if (t->flush_fd < 0) {
        int fd = loop_timer_add(t->loop, CTL_FLUSH_NS, on_flush, t);
        if (fd < 0)
            return fd;
        t->flush_fd = fd;
    }
    cl->head = cl->tail = 0;
    cl->pending_lost = cl->sent = cl->lost = cl->lost_logged = 0;
    snprintf(cl->sub_name, sizeof cl->sub_name, "%s", name);
    cl->sub_obj = obj_index;
    t->watchers++;
    return 0;
}

/* End a subscription (logged with its counts): its ring freed, the flush timer gone with the last. */
static void ctl_sub_end(ctl_t *t, ctl_client_t *cl)
{
    if (cl->sub_obj >= 0) {
        log_peer(cl->lost ? LOG_WARNING : LOG_INFO, cl->peer,
                 "control: client #%llu (%s) stops watching '%s': %llu setpoints sent, %llu "
                 "lost (ring full)",
                 (unsigned long long)cl->id, cl->peer, cl->sub_name, (unsigned long long)cl->sent,
                 (unsigned long long)cl->lost);
        cl->sub_obj = -1;
        t->watchers--;
    }
    free(cl->ring);
    cl->ring = NULL;
    if (!t->watchers && t->flush_fd >= 0) {
        loop_timer_del(t->loop, t->flush_fd);
        t->flush_fd = -1;
    }
}

void ctl_set_core(ctl_t *t, core_t *c)
{
    t->core = c;
    if (c) {
        c->tap = tap;
        c->tap_ctx = t;
    }
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++) {
        ctl_client_t *cl = &t->cl[i];
        if (cl->fd < 0)
            continue;
        if (cl->status_next >= 0) { /* a reply under way: ended, said so */
            cl->status_next = -1;
            ctl_sb_t sb = ctl_out_sb(cl);
            ctl_sb_printf(&sb, "{\"reply\":\"end\",\"interrupted\":\"reload\"}\n");
            ctl_out_commit(cl, &sb);
        }
        if (cl->sub_obj < 0)
            continue;
        obj_t *o = c ? core_obj_find(c, cl->sub_name) : NULL;
        if (o) {
            cl->sub_obj = (int)o->index;
            continue;
        }
        ctl_sub_more(t, cl); /* what it had queued still goes out first */
        ctl_sb_t sb = ctl_out_sb(cl);
        ctl_sb_printf(&sb, "{\"reply\":\"end\",\"object\":");
        ctl_sb_str(&sb, cl->sub_name);
        ctl_sb_printf(&sb, ",\"why\":\"no such object after a reload\"}\n");
        ctl_out_commit(cl, &sb);
        ctl_sub_end(t, cl);
        cl->closing = 1;
        pump(t, cl);
    }
}

void ctl_housekeeping(ctl_t *t)
{
    for (unsigned i = 0; t && i < CTL_CLIENTS_MAX; i++) {
        ctl_client_t *cl = &t->cl[i];
        if (cl->fd < 0 || cl->sub_obj < 0 || cl->lost == cl->lost_logged)
            continue;
        log_peer(LOG_WARNING, cl->peer,
                 "control: client #%llu (%s) reads '%s' too slowly: %llu setpoints dropped "
                 "(ring of %u full), %llu in all; it is told where",
                 (unsigned long long)cl->id, cl->peer, cl->sub_name,
                 (unsigned long long)(cl->lost - cl->lost_logged), CTL_RING,
                 (unsigned long long)cl->lost);
        cl->lost_logged = cl->lost;
    }
}

void ctl_close(ctl_t *t)
{
    if (!t)
        return;
    for (unsigned i = 0; i < CTL_CLIENTS_MAX; i++) {
        ctl_client_t *cl = &t->cl[i];
        if (cl->fd < 0)
            continue;
        /* best effort, never waiting: the setpoints queued, then goodbye */
        for (int k = 0; k < 64 && cl->fd >= 0 && cl->sub_obj >= 0 && cl->head != cl->tail; k++)
            pump(t, cl);
        if (cl->fd < 0)
            continue;
        cl->status_next = -1;
        ctl_sb_t sb = ctl_out_sb(cl);
        ctl_sb_printf(&sb, "{\"reply\":\"bye\",\"why\":\"trajd is exiting\"}\n");
        ctl_out_commit(cl, &sb);
        cl->closing = 1;
        pump(t, cl);
        client_close(t, cl, "closed: trajd is exiting");
    }
    guard_close(t);
    if (t->fd >= 0) {
        if (!t->ag.paused)
            loop_del(t->loop, t->fd);
        close(t->fd);
        struct stat st;
        if (stat(t->path, &st) == 0 && st.st_dev == t->dev && st.st_ino == t->ino)
            unlink(t->path); /* ours still: not one a newer trajd made */
    }
    if (t->flush_fd >= 0)
        loop_timer_del(t->loop, t->flush_fd);
    if (t->core && t->core->tap_ctx == t)
        t->core->tap = NULL;
    free(t);
}
