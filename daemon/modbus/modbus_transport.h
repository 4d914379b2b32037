/*
 * modbus_transport.h - the Modbus transport of trajd: plugs daemon/modbus/modbus_server (the
 * libmodbus server) and lib/proto/mbmap (the register map) into the daemon's seams
 * (transport.h, core.h).
 *
 * Roles: input (an object with `input = modbus` takes waypoints from its
 * waypoint block) and service (status of every object, commands), opened
 * when an object uses it or a [modbus] section is present.  Keys of the
 * [modbus] section: see modbus_server_config_set() and config/trajd.conf.
 *
 * In the tick (cycle callback, once per tick after every object was ticked)
 * the snapshot of every object is published into the input registers; the
 * server's fd is served by the same loop between ticks, so a request sees
 * one tick (see modbus_server.h).
 *
 * Commands (holding register 0 of an object's block):
 *   1 start  if the object is WAITING with waypoints buffered but fewer than
 *            the lookahead, close its input (engine_finish): it streams what
 *            it has and rests on the last waypoint.  In any other state it
 *            does nothing (streaming starts by itself once the lookahead is
 *            buffered).  Refused (03) when nothing is buffered.
 *   2 stop   engine_stop: brake along the path to rest now, drop what is
 *            buffered (FINISHED).
 *   3 clear  engine_clear: the same controlled stop, then WAITING.
 *   4 reset counters  engine_reset_counters and the Modbus per-object counters.
 *   5 finish engine_finish: end of input, run on to the last waypoint.
 * Holding register 1 of an object's block: feed override in percent
 * (0 .. 200, engine_set_override; above 200: exception 03).
 * While the daemon is stopping (SIGTERM) writes are refused with 03.
 * Waypoints written to an object whose input is not modbus: exception 02.
 */
#ifndef TRAJD_MBTRANSPORT_H
#define TRAJD_MBTRANSPORT_H

#include "transport.h"

extern const transport_t modbus_transport;

#endif
