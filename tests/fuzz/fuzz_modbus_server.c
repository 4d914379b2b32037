/*
 * fuzz_modbus_server.c - libFuzzer target for the Modbus request path: bytes arrive
 * on a TCP client connection (to the server's listener on 127.0.0.1, a port
 * of its choosing; one connection per input, accepted as trajd accepts one:
 * Linux reuses a loopback port in TIME_WAIT, net.ipv4.tcp_tw_reuse), go through
 * MBAP framing, mbmap_check_request / mbmap_decode_write_order, the write hooks and
 * libmodbus's modbus_reply on the mapping.  The pure codec functions also get
 * the raw input (as a PDU and as an RTU frame).
 *
 * Oracle beyond the sanitizers: every byte the server sends back is a
 * sequence of well-formed Modbus/TCP responses (protocol 0, sane length,
 * function echoed or exception with code 1, 2, 3 or 6), and the server never
 * holds more clients than it accepted.  Not covered: the RTU serial path
 * (needs a tty); its framing function is fuzzed directly.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "mbmap.h"
#include "modbus_server.h"

#define NOBJ 3

static double last_t[NOBJ];
static unsigned buffered[NOBJ];

static int wp_hook(void *ctx, unsigned k, const engine_waypoint_t *wp)
{
    (void)ctx;
    if (k >= NOBJ)
        abort(); /* the decoder let a bad object through */
    int bad = !isfinite(wp->t_s);
    for (int a = 0; a < ENGINE_AXES; a++)
        bad |= !isfinite(wp->pos_m[a]) || (wp->has_vel == 1 && !isfinite(wp->vel_m_s[a]));
    if (bad)
        return -ENGINE_ENOTFINITE; /* the engine's refusal (engine_push): exception 03 */
    if (wp->t_s < last_t[k])
        return -ENGINE_EBACKWARDS;
    if (buffered[k] >= 8) {
        buffered[k] = 0;
        return -ENGINE_EFULL;
    }
    buffered[k]++;
    last_t[k] = wp->t_s;
    return 0;
}

static int cmd_hook(void *ctx, unsigned k, unsigned cmd)
{
    (void)ctx;
    if (k >= NOBJ || cmd < MBMAP_CMD_START || cmd > MBMAP_CMD_FINISH)
        abort();
    if (cmd == MBMAP_CMD_CLEAR)
        last_t[k] = -INFINITY, buffered[k] = 0;
    return 0;
}

static modbus_server_t *srv;

static void check_responses(const uint8_t *b, size_t n)
{
    while (n >= 8) {
        unsigned proto = ((unsigned)b[2] << 8) | b[3];
        unsigned len = ((unsigned)b[4] << 8) | b[5];
        if (proto != 0 || len < 2 || len > 254)
            abort();
        if (n < 6 + (size_t)len)
            return; /* cut by our read buffer */
        uint8_t fc = b[7];
        if (fc & 0x80) {
            uint8_t code = b[8];
            if (len != 3 || (code != 1 && code != 2 && code != 3 && code != 6))
                abort();
        } else if (fc != 3 && fc != 4 && fc != 6 && fc != 16) {
            abort(); /* a normal answer to a function we do not serve */
        }
        b += 6 + len;
        n -= 6 + (size_t)len;
    }
}

/* A client connected to the server's listener, non-blocking. */
static int connect_client(void)
{
    struct sockaddr_in a = {.sin_family = AF_INET,
                            .sin_port = htons((uint16_t)modbus_server_tcp_port(srv)),
                            .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0 || connect(fd, (const struct sockaddr *)&a, sizeof a) < 0 ||
        fcntl(fd, F_SETFL, O_NONBLOCK) < 0)
        abort();
    return fd;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!srv) {
        modbus_server_config_t cfg;
        modbus_server_config_default(&cfg);
        snprintf(cfg.tcp_address, sizeof cfg.tcp_address, "127.0.0.1");
        cfg.tcp_port = 0;   /* a free port, read back below */
        cfg.peer_log_s = 0; /* no per-address notices: every input connects from here */
        cfg.writes_enabled = 1;
        cfg.n_objects = NOBJ;
        cfg.max_clients = 2;
        modbus_server_hooks_t hooks = {wp_hook, cmd_hook, NULL, NULL, NULL};
        srv = modbus_server_new(&cfg, &hooks, NULL, 0);
        if (!srv)
            abort();
        for (int k = 0; k < NOBJ; k++)
            last_t[k] = -INFINITY;
    }

    /* Pure paths on the raw bytes. */
    mbmap_write_t w;
    mbmap_check_request(NOBJ, 1, data, size);
    mbmap_decode_write_order(NOBJ, MBMAP_ORDER_ABCD, data, size, &w);
    int fl = mbmap_rtu_frame_len(data, size);
    if (fl > 2 && (size_t)fl <= size)
        mbmap_crc16(data, (size_t)fl - 2);

    /* A snapshot made of the input's bytes (NaN, inf, anything). */
    static mbmap_object_t objs[NOBJ];
    mbmap_daemon_t d;
    memset(&d, 0, sizeof d);
    for (int k = 0; k < NOBJ; k++) {
        size_t take = size < sizeof objs[k].sp ? size : sizeof objs[k].sp;
        memset(&objs[k], 0, sizeof objs[k]);
        memcpy(&objs[k].sp, data, take);
    }
    modbus_server_publish(srv, &d, objs);

    /* The request path over a real connection, accepted (bounded). */
    int cl = connect_client();
    modbus_server_stats_t st;
    for (int i = 0; i < 16; i++) {
        modbus_server_process(srv);
        modbus_server_stats(srv, &st);
        if (st.clients == 1)
            break;
    }
    if (st.clients != 1)
        abort();
    size_t off = 0;
    static uint8_t out[1 << 20];
    size_t got = 0;
    for (int round = 0; round < 64 && (off < size || round < 2); round++) {
        if (off < size) {
            ssize_t n = send(cl, data + off, size - off, MSG_DONTWAIT | MSG_NOSIGNAL);
            if (n > 0)
                off += (size_t)n;
        }
        if (modbus_server_process(srv) < 0)
            abort();
        ssize_t r = got < sizeof out ? recv(cl, out + got, sizeof out - got, MSG_DONTWAIT) : 0;
        if (r > 0)
            got += (size_t)r;
    }
    check_responses(out, got);
    close(cl);
    /* The server sees EOF and lets the client go (bounded). */
    for (int i = 0; i < 16; i++) {
        modbus_server_process(srv);
        modbus_server_stats(srv, &st);
        if (st.clients == 0)
            break;
    }
    modbus_server_stats(srv, &st);
    if (st.clients != 0)
        abort();
    return 0;
}
