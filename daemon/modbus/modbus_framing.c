/* modbus_framing.c - Modbus requests delimited: TCP by the MBAP length, RTU by
 * the function code or line silence (lib/proto/mbrtu.h). */
#include "modbus_server_int.h"

#include <string.h>
#include <sys/timerfd.h>
#include <unistd.h>

void mbs_client_read(modbus_server_t *s, client_t *c)
{
    ssize_t n = recv(c->fd, c->buf + c->len, sizeof c->buf - c->len, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        mbs_client_close(s, c);
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
            char what[96];
            snprintf(what, sizeof what,
                     "closed, no MBAP frame boundary to trust (protocol id %u, length %u):", proto,
                     length);
            s->st.dropped++;
            mbs_client_note(s, c, what, now);
            mbs_client_close_why(s, c, WHY_DROPPED);
            return;
        }
        size_t total = 6 + length;
        if (c->len < total)
            return;
        if (c->buf[7] & 0x80) {
            /* 128..255 is the exception range, not a function: no valid
             * answer exists (libmodbus would wrap fc + 0x80 to a request code). */
            s->st.dropped++;
            mbs_client_note(s, c, "closed, a function code in the exception range:", now);
            mbs_client_close_why(s, c, WHY_DROPPED);
            return;
        }
        uint64_t exc = s->st.exceptions;
        modbus_set_socket(s->tcp, c->fd);
        s->cur_peer = c->peer;
        int rc = mbs_serve(s, s->tcp, c->may_write, c->buf, (int)total, c->buf + 7, total - 7);
        modbus_set_socket(s->tcp, -1);
        s->cur_peer = "";
        c->requests++;
        c->exceptions += s->st.exceptions - exc;
        c->last_ns = now;
        if (rc < 0) { /* peer not reading its answers: let it go */
            s->st.dropped++;
            mbs_client_note(s, c, "closed, not reading its answers:", now);
            mbs_client_close_why(s, c, WHY_DROPPED);
            return;
        }
        memmove(c->buf, c->buf + total, c->len - total);
        c->len -= total;
        c->pending_ns = c->len ? now : 0;
    }
}

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
    mbs_serve(s, s->rtu, s->writes_enabled, f, (int)len, f + 1, len - 3);
    s->cur_peer = "";
}

void mbs_rtu_read(modbus_server_t *s)
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

void mbs_rtu_silence(modbus_server_t *s)
{
    uint64_t exp, e0 = s->rtu_rx.crc_errors;
    if (read(s->silfd, &exp, sizeof exp) < 0)
        return;
    mbrtu_silence(&s->rtu_rx, rtu_frame, s);
    s->st.rtu_crc_errors += s->rtu_rx.crc_errors - e0;
}
