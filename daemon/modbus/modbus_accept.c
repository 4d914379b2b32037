/* modbus_accept.c - the Modbus listener out of file descriptors (see modbus_accept.h). */
#include "modbus_accept.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <systemd/sd-daemon.h>
#include <unistd.h>

#include "log.h"

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

int mb_accept_init(mb_accept_t *a)
{
    memset(a, 0, sizeof *a);
    a->backoff_ms = MB_ACCEPT_BACKOFF_MIN_MS;
    a->reserve_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    if (a->reserve_fd < 0)
        return -errno;
    a->timer_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (a->timer_fd < 0) {
        int rc = -errno;
        close(a->reserve_fd);
        a->reserve_fd = -1;
        return rc;
    }
    a->open = 1;
    return 0;
}

void mb_accept_fini(mb_accept_t *a)
{
    if (!a->open)
        return;
    a->open = 0;
    mb_accept_report(a, 1);
    if (a->reserve_fd >= 0)
        close(a->reserve_fd);
    if (a->timer_fd >= 0)
        close(a->timer_fd);
    a->reserve_fd = a->timer_fd = -1;
}

static int is_shortage(int err)
{
    return err == EMFILE || err == ENFILE || err == ENOBUFS || err == ENOMEM;
}

static unsigned shortage(mb_accept_t *a, int lfd, int err)
{
    unsigned n = 0;
    a->shortages++;
    a->last_errno = err;
    if ((err == EMFILE || err == ENFILE) && a->reserve_fd >= 0) {
        close(a->reserve_fd);
        a->reserve_fd = -1;
        while (n < MB_ACCEPT_REFUSE_MAX) {
            int fd = accept4(lfd, NULL, NULL, SOCK_CLOEXEC);
            if (fd < 0)
                break; /* EAGAIN: the backlog is empty */
            close(fd);
            n++;
        }
        a->reserve_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    }
    a->refused += n;
    struct itimerspec t = {.it_value = {a->backoff_ms / 1000, (a->backoff_ms % 1000) * 1000000L}};
    if (a->timer_fd >= 0 && timerfd_settime(a->timer_fd, 0, &t, NULL) == 0) {
        a->paused = 1;
        a->pause_ms = a->backoff_ms;
        a->pauses++;
        a->backoff_ms *= 2;
        if (a->backoff_ms > MB_ACCEPT_BACKOFF_MAX_MS)
            a->backoff_ms = MB_ACCEPT_BACKOFF_MAX_MS;
    }
    mb_accept_report(a, 0);
    return n;
}

int mb_accept(mb_accept_t *a, int ep, int lfd, struct sockaddr *sa, socklen_t *sl,
              uint64_t *refused)
{
    int fd = accept4(lfd, sa, sl, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd >= 0) {
        a->backoff_ms = MB_ACCEPT_BACKOFF_MIN_MS;
        return fd;
    }
    int err = errno;
    if (a->open && is_shortage(err)) {
        *refused += shortage(a, lfd, err);
        if (a->paused) /* not polled until the back-off timer fires */
            epoll_ctl(ep, EPOLL_CTL_DEL, lfd, NULL);
    }
    errno = err;
    return -1;
}

void mb_accept_resume(mb_accept_t *a, int ep, int lfd, uint64_t data)
{
    uint64_t exp;
    if (read(a->timer_fd, &exp, sizeof exp) < 0 || !a->paused)
        return;
    a->paused = 0;
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = data};
    epoll_ctl(ep, EPOLL_CTL_ADD, lfd, &ev);
    mb_accept_report(a, 0);
}

int mb_systemd_listener(void)
{
    int n = sd_listen_fds(0);
    for (int i = 0; i < n; i++) {
        int fd = SD_LISTEN_FDS_START + i;
        if (sd_is_socket(fd, AF_UNSPEC, SOCK_STREAM, 1) > 0)
            return fd;
    }
    return -1;
}

void mb_accept_report(mb_accept_t *a, int final)
{
    if (a->shortages == a->logged_shortages)
        return;
    int64_t now = mono_ns();
    if (!final && a->logged_ns && now - a->logged_ns < 1000000000)
        return;
    log_msg(LOG_WARNING,
            "modbus: accept: %s: %llu connections refused (closed at once), %llu shortages "
            "so far; listener paused %lld ms at a time (up to %d ms)",
            strerror(a->last_errno), (unsigned long long)a->refused,
            (unsigned long long)a->shortages, (long long)a->pause_ms, MB_ACCEPT_BACKOFF_MAX_MS);
    a->logged_refused = a->refused;
    a->logged_shortages = a->shortages;
    a->logged_ns = now;
}
