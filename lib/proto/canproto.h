/*
 * canproto.h - trajd's CAN frames: every id, layout and scaling in one place,
 * encode/decode, waypoint reassembly, and bus-load arithmetic.
 *
 * Pure: no sockets, no clock, no allocation (reassembly slots are the
 * caller's).  The daemon's SocketCAN and candump-log transports move
 * canproto_frame_t; config/trajd.dbc is generated from the tables below by
 * `trajdbc` and a test checks that the checked-in file is that output.
 *
 * All multi-byte fields are little-endian (Intel byte order in the DBC).
 *
 * Frames per object (ids are per object and configurable; defaults for object
 * n, 0 <= n < 16, sit in 0x680..0x6CF, a range the CANopen predefined
 * connection set leaves unused, so trajd can share a bus with CiA 402 drives):
 *
 *  WAYPOINT (in, classic, DLC 8, default 0x680+n), multiplexed by byte 0:
 *    byte 0       mux: 0 TIME, 1 X, 2 Y, 3 Z, 4 COMMAND, 6 VELOCITY
 *    byte 1       seq: waypoint sequence number, low 8 bits
 *    bytes 2..7   TIME: t, uint48, 1 us per bit (sender's track clock)
 *                 X/Y/Z: position, int48, 1 um per bit
 *                 COMMAND: byte 2 = canproto_cmd_t, bytes 3..7 zero
 *                 VELOCITY: vx, vy, vz, int16 each, 1 cm/s per bit
 *                 (+-327.67 m/s; -32768 is refused): the source's
 *                 velocity at t (issue 31, the local methods)
 *    A waypoint is the four frames TIME, X, Y, Z with the same seq, in any
 *    order; it is complete when the fourth arrives.  A VELOCITY frame of that
 *    seq belongs to it if it comes before the fourth (send it first); after,
 *    it is a frame of a waypoint already handed out (counted as such).
 *  WAYPOINT_FD (in, CAN FD, length 32, default 0x690+n): one whole waypoint
 *    byte 0 mux 5, byte 1 seq, 2..7 t (uint48 us), 8..13 x, 14..19 y,
 *    20..25 z (int48 um), 26..31 zero; or mux 7, with 26..31 vx, vy, vz as
 *    in VELOCITY.
 *  SETPOINT (out, classic, DLC 8, default 0x6A0+n), 3 frames per cycle:
 *    byte 0       bits 0..1 axis (0 x, 1 y, 2 z), bits 4..6 engine state,
 *                 bit 7 HOLD
 *    byte 1       cycle counter, low 8 bits
 *    bytes 2..5   position, int32, 0.1 mm per bit (+-214 km); 0x80000000 =
 *                 no position yet (CANPROTO_SP_POS_NA: do not move)
 *    bytes 6..7   velocity, int16, 1 mm/s per bit (+-32.767 m/s)
 *  SETPOINT_FD (out, CAN FD, length 32, default 0x6B0+n), 1 frame per cycle:
 *    0..3 cycle uint32; 4..7 x, 8..11 y, 12..15 z (int32, 0.1 mm; 0x80000000
 *    = no position yet, with flags bit 4);
 *    16..19 vx, 20..23 vy, 24..27 vz (int32, 1 um/s); 28 state; 29 flags
 *    (ENGINE_SP_*); 30..31 track number, uint16.
 *  STATUS (out, classic, DLC 8, default 0x6C0+n), every status period and
 *    at once after a rejection or a loss:
 *    0 state (bits 0..2 engine state, bit 4 bus DOWN seen since last status,
 *      bit 5 TX dropped since last status, bit 6 a csv/stdout output of the
 *      object lost lines or failed to write since last status: the count is
 *      on Modbus, out_lost), bit 7 safety FAULT: the monitor holds the
 *      object's position until a CLEAR command), 1 last accepted seq (low 8 bits),
 *    2 free waypoint slots (saturated at 255), 3 lost waypoints (sequence
 *    gaps), 4 rejected waypoints (bad data; a full buffer is flow control,
 *    shown by last_err EFULL and last_seq not moving), 5 malformed frames, 6 dropped setpoints
 *    (late or TX queue full), 7 last error code (canproto_status_err_t).
 *    Counters 3..6 are modulo 256: a sender watches them change.
 *  STATUS2 (out, classic, DLC 8, default 0x6D0+n), multiplexed by byte 0 =
 *    page (canproto_st2_page_t); sent after STATUS, one page per STATUS: a
 *    page whose content changed first, else the pages in turn.  Counters in
 *    pages saturate at their field's maximum (they never wrap: a reader sees
 *    "at least this many").  Pages:
 *    1 FAULTS: 1..3 setpoint lines lost by the object's csv/stdout outputs
 *      (uint24), 4..5 failed output writes (uint16), 6..7 commands refused
 *      (uint16: the object is not writable, [object] writable = no).
 *    2 REJECTED: waypoints the engine refused, per reason (uint8 each,
 *      saturating at 255; the exact 32-bit counts are in the object's Modbus
 *      diagnostics block): 1 backwards, 2 same time, 3 speed, 4 acceleration,
 *      5 unconfirmed, 6 stale, 7 other (not finite, out of range, numeric).
 *    3 CLOCK (lib/engine/CLOCK.md): 1..3 data age now - t_s of the setpoint
 *      (int24, ms; negative while a trajectory waits for the clock to reach
 *      its start; 0x800000: none, a relative-time track or no position;
 *      saturating at +-0x7FFFFF), 4..5 the sender's clock drift absorbed (int16,
 *      0.1 ppm, + = sender fast, the daemon's one estimate; saturating), 6 the
 *      object's clock (0 relative, 1 on the daemon's clock, 2 undecided: its
 *      first waypoint decides), 7 reserved (0).
 *    5 BUS: 1 bus state (1 error-active, 2 error-warning, 3 error-passive,
 *      4 bus-off, 5 interface down; from the kernel's error frames,
 *      lib/proto/canerr.h), 2 TX error counter, 3 RX error counter (as last
 *      reported), 4..5 entries into bus-off (uint16), 6..7 error frames (uint16).
 *  SYNC (out, default 0x080, DLC 0, or DLC 1 with a counter 1..overflow as
 *    CiA 301 allows), once per cycle before the setpoints, optional.
 *  CiA 402 RPDO (out, one per axis, COB-ids configured, e.g. 0x200+node):
 *    target position 0x607A:00 int32 in drive increments (counts per metre
 *    configured), optionally preceded by controlword 0x6040:00 uint16.
 *    Never sent while trajd has no valid position (ENGINE_SP_NO_POSITION).
 *
 * Values that do not fit a field are clamped to its range and counted
 * (canproto_encode_* return CANPROTO_CLAMPED).
 */
