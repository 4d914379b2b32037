/* modbus_server.c - see modbus_server.h: configuration, set-up, the loop and
 * the published image (framing, sessions and dispatch in their own files). */
#include "modbus_server_int.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <string.h>
#include <sys/timerfd.h>
#include <unistd.h>

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

/* A numeric IPv4 or IPv6 address (what the listener takes: AI_NUMERICHOST),
 * checked here, at its line: a name or 999.1.1.1 passed --check-config and
 * the start then failed with exit 69 and no file:line.  0 or -EINVAL. */
static int set_address(modbus_server_config_t *cfg, const char *value, char *err, size_t errlen)
{
    unsigned char a[sizeof(struct in6_addr)];
    if (copy_str(cfg->tcp_address, sizeof cfg->tcp_address, value) < 0 ||
        (value[0] && inet_pton(AF_INET, value, a) != 1 && inet_pton(AF_INET6, value, a) != 1)) {
        msg(err, errlen,
            "'%s' is not a numeric IPv4 or IPv6 address (a name is not "
            "resolved: 127.0.0.1, 0.0.0.0, ::1, ::)",
            value);
        return -EINVAL;
    }
    return 0;
}

/* The numeric keys of [modbus]: name, least and greatest value, and the
 * field (an int, or an unsigned when is_u) it sets. */
#define NUM_KEY(k, lo, hi, f, u)                                                                   \
    {                                                                                              \
        k, lo, hi, offsetof(modbus_server_config_t, f), u                                          \
    }
static const struct {
    const char *key;
    long lo, hi;
    size_t off;
    int is_u;
} num_keys[] = {
    NUM_KEY("port", 0, 65535, tcp_port, 0),
    NUM_KEY("rtu_baud", 50, 4000000, rtu_baud, 0),
    NUM_KEY("rtu_data_bits", 7, 8, rtu_data_bits, 0),
    NUM_KEY("rtu_stop_bits", 1, 2, rtu_stop_bits, 0),
    NUM_KEY("unit_id", 1, 247, unit_id, 0),
    NUM_KEY("max_clients", 1, MODBUS_SERVER_MAX_CLIENTS_LIMIT, max_clients, 1),
    NUM_KEY("idle_timeout_ms", 0, 86400000, idle_timeout_ms, 1),
    NUM_KEY("request_timeout_ms", 100, 600000, request_timeout_ms, 1),
    NUM_KEY("peer_log_s", 0, 86400, peer_log_s, 1),
};

/* A numeric key's value into its field. */
static void set_num(modbus_server_config_t *cfg, unsigned k, long x)
{
    char *f = (char *)cfg + num_keys[k].off;
    if (num_keys[k].is_u) {
        unsigned u = (unsigned)x;
        memcpy(f, &u, sizeof u);
    } else {
        int i = (int)x;
        memcpy(f, &i, sizeof i);
    }
}

/* A key of [modbus]; a bad value says what the key takes (the caller puts
 * the file, line, section and key before it). */
