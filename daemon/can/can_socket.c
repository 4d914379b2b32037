/* can_socket.c - SocketCAN transport (see can_socket.h). */
#include "can_socket.h"

#include <errno.h>
#include <fcntl.h>
#include <net/if.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/sock_diag.h>

/* The receive queue asked for (SO_RCVBUFFORCE while trajd may, else
 * SO_RCVBUF up to net.core.rmem_max): about 2 000 frames, 4 s of a busy
 * 500 kbit/s bus, where the default holds a few hundred. */
#define CAN_SOCKET_RCVBUF (2 * 1024 * 1024)

struct can_socket {
    char ifname[IF_NAMESIZE];
    int fd_frames;
    struct can_filter filt[CAN_SOCKET_MAX_FILTERS];
    unsigned nfilt;
    int sock;
    can_socket_state_t state;
    int64_t last_try_ns;
    int tried;
    uint32_t ovfl; /* SK_MEMINFO_DROPS of this socket, as last read */
    can_socket_stats_t st;
};

can_socket_t *can_socket_new(const char *ifname, int fd_frames, const uint32_t *rx_ids,
                             unsigned n_rx)
{
    if (!ifname || !*ifname || strlen(ifname) >= IF_NAMESIZE || n_rx > CAN_SOCKET_MAX_FILTERS)
        return NULL;
    can_socket_t *b = calloc(1, sizeof *b);
    if (!b)
        return NULL;
    strcpy(b->ifname, ifname);
    b->fd_frames = fd_frames;
    for (unsigned i = 0; i < n_rx; i++) {
        /* exact standard-frame match: id, and EFF/RTR bits must be 0 */
        b->filt[i].can_id = rx_ids[i] & CAN_SFF_MASK;
        b->filt[i].can_mask = CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG;
    }
    b->nfilt = n_rx;
    b->sock = -1;
    return b;
}

static void go_down(can_socket_t *b, int err)
{
    if (b->sock >= 0)
        close(b->sock);
    b->sock = -1;
    if (b->state == CAN_SOCKET_UP)
        b->st.downs++;
    b->state = CAN_SOCKET_DOWN;
    b->st.last_errno = err;
}

void can_socket_free(can_socket_t *b)
{
    if (!b)
        return;
    if (b->sock >= 0)
        close(b->sock);
    free(b);
}

int can_socket_open(can_socket_t *b)
{
    int s = -1, rc, one = 1;
    struct sockaddr_can addr;
    struct ifreq ifr;

    if (b->sock >= 0) {
        close(b->sock);
        b->sock = -1;
    }
    b->state = CAN_SOCKET_DOWN;
    /* the socket first: a kernel without CAN (EAFNOSUPPORT) must be told
     * apart from an interface that is merely missing for now (ENODEV) */
    s = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
    if (s < 0) {
        rc = -errno;
        goto out;
    }
    unsigned idx = if_nametoindex(b->ifname);
    if (!idx) {
        rc = -ENODEV;
        goto out;
    }
    /* bind() succeeds on a down interface: ask whether it is up first */
    memset(&ifr, 0, sizeof ifr);
    strcpy(ifr.ifr_name, b->ifname);
    if (ioctl(s, SIOCGIFFLAGS, &ifr) < 0) {
        rc = -errno;
        goto out;
    }
    if (!(ifr.ifr_flags & IFF_UP)) {
        rc = -ENETDOWN;
        goto out;
    }
    /* an empty filter list receives nothing; ids in use only otherwise */
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_FILTER, b->nfilt ? b->filt : NULL,
                   (socklen_t)(b->nfilt * sizeof b->filt[0])) < 0) {
        rc = -errno;
        goto out;
    }
    /* every error class: the bus state comes from them (lib/proto/canerr.h) */
    can_err_mask_t emask = CAN_ERR_MASK;
    if (setsockopt(s, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &emask, sizeof emask) < 0 ||
        (b->fd_frames && setsockopt(s, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &one, sizeof one) < 0)) {
        rc = -errno;
        goto out;
    }
    /* a larger receive queue (refused is not fatal: a smaller one still
     * works; its drops are counted, can_socket_stats) */
    int rcv = CAN_SOCKET_RCVBUF;
    if (setsockopt(s, SOL_SOCKET, SO_RCVBUFFORCE, &rcv, sizeof rcv) < 0)
        (void)setsockopt(s, SOL_SOCKET, SO_RCVBUF, &rcv, sizeof rcv);
    b->ovfl = 0;
    memset(&addr, 0, sizeof addr);
    addr.can_family = AF_CAN;
    addr.can_ifindex = (int)idx;
    if (bind(s, (struct sockaddr *)&addr, sizeof addr) < 0) {
        rc = -errno;
        goto out;
    }
    b->sock = s;
    s = -1;
    b->state = CAN_SOCKET_UP;
    rc = 0;
out:
    if (s >= 0)
        close(s);
    if (rc)
        b->st.last_errno = -rc;
    return rc;
}

int can_socket_maintain(can_socket_t *b, int64_t now_ns)
{
    if (b->state == CAN_SOCKET_UP)
        return 0;
    if (b->tried && now_ns - b->last_try_ns < CAN_SOCKET_REOPEN_NS)
        return 0;
    b->tried = 1;
    b->last_try_ns = now_ns;
    if (can_socket_open(b) == 0) {
        b->st.reopens++;
        return 1;
    }
    return 0;
}

