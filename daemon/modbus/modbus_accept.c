/* modbus_accept.c - the Modbus listener out of file descriptors (see modbus_accept.h). */
#include "modbus_accept.h"

#include <errno.h>
#include <stddef.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <systemd/sd-daemon.h>

int mb_accept_init(mb_accept_t *a)
{
    return ag_init(a, "modbus", "closed at once");
}

int mb_accept(mb_accept_t *a, int ep, int lfd, struct sockaddr *sa, socklen_t *sl,
              uint64_t *refused)
{
    int fd = accept4(lfd, sa, sl, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd >= 0) {
        ag_accepted(a);
        return fd;
    }
    int err = errno;
    if (ag_is_shortage(err)) {
        *refused += ag_shortage(a, lfd, err, NULL, NULL);
        if (a->paused) /* not polled until the back-off timer fires */
            epoll_ctl(ep, EPOLL_CTL_DEL, lfd, NULL);
    }
    errno = err;
    return -1;
}

void mb_accept_resume(mb_accept_t *a, int ep, int lfd, uint64_t data)
{
    if (!ag_resume(a))
        return;
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = data};
    epoll_ctl(ep, EPOLL_CTL_ADD, lfd, &ev);
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
