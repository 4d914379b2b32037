/*
 * can_publish.h - what the CAN transport shows the rest of the daemon: the
 * bus (state, load, error-frame counters) into stats_t.bus and each CAN
 * object's drives into obj_t.drive (core.h), where Modbus and the control
 * socket read them.  No transport includes another's header.
 */
#ifndef TRAJD_CAN_PUBLISH_H
#define TRAJD_CAN_PUBLISH_H

#include <stdint.h>

#include "can_port.h"
#include "canerr.h"
#include "core.h"

/*
 * Publish into c: the bus in bus_state (CAN_BUS_*, as of the last
 * housekeeping), its worst-case load and error counters err, and for each
 * object i of c with port_index[i] >= 0 its drives (can_port object
 * port_index[i]).  In the transport's cycle, every tick.
 */
void can_publish(core_t *c, const can_port_t *port, const int *port_index, unsigned bus_state,
                 uint64_t rx_dropped, uint32_t load_permille, const canerr_bus_t *err);

#endif
