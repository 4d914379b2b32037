/* canproto_rx.c - waypoint reassembly: frames of the WAYPOINT ids into
 * waypoints, with the sequence tracking (canproto.h, "waypoint reassembly"). */
#include "canproto.h"
#include "canproto_le.h"

#include <string.h>

void canproto_rx_init(canproto_rx_t *rx, canproto_slot_t *slots, unsigned nslots)
{
    memset(rx, 0, sizeof *rx);
    rx->slots = slots;
    rx->nslots = nslots;
    canproto_rx_restart(rx);
}

void canproto_rx_restart(canproto_rx_t *rx)
{
    for (unsigned i = 0; i < rx->nslots; i++)
        memset(&rx->slots[i], 0, sizeof rx->slots[i]);
    rx->have_last = 0;
    rx->last_seq = 0;
}

static int malformed(canproto_rx_t *rx, int err)
{
    rx->st.malformed++;
    rx->st.malformed_by[err]++;
    return -err;
}

/* Signed distance of seq8 ahead of the last consumed waypoint (-128..127). */
static int seq_ahead(const canproto_rx_t *rx, uint8_t seq8)
{
    return (int)(int8_t)(uint8_t)(seq8 - (uint8_t)rx->last_seq);
}

/*
 * Duplicate or stale (only with a sequence history)?  Counts and returns 1
 * if the frame is to be ignored.
 */
static int seq_old(canproto_rx_t *rx, uint8_t seq8)
{
    if (!rx->have_last)
        return 0;
    int d = seq_ahead(rx, seq8);
    if (d == 0) {
        rx->st.duplicates++;
        return 1;
    }
    if (d < 0) {
        rx->st.out_of_order++;
        return 1;
    }
    return 0;
}

static void fill_out(const canproto_rx_t *rx, uint8_t seq8, uint64_t t_us,
                     const int64_t pos_um[ENGINE_AXES], const int16_t *vel_cm_s,
                     canproto_rx_out_t *out)
{
    memset(out, 0, sizeof *out);
    if (vel_cm_s) {
        out->wp.has_vel = 1;
        for (unsigned a = 0; a < ENGINE_AXES; a++)
            out->wp.vel_m_s[a] = (double)vel_cm_s[a] / CANPROTO_WP_VEL_BITS_PER_M_S;
    }
    /* Divide by the exact 1e6 rather than multiply by the inexact 1e-6: the
     * result is then the correctly rounded value of the decimal number, the
     * same double strtod gives for a track file with 6 decimals, so CAN input
     * and a replayed file drive the engine bit-identically. */
    out->wp.t_s = (double)t_us / CANPROTO_WP_BITS_PER_S;
    for (unsigned a = 0; a < ENGINE_AXES; a++)
        out->wp.pos_m[a] = (double)pos_um[a] / CANPROTO_WP_BITS_PER_M;
    if (rx->have_last) {
        int d = seq_ahead(rx, seq8); /* > 0: seq_old() ruled the rest out */
        out->wp.seq = rx->last_seq + (uint32_t)d;
        out->lost_before = (uint32_t)(d - 1);
    } else {
        out->wp.seq = seq8;
    }
}

static canproto_slot_t *slot_for(canproto_rx_t *rx, uint8_t seq8)
{
    /* nslots >= 1 (canproto_rx_init's contract), so slot 0 exists: the search
     * for the oldest starts there (it only matters when every slot is used) */
    canproto_slot_t *free_slot = NULL, *oldest = &rx->slots[0];
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (s->used && s->seq8 == seq8)
            return s;
        if (!s->used && !free_slot)
            free_slot = s;
        /* oldest = the one opened first: lowest arrival stamp */
        if (s->used && s->stamp < oldest->stamp)
            oldest = s;
    }
    canproto_slot_t *s = free_slot;
    if (!s) {
        /* every slot holds a partial waypoint: abandon the oldest */
        rx->st.incomplete++;
        s = oldest;
    }
    memset(s, 0, sizeof *s);
    s->used = 1;
    s->seq8 = seq8;
    s->stamp = ++rx->stamp;
    return s;
}

