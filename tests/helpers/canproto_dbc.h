/*
 * canproto_dbc.h - the description tables of trajd's CAN frames and the DBC text
 * (config/trajd.dbc) made from them: test and build-time scaffolding, not in libtrajd
 * (tests/helpers/canproto_dbc.c; the tool $(BUILD)/tests/canproto_dbc prints the DBC).
 */
#ifndef TRAJD_CANPROTO_DBC_H
#define TRAJD_CANPROTO_DBC_H

#include "canproto.h"

#include <stddef.h>

/* ---- description tables (DBC generation, docs, tests) ----------------------------- */

typedef struct {
    const char *name;   /* DBC signal name */
    int mux;            /* -1: not multiplexed, -2: the multiplexer, >= 0: mux value */
    unsigned start_bit; /* Intel (little-endian) start bit */
    unsigned bits;
    int is_signed;
    double factor;
    double offset;
    double min, max;
    const char *unit;
} canproto_signal_t;

typedef struct {
    const char *name; /* DBC message name */
    uint32_t id;      /* default id for object 0 */
    unsigned dlen;
    int fd;
    const char *sender;
    const canproto_signal_t *signals;
    unsigned nsignals;
} canproto_message_t;

/*
 * The messages of object 0 with default ids: WAYPOINT, WAYPOINT_FD, SETPOINT,
 * SETPOINT_FD, STATUS, SYNC and the CiA 402 RPDOs of nodes 1..3 (target
 * position only, in increments).
 */
const canproto_message_t *canproto_messages(unsigned *count);

/*
 * Write config/trajd.dbc (the DBC text for canproto_messages()) into buf.
 * Returns the length it needs (like snprintf: the text is complete if the
 * return is < len).
 */
int canproto_dbc(char *buf, size_t len);

#endif