#ifndef TRAJD_CANPROTO_H
#define TRAJD_CANPROTO_H
/* trajd public API: installed as <trajd/canproto.h> (make install; pkg-config trajd). */

#include <stddef.h>
#include <stdint.h>
#include "motion.h"

/* ---- frames ------------------------------------------------------------ */

#define CANPROTO_MAX_DLEN 64 /* CAN FD payload */
#define CANPROTO_CLASSIC_DLEN 8

/* canproto_frame_t.flags */
#define CANPROTO_F_EFF 0x01u /* 29-bit identifier */
#define CANPROTO_F_RTR 0x02u /* remote request (classic only) */
#define CANPROTO_F_ERR 0x04u /* error frame (from the kernel) */
#define CANPROTO_F_FD 0x08u  /* CAN FD frame */
#define CANPROTO_F_BRS 0x10u /* FD bit-rate switch */
#define CANPROTO_F_ESI 0x20u /* FD error state indicator */

#define CANPROTO_SFF_MASK 0x7FFu
#define CANPROTO_EFF_MASK 0x1FFFFFFFu

/* One frame, independent of <linux/can.h> (the daemon converts). */
typedef struct {
    uint32_t id;   /* 11 or 29 bits, no flag bits */
    uint8_t len;   /* payload bytes, 0..8 or a CAN FD length */
    uint8_t flags; /* CANPROTO_F_* */
    uint8_t data[CANPROTO_MAX_DLEN];
} canproto_frame_t;

/* ---- ids and layouts ------------------------------------------------------ */

#define CANPROTO_OBJECTS_DEFAULT_MAX 16
#define CANPROTO_ID_WAYPOINT_BASE 0x680u
#define CANPROTO_ID_WAYPOINT_FD_BASE 0x690u
#define CANPROTO_ID_SETPOINT_BASE 0x6A0u
#define CANPROTO_ID_SETPOINT_FD_BASE 0x6B0u
#define CANPROTO_ID_STATUS_BASE 0x6C0u
#define CANPROTO_ID_STATUS2_BASE 0x6D0u
#define CANPROTO_ID_SYNC_DEFAULT 0x080u
#define CANPROTO_CIA402_RPDO1_BASE 0x200u /* CiA 301 RPDO1 = 0x200 + node-id */
#define CANPROTO_CIA402_RPDO2_BASE 0x300u /* CiA 301 RPDO2 = 0x300 + node-id */
#define CANPROTO_CIA402_TPDO1_BASE 0x180u /* CiA 301 TPDO1 = 0x180 + node-id */

#define CANPROTO_WP_DLEN 8
#define CANPROTO_WP_FD_DLEN 32
#define CANPROTO_SP_DLEN 8
#define CANPROTO_SP_FD_DLEN 32
#define CANPROTO_STATUS_DLEN 8
#define CANPROTO_STATUS2_DLEN 8

/* STATUS2 pages (byte 0).  New pages take the next free number; a page is
 * 7 bytes (1..7), little-endian fields, counters saturating. */
typedef enum {
    CANPROTO_ST2_FAULTS = 1,   /* output and command faults (canproto_st2_faults_t) */
    CANPROTO_ST2_REJECTED = 2, /* waypoints refused, per reason (canproto_st2_rejected_t) */
    CANPROTO_ST2_CLOCK = 3,    /* data age and sender clock drift (canproto_st2_clock_t) */
    CANPROTO_ST2_DRIVE = 4,    /* the object's CiA 402 drives (canproto_status2_drive_t) */
    CANPROTO_ST2_BUS = 5,      /* CAN bus state from error frames (canproto_st2_bus_t) */
    CANPROTO_ST2_TIME = 6,     /* track time t_s of the setpoint (canproto_encode_status2_time) */
    CANPROTO_ST2_MOTION = 7,   /* underruns, D growth, moving joins, per-axis stops
                                * (canproto_st2_motion_t) */
    CANPROTO_ST2_PAGES = 8     /* pages are 1 .. CANPROTO_ST2_PAGES - 1 */
} canproto_st2_page_t;

