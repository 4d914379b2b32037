/* modbus_dispatch.c - one whole Modbus request answered: checked, a write
 * applied through the daemon's hooks, the reply by libmodbus. */
#include "modbus_server_int.h"

#include <string.h>

/*
 * Sequence numbers are the sender's (0 = not numbered): a step forward of d
 * within MODBUS_SERVER_SEQ_WINDOW means d - 1 waypoints it sent never
 * reached us.  The last number again is a repeat (a client retrying after a
 * reply it lost: the engine counts the duplicate), no jump.  A number outside
 * the window (a bogus 0xFFFFFFFF, a sender that restarted its numbering, an
 * older one) is not a loss: it is counted in seq_jumps and remembered; the numbering it starts is adopted
 * as soon as the next waypoint continues it, else the old one is kept.
 * Modular arithmetic, so a wrap from 0xFFFFFFFF to 1 is a step of 2.  A
 * number counted lost that comes late (writers racing, each one's waypoints
 * in order) is taken back, up to 63 behind the newest (s->missing).
 */
#define SEQ_MISSING_BITS 64u
static uint64_t missing_after_step(uint64_t mask, uint32_t d)
{
    /* the numbers skipped by a step of d: 1 .. d - 1 behind the new last */
    uint64_t m = d < SEQ_MISSING_BITS ? mask << d : 0;
    for (uint32_t i = 1; i < d && i < SEQ_MISSING_BITS; i++)
        m |= 1ull << i;
    return m;
}

static void count_seq(modbus_server_t *s, unsigned k, uint32_t seq)
{
    uint32_t last = s->last_seq[k], alt = s->alt_seq[k];
    if (!seq)
        return;
    if (!last) {
        s->last_seq[k] = seq;
        s->missing[k] = 0;
        return;
    }
    uint32_t d = seq - last, back = last - seq;
    if (d == 0)
        return; /* a repeat of the last one */
    if (back >= 1 && back < SEQ_MISSING_BITS && (s->missing[k] >> back) & 1u) {
        s->missing[k] &= ~(1ull << back); /* counted lost, came late after all */
        s->lost[k]--;
        return;
    }
    if (d >= 1 && d <= MODBUS_SERVER_SEQ_WINDOW) {
        s->lost[k] += d - 1;
        s->missing[k] = missing_after_step(s->missing[k], d);
    } else if (alt && seq - alt >= 1 && seq - alt <= MODBUS_SERVER_SEQ_WINDOW) {
        s->lost[k] += seq - alt - 1; /* the new numbering continues: adopt it */
        s->missing[k] = missing_after_step(0, seq - alt);
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
        /* it came (taken, or refused for its value: counted in rejected), so its
         * number is no gap; one the buffer had no room for comes again */
        if (r != -ENGINE_EFULL)
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
        s->missing[w->object] = 0;
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
int mbs_serve(modbus_server_t *s, modbus_t *ctx, int writes, const uint8_t *req, int req_len,
              const uint8_t *pdu, size_t pdu_len)
{
    int rc = mbmap_check_request(s->n_objects, writes, pdu, pdu_len);
    if (rc == 0 && (pdu[0] == MBMAP_FC_WRITE_SINGLE || pdu[0] == MBMAP_FC_WRITE_MULTIPLE)) {
        mbmap_write_t w;
        memset(&w, 0, sizeof w);
        w.object = s->n_objects;
        rc = mbmap_decode_write_order(s->n_objects, s->order, pdu, pdu_len, &w);
        /* a waypoint decoded but refused (a NaN or infinite value: mbmap.h) is
         * the engine's to refuse, as any source's: counted
         * (rejected_not_finite), logged with its peer and seq, and its number
         * came (no gap); still exception 03 */
        if (rc == 0 ||
            (rc == -MBMAP_EVALUE && w.kind == MBMAP_WRITE_WAYPOINT && w.object < s->n_objects))
            rc = apply_write(s, &w);
        if (rc == -MBMAP_EVALUE && w.object < s->n_objects) {
            s->mb_rejected[w.object]++;
            if ((w.kind == MBMAP_WRITE_COMMAND || w.kind == MBMAP_WRITE_OVERRIDE) &&
                s->hooks.refused)
                s->hooks.refused(s->hooks.ctx, w.object, &w);
        }
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
