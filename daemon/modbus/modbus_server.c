/* modbus_server.c - see modbus_server.h. */
#include "modbus_server.h"
#include "mbrtu.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <modbus.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "log.h"
#include "modbus_accept.h"

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

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

static void msg(char *err, size_t len, const char *fmt, ...)
{
    if (!err || !len)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, len, fmt, ap);
    va_end(ap);
}

static uint64_t tag(enum tag t, unsigned idx)
{
    return ((uint64_t)t << 32) | idx;
}

static int set_nonblock(int fd)
{
    int fl = fcntl(fd, F_GETFL);
    if (fl < 0 || fcntl(fd, F_SETFL, fl | O_NONBLOCK) < 0)
        return -errno;
    return 0;
}

static int ep_add(int ep, int fd, uint64_t data)
{
    struct epoll_event ev = {.events = EPOLLIN, .data.u64 = data};
    return epoll_ctl(ep, EPOLL_CTL_ADD, fd, &ev) < 0 ? -errno : 0;
}

/* ---- allow-list ---------------------------------------------------------- */

static int allow_parse(const char *list, allow_t *out, unsigned max, char *err, size_t errlen)
{
    unsigned n = 0;
    const char *p = list;
    if (!list)
        return 0;
    while (*p) {
        char tok[80], *slash;
        size_t l = strcspn(p, ", \t");
        if (l == 0) {
            p++;
            continue;
        }
        if (l >= sizeof tok || n >= max) {
            msg(err, errlen, "allow: entry too long or more than %u entries", max);
            return -EINVAL;
        }
        memcpy(tok, p, l);
        tok[l] = 0;
        p += l;
        allow_t a = {0};
        unsigned maxp;
        slash = strchr(tok, '/');
        if (slash)
            *slash = 0;
        if (inet_pton(AF_INET, tok, a.addr) == 1) {
            a.family = AF_INET;
            maxp = 32;
        } else if (inet_pton(AF_INET6, tok, a.addr) == 1) {
            a.family = AF_INET6;
            maxp = 128;
        } else {
            msg(err, errlen, "allow: '%s' is not an IPv4 or IPv6 address", tok);
            return -EINVAL;
        }
        a.prefix = maxp;
        if (slash) {
            char *end;
            long pl = strtol(slash + 1, &end, 10);
            if (*end || end == slash + 1 || pl < 0 || pl > (long)maxp) {
                msg(err, errlen, "allow: bad prefix length '/%s'", slash + 1);
                return -EINVAL;
            }
            a.prefix = (unsigned)pl;
        }
        out[n++] = a;
    }
    return (int)n;
}

int modbus_server_allow_check(const char *allow, char *err, size_t errlen)
{
    allow_t tmp[MODBUS_SERVER_ALLOW_MAX];
    return allow_parse(allow, tmp, MODBUS_SERVER_ALLOW_MAX, err, errlen);
}

static int prefix_match(const uint8_t *a, const uint8_t *b, unsigned bits)
{
    unsigned full = bits / 8, rest = bits % 8;
    if (memcmp(a, b, full))
        return 0;
    if (!rest)
        return 1;
    uint8_t mask = (uint8_t)(0xffu << (8 - rest));
    return (a[full] & mask) == (b[full] & mask);
}

static int in_list(const allow_t *list, unsigned n, const struct sockaddr_storage *ss);

static int allowed(const modbus_server_t *s, const struct sockaddr_storage *ss)
{
    return !s->n_allow || in_list(s->allow, s->n_allow, ss);
}

/* Writes for a client at ss (NULL: an adopted socket, RTU): writes = yes,
 * and the client in write_allow if there is one. */
static int may_write(const modbus_server_t *s, const struct sockaddr_storage *ss)
{
    if (!s->writes_enabled)
        return 0;
    if (!s->n_wallow)
        return 1;
    return ss && in_list(s->wallow, s->n_wallow, ss);
}

static int in_list(const allow_t *list, unsigned n, const struct sockaddr_storage *ss)
{
    uint8_t a4[4], a6[16];
    int has4 = 0, has6 = 0;
    if (ss->ss_family == AF_INET) {
        memcpy(a4, &((const struct sockaddr_in *)ss)->sin_addr, 4);
        has4 = 1;
    } else if (ss->ss_family == AF_INET6) {
        const struct in6_addr *in6 = &((const struct sockaddr_in6 *)ss)->sin6_addr;
        memcpy(a6, in6, 16);
        has6 = 1;
        if (IN6_IS_ADDR_V4MAPPED(in6)) {
            memcpy(a4, a6 + 12, 4);
            has4 = 1;
        }
    }
    for (unsigned i = 0; i < n; i++) {
        const allow_t *e = &list[i];
        if (e->family == AF_INET && has4 && prefix_match(e->addr, a4, e->prefix))
            return 1;
        if (e->family == AF_INET6 && has6 && prefix_match(e->addr, a6, e->prefix))
            return 1;
    }
    return 0;
}

/* ---- set-up ---------------------------------------------------------------- */

void modbus_server_config_default(modbus_server_config_t *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    snprintf(cfg->tcp_address, sizeof cfg->tcp_address, "%s", MODBUS_SERVER_DEFAULT_ADDRESS);
    cfg->tcp_port = MODBUS_SERVER_DEFAULT_PORT;
    cfg->systemd_socket = 1;
    cfg->rtu_baud = 9600;
    cfg->rtu_parity = 'N';
    cfg->rtu_data_bits = 8;
    cfg->rtu_stop_bits = 1;
    cfg->unit_id = 1;
    cfg->max_clients = MODBUS_SERVER_DEFAULT_MAX_CLIENTS;
    cfg->idle_timeout_ms = MODBUS_SERVER_DEFAULT_IDLE_MS;
    cfg->request_timeout_ms = MODBUS_SERVER_DEFAULT_REQUEST_MS;
    cfg->peer_log_s = MODBUS_SERVER_DEFAULT_PEER_LOG_S;
    cfg->n_objects = 1;
}