/* Waypoint multiplexer values (byte 0). */
enum canproto_mux {
    CANPROTO_MUX_TIME = 0,
    CANPROTO_MUX_X = 1,
    CANPROTO_MUX_Y = 2,
    CANPROTO_MUX_Z = 3,
    CANPROTO_MUX_COMMAND = 4,
    CANPROTO_MUX_FD_WAYPOINT = 5,
    CANPROTO_MUX_VELOCITY = 6,        /* classic: the source's velocity of waypoint seq */
    CANPROTO_MUX_FD_WAYPOINT_VEL = 7, /* FD: a whole waypoint with its velocity */
};
#define CANPROTO_WP_VEL_M_S_PER_BIT 0.01 /* int16, VELOCITY and WAYPOINT_FD mux 7 */
#define CANPROTO_WP_VEL_BITS_PER_M_S 100.0
#define CANPROTO_WP_PARTS 4 /* TIME, X, Y, Z */

/* Commands (WAYPOINT frame, mux COMMAND, byte 2; byte 3 the argument of
 * OVERRIDE, 0 for the others; bytes 4..7 zero). */
#define CANPROTO_OVERRIDE_MAX_PCT 200
typedef enum {
    CANPROTO_CMD_FINISH = 1,         /* end of input: run to the last waypoint (engine_finish) */
    CANPROTO_CMD_STOP = 2,           /* stop now along the path, latched until START or CLEAR */
    CANPROTO_CMD_CLEAR = 3,          /* engine_clear; sequence numbering restarts */
    CANPROTO_CMD_RESET_COUNTERS = 4, /* engine and CAN counters to zero */
    CANPROTO_CMD_OVERRIDE = 5,       /* feed override: byte 3 = percent, 0 .. 200
                                        (engine_set_override); 201..255 is a
                                        well-formed command the receiver refuses
                                        (a refused command, not a malformed frame) */
    CANPROTO_CMD_START = 6,          /* start: release a stop's latch and join the live
                                        track by a transfer (lib/engine/LIFECYCLE.md) */
    CANPROTO_CMD_COUNT
} canproto_cmd_t;

/* Scalings: physical value = raw * scale. */
#define CANPROTO_WP_T_S_PER_BIT 1e-6   /* uint48 */
#define CANPROTO_WP_POS_M_PER_BIT 1e-6 /* int48 */
#define CANPROTO_WP_BITS_PER_S 1e6     /* the same scalings as exact divisors */
#define CANPROTO_WP_BITS_PER_M 1e6
#define CANPROTO_SP_POS_M_PER_BIT 1e-4     /* int32 */
#define CANPROTO_SP_VEL_M_S_PER_BIT 1e-3   /* int16, classic */
#define CANPROTO_SPFD_VEL_M_S_PER_BIT 1e-6 /* int32, FD */

#define CANPROTO_U48_MAX 0xFFFFFFFFFFFFLL
#define CANPROTO_I48_MAX 0x7FFFFFFFFFFFLL
#define CANPROTO_I48_MIN (-CANPROTO_I48_MAX - 1)
/* Raw int48 position INT48_MIN means "not available" and is refused. */

/* SETPOINT byte 0 */
#define CANPROTO_SP_AXIS_MASK 0x03u
#define CANPROTO_SP_STATE_SHIFT 4
#define CANPROTO_SP_STATE_MASK 0x70u
#define CANPROTO_SP_HOLD 0x80u
/*
 * Position "not available" (int32 0x80000000) in SETPOINT and SETPOINT_FD:
 * trajd has no valid position yet (ENGINE_SP_NO_POSITION; FD flags bit 4 is
 * set too, classic frames set HOLD).  A subscriber must not move on it and
 * must not read it as -214 km: hold what it has, or stay disabled.  A real
 * position is never encoded as this value (it clamps one count above).
 */
#define CANPROTO_SP_POS_NA INT32_MIN

/* STATUS byte 0 */
#define CANPROTO_ST_STATE_MASK 0x07u
#define CANPROTO_ST_CLAMPED 0x08u /* a setpoint value was clipped to its field (tx_clamped) */
#define CANPROTO_ST_BUS_DOWN 0x10u
#define CANPROTO_ST_TX_DROP 0x20u
#define CANPROTO_ST_OUT_FAULT 0x40u /* a csv/stdout output of the object lost lines or failed */
#define CANPROTO_ST_FAULT 0x80u     /* the safety monitor holds the object (until clear) */

/* STATUS byte 7: the last thing that went wrong. */
typedef enum {
    CANPROTO_STERR_OK = 0,
    /* 1..ENGINE_ERROR_COUNT-1: engine_error of the last rejected waypoint */
    CANPROTO_STERR_MALFORMED = 0x40,    /* last malformed frame (see counters) */
    CANPROTO_STERR_LOST = 0x41,         /* a sequence gap was seen */
    CANPROTO_STERR_OUT_OF_ORDER = 0x42, /* a waypoint older than the last one arrived */
    CANPROTO_STERR_TX_DROPPED = 0x43,   /* setpoints dropped (late or queue full) */
    CANPROTO_STERR_BUS_DOWN = 0x44,     /* the interface went down */
    CANPROTO_STERR_OUTPUT = 0x45,       /* a csv/stdout output lost lines (disk full, I/O error) */
    CANPROTO_STERR_SAFETY = 0x46,       /* the safety monitor refused a setpoint (object held) */
    CANPROTO_STERR_DRIVE = 0x47,        /* a CiA 402 drive left Operation Enabled (fault, quick
                                           stop, disabled): the object is cleared, no target sent */
    CANPROTO_STERR_REFUSED = 0x48,      /* a command frame was refused: the object is not
                                           writable (STATUS2 page 1 counts them) */
} canproto_status_err_t;

