/*
 * modbus_server_int.h - the Modbus server's state, shared by its files and no
 * one else: modbus_server.c (set-up, loop, publish), modbus_framing.c (TCP and
 * RTU request framing), modbus_sessions.c (clients, peers, allow-lists,
 * accept, housekeeping), modbus_dispatch.c (a whole request answered).
 */
#ifndef TRAJD_MODBUS_SERVER_INT_H
#define TRAJD_MODBUS_SERVER_INT_H

#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <stdarg.h>
#include <stdio.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <time.h>

#include "mbrtu.h"
#include "modbus_accept.h"
#include "modbus_server.h"

/* Two whole TCP ADUs: a client may pipeline a second request behind the first. */
#define CLIENT_BUF (2 * MBMAP_TCP_ADU_MAX)
#define RTU_BUF (2 * MBMAP_RTU_ADU_MAX)
#define LISTEN_BACKLOG 128
#define ACCEPTS_PER_EVENT 16

enum tag { TAG_LISTEN = 1, TAG_HOUSEKEEPING, TAG_RTU, TAG_SILENCE, TAG_CLIENT, TAG_BACKOFF };

typedef struct {
    int family; /* AF_INET or AF_INET6 */
    uint8_t addr[16];
    unsigned prefix;
} allow_t;

typedef struct {
    int fd; /* -1: free slot */
    size_t len;
    int64_t connected_ns;
    int64_t last_ns;    /* last complete request, or the connection */
    int64_t pending_ns; /* first byte of the partial request in buf, 0 if none */
    uint64_t requests, exceptions, bytes_in;
    int peer_idx;  /* its entry in peers[], -1 if none */
    int may_write; /* writes = yes and in write_allow */
    char peer[64];
    uint8_t buf[CLIENT_BUF];
} client_t;

/* Counters of one client address over all its connections. */
typedef struct {
    char host[64];
    int64_t last_ns; /* last connection or close (0: free entry) */
    uint64_t n[6];   /* PEER_*: closed connections' counts */
    uint64_t logged[6];
} peer_t;
enum { PEER_CONN, PEER_REQ, PEER_EXC, PEER_EVICTED, PEER_SLOW, PEER_DROPPED };
/* Why a client is closed (its peer's counters). */
enum close_why {
    WHY_PEER = -1,
    WHY_EVICTED = PEER_EVICTED,
    WHY_SLOW = PEER_SLOW,
    WHY_DROPPED = PEER_DROPPED
};

struct modbus_server {
    unsigned n_objects;
    int writes_enabled;
    unsigned max_clients;
    int64_t idle_ns;
    int64_t request_ns;
    int unit_id;
    int64_t log_window_ns; /* rate limit of client messages: start of this second */
    unsigned log_count;    /* messages in it */
    unsigned log_suppressed;
    modbus_server_hooks_t hooks;
    int ep, lfd, hkfd, rtufd, silfd;
    int port;
    int from_systemd;
    modbus_t *tcp;
    modbus_t *rtu;
    modbus_mapping_t *map;
    modbus_mapping_t mirror; /* FC 03 at MBMAP_MIRROR_BASE: the input table, read-only */
    mbmap_order_t order;     /* [modbus] word_order */
    client_t *clients;
    allow_t allow[MODBUS_SERVER_ALLOW_MAX];
    unsigned n_allow;
    mbrtu_rx_t rtu_rx;                       /* RTU request framing (lib/proto/mbrtu.h) */
    allow_t wallow[MODBUS_SERVER_ALLOW_MAX]; /* write_allow */
    unsigned n_wallow;
    uint32_t gen;
    uint64_t *mb_rejected; /* per object */
    uint64_t *lost;        /* per object, sequence gaps of Modbus waypoints */
    uint32_t *last_seq;    /* per object, of the last waypoint accepted over Modbus */
    uint32_t *alt_seq;     /* per object, the last sequence number outside the window (0: none) */
    uint64_t *missing;     /* per object, bit i: last_seq - i was counted lost (1 <= i < 64);
                              it is taken back should it come late (count_seq) */
    uint64_t *seq_jumps;   /* per object, sequence numbers outside the window */
    const char *cur_peer;  /* the peer of the request being served ("" between requests) */
    char rtu_peer[80];     /* "rtu DEVICE unit N" */
    peer_t peers[MODBUS_SERVER_PEERS];
    unsigned n_peers;       /* entries in use */
    int64_t peer_log_ns;    /* summary lines at most this often (0: none) */
    int64_t peer_logged_ns; /* when the last summary ran */
    mbmap_daemon_t worst;   /* the mb_peers / mb_worst_* fields, refreshed by housekeeping */
    modbus_server_stats_t st;
    mb_accept_t acc; /* out of fds: the reserve fd and the back-off (modbus_accept.h) */
};

static inline int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

/* A message into err (NULL: none). */
static inline void msg(char *err, size_t len, const char *fmt, ...)
{
    if (!err || !len)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, len, fmt, ap);
    va_end(ap);
}

static inline uint64_t tag(enum tag t, unsigned idx)
{
    return ((uint64_t)t << 32) | idx;
}

static inline int set_nonblock(int fd)
{
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0)
        return -errno;
    return 0;
}

static inline int ep_add(int ep, int fd, uint64_t data)
{
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = data};
    return epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev) < 0 ? -errno : 0;
}

/* modbus_sessions.c */
/* Parse an allow-list into out[0..max-1]: the number of entries or -EINVAL. */
int mbs_allow_parse(const char *list, allow_t *out, unsigned max, char *err, size_t errlen);
/* Accept what the listener has (at most ACCEPTS_PER_EVENT). */
void mbs_accept(modbus_server_t *s);
/* The housekeeping timer: request and idle deadlines, peer summary, accept report. */
void mbs_housekeeping(modbus_server_t *s);
/* Close a client; why: WHY_* counted for its peer (WHY_PEER: the peer hung up). */
void mbs_client_close_why(modbus_server_t *s, client_t *c, int why);
/* A notice about client c ("what" then its counts), rate-limited. */
void mbs_client_note(modbus_server_t *s, const client_t *c, const char *what, int64_t now);
/* The peer summary now, whatever its interval (the server closes: an exit,
 * a reload), so that what happened since the last one is told. */
void mbs_peer_log_last(modbus_server_t *s);
void mbs_client_close(modbus_server_t *s, client_t *c);

/* modbus_framing.c */
/* A client's socket is readable: frame by the MBAP length, serve whole requests. */
void mbs_client_read(modbus_server_t *s, client_t *c);
/* The serial line is readable / silent (MODBUS_SERVER_RTU_SILENCE_MS). */
void mbs_rtu_read(modbus_server_t *s);
void mbs_rtu_silence(modbus_server_t *s);

/* modbus_dispatch.c */
/* Answer one whole request (req: the ADU, pdu: its PDU); what libmodbus
 * returned (< 0: the peer could not be written to). */
int mbs_serve(modbus_server_t *s, modbus_t *ctx, int writes, const uint8_t *req, int req_len,
              const uint8_t *pdu, size_t pdu_len);

#endif