static int parse_bool(const char *v, int *out)
{
    if (!strcmp(v, "yes") || !strcmp(v, "true") || !strcmp(v, "1") || !strcmp(v, "on"))
        return *out = 1, 0;
    if (!strcmp(v, "no") || !strcmp(v, "false") || !strcmp(v, "0") || !strcmp(v, "off"))
        return *out = 0, 0;
    return -EINVAL;
}

static int parse_uint(const char *v, long lo, long hi, long *out)
{
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    if (errno || end == v || *end || x < lo || x > hi)
        return -EINVAL;
    *out = x;
    return 0;
}

static int copy_str(char *dst, size_t len, const char *v)
{
    if (strlen(v) >= len)
        return -EINVAL;
    memcpy(dst, v, strlen(v) + 1);
    return 0;
}

int modbus_server_config_set(modbus_server_config_t *cfg, const char *key, const char *value,
                             char *err, size_t errlen)
{
    long x = 0;
    int rc = 0;
    if (!strcmp(key, "enabled"))
        rc = parse_bool(value, &cfg->enabled);
    else if (!strcmp(key, "writes"))
        rc = parse_bool(value, &cfg->writes_enabled);
    else if (!strcmp(key, "systemd_socket"))
        rc = parse_bool(value, &cfg->systemd_socket);
    else if (!strcmp(key, "address"))
        rc = copy_str(cfg->tcp_address, sizeof cfg->tcp_address, value);
    else if (!strcmp(key, "rtu_device"))
        rc = copy_str(cfg->rtu_device, sizeof cfg->rtu_device, value);
    else if (!strcmp(key, "allow")) {
        rc = copy_str(cfg->allow, sizeof cfg->allow, value);
        if (rc == 0 && modbus_server_allow_check(value, err, errlen) < 0)
            return -EINVAL;
    } else if (!strcmp(key, "write_allow")) {
        rc = copy_str(cfg->write_allow, sizeof cfg->write_allow, value);
        if (rc == 0 && modbus_server_allow_check(value, err, errlen) < 0)
            return -EINVAL;
    } else if (!strcmp(key, "port")) {
        if ((rc = parse_uint(value, 0, 65535, &x)) == 0)
            cfg->tcp_port = (int)x;
    } else if (!strcmp(key, "rtu_baud")) {
        if ((rc = parse_uint(value, 50, 4000000, &x)) == 0)
            cfg->rtu_baud = (int)x;
    } else if (!strcmp(key, "rtu_data_bits")) {
        if ((rc = parse_uint(value, 7, 8, &x)) == 0)
            cfg->rtu_data_bits = (int)x;
    } else if (!strcmp(key, "rtu_stop_bits")) {
        if ((rc = parse_uint(value, 1, 2, &x)) == 0)
            cfg->rtu_stop_bits = (int)x;
    } else if (!strcmp(key, "unit_id")) {
        if ((rc = parse_uint(value, 1, 247, &x)) == 0)
            cfg->unit_id = (int)x;
    } else if (!strcmp(key, "max_clients")) {
        if ((rc = parse_uint(value, 1, MODBUS_SERVER_MAX_CLIENTS_LIMIT, &x)) == 0)
            cfg->max_clients = (unsigned)x;
    } else if (!strcmp(key, "idle_timeout_ms")) {
        if ((rc = parse_uint(value, 0, 86400000, &x)) == 0)
            cfg->idle_timeout_ms = (unsigned)x;
    } else if (!strcmp(key, "request_timeout_ms")) {
        if ((rc = parse_uint(value, 100, 600000, &x)) == 0)
            cfg->request_timeout_ms = (unsigned)x;
    } else if (!strcmp(key, "peer_log_s")) {
        if ((rc = parse_uint(value, 0, 86400, &x)) == 0)
            cfg->peer_log_s = (unsigned)x;
    } else if (!strcmp(key, "word_order")) {
        if ((cfg->word_order = mbmap_order_parse(value)) < 0)
            rc = -EINVAL, cfg->word_order = MBMAP_ORDER_ABCD;
    } else if (!strcmp(key, "rtu_parity")) {
        if (!strcmp(value, "N") || !strcmp(value, "none"))
            cfg->rtu_parity = 'N';
        else if (!strcmp(value, "E") || !strcmp(value, "even"))
            cfg->rtu_parity = 'E';
        else if (!strcmp(value, "O") || !strcmp(value, "odd"))
            cfg->rtu_parity = 'O';
        else
            rc = -EINVAL;
    } else {
        msg(err, errlen, "modbus: unknown key '%s'", key);
        return -ENOENT;
    }
    if (rc < 0)
        msg(err, errlen, "modbus: bad value '%s' for %s", value, key);
    return rc;
}

static int tcp_listen(modbus_server_t *s, const modbus_server_config_t *cfg, char *err,
                      size_t errlen)
{
    struct addrinfo hints = {.ai_family = AF_UNSPEC,
                             .ai_socktype = SOCK_STREAM,
                             .ai_flags = AI_PASSIVE | AI_NUMERICSERV | AI_NUMERICHOST};
    struct addrinfo *res = NULL;
    char port[16];
    int fd = -1, rc, one = 1;

    if (cfg->systemd_socket && (fd = mb_systemd_listener()) >= 0) {
        s->lfd = fd;
        s->from_systemd = 1;
        goto bound;
    }
    snprintf(port, sizeof port, "%d", cfg->tcp_port);
    rc = getaddrinfo(cfg->tcp_address, port, &hints, &res);
    if (rc) {
        msg(err, errlen, "modbus: address %s: %s", cfg->tcp_address, gai_strerror(rc));
        return -EINVAL;
    }
    fd = socket(res->ai_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0 || setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) < 0 ||
        bind(fd, res->ai_addr, res->ai_addrlen) < 0 || listen(fd, LISTEN_BACKLOG) < 0) {
        rc = -errno;
        msg(err, errlen, "modbus: listen on %s port %d: %s", cfg->tcp_address, cfg->tcp_port,
            strerror(errno));
        if (fd >= 0)
            close(fd);
        freeaddrinfo(res);
        return rc;
    }
    freeaddrinfo(res);
    s->lfd = fd;