/* ---- errors ------------------------------------------------------------------ */

enum canproto_error {
    CANPROTO_OK = 0,
    CANPROTO_ELEN = 1, /* wrong length or frame kind (FD/classic/RTR/EFF) for the id */
    CANPROTO_EMUX = 2, /* unknown multiplexer value */
    CANPROTO_EVALUE =
        3, /* a field holds a forbidden value (reserved bits, n/a marker, unknown command) */
    CANPROTO_EID = 4,     /* not one of our ids */
    CANPROTO_ECONFIG = 5, /* invalid id or profile configuration */
    CANPROTO_ERROR_COUNT
};

/* Positive, non-error outcome of an encoder: some value was clamped to its field. */
#define CANPROTO_CLAMPED 1

/* Text for a canproto_error (positive or negated). */
const char *canproto_strerror(int err);

/* Valid CAN FD payload length? (0..8, 12, 16, 20, 24, 32, 48, 64) */
int canproto_fd_len_valid(unsigned len);

/* ---- per-object id configuration ------------------------------------------------- */

#define CANPROTO_CIA402_AXES ENGINE_AXES
#define CANPROTO_CIA402_SDO_MAX 8 /* configuration SDO writes per object */

/* What trajd does with an object's CiA 402 drives: each mode does what the one before does. */
typedef enum {
    CANPROTO_CIA402_OFF = 0,  /* no drives */
    CANPROTO_CIA402_TARGETS,  /* RPDOs: target position 0x607A (and the controlword) */
    CANPROTO_CIA402_FEEDBACK, /* and each drive's feedback TPDO (statusword, position) */
    CANPROTO_CIA402_MANAGED,  /* and their bring-up: NMT, SDO, controlword, heartbeat */
} canproto_cia402_mode_t;

typedef struct {
    uint32_t waypoint_id;    /* classic waypoint frames in */
    uint32_t waypoint_fd_id; /* FD waypoint frames in (used if fd) */
    uint32_t setpoint_id;    /* classic setpoints out */
    uint32_t setpoint_fd_id; /* FD setpoints out (used if fd) */
    uint32_t status_id;
    int fd;                                       /* 1: FD setpoints out and FD waypoints in */
    int brs;                                      /* 1: FD frames with bit-rate switch */
    int own;                                      /* 1: send trajd's own setpoint frames */
    canproto_cia402_mode_t cia402;                /* CANPROTO_CIA402_*: OFF = no RPDOs */
    uint32_t cia402_cob_id[CANPROTO_CIA402_AXES]; /* 0 = axis not sent */
    double cia402_counts_per_m; /* target increments per metre (> 0, finite: the caller's check) */
    int cia402_controlword;     /* 1: RPDO = controlword (2 bytes) + target (4 bytes) */
    uint16_t cia402_controlword_value; /* default 0x000F: enable operation */
    /* Per axis (a drive's own scale, direction and zero):
     *   increments = offset + (invert ? -1 : 1) * round(pos_m * counts_per_m)
     * counts_per_m 0 = cia402_counts_per_m. */
    double cia402_axis_counts_per_m[CANPROTO_CIA402_AXES];
    int cia402_invert[CANPROTO_CIA402_AXES];
    int32_t cia402_offset[CANPROTO_CIA402_AXES];
    /* Drive feedback (FEEDBACK, MANAGED): a TPDO per axis with statusword
     * 0x6041 (u16) then position actual value 0x6064 (i32) on cia402_tpdo_id
     * (0 = 0x180 + the node of the axis' COB-id, its low 7 bits). */
    uint32_t cia402_tpdo_id[CANPROTO_CIA402_AXES];
    /* Bring-up (MANAGED): NMT start, the SDO writes below to each axis' node
     * (node = low 7 bits of its COB-id), then the controlword written by SDO
     * (0x6040) from the statusword: Shutdown, Switch on, Enable operation.
     * Heartbeats (consumer time heartbeat_ms, 0 = not watched), EMCY and SDO
     * aborts are reported. */
    struct {
        uint16_t index;
        uint8_t sub;
        uint8_t size; /* 1, 2, 4 bytes */
        uint32_t value;
    } cia402_sdo[CANPROTO_CIA402_SDO_MAX];
    unsigned cia402_nsdo;
    uint32_t cia402_heartbeat_ms;
    uint32_t status2_id; /* STATUS2 out (pages) */
} canproto_ids_t;

/* The CANopen node-id of axis (low 7 bits of its COB-id), 0 if unused. */
unsigned canproto_cia402_node(const canproto_ids_t *ids, unsigned axis);

/* The feedback TPDO id of axis (0 if feedback is off or the axis unused). */
uint32_t canproto_cia402_tpdo(const canproto_ids_t *ids, unsigned axis);

/*
 * Drive increments for pos_m on axis (the formula above, clamped to int32;
 * *clamped set if it was).  And back: the position in metres of drive
 * increments inc (e.g. its 0x6064 position actual value).
 */
int32_t canproto_cia402_counts(const canproto_ids_t *ids, unsigned axis, double pos_m,
                               int *clamped);
double canproto_cia402_pos_m(const canproto_ids_t *ids, unsigned axis, int32_t inc);

