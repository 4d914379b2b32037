/*
 * canerr.h - SocketCAN error frames (linux/can/error.h) decoded into a bus
 * state and counters (constants from linux/can/error.h).  Pure: no I/O; the daemon reads the frames (a raw
 * socket with CAN_RAW_ERR_FILTER, or a candump log's "2000xxxx#" lines) and
 * hands them here.
 *
 * Error frame: can_id has CAN_ERR_FLAG (0x20000000) and a class mask in its
 * low bits; DLC 8.  The classes used:
 *   CAN_ERR_CRTL (0x004)      data[1]: RX/TX warning (0x04/0x08), RX/TX
 *                             passive (0x10/0x20), back to active (0x40),
 *                             RX/TX buffer overflow (0x01/0x02)
 *   CAN_ERR_BUSOFF (0x040)    bus off
 *   CAN_ERR_RESTARTED (0x100) controller restarted: error-active again
 *   CAN_ERR_CNT (0x200)       data[6] TX error counter, data[7] RX error counter
 *   CAN_ERR_TX_TIMEOUT, LOSTARB, PROT, TRX, ACK, BUSERROR (0x001, 0x002,
 *                             0x008, 0x010, 0x020, 0x080): counted as bus errors
 * A frame's state is the worst it names (bus-off, then passive, then
 * warning, then active); a frame naming none (an overflow, a protocol error)
 * leaves the state as it was.
 */
#ifndef TRAJD_CANERR_H
#define TRAJD_CANERR_H
/* trajd public API: installed as <trajd/canerr.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>

/* States: the values of MBMAP_CAN_* and linux/can/netlink.h's can_state + 1. */
#define CANERR_STATE_NONE 0 /* the frame names no state */
#define CANERR_STATE_ACTIVE 1
#define CANERR_STATE_WARNING 2
#define CANERR_STATE_PASSIVE 3
#define CANERR_STATE_BUS_OFF 4

#define CANERR_FLAG 0x20000000u /* CAN_ERR_FLAG in can_id */
#define CANERR_MASK 0x1fffffffu /* CAN_ERR_MASK: the class bits */
#define CANERR_DLC 8

typedef struct {
    uint8_t state;        /* CANERR_STATE_*, NONE if the frame names none */
    uint8_t bus_off;      /* CAN_ERR_BUSOFF */
    uint8_t restarted;    /* CAN_ERR_RESTARTED */
    uint8_t bus_error;    /* TX timeout, lost arbitration, protocol, transceiver, ACK, bus error */
    uint8_t overflow;     /* controller RX or TX buffer overflow */
    uint8_t has_counters; /* CAN_ERR_CNT: tx_err and rx_err are valid */
    uint8_t tx_err, rx_err;
} canerr_event_t;

/*
 * Decode an error frame: class is can_id & CANERR_MASK (the caller has seen
 * CANERR_FLAG), data/len its payload.  Returns 0, or -1 if len is not
 * CANERR_DLC or class has no known bit (nothing decoded, *ev zeroed).
 */
int canerr_decode(uint32_t cls, const uint8_t *data, size_t len, canerr_event_t *ev);

/* A bus's state and counters, from the error frames seen. */
typedef struct {
    uint8_t state;          /* CANERR_STATE_ACTIVE .. BUS_OFF */
    uint8_t tx_err, rx_err; /* last error counters reported (CAN_ERR_CNT) */
    uint64_t frames;        /* error frames decoded */
    uint64_t malformed;     /* error frames refused by canerr_decode */
    uint64_t warnings;      /* entries into error-warning (from active) */
    uint64_t passives;      /* entries into error-passive (from active or warning) */
    uint64_t bus_offs;      /* entries into bus-off */
    uint64_t restarts;      /* controller restarts */
    uint64_t bus_errors;    /* frames with a bus-error class (see above) */
    uint64_t overflows;     /* controller buffer overflows */
} canerr_bus_t;

/* Error-active, every counter 0. */
void canerr_bus_init(canerr_bus_t *b);

/* Decode one error frame into b.  Returns 1 if the state changed, 0 if not,
 * -1 if the frame is malformed (counted in b->malformed). */
int canerr_bus_frame(canerr_bus_t *b, uint32_t cls, const uint8_t *data, size_t len);

/* "error-active", "error-warning", "error-passive", "bus-off", "?" */
const char *canerr_state_name(unsigned state);

#endif