bound:;
    struct sockaddr_storage ss;
    socklen_t sl = sizeof ss;
    if (getsockname(s->lfd, (struct sockaddr *)&ss, &sl) == 0)
        s->port = ntohs(ss.ss_family == AF_INET6 ? ((struct sockaddr_in6 *)&ss)->sin6_port
                                                 : ((struct sockaddr_in *)&ss)->sin_port);
    if ((rc = set_nonblock(s->lfd)) < 0 || (rc = ep_add(s->ep, s->lfd, tag(TAG_LISTEN, 0))) < 0) {
        msg(err, errlen, "modbus: listening socket: %s", strerror(-rc));
        return rc;
    }
    /* Only used to build and send replies on a client's socket (modbus_set_socket). */
    s->tcp = modbus_new_tcp(NULL, 0);
    if (!s->tcp) {
        msg(err, errlen, "modbus: modbus_new_tcp: %s", modbus_strerror(errno));
        return -ENOMEM;
    }
    return 0;
}

static int rtu_open(modbus_server_t *s, const modbus_server_config_t *cfg, char *err, size_t errlen)
{
    int rc;
    if (cfg->unit_id < 1 || cfg->unit_id > 247) {
        msg(err, errlen, "modbus: unit_id %d outside 1..247", cfg->unit_id);
        return -EINVAL;
    }
    snprintf(s->rtu_peer, sizeof s->rtu_peer, "rtu %.60s unit %d", cfg->rtu_device, cfg->unit_id);
    s->rtu = modbus_new_rtu(cfg->rtu_device, cfg->rtu_baud, cfg->rtu_parity, cfg->rtu_data_bits,
                            cfg->rtu_stop_bits);
    if (!s->rtu || modbus_set_slave(s->rtu, cfg->unit_id) < 0 || modbus_connect(s->rtu) < 0) {
        rc = -errno;
        msg(err, errlen, "modbus: RTU %s: %s", cfg->rtu_device, modbus_strerror(errno));
        return rc ? rc : -EINVAL;
    }
    s->rtufd = modbus_get_socket(s->rtu);
    s->silfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (s->silfd < 0 || (rc = set_nonblock(s->rtufd)) < 0 ||
        (rc = ep_add(s->ep, s->rtufd, tag(TAG_RTU, 0))) < 0 ||
        (rc = ep_add(s->ep, s->silfd, tag(TAG_SILENCE, 0))) < 0) {
        rc = -errno;
        msg(err, errlen, "modbus: RTU %s: %s", cfg->rtu_device, strerror(errno));
        return rc;
    }
    return 0;
}

/* The settings of cfg the server keeps (checked; lists parsed).  0 or -1. */
static int settings_take(modbus_server_t *s, const modbus_server_config_t *cfg, char *err,
                         size_t errlen)
{
    if (cfg->max_clients < 1 || cfg->max_clients > MODBUS_SERVER_MAX_CLIENTS_LIMIT) {
        msg(err, errlen, "modbus: max_clients %u outside 1..%d", cfg->max_clients,
            MODBUS_SERVER_MAX_CLIENTS_LIMIT);
        return -1;
    }
    int rc = allow_parse(cfg->allow, s->allow, MODBUS_SERVER_ALLOW_MAX, err, errlen);
    if (rc < 0)
        return -1;
    s->n_allow = (unsigned)rc;
    rc = allow_parse(cfg->write_allow, s->wallow, MODBUS_SERVER_ALLOW_MAX, err, errlen);
    if (rc < 0)
        return -1;
    s->n_wallow = (unsigned)rc;
    s->n_objects = cfg->n_objects;
    s->writes_enabled = cfg->writes_enabled;
    s->max_clients = cfg->max_clients;
    s->idle_ns = (int64_t)cfg->idle_timeout_ms * 1000000;
    s->request_ns = (int64_t)(cfg->request_timeout_ms ? cfg->request_timeout_ms
                                                      : MODBUS_SERVER_DEFAULT_REQUEST_MS) *
                    1000000;
    s->unit_id = cfg->unit_id;
    s->peer_log_ns = (int64_t)cfg->peer_log_s * 1000000000;
    s->peer_logged_ns = now_ns();
    s->order = cfg->word_order >= 0 && cfg->word_order <= MBMAP_ORDER_DCBA
                   ? (mbmap_order_t)cfg->word_order
                   : MBMAP_ORDER_ABCD;
    return 0;
}