/* Defaults for object n (0-based): the bases above + n, own frames, no FD, no CiA 402. */
void canproto_ids_default(canproto_ids_t *ids, unsigned n);

/*
 * Check one object's ids: all 11-bit, pairwise distinct among those in use.
 * Returns 0 or -CANPROTO_ECONFIG (why, if not NULL, names the rule).
 */
int canproto_ids_check(const canproto_ids_t *ids, const char **why);

/* Most ids one object can use: 2 waypoint, 1 setpoint, 2 status, 3 CiA 402, 3 feedback. */
#define CANPROTO_IDS_MAX 16

/*
 * Every id this object uses (waypoint, setpoint, status, CiA 402 RPDOs), in
 * a fixed order, for clash checks.  out holds CANPROTO_IDS_MAX; returns the count.
 */
unsigned canproto_ids_in_use(const canproto_ids_t *ids, uint32_t out[CANPROTO_IDS_MAX]);

/*
 * The ids a receiver must let through for this object (waypoint ids in use).
 * Writes at most max ids into out; returns how many there are.
 */
unsigned canproto_ids_rx(const canproto_ids_t *ids, uint32_t *out, unsigned max);

/* ---- encoders (sender side and tests; the daemon uses the setpoint ones) ------------ */

/*
 * Encode waypoint wp as the four classic frames TIME, X, Y, Z (out[4]) on id,
 * with seq = wp->seq & 0xFF.  Returns 0, CANPROTO_CLAMPED (t < 0 or a value out
 * of range was clamped), or -CANPROTO_EVALUE (NaN/inf).
 */
int canproto_encode_waypoint(uint32_t id, const engine_waypoint_t *wp,
                             canproto_frame_t out[CANPROTO_WP_PARTS]);

/* Same, as one CAN FD frame (mux 7 with wp's velocity when wp->has_vel).
 * Same returns. */
int canproto_encode_waypoint_fd(uint32_t id, const engine_waypoint_t *wp, canproto_frame_t *out);

/* The VELOCITY frame of wp (wp->vel_m_s, seq = wp->seq & 0xFF): send it
 * before wp's four frames.  Same returns. */
int canproto_encode_waypoint_vel(uint32_t id, const engine_waypoint_t *wp, canproto_frame_t *out);

/* A COMMAND frame on the waypoint id.  Returns 0 or -CANPROTO_EVALUE. */
int canproto_encode_command(uint32_t id, canproto_cmd_t cmd, canproto_frame_t *out);
/* The OVERRIDE command with percent (0 .. CANPROTO_OVERRIDE_MAX_PCT) in byte 3.
 * Returns 0 or -CANPROTO_EVALUE (percent out of range). */
int canproto_encode_override(uint32_t id, unsigned percent, canproto_frame_t *out);

/*
 * The three classic SETPOINT frames of sp (out[3]).  With ENGINE_SP_NO_POSITION
 * the positions are CANPROTO_SP_POS_NA, velocities 0, HOLD set.  Otherwise
 * NaN is sent as 0 and counted like a clamp.  Returns 0 or CANPROTO_CLAMPED.
 */
int canproto_encode_setpoint(uint32_t id, const engine_setpoint_t *sp,
                             canproto_frame_t out[ENGINE_AXES]);

/* The one FD SETPOINT frame of sp.  Returns 0 or CANPROTO_CLAMPED. */
int canproto_encode_setpoint_fd(uint32_t id, int brs, const engine_setpoint_t *sp,
                                canproto_frame_t *out);

/* SYNC frame: DLC 0 if counter == 0, else DLC 1 with the counter. */
void canproto_encode_sync(uint32_t id, uint8_t counter, canproto_frame_t *out);

/*
 * CiA 402 RPDO for one axis: 0x607A target position =
 * canproto_cia402_counts(pos_m), clamped to int32.  Returns 0,
 * CANPROTO_CLAMPED, or -CANPROTO_ECONFIG (axis not configured).
 */
int canproto_encode_cia402(const canproto_ids_t *ids, unsigned axis, double pos_m,
                           canproto_frame_t *out);

/* STATUS frame contents. */
typedef struct {
    uint8_t state; /* engine_state_t */
    uint8_t flags; /* CANPROTO_ST_BUS_DOWN | _TX_DROP | _OUT_FAULT | _FAULT */
    uint32_t last_seq;
    uint32_t free;
    uint32_t lost;
    uint32_t rejected;
    uint32_t malformed;
    uint32_t dropped;
    uint8_t last_err; /* canproto_status_err_t or engine_error */
} canproto_status_t;

void canproto_encode_status(uint32_t id, const canproto_status_t *st, canproto_frame_t *out);

/* STATUS2 page 4: the object's CiA 402 drives. */
#define CANPROTO_S2_NO_DRIVE 0x0Fu /* state nibble of an axis without a drive */
#define CANPROTO_S2_NMT_NONE 0xFFu /* no heartbeat heard */
typedef struct {
    /* cia402_state_t of each axis (8 = not heard yet), CANPROTO_S2_NO_DRIVE if none:
     * byte 1 bits 0..3 x, 4..7 y; byte 2 bits 0..3 z */
    uint8_t state[CANPROTO_CIA402_AXES];
    int hb_lost; /* byte 2 bit 6: a drive's heartbeat not heard within cia402_heartbeat_ms */
    int held;    /* byte 2 bit 7: a drive left Operation Enabled; held until clear */
    uint16_t statusword; /* bytes 3..4 (LE): of the first drive axis not in Operation Enabled,
                          * else of the first drive axis */
    uint8_t nmt;         /* byte 5: heartbeat NMT state of that axis' node, 0xFF = none heard */
    uint16_t emcy;       /* bytes 6..7 (LE): error code of the last EMCY, 0 = none */
} canproto_status2_drive_t;

