/* modbus_sessions.c - the TCP clients of the Modbus server: allow-lists,
 * accept and eviction, per-client and per-address counters, deadlines
 * (policy in modbus_server.h). */
#include "modbus_server_int.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "log.h"

/* ---- allow-list ---------------------------------------------------------- */

int mbs_allow_parse(const char *list, allow_t *out, unsigned max, char *err, size_t errlen)
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
    return mbs_allow_parse(allow, tmp, MODBUS_SERVER_ALLOW_MAX, err, errlen);
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

/* Writes for a client at ss: writes = yes, and the client in write_allow if
 * there is one. */
static int may_write(const modbus_server_t *s, const struct sockaddr_storage *ss)
{
    if (!s->writes_enabled)
        return 0;
    if (!s->n_wallow)
        return 1;
    return in_list(s->wallow, s->n_wallow, ss);
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

void mbs_client_close_why(modbus_server_t *s, client_t *c, int why)
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

void mbs_client_close(modbus_server_t *s, client_t *c)
{
    mbs_client_close_why(s, c, WHY_PEER);
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
static void peer_log(modbus_server_t *s, int64_t now, int last)
{
    if (!s->peer_log_ns || (!last && now - s->peer_logged_ns < s->peer_log_ns))
        return;
    /* the interval, or (the server closing) the time since the last summary */
    double span_s = last ? (double)(now - s->peer_logged_ns) / 1e9 : (double)s->peer_log_ns / 1e9;
    s->peer_logged_ns = now;
    for (unsigned k = 0; k < s->n_peers; k++) {
        uint64_t n[6], *was = s->peers[k].logged, d[6];
        peer_counts(s, k, n);
        for (int j = 0; j < 6; j++)
            d[j] = n[j] - was[j];
        if (!d[PEER_EXC] && !d[PEER_EVICTED] && !d[PEER_SLOW] && !d[PEER_DROPPED])
            continue;
        log_msg(LOG_NOTICE,
                "modbus: client %s in the last %.*f s: %llu connections, %llu requests, %llu "
                "exceptions, %llu evicted, %llu slow, %llu dropped (since start: %llu requests, "
                "%llu exceptions, %llu evicted, %llu slow, %llu dropped)",
                s->peers[k].host, last ? 1 : 0, span_s, (unsigned long long)d[PEER_CONN],
                (unsigned long long)d[PEER_REQ], (unsigned long long)d[PEER_EXC],
                (unsigned long long)d[PEER_EVICTED], (unsigned long long)d[PEER_SLOW],
                (unsigned long long)d[PEER_DROPPED], (unsigned long long)n[PEER_REQ],
                (unsigned long long)n[PEER_EXC], (unsigned long long)n[PEER_EVICTED],
                (unsigned long long)n[PEER_SLOW], (unsigned long long)n[PEER_DROPPED]);
        memcpy(was, n, sizeof n);
    }
}

void mbs_peer_log_last(modbus_server_t *s)
{
    peer_log(s, now_ns(), 1);
}

/* A notice about a client, at most MODBUS_SERVER_LOG_PER_S a second (the
 * rest counted and reported with the next one that passes). */
void mbs_client_note(modbus_server_t *s, const client_t *c, const char *what, int64_t now)
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

/* "host:port" of the client at ss ("" if neither IPv4 nor IPv6). */
static void peer_name(const struct sockaddr_storage *ss, char *out, size_t len)
{
    char host[INET6_ADDRSTRLEN] = "?";
    unsigned port = 0;
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
            mbs_client_note(s, c, "evicted to admit a newcomer:", now);
            mbs_client_close_why(s, c, WHY_EVICTED);
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
    peer_name(ss, c->peer, sizeof c->peer);
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
            mbs_client_close(s, c);
    }
}

void mbs_accept(modbus_server_t *s)
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

void mbs_housekeeping(modbus_server_t *s)
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
            mbs_client_note(s, c, "closed, request not whole within request_timeout_ms:", now);
            mbs_client_close_why(s, c, WHY_SLOW);
        } else if (!c->pending_ns && s->idle_ns > 0 && now - c->last_ns > s->idle_ns) {
            s->st.dropped++;
            mbs_client_note(s, c, "closed, idle longer than idle_timeout_ms:", now);
            mbs_client_close_why(s, c, WHY_DROPPED);
        }
    }
    peer_worst(s);
    peer_log(s, now, 0);
    ag_report(&s->acc, 0);
}