modbus_server_t *modbus_server_new(const modbus_server_config_t *cfg,
                                   const modbus_server_hooks_t *hooks, char *err, size_t errlen)
{
    modbus_server_t *s = calloc(1, sizeof *s);
    if (!s) {
        msg(err, errlen, "modbus: out of memory");
        return NULL;
    }
    s->ep = s->lfd = s->hkfd = s->rtufd = s->silfd = -1;
    s->port = -1;
    if (cfg->n_objects < 1 || cfg->n_objects > MBMAP_MAX_OBJECTS) {
        msg(err, errlen, "modbus: %u objects, the map holds 1..%d", cfg->n_objects,
            MBMAP_MAX_OBJECTS);
        goto fail;
    }
    if (settings_take(s, cfg, err, errlen) < 0)
        goto fail;
    if (hooks)
        s->hooks = *hooks;

    s->clients = calloc(s->max_clients, sizeof *s->clients);
    s->mb_rejected = calloc(s->n_objects, sizeof *s->mb_rejected);
    s->lost = calloc(s->n_objects, sizeof *s->lost);
    s->last_seq = calloc(s->n_objects, sizeof *s->last_seq);
    s->alt_seq = calloc(s->n_objects, sizeof *s->alt_seq);
    s->seq_jumps = calloc(s->n_objects, sizeof *s->seq_jumps);
    s->map = modbus_mapping_new(0, 0, (int)MBMAP_TABLE_REGS(s->n_objects),
                                (int)MBMAP_TABLE_REGS(s->n_objects));
    if (!s->clients || !s->mb_rejected || !s->lost || !s->last_seq || !s->alt_seq ||
        !s->seq_jumps || !s->map) {
        msg(err, errlen, "modbus: out of memory");
        goto fail;
    }
    for (unsigned i = 0; i < s->max_clients; i++)
        s->clients[i].fd = -1;
    s->mirror.start_registers = MBMAP_MIRROR_BASE;
    s->mirror.nb_registers = (int)MBMAP_TABLE_REGS(s->n_objects);
    s->mirror.tab_registers = s->map->tab_input_registers;

    s->ep = epoll_create1(EPOLL_CLOEXEC);
    s->hkfd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (s->ep < 0 || s->hkfd < 0) {
        msg(err, errlen, "modbus: epoll/timerfd: %s", strerror(errno));
        goto fail;
    }
    struct itimerspec hk = {
        .it_interval = {0, MODBUS_SERVER_HOUSEKEEPING_MS * 1000000L},
        .it_value = {0, MODBUS_SERVER_HOUSEKEEPING_MS * 1000000L},
    };
    if (timerfd_settime(s->hkfd, 0, &hk, NULL) < 0 ||
        ep_add(s->ep, s->hkfd, tag(TAG_HOUSEKEEPING, 0)) < 0 || mb_accept_init(&s->acc) < 0 ||
        ep_add(s->ep, s->acc.timer_fd, tag(TAG_BACKOFF, 0)) < 0) {
        msg(err, errlen, "modbus: timer: %s", strerror(errno));
        goto fail;
    }
    if ((cfg->tcp_address[0] || (cfg->systemd_socket && mb_systemd_listener() >= 0)) &&
        tcp_listen(s, cfg, err, errlen) < 0)
        goto fail;
    if (cfg->rtu_device[0] && rtu_open(s, cfg, err, errlen) < 0)
        goto fail;
    /* The image before the first tick: magic, version, object count. */
    mbmap_daemon_t d = {.objects = (uint16_t)s->n_objects,
                        .writes_enabled = (uint16_t)(s->writes_enabled != 0)};
    mbmap_encode_daemon(s->map->tab_input_registers, &d);
    mbmap_order_image(s->map->tab_input_registers, 0, s->order);
    return s;
fail:
    modbus_server_free(s);
    return NULL;
}

static void client_close_why(modbus_server_t *s, client_t *c, int why)
{
    if (c->fd < 0)
        return;
    if (c->peer_idx >= 0) {
        peer_t *p = &s->peers[c->peer_idx];
        p->n[PEER_REQ] += c->requests;
        p->n[PEER_EXC] += c->exceptions;
        if (why >= 0)
            p->n[why]++;
        p->last_ns = now_ns();
    }
    epoll_ctl(s->ep, EPOLL_CTL_DEL, c->fd, NULL);
    close(c->fd);
    c->fd = -1;
    c->len = 0;
    s->st.clients--;
}

static void client_close(modbus_server_t *s, client_t *c)
{
    client_close_why(s, c, WHY_PEER);
}

/* The entry of host ("a.b.c.d" or an IPv6 text): found, a free one, or the
 * least recently seen one no connected client uses (forgotten); -1 if none. */
static int peer_find(modbus_server_t *s, const char *host, int64_t now)
{
    int lru = -1;
    for (unsigned k = 0; k < s->n_peers; k++)
        if (!strcmp(s->peers[k].host, host))
            return (int)k;
    if (s->n_peers < MODBUS_SERVER_PEERS) {
        lru = (int)s->n_peers++;
    } else {
        for (unsigned k = 0; k < MODBUS_SERVER_PEERS; k++) {
            int used = 0;
            for (unsigned i = 0; i < s->max_clients && !used; i++)
                used = s->clients[i].fd >= 0 && s->clients[i].peer_idx == (int)k;
            if (!used && (lru < 0 || s->peers[k].last_ns < s->peers[lru].last_ns))
                lru = (int)k;
        }
        if (lru < 0)
            return -1;
    }
    memset(&s->peers[lru], 0, sizeof s->peers[lru]);
    snprintf(s->peers[lru].host, sizeof s->peers[lru].host, "%s", host);
    s->peers[lru].last_ns = now;
    return lru;
}

/* Peer k's counts: its closed connections plus the connected ones. */
static void peer_counts(const modbus_server_t *s, unsigned k, uint64_t n[6])
{
    memcpy(n, s->peers[k].n, 6 * sizeof n[0]);
    for (unsigned i = 0; i < s->max_clients; i++) {
        const client_t *c = &s->clients[i];
        if (c->fd >= 0 && c->peer_idx == (int)k) {
            n[PEER_REQ] += c->requests;
            n[PEER_EXC] += c->exceptions;
        }
    }
}

/* mb_worst_family, _ipv4 and _addr of host ("a.b.c.d" or an IPv6 text):
 * the address as 16 bytes, an IPv4 one as ::ffff:a.b.c.d (RFC 4291
 * 2.5.5.2), which is also how a dual-stack socket gives an IPv4 client:
 * family 4 for both. */
static void peer_address(const char *host, mbmap_daemon_t *w)
{
    uint8_t a[16] = {0};
    struct in_addr a4;
    if (inet_pton(AF_INET, host, &a4) == 1) {
        a[10] = a[11] = 0xff;
        memcpy(a + 12, &a4, 4);
    } else if (inet_pton(AF_INET6, host, a) != 1) {
        return; /* not an address: family 0 */
    }
    static const uint8_t mapped[12] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff};
    int v4 = memcmp(a, mapped, sizeof mapped) == 0;
    w->mb_worst_family = v4 ? 4 : 6;
    w->mb_worst_ipv4 = v4 ? (uint32_t)a[12] << 24 | (uint32_t)a[13] << 16 | (uint32_t)a[14] << 8 |
                                a[15]
                          : 0;
    for (unsigned i = 0; i < MBMAP_X_MB_WORST_ADDR_GROUPS; i++)
        w->mb_worst_addr[i] = (uint16_t)(a[2 * i] << 8 | a[2 * i + 1]);
}

/* mb_peers and the mb_worst_* fields: the address with the most drops
 * (evicted, slow, dropped), then the most exceptions; none if all are 0. */
