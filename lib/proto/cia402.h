/*
 * cia402.h - the master side of a CiA 402 drive on CANopen, pure: the frames
 * trajd sends to bring a drive up (NMT, expedited SDO download), the frames
 * it reads back (SDO replies and aborts, heartbeat, EMCY, the drive's TPDO
 * with statusword 0x6041 and position actual value 0x6064), and the drive
 * state machine of CiA 402 (statusword bit patterns, the controlword that
 * leads towards Operation Enabled).  No sockets, no clock: the daemon
 * (daemon/can/can_port.c) moves the frames and passes time in.
 *
 * References: CiA 301 (NMT 0x000, SYNC 0x080, EMCY 0x080 + node, TPDO1
 * 0x180 + node, RPDO1 0x200 + node, SDO 0x600 + node / 0x580 + node,
 * heartbeat 0x700 + node; SDO abort codes, table 22) and CiA 402-2 (state
 * machine, statusword and controlword, objects 0x6040, 0x6041, 0x6060,
 * 0x6064, 0x607A, 0x60C2).
 */
#ifndef TRAJD_CIA402_H
#define TRAJD_CIA402_H
/* trajd public API: installed as <trajd/cia402.h> (make install; pkg-config trajd). */

#include <stdint.h>

#include "canproto.h"

/* CiA 301 function codes (COB-ID = base + node-id, node 1..127). */
#define CIA402_COB_NMT 0x000u
#define CIA402_COB_EMCY 0x080u
#define CIA402_COB_TPDO1 0x180u
#define CIA402_COB_RPDO1 0x200u
#define CIA402_COB_SDO_TX 0x580u /* server (drive) -> client (trajd) */
#define CIA402_COB_SDO_RX 0x600u /* client (trajd) -> server (drive) */
#define CIA402_COB_HEARTBEAT 0x700u
#define CIA402_NODE_MAX 127

/* NMT commands (CiA 301 7.2.8.3.1) */
enum cia402_nmt {
    CIA402_NMT_START = 0x01,
    CIA402_NMT_STOP = 0x02,
    CIA402_NMT_PREOP = 0x80,
    CIA402_NMT_RESET_NODE = 0x81,
    CIA402_NMT_RESET_COMM = 0x82,
};

/* Heartbeat / NMT states of a node (CiA 301 7.2.8.3.2) */
enum cia402_nmt_state {
    CIA402_HB_BOOTUP = 0x00,
    CIA402_HB_STOPPED = 0x04,
    CIA402_HB_OPERATIONAL = 0x05,
    CIA402_HB_PREOP = 0x7F,
};

/* Objects trajd uses. */
#define CIA402_OBJ_CONTROLWORD 0x6040u
#define CIA402_OBJ_STATUSWORD 0x6041u
#define CIA402_OBJ_MODE 0x6060u /* modes of operation: 8 = CSP */
#define CIA402_OBJ_POSITION_ACTUAL 0x6064u
#define CIA402_OBJ_TARGET_POSITION 0x607Au
#define CIA402_OBJ_INTERP_PERIOD 0x60C2u /* sub 1 value, sub 2 index (10^index s) */
#define CIA402_MODE_CSP 8

/* Controlword commands (CiA 402-2, table 28; bits 0..3 and 7). */
#define CIA402_CW_DISABLE_VOLTAGE 0x0000u
#define CIA402_CW_SHUTDOWN 0x0006u
#define CIA402_CW_SWITCH_ON 0x0007u
#define CIA402_CW_ENABLE_OPERATION 0x000Fu
#define CIA402_CW_QUICK_STOP 0x0002u
#define CIA402_CW_FAULT_RESET 0x0080u /* on its rising edge */

/* Drive states (CiA 402-2, figure 13 and table 30). */
typedef enum {
    CIA402_NOT_READY = 0,          /* xxxx xxxx x0xx 0000 */
    CIA402_SWITCH_ON_DISABLED = 1, /* xxxx xxxx x1xx 0000 */
    CIA402_READY = 2,              /* xxxx xxxx x01x 0001 ready to switch on */
    CIA402_SWITCHED_ON = 3,        /* xxxx xxxx x01x 0011 */
    CIA402_OPERATION_ENABLED = 4,  /* xxxx xxxx x01x 0111 */
    CIA402_QUICK_STOP_ACTIVE = 5,  /* xxxx xxxx x00x 0111 */
    CIA402_FAULT_REACTION = 6,     /* xxxx xxxx x0xx 1111 */
    CIA402_FAULT = 7,              /* xxxx xxxx x0xx 1000 */
    CIA402_STATE_UNKNOWN = 8,      /* no pattern matches (or no statusword yet) */
} cia402_state_t;

/* The state a statusword shows. */
cia402_state_t cia402_state(uint16_t statusword);

/* "operation enabled", ... */
const char *cia402_state_name(cia402_state_t s);

