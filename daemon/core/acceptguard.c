/* acceptguard.c - a listening socket out of file descriptors (see acceptguard.h). */
#include "acceptguard.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "log.h"

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

int ag_init(acceptguard_t *a, const char *who, const char *told)
{
    memset(a, 0, sizeof *a);
    a->who = who;
    a->told = told;
    a->backoff_ms = AG_BACKOFF_MIN_MS;
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

void ag_fini(acceptguard_t *a)
{
    if (!a->open)
        return;
    a->open = 0;
    ag_report(a, 1);
    if (a->reserve_fd >= 0)
        close(a->reserve_fd);
    if (a->timer_fd >= 0)
        close(a->timer_fd);
    a->reserve_fd = a->timer_fd = -1;
}

int ag_is_shortage(int err)
{
    return err == EMFILE || err == ENFILE || err == ENOBUFS || err == ENOMEM;
}

unsigned ag_shortage(acceptguard_t *a, int lfd, int err, ag_tell_fn tell, void *ctx)
{
    unsigned n = 0;
    if (!a->open)
        return 0;
    a->shortages++;
    a->last_errno = err;
    if ((err == EMFILE || err == ENFILE) && a->reserve_fd >= 0) {
        close(a->reserve_fd);
        a->reserve_fd = -1;
        while (n < AG_REFUSE_MAX) {
            int fd = accept4(lfd, NULL, NULL, SOCK_CLOEXEC);
            if (fd < 0)
                break; /* EAGAIN: the backlog is empty */
            if (tell)
                tell(fd, err, ctx);
            close(fd);
            n++;
        }
        a->reserve_fd = open("/dev/null", O_RDONLY | O_CLOEXEC);
    }
    a->refused += n;
    struct itimerspec t = {.it_value = {a->backoff_ms / 1000, (a->backoff_ms % 1000) * 1000000L}};
    if (!a->paused && a->timer_fd >= 0 && timerfd_settime(a->timer_fd, 0, &t, NULL) == 0) {
        a->paused = 1;
        a->pause_ms = a->backoff_ms;
        a->backoff_ms *= 2;
        if (a->backoff_ms > AG_BACKOFF_MAX_MS)
            a->backoff_ms = AG_BACKOFF_MAX_MS;
    }
    ag_report(a, 0);
    return n;
}

void ag_accepted(acceptguard_t *a)
{
    a->backoff_ms = AG_BACKOFF_MIN_MS;
}

int ag_resume(acceptguard_t *a)
{
    uint64_t exp;
    if (read(a->timer_fd, &exp, sizeof exp) < 0 || !a->paused)
        return 0;
    a->paused = 0;
    ag_report(a, 0);
    return 1;
}

void ag_report(acceptguard_t *a, int final)
{
    if (a->shortages == a->logged_shortages)
        return;
    int64_t now = mono_ns();
    if (!final && a->logged_ns && now - a->logged_ns < 1000000000)
        return;
    log_msg(LOG_WARNING,
            "%s: accept: %s: %llu connections refused (%s), %llu shortages so far; listener "
            "paused %lld ms at a time (up to %d ms)",
            a->who, strerror(a->last_errno), (unsigned long long)a->refused, a->told,
            (unsigned long long)a->shortages, (long long)a->pause_ms, AG_BACKOFF_MAX_MS);
    a->logged_shortages = a->shortages;
    a->logged_ns = now;
}