static void peer_worst(modbus_server_t *s)
{
    uint64_t best_d = 0, best_e = 0, n[6];
    int best = -1;
    for (unsigned k = 0; k < s->n_peers; k++) {
        peer_counts(s, k, n);
        uint64_t d = n[PEER_EVICTED] + n[PEER_SLOW] + n[PEER_DROPPED];
        if ((d || n[PEER_EXC]) && (d > best_d || (d == best_d && n[PEER_EXC] > best_e))) {
            best = (int)k;
            best_d = d;
            best_e = n[PEER_EXC];
        }
    }
    memset(&s->worst, 0, sizeof s->worst);
    s->worst.mb_peers = (uint16_t)s->n_peers;
    if (best < 0)
        return;
    peer_counts(s, (unsigned)best, n);
    peer_address(s->peers[best].host, &s->worst);
    s->worst.mb_worst_requests = n[PEER_REQ];
    s->worst.mb_worst_exceptions = n[PEER_EXC];
    s->worst.mb_worst_drops = best_d;
}

/* Every peer_log_s: one notice line per client address that got exceptions
 * or was dropped since the last summary, with those counts and its totals. */
static void peer_log(modbus_server_t *s, int64_t now)
{
    if (!s->peer_log_ns || now - s->peer_logged_ns < s->peer_log_ns)
        return;
    s->peer_logged_ns = now;
    for (unsigned k = 0; k < s->n_peers; k++) {
        uint64_t n[6], *was = s->peers[k].logged, d[6];
        peer_counts(s, k, n);
        for (int j = 0; j < 6; j++)
            d[j] = n[j] - was[j];
        if (!d[PEER_EXC] && !d[PEER_EVICTED] && !d[PEER_SLOW] && !d[PEER_DROPPED])
            continue;
        log_msg(LOG_NOTICE,
                "modbus: client %s in the last %.0f s: %llu connections, %llu requests, %llu "
                "exceptions, %llu evicted, %llu slow, %llu dropped (since start: %llu requests, "
                "%llu exceptions, %llu evicted, %llu slow, %llu dropped)",
                s->peers[k].host, (double)s->peer_log_ns / 1e9, (unsigned long long)d[PEER_CONN],
                (unsigned long long)d[PEER_REQ], (unsigned long long)d[PEER_EXC],
                (unsigned long long)d[PEER_EVICTED], (unsigned long long)d[PEER_SLOW],
                (unsigned long long)d[PEER_DROPPED], (unsigned long long)n[PEER_REQ],
                (unsigned long long)n[PEER_EXC], (unsigned long long)n[PEER_EVICTED],
                (unsigned long long)n[PEER_SLOW], (unsigned long long)n[PEER_DROPPED]);
        memcpy(was, n, sizeof n);
    }
}

void modbus_server_free(modbus_server_t *s)
{
    if (!s)
        return;
    if (s->clients)
        for (unsigned i = 0; i < s->max_clients; i++)
            client_close(s, &s->clients[i]);
    if (s->tcp)
        modbus_free(s->tcp); /* never connected: its socket is not ours */
    if (s->rtu) {
        modbus_close(s->rtu);
        modbus_free(s->rtu);
    }
    /* A socket passed by systemd stays open for the life of the process: a
     * reload (free + new) finds it again with sd_listen_fds, and clients
     * connecting meanwhile wait in its backlog. */
    if (s->lfd >= 0 && !s->from_systemd)
        close(s->lfd);
    if (s->hkfd >= 0)
        close(s->hkfd);
    if (s->silfd >= 0)
        close(s->silfd);
    mb_accept_fini(&s->acc);
    if (s->ep >= 0)
        close(s->ep);
    if (s->map)
        modbus_mapping_free(s->map);
    free(s->clients);
    free(s->mb_rejected);
    free(s->lost);
    free(s->last_seq);
    free(s->alt_seq);
    free(s->seq_jumps);
    free(s);
}

int modbus_server_fd(const modbus_server_t *s)
{
    return s->ep;
}

const char *modbus_server_peer(const modbus_server_t *s)
{
    return s->cur_peer ? s->cur_peer : "";
}

int modbus_server_tcp_port(const modbus_server_t *s)
{
    return s->port;
}

int modbus_server_tcp_from_systemd(const modbus_server_t *s)
{
    return s->from_systemd;
}

uint32_t modbus_server_generation(const modbus_server_t *s)
{
    return s->gen;
}

void modbus_server_stats(const modbus_server_t *s, modbus_server_stats_t *st)
{
    *st = s->st;
}

int modbus_server_client(const modbus_server_t *s, unsigned i, modbus_server_client_t *out)
{
    if (i >= s->max_clients || s->clients[i].fd < 0)
        return -ENOENT;
    const client_t *c = &s->clients[i];
    memset(out, 0, sizeof *out);
    snprintf(out->peer, sizeof out->peer, "%s", c->peer);
    out->connected_ns = c->connected_ns;
    out->requests = c->requests;
    out->exceptions = c->exceptions;
    out->bytes_in = c->bytes_in;
    out->pending_since_ns = c->pending_ns;
    out->last_request_ns = c->last_ns;
    return 0;
}

/* A notice about a client, at most MODBUS_SERVER_LOG_PER_S a second (the
 * rest counted and reported with the next one that passes). */
static void client_note(modbus_server_t *s, const client_t *c, const char *what, int64_t now)
{
    if (now - s->log_window_ns >= 1000000000) {
        s->log_window_ns = now;
        s->log_count = 0;
    }
    if (s->log_count >= MODBUS_SERVER_LOG_PER_S) {
        s->log_suppressed++;
        return;
    }
    s->log_count++;
    char more[64] = "";
    if (s->log_suppressed)
        snprintf(more, sizeof more, " (%u more such messages not shown)", s->log_suppressed);
    s->log_suppressed = 0;
    log_peer(LOG_NOTICE, c->peer[0] ? c->peer : NULL,
             "modbus: %s %s after %.1f s: %llu requests, %llu exceptions, %llu bytes%s%s", what,
             c->peer[0] ? c->peer : "(socket)", (double)(now - c->connected_ns) / 1e9,
             (unsigned long long)c->requests, (unsigned long long)c->exceptions,
             (unsigned long long)c->bytes_in, c->pending_ns ? ", a partial request pending" : "",
             more);
}

/* ---- requests ------------------------------------------------------------- */