int modbus_server_config_set(modbus_server_config_t *cfg, const char *key, const char *value,
                             char *err, size_t errlen)
{
    long x = 0;
    int rc = 0;
    const char *expect = "yes or no";
    for (unsigned k = 0; k < sizeof num_keys / sizeof num_keys[0]; k++)
        if (!strcmp(key, num_keys[k].key)) {
            if (parse_uint(value, num_keys[k].lo, num_keys[k].hi, &x) < 0) {
                msg(err, errlen, "expected a number in [%ld, %ld], got '%s'", num_keys[k].lo,
                    num_keys[k].hi, value);
                return -EINVAL;
            }
            set_num(cfg, k, x);
            return 0;
        }
    if (!strcmp(key, "enabled"))
        rc = parse_bool(value, &cfg->enabled);
    else if (!strcmp(key, "writes"))
        rc = parse_bool(value, &cfg->writes_enabled);
    else if (!strcmp(key, "systemd_socket"))
        rc = parse_bool(value, &cfg->systemd_socket);
    else if (!strcmp(key, "address"))
        return set_address(cfg, value, err, errlen);
    else if (!strcmp(key, "rtu_device")) {
        rc = copy_str(cfg->rtu_device, sizeof cfg->rtu_device, value);
        expect = "a device path (too long)";
    } else if (!strcmp(key, "allow")) {
        rc = copy_str(cfg->allow, sizeof cfg->allow, value);
        if (rc == 0 && modbus_server_allow_check(value, err, errlen) < 0)
            return -EINVAL;
        expect = "a list of addresses (too long)";
    } else if (!strcmp(key, "write_allow")) {
        rc = copy_str(cfg->write_allow, sizeof cfg->write_allow, value);
        if (rc == 0 && modbus_server_allow_check(value, err, errlen) < 0)
            return -EINVAL;
        expect = "a list of addresses (too long)";
    } else if (!strcmp(key, "word_order")) {
        if ((cfg->word_order = mbmap_order_parse(value)) < 0)
            rc = -EINVAL, cfg->word_order = MBMAP_ORDER_ABCD;
        expect = "ABCD, CDAB, BADC or DCBA";
    } else if (!strcmp(key, "rtu_parity")) {
        if (!strcmp(value, "N") || !strcmp(value, "none"))
            cfg->rtu_parity = 'N';
        else if (!strcmp(value, "E") || !strcmp(value, "even"))
            cfg->rtu_parity = 'E';
        else if (!strcmp(value, "O") || !strcmp(value, "odd"))
            cfg->rtu_parity = 'O';
        else
            rc = -EINVAL;
        expect = "N, E or O (none, even, odd)";
    } else {
        msg(err, errlen, "unknown key '%s'", key);
        return -ENOENT;
    }
    if (rc < 0)
        msg(err, errlen, "expected %s, got '%s'", expect, value);
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
    int rc = mbs_allow_parse(cfg->allow, s->allow, MODBUS_SERVER_ALLOW_MAX, err, errlen);
    if (rc < 0)
        return -1;
    s->n_allow = (unsigned)rc;
    rc = mbs_allow_parse(cfg->write_allow, s->wallow, MODBUS_SERVER_ALLOW_MAX, err, errlen);
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
    s->missing = calloc(s->n_objects, sizeof *s->missing);
    s->seq_jumps = calloc(s->n_objects, sizeof *s->seq_jumps);
    s->map = modbus_mapping_new(0, 0, (int)MBMAP_TABLE_REGS(s->n_objects),
                                (int)MBMAP_TABLE_REGS(s->n_objects));
    if (!s->clients || !s->mb_rejected || !s->lost || !s->last_seq || !s->alt_seq || !s->missing ||
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

void modbus_server_free(modbus_server_t *s)
{
    if (!s)
        return;
    if (s->clients) {
        for (unsigned i = 0; i < s->max_clients; i++)
            mbs_client_close(s, &s->clients[i]);
        mbs_peer_log_last(s); /* what came since the last summary: told */
    }
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
    ag_fini(&s->acc);
    if (s->ep >= 0)
        close(s->ep);
    if (s->map)
        modbus_mapping_free(s->map);
    free(s->clients);
    free(s->mb_rejected);
    free(s->lost);
    free(s->last_seq);
    free(s->alt_seq);
    free(s->missing);
    free(s->seq_jumps);
    free(s);
}

void modbus_server_obj_seq(const modbus_server_t *s, unsigned k, modbus_server_obj_seq_t *out)
{
    memset(out, 0, sizeof *out);
    if (k >= s->n_objects)
        return;
    *out = (modbus_server_obj_seq_t){s->mb_rejected[k], s->lost[k],     s->seq_jumps[k],
                                     s->missing[k],     s->last_seq[k], s->alt_seq[k]};
}

void modbus_server_set_obj_seq(modbus_server_t *s, unsigned k, const modbus_server_obj_seq_t *in)
{
    if (k >= s->n_objects)
        return;
    s->mb_rejected[k] = in->mb_rejected;
    s->lost[k] = in->lost;
    s->seq_jumps[k] = in->seq_jumps;
    s->missing[k] = in->missing;
    s->last_seq[k] = in->last_seq;
    s->alt_seq[k] = in->alt_seq;
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

void modbus_server_stats(const modbus_server_t *s, modbus_server_stats_t *st)
{
    *st = s->st;
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
        case TAG_LISTEN: mbs_accept(s); break;
        case TAG_HOUSEKEEPING: mbs_housekeeping(s); break;
        case TAG_RTU: mbs_rtu_read(s); break;
        case TAG_SILENCE: mbs_rtu_silence(s); break;
        case TAG_BACKOFF: mb_accept_resume(&s->acc, s->ep, s->lfd, tag(TAG_LISTEN, 0)); break;
        case TAG_CLIENT:
            if (idx < s->max_clients && s->clients[idx].fd >= 0)
                mbs_client_read(s, &s->clients[idx]);
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
        /* the override holding register reads the override in force, whoever
         * set it (trajctl, CAN, a clear), not the last value written here */
        s->map->tab_registers[MBMAP_OBJ_BASE(k) + MBMAP_H_OVERRIDE] =
            ir[MBMAP_OBJ_BASE(k) + MBMAP_O_OVERRIDE];
    }
    mbmap_order_image(ir, s->n_objects, s->order);
    mbmap_order_diag(ir, s->n_objects, s->order);
}
