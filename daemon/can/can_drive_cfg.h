/*
 * can_drive_cfg.h - the CiA 402 keys of the "can" transport's configuration
 * that are more than a number (daemon/can/can_transport.c parses the rest).
 */
#ifndef TRAJD_CAN_DRIVE_CFG_H
#define TRAJD_CAN_DRIVE_CFG_H

#include "canproto.h"
#include "cfg.h"

/* can.cia402_sdo = "0x6060:0=8/1, 0x60C2:1=10/1, 0x60C2:2=-3/1": index:sub=value/size
 * in bytes, into ids->cia402_sdo / cia402_nsdo.  Returns 0 or -CFG_EVALUE. */
int can_cfg_sdo_list(const cfg_kv_t *kv, canproto_ids_t *ids, char *why, size_t wl);

/* [can] heartbeat_node (0 = none, 1..127) and heartbeat_ms (10..60000): trajd's
 * own heartbeat as CANopen master.  Returns 0 or -CFG_EVALUE. */
int can_cfg_heartbeat(const cfg_kv_t *kv, int *node, int *ms, char *why, size_t wl);

#endif