int can_socket_fd(const can_socket_t *b)
{
    return b->state == CAN_SOCKET_UP ? b->sock : -1;
}

can_socket_state_t can_socket_state(const can_socket_t *b)
{
    return b->state;
}

static int is_down_errno(int e)
{
    return e == ENETDOWN || e == ENODEV || e == ENXIO || e == ENETUNREACH;
}

int can_socket_send(can_socket_t *b, const canproto_frame_t *f)
{
    struct canfd_frame cf;
    size_t mtu;

    if (b->state != CAN_SOCKET_UP) {
        b->st.tx_dropped_down++;
        return -ENETDOWN;
    }
    memset(&cf, 0, sizeof cf);
    cf.can_id = f->id & ((f->flags & CANPROTO_F_EFF) ? CAN_EFF_MASK : CAN_SFF_MASK);
    if (f->flags & CANPROTO_F_EFF)
        cf.can_id |= CAN_EFF_FLAG;
    if (f->flags & CANPROTO_F_FD) {
        if (!b->fd_frames || !canproto_fd_len_valid(f->len))
            return -EINVAL;
        mtu = CANFD_MTU;
        cf.flags = (uint8_t)(((f->flags & CANPROTO_F_BRS) ? CANFD_BRS : 0) |
                             ((f->flags & CANPROTO_F_ESI) ? CANFD_ESI : 0));
    } else {
        if (f->len > CAN_MAX_DLEN)
            return -EINVAL;
        mtu = CAN_MTU;
        if (f->flags & CANPROTO_F_RTR)
            cf.can_id |= CAN_RTR_FLAG;
    }
    cf.len = f->len;
    memcpy(cf.data, f->data, f->len);
    ssize_t n = write(b->sock, &cf, mtu);
    if (n == (ssize_t)mtu) {
        b->st.tx_frames++;
        return 0;
    }
    if (n >= 0) { /* a raw CAN socket never writes part of a frame; count it if it did */
        b->st.tx_errors++;
        return -EIO;
    }
    int e = errno;
    if (e == ENOBUFS || e == EAGAIN) {
        b->st.tx_dropped_full++;
        return -e;
    }
    if (is_down_errno(e)) {
        b->st.tx_dropped_down++;
        go_down(b, e);
        return -e;
    }
    b->st.tx_errors++;
    b->st.last_errno = e;
    return -e;
}

int can_socket_recv(can_socket_t *b, canproto_frame_t *f)
{
    struct canfd_frame cf;

    if (b->state != CAN_SOCKET_UP)
        return -ENETDOWN;
    for (;;) {
        ssize_t n = read(b->sock, &cf, sizeof cf);
        if (n < 0) {
            int e = errno;
            if (e == EAGAIN || e == EINTR)
                return 0;
            if (is_down_errno(e)) {
                go_down(b, e);
                return -e;
            }
            b->st.rx_errors++;
            b->st.last_errno = e;
            return -e;
        }
        if (n != CAN_MTU && n != CANFD_MTU) {
            b->st.rx_errors++;
            continue;
        }
        memset(f, 0, sizeof *f);
        if (cf.can_id & CAN_ERR_FLAG) {
            /* the kernel's report of the controller (bus state, errors) */
            f->flags |= CANPROTO_F_ERR;
            f->id = cf.can_id & CAN_ERR_MASK;
        } else if (cf.can_id & CAN_EFF_FLAG) {
            f->flags |= CANPROTO_F_EFF;
            f->id = cf.can_id & CAN_EFF_MASK;
        } else {
            f->id = cf.can_id & CAN_SFF_MASK;
        }
        if (n == CANFD_MTU) {
            f->flags |= CANPROTO_F_FD;
            if (cf.flags & CANFD_BRS)
                f->flags |= CANPROTO_F_BRS;
            if (cf.flags & CANFD_ESI)
                f->flags |= CANPROTO_F_ESI;
            f->len = cf.len > CANFD_MAX_DLEN ? CANFD_MAX_DLEN : cf.len;
        } else {
            if (cf.can_id & CAN_RTR_FLAG)
                f->flags |= CANPROTO_F_RTR;
            f->len = cf.len > CAN_MAX_DLEN ? CAN_MAX_DLEN : cf.len;
        }
        memcpy(f->data, cf.data, f->len);
        b->st.rx_frames++;
        return 1;
    }
}

void can_socket_stats(can_socket_t *b, can_socket_stats_t *st)
{
    /* the frames the kernel dropped, its receive queue full: the socket's own
     * count (SO_MEMINFO, SK_MEMINFO_DROPS), read now (SO_RXQ_OVFL tells it only
     * with a frame queued after the drops, and none may come) */
    uint32_t mi[SK_MEMINFO_VARS];
    socklen_t len = sizeof mi;
    if (b->sock >= 0 && getsockopt(b->sock, SOL_SOCKET, SO_MEMINFO, mi, &len) == 0 &&
        len > SK_MEMINFO_DROPS * sizeof mi[0]) {
        b->st.rx_overflow += (uint32_t)(mi[SK_MEMINFO_DROPS] - b->ovfl); /* (wraps at 2^32) */
        b->ovfl = mi[SK_MEMINFO_DROPS];
    }
    *st = b->st;
}
