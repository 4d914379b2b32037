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
    rx->last_t_s = 0;
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

/* seq_ahead, or 1 (new) without a sequence history. */
static int seq_dist(const canproto_rx_t *rx, uint8_t seq8)
{
    return rx->have_last ? seq_ahead(rx, seq8) : 1;
}

/*
 * Time t_us (TIME field) later than the last consumed waypoint's?  The same
 * conversion as fill_out's, so the comparison is the engine's.  A waypoint
 * behind that is later is a sender that restarted its numbering.
 */
static int later(const canproto_rx_t *rx, uint64_t t_us)
{
    return (double)t_us / CANPROTO_WP_BITS_PER_S > rx->last_t_s;
}

/* Frames a slot holds (one per part received). */
static unsigned parts(uint8_t have)
{
    unsigned n = 0;
    for (; have; have &= (uint8_t)(have - 1))
        n++;
    return n;
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
    if (!rx->have_last) {
        out->wp.seq = seq8;
        return;
    }
    int d = seq_ahead(rx, seq8); /* != 0: duplicates were ruled out */
    if (d < 0) {
        /* behind but later (the caller judged it): a restart of the sender's
         * numbering, nothing lost; the extended number still goes forward,
         * so it never repeats one already handed out */
        out->wp.seq = rx->last_seq + (uint8_t)(seq8 - (uint8_t)rx->last_seq);
        out->resync = 1;
        return;
    }
    out->wp.seq = rx->last_seq + (uint32_t)d;
    out->lost_before = (uint32_t)(d - 1);
}

/* A partial waypoint behind the last consumed one (a late one, or a
 * restarted sender's not judged yet)? */
static int slot_behind(const canproto_rx_t *rx, const canproto_slot_t *s)
{
    return rx->have_last && seq_ahead(rx, s->seq8) < 0;
}

/* Give up partial waypoint s: one behind was never taken (its frames are out
 * of order), one ahead is incomplete (and its seq will count as lost). */
static void abandon(canproto_rx_t *rx, canproto_slot_t *s)
{
    if (slot_behind(rx, s))
        rx->st.out_of_order += parts(s->have);
    else
        rx->st.incomplete++;
    memset(s, 0, sizeof *s);
}

/* The oldest (first opened) of a and b, either may be NULL. */
static canproto_slot_t *older(canproto_slot_t *a, canproto_slot_t *b)
{
    return !a || (b && b->stamp < a->stamp) ? b : a;
}

/*
 * The slot of seq8, or a new one.  Every slot in use: a frame ahead abandons
 * the oldest slot behind, else the oldest; a frame behind (behind = 1) the
 * oldest stale slot, else the oldest behind, never a live partial waypoint
 * ahead: NULL, the frame is dropped.  So late frames cannot cost a waypoint
 * ahead, and a restarted sender still finds room when the old one left
 * partial waypoints that will never complete.
 */
static canproto_slot_t *slot_for(canproto_rx_t *rx, uint8_t seq8, int behind)
{
    canproto_slot_t *free_slot = NULL, *oldest = NULL, *oldest_behind = NULL, *stale = NULL;
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (!s->used) {
            free_slot = free_slot ? free_slot : s;
            continue;
        }
        if (s->seq8 == seq8)
            return s;
        oldest = older(oldest, s);
        if (slot_behind(rx, s))
            oldest_behind = older(oldest_behind, s);
        if (rx->tick - s->seen >= CANPROTO_RX_STALE_FRAMES)
            stale = older(stale, s);
    }
    canproto_slot_t *s = free_slot;
    if (!s && behind)
        s = stale ? stale : oldest_behind;
    else if (!s)
        s = oldest_behind ? oldest_behind : oldest;
    if (!s)
        return NULL;
    if (s->used)
        abandon(rx, s);
    memset(s, 0, sizeof *s);
    s->used = 1;
    s->seq8 = seq8;
    s->stamp = ++rx->stamp;
    return s;
}