/*
 * Sequence numbers are the sender's (0 = not numbered): a step forward of d
 * within MODBUS_SERVER_SEQ_WINDOW means d - 1 waypoints it sent never
 * reached us.  A number outside the window (a bogus 0xFFFFFFFF, a sender
 * that restarted its numbering, a repeat or an older one) is not a loss: it
 * is counted in seq_jumps and remembered; the numbering it starts is adopted
 * as soon as the next waypoint continues it, else the old one is kept.
 * Modular arithmetic, so a wrap from 0xFFFFFFFF to 1 is a step of 2.
 */
static void count_seq(modbus_server_t *s, unsigned k, uint32_t seq)
{
    uint32_t last = s->last_seq[k], alt = s->alt_seq[k];
    if (!seq)
        return;
    if (!last) {
        s->last_seq[k] = seq;
        return;
    }
    uint32_t d = seq - last;
    if (d >= 1 && d <= MODBUS_SERVER_SEQ_WINDOW) {
        s->lost[k] += d - 1;
    } else if (alt && seq - alt >= 1 && seq - alt <= MODBUS_SERVER_SEQ_WINDOW) {
        s->lost[k] += seq - alt - 1; /* the new numbering continues: adopt it */
    } else {
        s->seq_jumps[k]++;
        s->alt_seq[k] = seq;
        return;
    }
    s->last_seq[k] = seq;
    s->alt_seq[k] = 0;
}

/* Apply a validated write; returns 0 or -MBMAP_E*. */
static int apply_write(modbus_server_t *s, const mbmap_write_t *w)
{
    int r;
    if (w->kind == MBMAP_WRITE_WAYPOINT) {
        r = s->hooks.waypoint ? s->hooks.waypoint(s->hooks.ctx, w->object, &w->wp) : -ENGINE_ESTATE;
        if (r == MODBUS_SERVER_HOOK_EADDRESS)
            return -MBMAP_EADDRESS;
        if (r == 0)
            count_seq(s, w->object, w->wp.seq);
        return mbmap_from_engine(r);
    }
    if (w->kind == MBMAP_WRITE_OVERRIDE) {
        r = s->hooks.override ? s->hooks.override(s->hooks.ctx, w->object, w->override_pct)
                              : -ENGINE_ESTATE;
        if (r == MODBUS_SERVER_HOOK_EADDRESS)
            return -MBMAP_EADDRESS;
        return mbmap_from_engine(r);
    }
    if (w->command == MBMAP_CMD_RESET_COUNTERS) {
        s->mb_rejected[w->object] = 0;
        s->lost[w->object] = 0;
        s->seq_jumps[w->object] = 0;
    }
    if (w->command == MBMAP_CMD_CLEAR) {
        s->last_seq[w->object] = 0;
        s->alt_seq[w->object] = 0;
    }
    r = s->hooks.command ? s->hooks.command(s->hooks.ctx, w->object, w->command) : -ENGINE_ESTATE;
    if (r == MODBUS_SERVER_HOOK_EADDRESS)
        return -MBMAP_EADDRESS;
    return mbmap_from_engine(r);
}

/*
 * Answer one whole request.  req/req_len is the ADU as libmodbus expects it
 * (MBAP or address first, no CRC checked here), pdu/pdu_len its PDU.
 * Returns what libmodbus returned (< 0: the peer could not be written to).
 */
static int serve(modbus_server_t *s, modbus_t *ctx, int writes, const uint8_t *req, int req_len,
                 const uint8_t *pdu, size_t pdu_len)
{
    int rc = mbmap_check_request(s->n_objects, writes, pdu, pdu_len);
    if (rc == 0 && (pdu[0] == MBMAP_FC_WRITE_SINGLE || pdu[0] == MBMAP_FC_WRITE_MULTIPLE)) {
        mbmap_write_t w;
        memset(&w, 0, sizeof w);
        w.object = s->n_objects;
        rc = mbmap_decode_write_order(s->n_objects, s->order, pdu, pdu_len, &w);
        if (rc == 0)
            rc = apply_write(s, &w);
        if (rc == -MBMAP_EVALUE && w.object < s->n_objects)
            s->mb_rejected[w.object]++;
    }
    s->st.requests++;
    if (rc < 0) {
        s->st.exceptions++;
        return modbus_reply_exception(ctx, req, (unsigned)-rc);
    }
    /* Validated above, so libmodbus takes none of its error paths (some of
     * which sleep for the response timeout and flush the socket). */
    if (pdu[0] == MBMAP_FC_READ_HOLDING && (((unsigned)pdu[1] << 8) | pdu[2]) >= MBMAP_MIRROR_BASE)
        return modbus_reply(ctx, req, req_len, &s->mirror);
    return modbus_reply(ctx, req, req_len, s->map);
}

static void client_read(modbus_server_t *s, client_t *c)
{
    ssize_t n = recv(c->fd, c->buf + c->len, sizeof c->buf - c->len, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        client_close(s, c);
        return;
    }
    if (n < 0)
        return;
    int64_t now = now_ns();
    if (c->len == 0)
        c->pending_ns = now; /* the deadline runs from a request's first byte */
    c->len += (size_t)n;
    c->bytes_in += (uint64_t)n;
    /* MBAP: transaction id (2), protocol id (2) = 0, length (2) = unit + PDU. */
    while (c->len >= 7) {
        unsigned proto = ((unsigned)c->buf[2] << 8) | c->buf[3];
        unsigned length = ((unsigned)c->buf[4] << 8) | c->buf[5];
        if (proto != 0 || length < 2 || length > 1 + MBMAP_PDU_MAX) {
            /* A byte stream with no frame boundary we can trust: drop it. */
            s->st.dropped++;
            client_close_why(s, c, WHY_DROPPED);
            return;
        }
        size_t total = 6 + length;
        if (c->len < total)
            return;
        if (c->buf[7] & 0x80) {
            /* 128..255 is the exception range, not a function: no valid
             * answer exists (libmodbus would wrap fc + 0x80 to a request code). */
            s->st.dropped++;
            client_close_why(s, c, WHY_DROPPED);
            return;
        }
        uint64_t exc = s->st.exceptions;
        modbus_set_socket(s->tcp, c->fd);
        s->cur_peer = c->peer;
        int rc = serve(s, s->tcp, c->may_write, c->buf, (int)total, c->buf + 7, total - 7);
        modbus_set_socket(s->tcp, -1);
        s->cur_peer = "";
        c->requests++;
        c->exceptions += s->st.exceptions - exc;
        c->last_ns = now;
        if (rc < 0) { /* peer not reading its answers: let it go */
            s->st.dropped++;
            client_close_why(s, c, WHY_DROPPED);
            return;
        }
        memmove(c->buf, c->buf + total, c->len - total);
        c->len -= total;
        c->pending_ns = c->len ? now : 0;
    }
}