int canproto_rx_frame(canproto_rx_t *rx, const canproto_frame_t *f, int is_fd_id,
                      canproto_rx_out_t *out)
{
    rx->st.frames++;
    if (f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF))
        return malformed(rx, CANPROTO_ELEN);

    if (is_fd_id) {
        if (!(f->flags & CANPROTO_F_FD) || f->len != CANPROTO_WP_FD_DLEN)
            return malformed(rx, CANPROTO_ELEN);
        int with_vel = f->data[0] == CANPROTO_MUX_FD_WAYPOINT_VEL;
        if (f->data[0] != CANPROTO_MUX_FD_WAYPOINT && !with_vel)
            return malformed(rx, CANPROTO_EMUX);
        int16_t vel[ENGINE_AXES];
        for (unsigned a = 0; a < ENGINE_AXES; a++) {
            vel[a] = (int16_t)get_le(&f->data[26 + 2 * a], 2);
            if (with_vel ? vel[a] == INT16_MIN : vel[a] != 0)
                return malformed(rx, CANPROTO_EVALUE);
        }
        int64_t pos[ENGINE_AXES];
        for (unsigned a = 0; a < ENGINE_AXES; a++) {
            pos[a] = sext(get_le(&f->data[8 + 6 * a], 6), 48);
            if (pos[a] == CANPROTO_I48_MIN)
                return malformed(rx, CANPROTO_EVALUE);
        }
        uint8_t seq8 = f->data[1];
        if (seq_old(rx, seq8))
            return CANPROTO_RX_NONE;
        fill_out(rx, seq8, get_le(&f->data[2], 6), pos, with_vel ? vel : NULL, out);
        rx->st.completed++;
        return CANPROTO_RX_WAYPOINT;
    }

    if ((f->flags & CANPROTO_F_FD) || f->len != CANPROTO_WP_DLEN)
        return malformed(rx, CANPROTO_ELEN);
    unsigned mux = f->data[0];
    if (mux == CANPROTO_MUX_COMMAND) {
        unsigned cmd = f->data[2];
        if (cmd < CANPROTO_CMD_FINISH || cmd >= CANPROTO_CMD_COUNT)
            return malformed(rx, CANPROTO_EVALUE);
        unsigned arg = f->data[3];
        if (cmd != CANPROTO_CMD_OVERRIDE && arg != 0) /* above 200 %: the receiver refuses */
            return malformed(rx, CANPROTO_EVALUE);
        for (unsigned i = 4; i < CANPROTO_WP_DLEN; i++)
            if (f->data[i])
                return malformed(rx, CANPROTO_EVALUE);
        memset(out, 0, sizeof *out);
        out->cmd = (canproto_cmd_t)cmd;
        out->cmd_arg = arg;
        rx->st.commands++;
        return CANPROTO_RX_COMMAND;
    }
    if (mux > CANPROTO_MUX_Z && mux != CANPROTO_MUX_VELOCITY)
        return malformed(rx, CANPROTO_EMUX);
    uint64_t raw = get_le(&f->data[2], 6);
    int16_t vel[ENGINE_AXES];
    if (mux == CANPROTO_MUX_VELOCITY) {
        for (unsigned a = 0; a < ENGINE_AXES; a++)
            if ((vel[a] = (int16_t)get_le(&f->data[2 + 2 * a], 2)) == INT16_MIN)
                return malformed(rx, CANPROTO_EVALUE);
    } else if (mux != CANPROTO_MUX_TIME && sext(raw, 48) == CANPROTO_I48_MIN) {
        return malformed(rx, CANPROTO_EVALUE);
    }

    uint8_t seq8 = f->data[1];
    if (seq_old(rx, seq8))
        return CANPROTO_RX_NONE;
    canproto_slot_t *s = slot_for(rx, seq8);
    unsigned bit = 1u << mux;
    if (s->have & bit)
        rx->st.duplicates++; /* the same part twice: the later one wins */
    s->have |= (uint8_t)bit;
    if (mux == CANPROTO_MUX_TIME)
        s->t_us = raw;
    else if (mux == CANPROTO_MUX_VELOCITY)
        memcpy(s->vel_cm_s, vel, sizeof vel);
    else
        s->pos_um[mux - 1] = sext(raw, 48);
    unsigned all = (1u << CANPROTO_WP_PARTS) - 1;
    if ((s->have & all) != all)
        return CANPROTO_RX_NONE;
    fill_out(rx, seq8, s->t_us, s->pos_um,
             s->have & (1u << CANPROTO_MUX_VELOCITY) ? s->vel_cm_s : NULL, out);
    memset(s, 0, sizeof *s);
    rx->st.completed++;
    return CANPROTO_RX_WAYPOINT;
}

void canproto_rx_consume(canproto_rx_t *rx, const canproto_rx_out_t *out)
{
    rx->st.lost += out->lost_before;
    rx->last_seq = out->wp.seq;
    rx->have_last = 1;
    /* partial waypoints at or behind the consumed one can never be used now */
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (s->used && seq_ahead(rx, s->seq8) <= 0) {
            rx->st.incomplete++;
            memset(s, 0, sizeof *s);
        }
    }
}
