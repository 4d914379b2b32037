/* can_publish.c - see can_publish.h. */
#include "can_publish.h"

#include <string.h>

#include "can_transport.h"

_Static_assert(CORE_BUS_ACTIVE == CAN_BUS_ERROR_ACTIVE &&
                   CORE_BUS_WARNING == CAN_BUS_ERROR_WARNING &&
                   CORE_BUS_PASSIVE == CAN_BUS_ERROR_PASSIVE && CORE_BUS_OFF == CAN_BUS_OFF &&
                   CORE_BUS_DOWN == CAN_BUS_DOWN && CORE_DRIVE_NONE == CANPROTO_S2_NO_DRIVE &&
                   CORE_DRIVE_NMT_NONE == CANPROTO_S2_NMT_NONE &&
                   CANPROTO_CIA402_AXES == ENGINE_AXES,
               "core.h CORE_BUS_* / CORE_DRIVE_* and the CAN values disagree");

static void publish_drive(const can_port_t *port, unsigned k, core_drive_t *dr, core_rx_t *rx)
{
    canproto_status2_drive_t d;
    can_port_obj_stats_t st;
    can_port_drive_summary(port, k, &d);
    can_port_obj_stats(port, k, &st);
    memset(dr, 0, sizeof *dr);
    dr->published = 1;
    memcpy(dr->state, d.state, sizeof dr->state);
    dr->hb_lost = d.hb_lost;
    dr->held = d.held;
    dr->statusword = d.statusword;
    dr->nmt = d.nmt;
    dr->emcy = d.emcy;
    dr->emcy_frames = st.emcy;
    dr->sdo_aborts = st.sdo_aborts;
    dr->last_abort = st.last_abort;
    dr->hb_timeouts = st.heartbeat_lost;
    dr->tx_clamped = st.tx_clamped;
    rx->lost = st.rx.lost;
    rx->resyncs = st.rx.resyncs;
}

void can_publish(core_t *c, const can_port_t *port, const int *port_index, unsigned bus_state,
                 uint64_t rx_dropped, uint32_t load_permille, const canerr_bus_t *err)
{
    core_bus_t *b = &c->stats->bus;
    b->state = bus_state;
    b->load_permille = load_permille;
    b->err_frames = err->frames;
    b->warnings = err->warnings;
    b->passives = err->passives;
    b->bus_offs = err->bus_offs;
    b->restarts = err->restarts;
    b->bus_errors = err->bus_errors;
    b->overflows = err->overflows;
    b->rx_dropped = rx_dropped;
    b->tx_err = err->tx_err;
    b->rx_err = err->rx_err;
    for (unsigned i = 0; i < c->nobj && i < CFG_OBJECTS_MAX; i++)
        if (port_index[i] >= 0)
            publish_drive(port, (unsigned)port_index[i], &c->obj[i].drive, &c->obj[i].rx);
}