/*
 * The client to evict for a newcomer (policy in modbus_server.h), or NULL if
 * every client is within MODBUS_SERVER_EVICT_GRACE_MS of its connection.
 */
static client_t *eviction_victim(modbus_server_t *s, int64_t now)
{
    client_t *best = NULL;
    int best_proven = 0;
    int64_t best_since = 0;
    for (unsigned i = 0; i < s->max_clients; i++) {
        client_t *c = &s->clients[i];
        if (c->fd < 0 || now - c->connected_ns < (int64_t)MODBUS_SERVER_EVICT_GRACE_MS * 1000000)
            continue;
        int proven = c->requests > 0;
        int64_t since = c->pending_ns ? c->pending_ns : c->last_ns; /* waiting since */
        if (!best || proven < best_proven || (proven == best_proven && since < best_since)) {
            best = c;
            best_proven = proven;
            best_since = since;
        }
    }
    return best;
}

static void peer_name(int fd, const struct sockaddr_storage *ss, char *out, size_t len)
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
    struct sockaddr_storage tmp;
    if (!ss) {
        socklen_t sl = sizeof tmp;
        if (getpeername(fd, (struct sockaddr *)&tmp, &sl) < 0) {
            out[0] = 0;
            return;
        }
        ss = &tmp;
    }
    if (ss->ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)ss;
        inet_ntop(AF_INET, &a->sin_addr, host, sizeof host);
        port = ntohs(a->sin_port);
    } else if (ss->ss_family == AF_INET6) {
        const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)ss;
        inet_ntop(AF_INET6, &a->sin6_addr, host, sizeof host);
        port = ntohs(a->sin6_port);
    } else {
        out[0] = 0;
        return;
    }
    snprintf(out, len, "%s:%u", host, port);
}

static void reap_hung_up(modbus_server_t *s);

static int client_add(modbus_server_t *s, int fd, const struct sockaddr_storage *ss)
{
    int64_t now = now_ns();
    client_t *c = NULL;
    for (unsigned i = 0; i < s->max_clients && !c; i++)
        if (s->clients[i].fd < 0)
            c = &s->clients[i];
    if (!c) {
        c = eviction_victim(s, now);
        if (c) {
            s->st.evicted++;
            client_note(s, c, "evicted to admit a newcomer:", now);
            client_close_why(s, c, WHY_EVICTED);
        }
    }
    if (!c || set_nonblock(fd) < 0 ||
        ep_add(s->ep, fd, tag(TAG_CLIENT, (unsigned)(c - s->clients))) < 0) {
        s->st.refused++;
        close(fd);
        return -EMFILE;
    }
    memset(c, 0, offsetof(client_t, buf));
    c->fd = fd;
    c->connected_ns = now;
    c->last_ns = now;
    c->may_write = may_write(s, ss);
    peer_name(fd, ss, c->peer, sizeof c->peer);
    s->st.clients++;
    s->st.connections++;
    char host[sizeof c->peer];
    snprintf(host, sizeof host, "%s", c->peer);
    char *colon = strrchr(host, ':'); /* host:port, the host without the port */
    if (colon)
        *colon = 0;
    c->peer_idx = host[0] ? peer_find(s, host, now) : -1;
    if (c->peer_idx >= 0) {
        s->peers[c->peer_idx].n[PEER_CONN]++;
        s->peers[c->peer_idx].last_ns = now;
    }
    return 0;
}

int modbus_server_adopt(modbus_server_t *s, int fd)
{
    if (s->st.clients >= s->max_clients)
        reap_hung_up(s);
    return client_add(s, fd, NULL);
}

/*
 * At the client limit, free the slots of clients that have already hung up
 * but whose close this loop has not read yet (a client that disconnects and
 * reconnects at once would otherwise be refused for its own old slot).
 * Only runs at the limit: O(max_clients) zero-timeout polls.
 */
static void reap_hung_up(modbus_server_t *s)
{
    for (unsigned i = 0; i < s->max_clients; i++) {
        client_t *c = &s->clients[i];
        struct pollfd p = {.fd = c->fd, .events = POLLRDHUP};
        if (c->fd >= 0 && poll(&p, 1, 0) > 0 &&
            (p.revents & (POLLRDHUP | POLLHUP | POLLERR | POLLNVAL)))
            client_close(s, c);
    }
}

static void do_accept(modbus_server_t *s)
{
    for (int i = 0; i < ACCEPTS_PER_EVENT; i++) {
        struct sockaddr_storage ss;
        socklen_t sl = sizeof ss;
        int fd = mb_accept(&s->acc, s->ep, s->lfd, (struct sockaddr *)&ss, &sl, &s->st.refused);
        if (fd < 0)
            return; /* EAGAIN, a connection reset before accept, out of fds (modbus_accept.h) */
        if (!allowed(s, &ss)) {
            s->st.refused++;
            close(fd);
            continue;
        }
        if (s->st.clients >= s->max_clients)
            reap_hung_up(s);
        client_add(s, fd, &ss);
    }
}