void canproto_encode_status2_drive(uint32_t id, const canproto_status2_drive_t *d,
                                   canproto_frame_t *out);

/* ---- decoders ------------------------------------------------------------------ */

/* One decoded SETPOINT frame (classic: one axis; FD: all). */
typedef struct {
    unsigned axis;  /* classic only */
    uint32_t cycle; /* classic: low 8 bits */
    uint8_t state;
    uint8_t flags;  /* classic: ENGINE_SP_HOLD, and ENGINE_SP_NO_POSITION from the marker */
    uint16_t track; /* FD only */
    double pos_m[ENGINE_AXES]; /* classic: [axis] only; NaN for CANPROTO_SP_POS_NA */
    double vel_m_s[ENGINE_AXES];
} canproto_setpoint_t;

/* Decode a classic or FD SETPOINT frame.  Returns 0, -CANPROTO_ELEN, -CANPROTO_EVALUE. */
int canproto_decode_setpoint(const canproto_frame_t *f, canproto_setpoint_t *out);

/* Decode a STATUS frame.  Returns 0 or -CANPROTO_ELEN. */
int canproto_decode_status(const canproto_frame_t *f, canproto_status_t *out);

/* STATUS2 page 1, FAULTS (values above a field's maximum are sent as the maximum). */
#define CANPROTO_ST2_U24_MAX 0xFFFFFFu
typedef struct {
    uint64_t out_lost;    /* setpoint lines lost by the object's csv/stdout outputs (uint24) */
    uint64_t out_errors;  /* failed writes of those outputs (uint16) */
    uint64_t cmd_refused; /* command frames refused: not writable, or held (uint16) */
} canproto_st2_faults_t;

void canproto_encode_status2_faults(uint32_t id, const canproto_st2_faults_t *p,
                                    canproto_frame_t *out);

/* STATUS2 page 5, BUS (counters saturate at 65535). */
typedef struct {
    uint8_t state; /* 1 error-active .. 4 bus-off, 5 down (MBMAP_CAN_*) */
    uint8_t tx_err, rx_err;
    uint64_t bus_offs;   /* entries into bus-off (uint16) */
    uint64_t err_frames; /* error frames received (uint16) */
} canproto_st2_bus_t;

void canproto_encode_status2_bus(uint32_t id, const canproto_st2_bus_t *p, canproto_frame_t *out);
/* Decode STATUS2 page 5.  Returns 0, -CANPROTO_ELEN, or -CANPROTO_EMUX (another page). */
int canproto_decode_status2_bus(const canproto_frame_t *f, canproto_st2_bus_t *out);

/* The page of a STATUS2 frame (1 .. CANPROTO_ST2_PAGES - 1), or -CANPROTO_ELEN
 * (wrong length or kind) or -CANPROTO_EMUX (page 0 or unknown). */
int canproto_status2_page(const canproto_frame_t *f);

/* Decode STATUS2 page 1.  Returns 0, -CANPROTO_ELEN, or -CANPROTO_EMUX (another page). */
int canproto_decode_status2_faults(const canproto_frame_t *f, canproto_st2_faults_t *out);
/* Decode STATUS2 page 4.  Returns 0, -CANPROTO_ELEN, -CANPROTO_EMUX (another page). */
int canproto_decode_status2_drive(const canproto_frame_t *f, canproto_status2_drive_t *out);

/* STATUS2 page 3, CLOCK (lib/engine/CLOCK.md). */
#define CANPROTO_ST2_AGE_NA (-8388608) /* bytes 1..3 (int24): no age (NaN) */
#define CANPROTO_ST2_AGE_MAX 8388607   /* ms; ages beyond +-this are sent as +-this */
#define CANPROTO_ST2_AGE_S_PER_BIT 1e-3
#define CANPROTO_ST2_DRIFT_PPM_PER_BIT 0.1
#define CANPROTO_ST2_DRIFT_NA (-32768) /* bytes 4..5: no estimate (NaN) */
typedef enum {
    CANPROTO_ST2_CLOCK_RELATIVE = 0,  /* its own origin (relative time) */
    CANPROTO_ST2_CLOCK_ON = 1,        /* played out on the daemon's clock */
    CANPROTO_ST2_CLOCK_UNDECIDED = 2, /* clock = auto: its first waypoint decides */
} canproto_st2_clocked_t;
typedef struct {
    double age_s;     /* now - t_s, s (NaN: none); sent to 1 ms */
    double drift_ppm; /* sender clock drift absorbed, ppm (NaN: none); to 0.1 ppm */
    uint8_t clocked;  /* canproto_st2_clocked_t */
} canproto_st2_clock_t;

void canproto_encode_status2_clock(uint32_t id, const canproto_st2_clock_t *p,
                                   canproto_frame_t *out);
/* Decode STATUS2 page 3: age and drift as the field's value times its LSB,
 * NaN for the n/a codes.  Returns 0, -CANPROTO_ELEN, or -CANPROTO_EMUX. */
int canproto_decode_status2_clock(const canproto_frame_t *f, canproto_st2_clock_t *out);

