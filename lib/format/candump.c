/* candump.c - candump log text <-> frames (see candump.h). */
#include "candump.h"

#include <stdio.h>
#include <string.h>

/* Linux <linux/can.h> values in the text form (the text is Linux's, not ours). */
#define CANDUMP_ERR_FLAG 0x20000000u
#define CANDUMP_FD_BRS 0x01u
#define CANDUMP_FD_ESI 0x02u

static const char *const candump_errors[CANDUMP_ERROR_COUNT] = {
    [CANDUMP_OK] = "ok",
    [CANDUMP_ESKIP] = "comment or blank line",
    [CANDUMP_ESYNTAX] = "not a candump frame",
    [CANDUMP_ELEN] = "too many data bytes or invalid CAN FD length",
    [CANDUMP_ESPACE] = "buffer too small",
};

const char *candump_strerror(int err)
{
    if (err < 0)
        err = -err;
    if (err >= CANDUMP_ERROR_COUNT)
        return "unknown candump error";
    return candump_errors[err];
}

static int hexval(char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static int at_end(const char *s)
{
    while (*s == '\n' || *s == '\r')
        s++;
    return *s == '\0';
}

int candump_parse_frame(const char *s, canproto_frame_t *f)
{
    memset(f, 0, sizeof *f);
    unsigned ndig = 0;
    uint32_t id = 0;
    while (ndig < 9 && hexval(s[ndig]) >= 0) {
        id = id << 4 | (uint32_t)hexval(s[ndig]);
        ndig++;
    }
    if (s[ndig] != '#' || (ndig != 3 && ndig != 8))
        return -CANDUMP_ESYNTAX;
    if (ndig == 8) {
        if (id & CANDUMP_ERR_FLAG) {
            f->flags |= CANPROTO_F_ERR;
            id &= CANPROTO_EFF_MASK;
        } else if (id > CANPROTO_EFF_MASK) {
            return -CANDUMP_ESYNTAX;
        } else {
            f->flags |= CANPROTO_F_EFF;
        }
    }
    f->id = id;
    const char *p = s + ndig + 1;
    unsigned max = CANPROTO_CLASSIC_DLEN;
    if (*p == '#') { /* CAN FD */
        int fl = hexval(p[1]);
        if (fl < 0)
            return -CANDUMP_ESYNTAX;
        f->flags |= CANPROTO_F_FD;
        if (fl & CANDUMP_FD_BRS)
            f->flags |= CANPROTO_F_BRS;
        if (fl & CANDUMP_FD_ESI)
            f->flags |= CANPROTO_F_ESI;
        p += 2;
        max = CANPROTO_MAX_DLEN;
    } else if (*p == 'R' || *p == 'r') {
        f->flags |= CANPROTO_F_RTR;
        p++;
        int d = hexval(*p);
        if (d >= 0 && d <= 8) {
            f->len = (uint8_t)d;
            p++;
        }
        return at_end(p) ? 0 : -CANDUMP_ESYNTAX;
    }
    unsigned n = 0;
    while (!at_end(p)) {
        if (*p == '.') { /* cansend allows '.' between bytes */
            p++;
            continue;
        }
        int hi = hexval(p[0]), lo = hi >= 0 ? hexval(p[1]) : -1;
        if (hi < 0 || lo < 0)
            return -CANDUMP_ESYNTAX;
        if (n >= max)
            return -CANDUMP_ELEN;
        f->data[n++] = (uint8_t)(hi << 4 | lo);
        p += 2;
    }
    if ((f->flags & CANPROTO_F_FD) && !canproto_fd_len_valid(n))
        return -CANDUMP_ELEN;
    f->len = (uint8_t)n;
    return 0;
}

int candump_parse_line(const char *s, candump_line_t *out)
{
    memset(out, 0, sizeof *out);
    while (*s == ' ' || *s == '\t')
        s++;
    if (*s == '#' || at_end(s))
        return -CANDUMP_ESKIP;
    if (*s == '(') {
        const char *p = s + 1;
        int64_t sec = 0, usec = 0;
        unsigned nd = 0;
        while (*p >= '0' && *p <= '9' && nd < 12) { /* 12 digits: no overflow below */
            sec = sec * 10 + (*p++ - '0');
            nd++;
        }
        if (!nd || *p++ != '.')
            return -CANDUMP_ESYNTAX; /* also more than 12 digits of seconds */
        nd = 0;
        while (*p >= '0' && *p <= '9') {
            if (nd < 6)
                usec = usec * 10 + (*p - '0');
            p++;
            nd++;
        }
        if (!nd || *p++ != ')')
            return -CANDUMP_ESYNTAX;
        for (; nd < 6; nd++)
            usec *= 10;
        out->ts_us = sec * 1000000 + usec;
        if (*p != ' ')
            return -CANDUMP_ESYNTAX;
        while (*p == ' ')
            p++;
        size_t k = 0;
        while (*p && *p != ' ' && *p != '\t') {
            if (k >= CANDUMP_IFNAME_MAX)
                return -CANDUMP_ESYNTAX;
            out->ifname[k++] = *p++;
        }
        out->ifname[k] = '\0';
        if (!k)
            return -CANDUMP_ESYNTAX;
        while (*p == ' ' || *p == '\t')
            p++;
        s = p;
    }
    /* Newer can-utils and python-can append a direction field " R" / " T": drop it. */
    char fr[8 + 3 + 2 * CANPROTO_MAX_DLEN + 2 + 16];
    size_t k = 0;
    while (s[k] && s[k] != ' ' && s[k] != '\t' && s[k] != '\n' && s[k] != '\r') {
        if (k + 1 >= sizeof fr)
            return -CANDUMP_ESYNTAX;
        fr[k] = s[k];
        k++;
    }
    fr[k] = '\0';
    const char *rest = s + k;
    while (*rest == ' ' || *rest == '\t')
        rest++;
    if ((*rest == 'R' || *rest == 'T') && at_end(rest + 1))
        rest++;
    if (!at_end(rest))
        return -CANDUMP_ESYNTAX;
    return candump_parse_frame(fr, &out->frame);
}

static const char hexd[] = "0123456789ABCDEF";

int candump_format_frame(char *buf, size_t len, const canproto_frame_t *f)
{
    char tmp[8 + 3 + 2 * CANPROTO_MAX_DLEN + 2];
    size_t n = 0;
    unsigned dlen = f->len;
    if (f->flags & (CANPROTO_F_EFF | CANPROTO_F_ERR)) {
        uint32_t id = (f->id & CANPROTO_EFF_MASK) |
                      ((f->flags & CANPROTO_F_ERR) ? CANDUMP_ERR_FLAG : 0);
        for (int i = 7; i >= 0; i--)
            tmp[n++] = hexd[(id >> (4 * i)) & 0xF];
    } else {
        for (int i = 2; i >= 0; i--)
            tmp[n++] = hexd[(f->id >> (4 * i)) & 0xF];
    }
    tmp[n++] = '#';
    if (f->flags & CANPROTO_F_FD) {
        unsigned fl = ((f->flags & CANPROTO_F_BRS) ? CANDUMP_FD_BRS : 0) |
                      ((f->flags & CANPROTO_F_ESI) ? CANDUMP_FD_ESI : 0);
        tmp[n++] = '#';
        tmp[n++] = hexd[fl];
        if (dlen > CANPROTO_MAX_DLEN)
            dlen = CANPROTO_MAX_DLEN;
    } else if (f->flags & CANPROTO_F_RTR) {
        tmp[n++] = 'R';
        if (f->len && f->len <= CANPROTO_CLASSIC_DLEN) /* can-utils: "123#R3" */
            tmp[n++] = hexd[f->len];
        dlen = 0;
    } else if (dlen > CANPROTO_CLASSIC_DLEN) {
        dlen = CANPROTO_CLASSIC_DLEN;
    }
    for (unsigned i = 0; i < dlen; i++) {
        tmp[n++] = hexd[f->data[i] >> 4];
        tmp[n++] = hexd[f->data[i] & 0xF];
    }
    if (n + 1 > len)
        return -CANDUMP_ESPACE;
    memcpy(buf, tmp, n);
    buf[n] = '\0';
    return (int)n;
}

int candump_format_line(char *buf, size_t len, int64_t ts_us, const char *ifname,
                        const canproto_frame_t *f)
{
    char fr[8 + 3 + 2 * CANPROTO_MAX_DLEN + 2];
    int k = candump_format_frame(fr, sizeof fr, f);
    if (k < 0)
        return k;
    int n = snprintf(buf, len, "(%010lld.%06lld) %s %s\n", (long long)(ts_us / 1000000),
                     (long long)(ts_us % 1000000), ifname, fr);
    if (n < 0 || (size_t)n >= len)
        return -CANDUMP_ESPACE;
    return n;
}