static void housekeeping(modbus_server_t *s)
{
    uint64_t exp;
    if (read(s->hkfd, &exp, sizeof exp) < 0)
        return;
    int64_t now = now_ns();
    for (unsigned i = 0; i < s->max_clients; i++) {
        client_t *c = &s->clients[i];
        if (c->fd < 0)
            continue;
        if (c->pending_ns && now - c->pending_ns > s->request_ns) {
            /* trickling: the deadline is for the whole request, not per byte */
            s->st.slow++;
            s->st.dropped++;
            client_note(s, c, "closed, request not whole within request_timeout_ms:", now);
            client_close_why(s, c, WHY_SLOW);
        } else if (!c->pending_ns && s->idle_ns > 0 && now - c->last_ns > s->idle_ns) {
            s->st.dropped++;
            client_close_why(s, c, WHY_DROPPED);
        }
    }
    peer_worst(s);
    peer_log(s, now);
    mb_accept_report(&s->acc, 0);
}

/* ---- RTU ---------------------------------------------------------------- */

static void rtu_arm_silence(modbus_server_t *s)
{
    struct itimerspec t = {.it_value = {0, MODBUS_SERVER_RTU_SILENCE_MS * 1000000L}};
    timerfd_settime(s->silfd, 0, &t, NULL);
}

static void rtu_frame(void *ctx, const uint8_t *f, size_t len)
{
    modbus_server_t *s = ctx;
    if (f[0] != s->unit_id || (f[1] & 0x80)) /* not ours, broadcast, or no function */
        return;
    s->cur_peer = s->rtu_peer;
    serve(s, s->rtu, s->writes_enabled, f, (int)len, f + 1, len - 3);
    s->cur_peer = "";
}

static void rtu_read(modbus_server_t *s)
{
    uint8_t b[RTU_BUF];
    uint64_t e0 = s->rtu_rx.crc_errors;
    ssize_t n = read(s->rtufd, b, mbrtu_space(&s->rtu_rx));
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
        return;
    if (n <= 0) {
        /* The line is gone (pty peer closed, USB adapter unplugged): stop
         * watching it rather than spin on EPOLLHUP.  Not reopened (a limit). */
        epoll_ctl(s->ep, EPOLL_CTL_DEL, s->rtufd, NULL);
        s->st.rtu_down = 1;
        return;
    }
    rtu_arm_silence(s);
    mbrtu_bytes(&s->rtu_rx, b, (size_t)n, rtu_frame, s);
    s->st.rtu_crc_errors += s->rtu_rx.crc_errors - e0;
}

static void rtu_silence(modbus_server_t *s)
{
    uint64_t exp, e0 = s->rtu_rx.crc_errors;
    if (read(s->silfd, &exp, sizeof exp) < 0)
        return;
    mbrtu_silence(&s->rtu_rx, rtu_frame, s);
    s->st.rtu_crc_errors += s->rtu_rx.crc_errors - e0;
}

/* ---- loop ----------------------------------------------------------------- */

int modbus_server_process(modbus_server_t *s)
{
    struct epoll_event ev[MODBUS_SERVER_EVENTS_PER_CALL];
    int n = epoll_wait(s->ep, ev, MODBUS_SERVER_EVENTS_PER_CALL, 0);
    if (n < 0)
        return errno == EINTR ? 0 : -errno;
    if (n == 0)
        return 0;
    int64_t t0 = now_ns();
    for (int i = 0; i < n; i++) {
        unsigned t = (unsigned)(ev[i].data.u64 >> 32);
        unsigned idx = (unsigned)(ev[i].data.u64 & 0xffffffffu);
        switch (t) {
        case TAG_LISTEN: do_accept(s); break;
        case TAG_HOUSEKEEPING: housekeeping(s); break;
        case TAG_RTU: rtu_read(s); break;
        case TAG_SILENCE: rtu_silence(s); break;
        case TAG_BACKOFF: mb_accept_resume(&s->acc, s->ep, s->lfd, tag(TAG_LISTEN, 0)); break;
        case TAG_CLIENT:
            if (idx < s->max_clients && s->clients[idx].fd >= 0)
                client_read(s, &s->clients[idx]);
            break;
        default: break;
        }
    }
    uint64_t dt = (uint64_t)(now_ns() - t0);
    s->st.process_calls++;
    s->st.process_total_ns += dt;
    if (dt > s->st.process_max_ns)
        s->st.process_max_ns = dt;
    return 0;
}

void modbus_server_publish(modbus_server_t *s, const mbmap_daemon_t *d, const mbmap_object_t *objs)
{
    uint16_t *ir = s->map->tab_input_registers;
    mbmap_daemon_t dd = *d;
    s->gen++;
    dd.generation = s->gen;
    dd.objects = (uint16_t)s->n_objects;
    dd.writes_enabled = (uint16_t)(s->writes_enabled != 0);
    dd.mb_requests = s->st.requests;
    dd.mb_exceptions = s->st.exceptions;
    dd.mb_refused = s->st.refused;
    dd.mb_clients = (uint16_t)s->st.clients;
    dd.mb_evicted = s->st.evicted;
    dd.mb_slow = s->st.slow;
    dd.mb_connections = s->st.connections;
    dd.mb_dropped = s->st.dropped;
    dd.mb_peers = s->worst.mb_peers;
    dd.mb_worst_family = s->worst.mb_worst_family;
    dd.mb_worst_ipv4 = s->worst.mb_worst_ipv4;
    dd.mb_worst_requests = s->worst.mb_worst_requests;
    dd.mb_worst_exceptions = s->worst.mb_worst_exceptions;
    dd.mb_worst_drops = s->worst.mb_worst_drops;
    memcpy(dd.mb_worst_addr, s->worst.mb_worst_addr, sizeof dd.mb_worst_addr);
    mbmap_encode_daemon(ir, &dd);
    for (unsigned k = 0; k < s->n_objects; k++) {
        if (objs[k].absent)
            continue; /* no object has this id: all 0 */
        mbmap_object_t o = objs[k];
        o.mb_rejected = s->mb_rejected[k];
        o.lost += s->lost[k];
        o.seq_jumps += s->seq_jumps[k];
        memcpy(o.mb_worst_addr, dd.mb_worst_addr, sizeof o.mb_worst_addr);
        mbmap_encode_object(ir, k, s->gen, &o);
        mbmap_encode_diag(ir, k, s->gen, &o);
    }
    mbmap_order_image(ir, s->n_objects, s->order);
    mbmap_order_diag(ir, s->n_objects, s->order);
}