/* STATUS2 page 6, TIME: bytes 1..7 the setpoint's track time t_s as int56 in
 * us (the unit of the waypoint TIME frame; seconds since the epoch fit), so a
 * setpoint frame can be put beside the waypoint it passes; a page of values. */
#define CANPROTO_ST2_TIME_NA (-36028797018963968LL) /* int56 minimum: no time (NaN) */
#define CANPROTO_ST2_TIME_S_PER_BIT 1e-6
void canproto_encode_status2_time(uint32_t id, double t_s, canproto_frame_t *out);
/* Decode STATUS2 page 6: t_s (NaN for the n/a code).  Returns 0, -CANPROTO_ELEN,
 * or -CANPROTO_EMUX (another page). */
int canproto_decode_status2_time(const canproto_frame_t *f, double *t_s);

/* STATUS2 page 2, REJECTED: waypoints refused per reason (uint8, saturating). */
typedef struct {
    uint64_t backwards;   /* ENGINE_EBACKWARDS */
    uint64_t same_time;   /* ENGINE_ESAMETIME */
    uint64_t speed;       /* ENGINE_ESPEED */
    uint64_t accel;       /* ENGINE_EACCEL */
    uint64_t unconfirmed; /* ENGINE_EUNCONFIRMED */
    uint64_t stale;       /* ENGINE_ESTALE */
    uint64_t other;       /* ENGINE_ENOTFINITE + ENGINE_ERANGE + ENGINE_ENUMERIC */
} canproto_st2_rejected_t;

/* The page's counters from an engine_status_t's rejected_by[]. */
void canproto_st2_rejected_from(const uint64_t rejected_by[ENGINE_ERROR_COUNT],
                                canproto_st2_rejected_t *out);

void canproto_encode_status2_rejected(uint32_t id, const canproto_st2_rejected_t *p,
                                      canproto_frame_t *out);

/* Decode STATUS2 page 2.  Returns 0, -CANPROTO_ELEN, or -CANPROTO_EMUX (another page). */
int canproto_decode_status2_rejected(const canproto_frame_t *f, canproto_st2_rejected_t *out);

/* STATUS2 page 7, MOTION (issues 26, 32): the engine's motion counters
 * (engine_status_t), each saturating at its field's maximum; a page of events
 * (a change sends it first).  axis_lost_s is not here: it grows every tick
 * the per-axis limits slow the output, so the page would change every tick
 * and take the other pages' turns (Modbus diagnostics and --summary give it). */
typedef struct {
    uint64_t underruns;        /* transitions into UNDERRUN (bytes 1..2, uint16) */
    uint64_t delay_grown;      /* D stated anew, longer (byte 3, uint8) */
    uint64_t transfers_moving; /* re-anchors joined moving (byte 4, uint8) */
    uint64_t reserve_slowed;   /* slowdowns for D's stop reserve, input on time (byte 5) */
    uint64_t axis_beyond;      /* stops before a segment beyond the per-axis limits (byte 6) */
    uint64_t axis_lag_stops;   /* stops because the per-axis lag passed max_lag_s (byte 7) */
} canproto_st2_motion_t;

/* The page's counters from an engine_status_t. */
void canproto_st2_motion_from(const engine_status_t *st, canproto_st2_motion_t *out);

void canproto_encode_status2_motion(uint32_t id, const canproto_st2_motion_t *p,
                                    canproto_frame_t *out);

/* Decode STATUS2 page 7.  Returns 0, -CANPROTO_ELEN, or -CANPROTO_EMUX (another page). */
int canproto_decode_status2_motion(const canproto_frame_t *f, canproto_st2_motion_t *out);

/* ---- waypoint reassembly ------------------------------------------------------------ */

typedef struct {
    int used;
    uint8_t seq8;
    uint8_t have; /* bit per part (1 << mux; VELOCITY's too) */
    uint64_t t_us;
    int64_t pos_um[ENGINE_AXES];
    int16_t vel_cm_s[ENGINE_AXES];
    uint32_t stamp; /* order in which slots were opened (oldest is evicted) */
    uint32_t seen;  /* canproto_rx_t.tick of its last frame (stale: CANPROTO_RX_STALE_FRAMES) */
} canproto_slot_t;

typedef struct {
    uint64_t frames;    /* frames offered */
    uint64_t malformed; /* sum of malformed_by */
    uint64_t malformed_by[CANPROTO_ERROR_COUNT];
    uint64_t completed;    /* waypoints reassembled and handed out */
    uint64_t lost;         /* waypoints never handed out (sequence gaps) */
    uint64_t duplicates;   /* frames or waypoints already handed out, ignored */
    uint64_t out_of_order; /* frames of a waypoint older than the last handed out (1..128
                            * behind, its time not later), dropped */
    uint64_t incomplete;   /* partial waypoints ahead abandoned (also counted in lost) */
    uint64_t commands;
    uint64_t resyncs;     /* waypoints behind but later in time, taken: the sender restarted
                           * its numbering (canproto_rx_frame) */
    uint8_t resync_seq;   /* the last resync: the waypoint's seq (8 bits) ... */
    uint8_t resync_after; /* ... and the seq of the waypoint consumed before it */
} canproto_rx_stats_t;

typedef struct {
    canproto_slot_t *slots; /* caller's */
    unsigned nslots;
    int have_last;     /* a waypoint was consumed since init/restart */
    uint32_t last_seq; /* extended sequence number of the last consumed waypoint */
    double last_t_s;   /* its time (wp.t_s), if have_last */
    uint32_t stamp;    /* slots opened */
    uint32_t tick;     /* classic waypoint frames offered to the slots (their age) */
    canproto_rx_stats_t st;
} canproto_rx_t;

