/* canerr.c - see canerr.h. */
#include "canerr.h"

#include <string.h>

#include <linux/can.h>
#include <linux/can/error.h>

_Static_assert(CANERR_FLAG == CAN_ERR_FLAG && CANERR_MASK == CAN_ERR_MASK &&
                   CANERR_DLC == CAN_ERR_DLC,
               "canerr.h and linux/can/error.h disagree");

#define ERR_KNOWN                                                                                  \
    (CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_CRTL | CAN_ERR_PROT | CAN_ERR_TRX |            \
     CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_BUSERROR | CAN_ERR_RESTARTED | CAN_ERR_CNT)
#define ERR_BUS                                                                                    \
    (CAN_ERR_TX_TIMEOUT | CAN_ERR_LOSTARB | CAN_ERR_PROT | CAN_ERR_TRX | CAN_ERR_ACK |             \
     CAN_ERR_BUSERROR)

int canerr_decode(uint32_t cls, const uint8_t *data, size_t len, canerr_event_t *ev)
{
    memset(ev, 0, sizeof *ev);
    cls &= CANERR_MASK;
    if (len != CANERR_DLC || !data || !(cls & ERR_KNOWN))
        return -1;
    uint8_t crtl = (cls & CAN_ERR_CRTL) ? data[1] : 0;
    if (cls & CAN_ERR_BUSOFF)
        ev->state = CANERR_STATE_BUS_OFF;
    else if (crtl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE))
        ev->state = CANERR_STATE_PASSIVE;
    else if (crtl & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING))
        ev->state = CANERR_STATE_WARNING;
    else if ((crtl & CAN_ERR_CRTL_ACTIVE) || (cls & CAN_ERR_RESTARTED))
        ev->state = CANERR_STATE_ACTIVE;
    ev->bus_off = (cls & CAN_ERR_BUSOFF) != 0;
    ev->restarted = (cls & CAN_ERR_RESTARTED) != 0;
    ev->bus_error = (cls & ERR_BUS) != 0;
    ev->overflow = (crtl & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW)) != 0;
    if (cls & CAN_ERR_CNT) {
        ev->has_counters = 1;
        ev->tx_err = data[6];
        ev->rx_err = data[7];
    }
    return 0;
}

void canerr_bus_init(canerr_bus_t *b)
{
    memset(b, 0, sizeof *b);
    b->state = CANERR_STATE_ACTIVE;
}

int canerr_bus_frame(canerr_bus_t *b, uint32_t cls, const uint8_t *data, size_t len)
{
    canerr_event_t ev;
    if (canerr_decode(cls, data, len, &ev) < 0) {
        b->malformed++;
        return -1;
    }
    b->frames++;
    b->restarts += ev.restarted;
    b->bus_errors += ev.bus_error;
    b->overflows += ev.overflow;
    if (ev.has_counters) {
        b->tx_err = ev.tx_err;
        b->rx_err = ev.rx_err;
    }
    if (ev.state == CANERR_STATE_NONE || ev.state == b->state)
        return 0;
    if (ev.state == CANERR_STATE_WARNING && b->state < CANERR_STATE_WARNING)
        b->warnings++;
    else if (ev.state == CANERR_STATE_PASSIVE && b->state < CANERR_STATE_PASSIVE)
        b->passives++;
    else if (ev.state == CANERR_STATE_BUS_OFF)
        b->bus_offs++;
    b->state = ev.state;
    return 1;
}

const char *canerr_state_name(unsigned state)
{
    switch (state) {
    case CANERR_STATE_ACTIVE: return "error-active";
    case CANERR_STATE_WARNING: return "error-warning";
    case CANERR_STATE_PASSIVE: return "error-passive";
    case CANERR_STATE_BUS_OFF: return "bus-off";
    default: return "?";
    }
}