/*
 * The controlword that takes a drive in state s one step towards Operation
 * Enabled (Shutdown -> Switch on -> Enable operation), or keeps it there.
 * A drive in FAULT gets Disable voltage, and Fault reset only if reset is
 * set (the caller sets it for one frame, after at least one without: the
 * reset acts on the rising edge of bit 7).  QUICK STOP ACTIVE gets Disable
 * voltage (leaving it is a decision: the drive then goes to Switch on
 * disabled, and the usual sequence follows).  NOT READY, FAULT REACTION and
 * UNKNOWN get Disable voltage (nothing to command while the drive is busy).
 */
uint16_t cia402_controlword_towards_enabled(cia402_state_t s, int reset);

/*
 * The controlword that keeps a drive in state s where it is (no transition of
 * CiA 402-2 figure 13): Enable operation in Operation Enabled, Switch on in
 * Switched on, Shutdown in Ready to switch on, Disable voltage else.  What a
 * master that has not decided anything yet sends (a restarted trajd adopting
 * running drives: never Disable voltage to a drive in Operation Enabled).
 */
uint16_t cia402_controlword_hold(cia402_state_t s);

/* ---- encoders ---- */

/* NMT command cmd to node (0 = all nodes): id 0x000, 2 bytes. */
void cia402_encode_nmt(uint8_t cmd, uint8_t node, canproto_frame_t *out);

/* The RPDO on cob: the controlword cw (if with_cw: 6 bytes) then the target
 * position 0x607A (4 bytes), little-endian. */
void cia402_encode_rpdo(uint32_t cob, int with_cw, uint16_t cw, int32_t target,
                        canproto_frame_t *out);

/* A heartbeat as NMT master: 0x700 + node, 1 byte, operational (0x05). */
void cia402_encode_heartbeat(uint8_t node, canproto_frame_t *out);

/*
 * Expedited SDO download (write) of size bytes (1, 2 or 4) of value to
 * index:sub on node: id 0x600 + node, 8 bytes, command 0x2F/0x2B/0x23.
 * Returns 0 or -CANPROTO_EVALUE (node or size invalid).
 */
int cia402_encode_sdo_download(uint8_t node, uint16_t index, uint8_t sub, uint32_t value,
                               unsigned size, canproto_frame_t *out);

/*
 * Expedited SDO upload (read) request of index:sub on node: id 0x600 + node,
 * 8 bytes, command 0x40.  Returns 0 or -CANPROTO_EVALUE (node invalid).
 */
int cia402_encode_sdo_upload(uint8_t node, uint16_t index, uint8_t sub, canproto_frame_t *out);

/* ---- decoders (frames from the drive) ---- */

typedef enum {
    CIA402_SDO_DOWNLOAD_OK = 1, /* 0x60: the write was done */
    CIA402_SDO_ABORT = 2,       /* 0x80: refused, abort_code says why */
    CIA402_SDO_UPLOAD = 3,      /* 0x4x: an expedited read reply (value) */
} cia402_sdo_kind_t;

typedef struct {
    cia402_sdo_kind_t kind;
    uint16_t index;
    uint8_t sub;
    uint32_t value;      /* UPLOAD */
    uint32_t abort_code; /* ABORT */
} cia402_sdo_reply_t;

/*
 * An SDO server reply (id 0x580 + node, 8 bytes).  Returns 0, -CANPROTO_EID
 * (not node's SDO reply id), -CANPROTO_ELEN (not 8 bytes, RTR, FD, 29-bit),
 * -CANPROTO_EVALUE (a command byte trajd never asked for: segmented, block).
 */
int cia402_decode_sdo_reply(uint8_t node, const canproto_frame_t *f, cia402_sdo_reply_t *out);

/* Text for an SDO abort code (CiA 301 table 22), "unknown abort code" else. */
const char *cia402_sdo_abort_text(uint32_t code);

/*
 * A heartbeat or boot-up (id 0x700 + node, 1 byte).  Returns 0 with *node
 * and *state, -CANPROTO_EID (not a heartbeat id), -CANPROTO_ELEN,
 * -CANPROTO_EVALUE (bit 7 toggle set or an undefined state).
 */
int cia402_decode_heartbeat(const canproto_frame_t *f, uint8_t *node, uint8_t *state);

/*
 * An EMCY (id 0x080 + node, 8 bytes, node 1..127: 0x080 itself is SYNC).
 * Returns 0 with *node, *code (error code, 0 = error reset) and *reg (error
 * register 0x1001), -CANPROTO_EID, -CANPROTO_ELEN.
 */
int cia402_decode_emcy(const canproto_frame_t *f, uint8_t *node, uint16_t *code, uint8_t *reg);

/*
 * The drive's feedback TPDO (trajd's expected mapping: statusword 0x6041
 * u16, then position actual value 0x6064 i32; 6 bytes, or more with bytes
 * trajd ignores).  Returns 0, -CANPROTO_ELEN.
 */
int cia402_decode_feedback(const canproto_frame_t *f, uint16_t *statusword, int32_t *pos_inc);

#endif