/* What canproto_rx_frame produced. */
typedef enum {
    CANPROTO_RX_NONE = 0,     /* frame absorbed (part of a waypoint, duplicate, stale) */
    CANPROTO_RX_WAYPOINT = 1, /* a complete waypoint is in out->wp (not yet consumed) */
    CANPROTO_RX_COMMAND = 2,  /* out->cmd */
} canproto_rx_kind_t;

typedef struct {
    engine_waypoint_t wp; /* wp.seq: extended 32-bit sequence number */
    canproto_cmd_t cmd;
    unsigned cmd_arg;     /* byte 3: OVERRIDE percent (0 for the other commands) */
    uint32_t lost_before; /* waypoints missing between the last consumed one and this */
    uint32_t resync;      /* 1: behind the last consumed one but later in time (a sender
                           * that restarted its numbering): the tracking restarts from it */
} canproto_rx_out_t;

/*
 * Attach nslots caller-owned slots (>= 1; 2 tolerates the frames of two
 * consecutive waypoints interleaving) and start with no sequence history.
 */
void canproto_rx_init(canproto_rx_t *rx, canproto_slot_t *slots, unsigned nslots);

/* Forget partial waypoints and the sequence history (CLEAR); counters kept. */
void canproto_rx_restart(canproto_rx_t *rx);

/*
 * A slot that had no frame while this many classic waypoint frames were
 * offered is stale: a frame behind may take it (canproto_rx_frame).
 */
#define CANPROTO_RX_STALE_FRAMES 32u

/*
 * Offer one frame received on a waypoint id (is_fd_id: it came on the FD
 * waypoint id).  Sequence numbers are 8 bits on the wire; a waypoint whose
 * seq is 1..127 ahead of the last consumed one is new (a gap of k counts k
 * lost when it is consumed), 0 behind is a duplicate.  One 1..128 behind is
 * judged by its time once complete: later than the last consumed one's, it
 * is a sender that restarted its numbering (out->resync; the tracking
 * restarts from it, nothing counted lost, its extended number still goes
 * forward); else it is out of order, dropped (its frames counted).  So the
 * frames of a waypoint behind reassemble too, but never at the cost of a
 * partial waypoint ahead: a frame behind takes a free slot, else a stale one
 * (CANPROTO_RX_STALE_FRAMES), else the oldest slot behind, else it is
 * dropped; a frame ahead takes a free slot, else the oldest slot behind,
 * else the oldest slot.  A completed waypoint is NOT consumed yet: the
 * caller offers it to the engine and calls canproto_rx_consume() unless the
 * engine answered EFULL, so the sender can repeat it after reading STATUS.
 * Returns a canproto_rx_kind_t, or a negated canproto_error for a malformed
 * frame (counted, nothing else changed).
 */
int canproto_rx_frame(canproto_rx_t *rx, const canproto_frame_t *f, int is_fd_id,
                      canproto_rx_out_t *out);

/* Mark the waypoint out->wp (from canproto_rx_frame) as consumed: counts its
 * gap, or its resync; partial waypoints at or behind it are abandoned. */
void canproto_rx_consume(canproto_rx_t *rx, const canproto_rx_out_t *out);

/* ---- bus load ------------------------------------------------------------------ */

/*
 * Worst-case length of one frame on the wire, in seconds, including the
 * worst-case bit stuffing and the 3-bit interframe space.
 *  classic: 8n + 47 + floor((34 + 8n - 1)/4) bits for 11-bit ids, 8n + 67 +
 *    floor((54 + 8n - 1)/4) for 29-bit ids (Davis, Burns, Bril, Lukkien 2007,
 *    "CAN schedulability analysis: refuted, revisited and revised", eq. 2-3);
 *  FD: arbitration phase (SOF..BRS, 17 or 36 bits, dynamic stuffing),
 *    data phase at data_bitrate if BRS (ESI, DLC, data with dynamic stuffing,
 *    stuff count + CRC17/21 with fixed stuff bits), tail at the nominal rate
 *    (CRC delimiter, ACK, ACK delimiter, EOF, IFS: 13 bits).  ISO 11898-1:2015.
 * len must be a valid length for the kind; bitrates > 0 (data_bitrate only
 * used with FD + BRS).  Returns a negative value for invalid arguments.
 */
double canproto_frame_time_s(unsigned len, int fd, int brs, int eff, double bitrate,
                             double data_bitrate);

/* Worst-case bits at the nominal rate equivalent: frame_time_s * bitrate. */
double canproto_frame_bits(unsigned len, int fd, int brs, int eff, double bitrate,
                           double data_bitrate);

/* Traffic trajd puts on the bus for one object (output) plus its expected input. */
typedef struct {
    double rate_hz;     /* setpoint cycles per second */
    double status_hz;   /* STATUS frames per second */
    double waypoint_hz; /* expected waypoints per second in (from the sender) */
} canproto_traffic_t;

/*
 * Worst-case bus time per second (the load, 0..1+) of nobj objects with ids
 * (an array of nobj), with a SYNC of sync_dlen bytes per cycle if sync is set.
 * Returns the load, or a negative value for invalid arguments.
 */
double canproto_busload(const canproto_ids_t *ids, unsigned nobj, int sync, unsigned sync_dlen,
                        const canproto_traffic_t *tr, double bitrate, double data_bitrate);

#endif