/* A whole FD waypoint (frame checked): judged at once. */
static int rx_fd(canproto_rx_t *rx, const canproto_frame_t *f, const int64_t pos[ENGINE_AXES],
                 const int16_t *vel, canproto_rx_out_t *out)
{
    uint8_t seq8 = f->data[1];
    uint64_t t_us = get_le(&f->data[2], 6);
    int d = seq_dist(rx, seq8);
    if (d == 0) {
        rx->st.duplicates++;
        return CANPROTO_RX_NONE;
    }
    if (d < 0 && !later(rx, t_us)) {
        rx->st.out_of_order++;
        return CANPROTO_RX_NONE;
    }
    fill_out(rx, seq8, t_us, pos, vel, out);
    rx->st.completed++;
    return CANPROTO_RX_WAYPOINT;
}

/* One part (mux) of a classic waypoint (frame checked): into its slot; the
 * waypoint is judged when its fourth part arrives. */
static int rx_part(canproto_rx_t *rx, const canproto_frame_t *f, unsigned mux, uint64_t raw,
                   const int16_t vel[ENGINE_AXES], canproto_rx_out_t *out)
{
    uint8_t seq8 = f->data[1];
    int d = seq_dist(rx, seq8);
    if (d == 0) {
        rx->st.duplicates++;
        return CANPROTO_RX_NONE;
    }
    rx->tick++;
    canproto_slot_t *s = slot_for(rx, seq8, d < 0);
    if (!s) {
        rx->st.out_of_order++; /* behind, and no room but ahead's */
        return CANPROTO_RX_NONE;
    }
    s->seen = rx->tick;
    unsigned bit = 1u << mux;
    if (s->have & bit)
        rx->st.duplicates++; /* the same part twice: the later one wins */
    s->have |= (uint8_t)bit;
    if (mux == CANPROTO_MUX_TIME)
        s->t_us = raw;
    else if (mux == CANPROTO_MUX_VELOCITY)
        memcpy(s->vel_cm_s, vel, sizeof s->vel_cm_s);
    else
        s->pos_um[mux - 1] = sext(raw, 48);
    unsigned all = (1u << CANPROTO_WP_PARTS) - 1;
    if ((s->have & all) != all)
        return CANPROTO_RX_NONE;
    canproto_slot_t w = *s;
    memset(s, 0, sizeof *s);
    if (d < 0 && !later(rx, w.t_us)) {
        rx->st.out_of_order += parts(w.have); /* a late one: its frames dropped */
        return CANPROTO_RX_NONE;
    }
    fill_out(rx, seq8, w.t_us, w.pos_um, w.have & (1u << CANPROTO_MUX_VELOCITY) ? w.vel_cm_s : NULL,
             out);
    rx->st.completed++;
    return CANPROTO_RX_WAYPOINT;
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
        return rx_fd(rx, f, pos, with_vel ? vel : NULL, out);
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
    int16_t vel[ENGINE_AXES] = {0};
    if (mux == CANPROTO_MUX_VELOCITY) {
        for (unsigned a = 0; a < ENGINE_AXES; a++)
            if ((vel[a] = (int16_t)get_le(&f->data[2 + 2 * a], 2)) == INT16_MIN)
                return malformed(rx, CANPROTO_EVALUE);
    } else if (mux != CANPROTO_MUX_TIME && sext(raw, 48) == CANPROTO_I48_MIN) {
        return malformed(rx, CANPROTO_EVALUE);
    }
    return rx_part(rx, f, mux, raw, vel, out);
}

void canproto_rx_consume(canproto_rx_t *rx, const canproto_rx_out_t *out)
{
    int had = rx->have_last;
    uint8_t was = (uint8_t)rx->last_seq;
    rx->st.lost += out->lost_before;
    if (out->resync) {
        rx->st.resyncs++;
        rx->st.resync_seq = (uint8_t)out->wp.seq;
        rx->st.resync_after = was;
    }
    rx->last_seq = out->wp.seq;
    rx->last_t_s = out->wp.t_s;
    rx->have_last = 1;
    /* partial waypoints at or behind the consumed one can never be used now:
     * those that were behind before it too were late (out of order) */
    for (unsigned i = 0; i < rx->nslots; i++) {
        canproto_slot_t *s = &rx->slots[i];
        if (!s->used || seq_ahead(rx, s->seq8) > 0)
            continue;
        if (had && (int8_t)(uint8_t)(s->seq8 - was) < 0)
            rx->st.out_of_order += parts(s->have);
        else
            rx->st.incomplete++;
        memset(s, 0, sizeof *s);
    }
}
