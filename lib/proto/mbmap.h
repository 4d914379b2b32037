/*
 * mbmap.h - trajd's Modbus register map: the single source of every address,
 * type, scaling and word order.  Pure: encodes a status snapshot into a
 * register image, validates requests and decodes holding-register writes into
 * commands and waypoints, with the Modbus exception code to answer.  No I/O.
 * The table in config/PROTOCOL.md is generated from mbmap_fields() (tests/e2e/test_mbmap_readme.sh
 * fails if the two differ).
 *
 * Addresses are the 0-based addresses carried in the PDU (mbpoll: use -0, or
 * add 1).  Objects are selected by BLOCK OFFSET, not by unit id: the daemon
 * block is at 0, object k (its `id = k` in the config, never its place in
 * the file) at MBMAP_OBJ_BASE(k) = 100 * (k + 1), both in the input and in the
 * holding registers.  A block of an id no object has reads all 0 (GEN 0) and
 * refuses writes (exception 02).  Why: an RTU
 * line gives the daemon one slave address (unit ids 248..255 are reserved and
 * 0 is broadcast, so unit ids would cap the objects and collide with other
 * slaves on the bus), many TCP gateways and SCADA tools rewrite or ignore the
 * unit id, and one address space works the same over TCP and RTU.  Over TCP
 * any unit id is answered; over RTU only the configured one.
 *
 * Types and word order ("ABCD", big-endian words, most significant first):
 *   u16  one register;
 *   u32  two registers, high word first (counters are the low 32 bits of the
 *        daemon's 64-bit counters: they wrap);
 *   f32  IEEE-754 binary32, high word first (libmodbus modbus_get_float_abcd,
 *        mbpoll -B -t 3:float, pymodbus Endian.Big byte and word order);
 *   f64  IEEE-754 binary64, four registers, most significant first
 *        (track time, and the waypoint input so a track is fed exactly).
 *
 * Consistency: the daemon rewrites the whole image once per tick, between
 * requests (one thread, one loop); a request is answered from one image, so
 * one read never mixes two ticks.  Every block starts with the snapshot
 * generation (GEN) and ends with a copy of it (GEN_TAIL): a read of a whole
 * block with GEN == GEN_TAIL is from one tick (the tests check this).
 */
#ifndef TRAJD_MBMAP_H
#define TRAJD_MBMAP_H
/* trajd public API: installed as <trajd/mbmap.h> (make install; pkg-config trajd). */
/* The #define tables are read by the tests (tests/helpers/mbsim.py,
 * tests/oracle/test_trajreplay.py) one line each: kept as written. */
/* clang-format off */

#include <stddef.h>
#include <stdint.h>
#include "motion.h"

#define MBMAP_VERSION 1
#define MBMAP_MAGIC 0x7444u          /* "tD": register 0, to recognise trajd */
#define MBMAP_MAX_OBJECTS 64
#define MBMAP_BLOCK 100              /* registers per block */
#define MBMAP_OBJ_BASE(k) (MBMAP_BLOCK * (1u + (unsigned)(k)))
/* Registers of the daemon and object blocks for n objects. */
#define MBMAP_REGS(n) (MBMAP_BLOCK * (1u + (unsigned)(n)))
/* Object k's diagnostics block (input registers): after the space of every
 * possible object block, so adding objects never moves it. */
#define MBMAP_X_BASE(k) (MBMAP_BLOCK * (1u + MBMAP_MAX_OBJECTS + (unsigned)(k)))
/* Registers in each table (input and holding) for n objects: the daemon and
 * object blocks, then (after object slots n..MBMAP_MAX_OBJECTS-1, not
 * served) the n diagnostics blocks. */
#define MBMAP_TABLE_REGS(n) MBMAP_X_BASE(n)

/* Modbus protocol limits (Modbus Application Protocol V1.1b3, 6.3, 6.4, 6.12). */
#define MBMAP_MAX_READ 125           /* registers per read (FC 03, 04) */
#define MBMAP_MAX_WRITE 123          /* registers per write multiple (FC 16) */
#define MBMAP_PDU_MAX 253            /* function code + data */
#define MBMAP_TCP_ADU_MAX 260        /* MBAP (7) + PDU */
#define MBMAP_RTU_ADU_MAX 256        /* address + PDU + CRC */

/* Function codes served; every other one is answered with exception 01. */
#define MBMAP_FC_READ_HOLDING 0x03
#define MBMAP_FC_READ_INPUT 0x04
#define MBMAP_FC_WRITE_SINGLE 0x06
#define MBMAP_FC_WRITE_MULTIPLE 0x10

/* FC 03 mirror: holding register MBMAP_MIRROR_BASE + a reads input register a
 * (read-only; writes there are exception 02), for HMIs that read holding
 * registers only.  Above every holding and input block (MBMAP_REGS of 129
 * blocks < MBMAP_MIRROR_BASE, and MBMAP_MIRROR_BASE + that < 65536). */
#define MBMAP_MIRROR_BASE 20000

/* ---- daemon block, input registers (absolute addresses) ---------------- */
#define MBMAP_D_MAGIC 0              /* u16 MBMAP_MAGIC */
#define MBMAP_D_VERSION 1            /* u16 MBMAP_VERSION */
#define MBMAP_D_OBJECTS 2            /* u16 object blocks: the highest object id + 1 (a block whose GEN reads 0 has no object) */
#define MBMAP_D_WRITES 3             /* u16 1 if writes are enabled */
#define MBMAP_D_GEN 4                /* u32 snapshot generation (+1 per tick; 0 = none published yet, all values 0) */
#define MBMAP_D_UPTIME_S 6           /* u32 */
#define MBMAP_D_PERIOD_US 8          /* u32 output period */
#define MBMAP_D_LATE_P50_US 10       /* u32 tick lateness */
#define MBMAP_D_LATE_P99_US 12       /* u32 */
#define MBMAP_D_LATE_MAX_US 14       /* u32 */
#define MBMAP_D_MISSED_TICKS 16      /* u32 timer expirations missed by the loop */
#define MBMAP_D_CAN_STATE 18         /* u16 MBMAP_CAN_* */
#define MBMAP_D_CAN_LOAD 19          /* u16 bus load, 0.1 % */
#define MBMAP_D_MB_REQUESTS 20       /* u32 Modbus requests answered */
#define MBMAP_D_MB_EXCEPTIONS 22     /* u32 exception responses sent */
#define MBMAP_D_MB_REFUSED 24        /* u32 connections refused (allow-list; max clients; out
                                      * of fds; see modbus_server.h's connection policy) */
#define MBMAP_D_MB_CLIENTS 26        /* u16 TCP clients connected now */
#define MBMAP_D_MB_EVICTED 28        /* u32 clients evicted at max_clients to admit a newcomer */
#define MBMAP_D_MB_SLOW 30           /* u32 clients dropped: a request not whole within request_timeout_ms */
#define MBMAP_D_OUT_LOST 32          /* u32 setpoint lines lost by the outputs (all objects) */
#define MBMAP_D_OUT_FAULT 34         /* u16 1 if an output failed to write (disk full, I/O error) */
#define MBMAP_D_DRIVE_EMCY 36        /* u32 EMCY frames from CiA 402 drives (all objects) */
#define MBMAP_D_DRIVE_LAST_ABORT 38  /* u32 abort code of the last SDO abort from a drive, 0 = none */
#define MBMAP_D_DRIVE_SDO_ABORTS 40  /* u16 SDO writes drives refused (all objects, saturates) */
#define MBMAP_D_DRIVE_HB_LOST 41     /* u16 heartbeat consumer timeouts (all objects, saturates) */
#define MBMAP_D_CLOCK_DRIFT 42       /* f32 sender clock drift absorbed, ppm (lib/engine/CLOCK.md) */
#define MBMAP_D_CLOCK_DELAY 44       /* f32 play-out delay D, s */
#define MBMAP_D_CLOCK_MODE 46        /* u16 [daemon] clock: 0 auto, 1 epoch, 2 relative */
#define MBMAP_D_CLOCK_OBJECTS 47     /* u16 objects played out on the clock */
#define MBMAP_D_MB_CONNECTIONS 48    /* u32 TCP connections accepted */
#define MBMAP_D_MB_DROPPED 50        /* u32 clients closed by the server (framing, idle, answers not read, slow) */
#define MBMAP_D_MB_PEERS 52          /* u16 client addresses seen (at most MODBUS_SERVER_PEERS kept) */
#define MBMAP_D_MB_WORST_FAMILY 53   /* u16 the client address with the most drops, then exceptions: 0 none, 4 IPv4, 6 IPv6 */
#define MBMAP_D_MB_WORST_IPV4 54     /* u32 its IPv4 address (a.b.c.d = a*2^24 + b*2^16 + c*2^8 + d; 0 if IPv6: any address in MBMAP_X_MB_WORST_ADDR) */
#define MBMAP_D_MB_WORST_REQUESTS 56 /* u32 requests it sent */
#define MBMAP_D_MB_WORST_EXCEPTIONS 58 /* u32 exception responses it got */
#define MBMAP_D_MB_WORST_DROPS 60    /* u32 its connections evicted, dropped slow or closed by the server */
#define MBMAP_D_CAN_ERR_FRAMES 64    /* u32 CAN error frames received (lib/proto/canerr.h) */
#define MBMAP_D_CAN_WARNINGS 66      /* u32 entries into error-warning */
#define MBMAP_D_CAN_PASSIVES 68      /* u32 entries into error-passive */
#define MBMAP_D_CAN_BUS_OFFS 70      /* u32 entries into bus-off */
#define MBMAP_D_CAN_RESTARTS 72      /* u32 controller restarts */
#define MBMAP_D_CAN_BUS_ERRORS 74    /* u32 error frames with a bus-error class (protocol, ACK, arbitration, ...) */
#define MBMAP_D_CAN_OVERFLOWS 76     /* u32 controller RX/TX buffer overflows */
#define MBMAP_D_CAN_TX_ERR 78        /* u16 TX error counter, last reported */
#define MBMAP_D_CAN_RX_ERR 79        /* u16 RX error counter, last reported */
#define MBMAP_D_LOG_DROPPED 80       /* u32 log lines dropped: the log thread's queue was full */
#define MBMAP_D_CAN_RX_DROPPED 82    /* u32 CAN frames the kernel dropped: trajd's receive queue full */
#define MBMAP_D_GEN_TAIL 98          /* u32 copy of GEN */

/* ---- object block, input registers (offset from MBMAP_OBJ_BASE(k)) ------ */
#define MBMAP_O_GEN 0                /* u32 snapshot generation */
#define MBMAP_O_STATE 2              /* u16 engine_state_t, or MBMAP_STATE_HELD */
#define MBMAP_O_FLAGS 3              /* u16 ENGINE_SP_* of the setpoint */
#define MBMAP_O_CYCLE 4              /* u32 setpoint tick counter */
#define MBMAP_O_TRACK 6              /* u32 trajectory number */
#define MBMAP_O_BUFFERED 8           /* u32 waypoints buffered */
#define MBMAP_O_FREE 10              /* u32 waypoints that can still be written */
#define MBMAP_O_LOOKAHEAD 12         /* u32 waypoints of lookahead needed */
#define MBMAP_O_AHEAD_S 14           /* f32 lookahead available, s of track time */
#define MBMAP_O_LAST_SEQ 16          /* u32 sequence number of the last accepted waypoint */
#define MBMAP_O_T_S 18               /* f64 track time of the setpoint, s */
#define MBMAP_O_POS 22               /* f32 x3 position, m */
#define MBMAP_O_VEL 28               /* f32 x3 velocity, m/s */
#define MBMAP_O_ACC 34               /* f32 x3 acceleration, m/s^2 */
#define MBMAP_O_ACCEPTED 40          /* u32 waypoints accepted */
#define MBMAP_O_REJECTED 42          /* u32 waypoints rejected by the engine (all inputs; not EFULL) */
#define MBMAP_O_LOST 44              /* u32 waypoints lost (gaps in sequence numbers: Modbus or CAN input) */
#define MBMAP_O_UNDERRUNS 46         /* u32 transitions into underrun */
#define MBMAP_O_MISSED_TICKS 48      /* u32 ticks stepped over */
#define MBMAP_O_DUPLICATES 50        /* u32 exact duplicates dropped */
#define MBMAP_O_MB_REJECTED 52       /* u32 Modbus writes refused with exception 03 */
#define MBMAP_O_LATE_P99_US 54       /* u32 tick lateness (the daemon's loop) */
#define MBMAP_O_LATE_MAX_US 56       /* u32 */
#define MBMAP_O_CAN_STATE 58         /* u16 MBMAP_CAN_* of the object's bus */
#define MBMAP_O_CAN_LOAD 59          /* u16 bus load, 0.1 % */
#define MBMAP_O_UPTIME_S 60          /* u32 */
#define MBMAP_O_FULL 62              /* u32 waypoints refused with a full buffer (flow control) */
#define MBMAP_O_OUT_LOST 64          /* u32 setpoint lines of this object lost by its outputs */
#define MBMAP_O_OUT_FAULT 66         /* u16 1 if an output of this object failed to write */
#define MBMAP_O_SEQ_JUMPS 68         /* u32 sequence numbers outside the plausible window */
#define MBMAP_O_RATE 70              /* f32 time-scaling rate ds/dt of the output (1 = as solved) */
#define MBMAP_O_OVERRIDE 72          /* u16 feed override in force, % */
#define MBMAP_O_HARD_STOPS 74        /* u32 the curve ended under a moving output (should stay 0) */
#define MBMAP_O_DRIVE_STATES 76      /* u16 CiA 402 state per axis: bits 0..3 x, 4..7 y, 8..11 z; bit 14 heartbeat lost, 15 held */
#define MBMAP_O_DRIVE_STATUSWORD 77  /* u16 statusword of the first drive axis not in Operation Enabled, else the first */
#define MBMAP_O_DRIVE_NMT 78         /* u16 heartbeat NMT state of that node (0xFF: none heard) */
#define MBMAP_O_DRIVE_EMCY 79        /* u16 error code of the last EMCY from the object's drives */
#define MBMAP_O_AGE_S 80             /* f32 data age: now - t_s on the sender's time base (NaN: relative time) */
#define MBMAP_O_CLOCKED 82           /* u16 1 if played out on the daemon's clock */
#define MBMAP_O_HEALTH 83            /* u16 MBMAP_HEALTH_* bits: 0 = nothing to alarm on */
#define MBMAP_O_LAT 84               /* f64 latitude of the setpoint, degrees (WGS84; NaN: not geographic or no position) */
#define MBMAP_O_LON 88               /* f64 longitude, degrees */
#define MBMAP_O_ALT 92               /* f64 height above the WGS84 ellipsoid, m */
#define MBMAP_O_GEN_TAIL 98          /* u32 copy of GEN */

/* ---- diagnostics block, input registers (offset from MBMAP_X_BASE(k)) -- */
/* Waypoints refused, per reason: the u32 for engine_error c (lib/motion.h)
 * is at MBMAP_X_REJECTED_BY + 2 * (c - 1); the codes that are not reasons for
 * data (6..9) read 0.  Their sum is the object block's rejected. */
#define MBMAP_X_GEN 0                /* u32 snapshot generation (the object block's) */
#define MBMAP_X_REJECTED_BY 2        /* first of the per-reason counters */
#define MBMAP_X_REJ_NOTFINITE 2      /* u32 ENGINE_ENOTFINITE (1): NaN or infinite */
#define MBMAP_X_REJ_RANGE 4          /* u32 ENGINE_ERANGE (2) */
#define MBMAP_X_REJ_BACKWARDS 6      /* u32 ENGINE_EBACKWARDS (3) */
#define MBMAP_X_REJ_SAMETIME 8       /* u32 ENGINE_ESAMETIME (4) */
#define MBMAP_X_REJ_SPEED 10         /* u32 ENGINE_ESPEED (5) */
#define MBMAP_X_REJ_NUMERIC 20       /* u32 ENGINE_ENUMERIC (10) */
#define MBMAP_X_REJ_ACCEL 22         /* u32 ENGINE_EACCEL (11) */
#define MBMAP_X_REJ_UNCONFIRMED 24   /* u32 ENGINE_EUNCONFIRMED (12) */
#define MBMAP_X_REJ_STALE 26         /* u32 ENGINE_ESTALE (13) */
#define MBMAP_X_AXIS_LOST_S 40       /* f64 time lost to the per-axis limits, s (engine_status_t axis_lost_s) */
#define MBMAP_X_AXIS_SLOWED 44       /* u32 segments the per-axis limits slow */
#define MBMAP_X_TRANSFERS_MOVING 46  /* u32 re-anchors joined moving (engine_status_t transfers_moving) */
#define MBMAP_X_DELAY_GROWN 48       /* u32 times D grew with the input's intervals or top speed (delay_grown) */
#define MBMAP_X_AXIS_LAG_STOPS 70    /* u32 stops because the per-axis limits' lag passed max_lag_s */
#define MBMAP_X_AXIS_BEYOND 72       /* u32 stops before a segment the per-axis limits cannot follow */
#define MBMAP_X_RESERVE_SLOWED 74    /* u32 slowdowns short of D's stop reserve, input on time */
#define MBMAP_X_LIMITS_LOST_S 76     /* f64 time lost to the object's own speed/acceleration limits, s (limits_lost_s) */
#define MBMAP_X_LIMITS_SLOWED 80     /* u32 segments those limits slow (limits_slowed) */
#define MBMAP_X_RESYNCS 82           /* u32 its CAN sender restarted its numbering, followed (canproto resyncs) */
#define MBMAP_X_DELAY_S 84           /* f64 the play-out delay D its output holds, s (obj_delay_s) */
#define MBMAP_X_DROPPED 88           /* u32 waypoints accepted that a stop or clear dropped unplayed (engine_status_t dropped) */
#define MBMAP_X_UNJUDGED 90          /* u32 waypoints taken and dropped before their verdict (engine_status_t unjudged) */
#define MBMAP_X_HEADING 50           /* f64 heading axis, degrees in (-180, 180] (NaN: none) */
#define MBMAP_X_HEADING_UNWRAPPED 54 /* f64 the same, continuous (no jump at +-180): for a rotary axis */
#define MBMAP_X_TX_CLAMPED 58       /* u32 setpoints sent on CAN with a value clipped to its field (speed beyond the SETPOINT frame's +-32.767 m/s ...) */
#define MBMAP_X_MB_WORST_ADDR 62     /* u16 x8 the daemon's worst Modbus client (mb_worst_*): its address as 8 groups of 16 bits in IPv6 text order (RFC 4291 2.2), an IPv4 client as ::ffff:a.b.c.d (2.5.5.2); all 0: none; the same in every diagnostics block */
#define MBMAP_X_MB_WORST_ADDR_GROUPS 8
#define MBMAP_X_GEN_TAIL 98          /* u32 copy of GEN */

/* ---- object block, holding registers (offset from MBMAP_OBJ_BASE(k)) ---- */
#define MBMAP_H_COMMAND 0            /* u16 write MBMAP_CMD_* (FC 06 or FC 16 of 1) */
#define MBMAP_H_OVERRIDE 1           /* u16 feed override, % (0 .. MBMAP_OVERRIDE_MAX_PCT) */
#define MBMAP_OVERRIDE_MAX_PCT 200
#define MBMAP_H_WP 10                /* first register of the waypoint block */
#define MBMAP_H_WP_SEQ 10            /* u32 sequence number */
#define MBMAP_H_WP_T_S 12            /* f64 time, s */
#define MBMAP_H_WP_POS 16            /* f64 x3 x, y, z, m */
#define MBMAP_H_WP_COUNT 18          /* the block is written whole, by one FC 16 */
/* The same waypoint in float32 (for PLCs without float64), written whole by
 * one FC 16: 24 significant bits, so a time of t s is kept to t * 2^-24 (6 us
 * at 100 s, 0.5 ms at 8 000 s: relative times only) and a coordinate of x m to
 * x * 2^-24 (60 um at 1 km). */
#define MBMAP_H_WPF 30               /* first register of the float32 waypoint block */
#define MBMAP_H_WPF_SEQ 30           /* u32 sequence number */
#define MBMAP_H_WPF_T_S 32           /* f32 time, s */
#define MBMAP_H_WPF_POS 34           /* f32 x3 x, y, z, m */
#define MBMAP_H_WPF_COUNT 10
/* A waypoint with the source's velocity (issue 31: the local methods pass
 * through it at that velocity), float64, written whole by one FC 16. */
#define MBMAP_H_WPV 40               /* first register of the waypoint-with-velocity block */
#define MBMAP_H_WPV_SEQ 40           /* u32 sequence number */
#define MBMAP_H_WPV_T_S 42           /* f64 time, s */
#define MBMAP_H_WPV_POS 46           /* f64 x3 x, y, z, m */
#define MBMAP_H_WPV_VEL 58           /* f64 x3 vx, vy, vz, m/s */
#define MBMAP_H_WPV_COUNT 30

/* Commands (holding register MBMAP_H_COMMAND). */
#define MBMAP_CMD_START 1            /* release a stop's latch and join the live track by a
                                        transfer; waiting: start with what is buffered */
#define MBMAP_CMD_STOP 2             /* stop now along the path, latched until START or CLEAR */
#define MBMAP_CMD_CLEAR 3            /* stop along the path, drop, WAITING (engine_clear) */
#define MBMAP_CMD_RESET_COUNTERS 4   /* engine_reset_counters + Modbus counters */
#define MBMAP_CMD_FINISH 5           /* end of input: run to the last waypoint (engine_finish) */

/* The state register while the object is held (a safety fault, a drive
 * fault or lost, a feed hold until clear): whatever its engine does under it. */
#define MBMAP_STATE_HELD 4
#define MBMAP_STATE_STOPPED 5 /* a stop latched until start or clear (braking, then at rest) */

/* Health bits (MBMAP_O_HEALTH): one per condition an HMI alarms on. */
#define MBMAP_HEALTH_SAFETY 0x01     /* the safety monitor holds the object (flag ENGINE_SP_FAULT) */
#define MBMAP_HEALTH_DRIVE 0x02      /* a CiA 402 drive faulted, quick-stopped, lost its heartbeat or is held */
#define MBMAP_HEALTH_OUTPUT 0x04     /* an output of the object failed to write (lines lost) */
#define MBMAP_HEALTH_UNDERRUN 0x08   /* underrun: waypoints late, the output slows or holds */
#define MBMAP_HEALTH_STALE 0x10      /* stale input: on the clock, the data age exceeds D + 1 s */
#define MBMAP_HEALTH_CLOCK 0x20      /* on the clock, and the system clock is not synchronised */
#define MBMAP_HEALTH_HELD 0x40       /* feed hold until clear (a drive's heartbeat lost) */

/* CAN bus state (MBMAP_D_CAN_STATE, MBMAP_O_CAN_STATE). */
#define MBMAP_CAN_NONE 0             /* no CAN on this object / daemon */
#define MBMAP_CAN_ACTIVE 1           /* error-active */
#define MBMAP_CAN_WARNING 2
#define MBMAP_CAN_PASSIVE 3
#define MBMAP_CAN_BUS_OFF 4
#define MBMAP_CAN_DOWN 5             /* interface down */

/*
 * Errors.  The values are the Modbus exception codes to answer, so that
 * -err is what goes on the wire.
 */
enum mbmap_error {
    MBMAP_OK = 0,
    MBMAP_EFUNCTION = 1,  /* illegal function: not served, or writes disabled */
    MBMAP_EADDRESS = 2,   /* illegal data address: outside the map or a partial block */
    MBMAP_EVALUE = 3,     /* illegal data value: bad count/length, NaN, unknown command,
                             waypoint refused by the engine */
    MBMAP_EBUSY = 6,      /* server busy: waypoint buffer full, retry later */
};

/* Text for an mbmap_error (positive or negated). */
const char *mbmap_strerror(int err);

/* ---- snapshot --------------------------------------------------------- */

typedef struct {
    uint32_t generation;
    uint16_t objects;
    uint16_t writes_enabled;
    uint64_t uptime_s;
    uint32_t period_us;
    uint32_t late_p50_us, late_p99_us, late_max_us;
    uint64_t missed_ticks;
    uint16_t can_state, can_load_permille;
    uint64_t mb_requests, mb_exceptions, mb_refused;
    uint16_t mb_clients;
    uint64_t mb_evicted, mb_slow;
    uint64_t out_lost;
    uint16_t out_fault;
    uint64_t log_dropped;
    uint64_t mb_connections, mb_dropped;
    uint16_t mb_peers, mb_worst_family;
    uint32_t mb_worst_ipv4;
    uint16_t mb_worst_addr[MBMAP_X_MB_WORST_ADDR_GROUPS]; /* in the diagnostics blocks */
    uint64_t mb_worst_requests, mb_worst_exceptions, mb_worst_drops;
    uint64_t can_err_frames, can_warnings, can_passives, can_bus_offs, can_restarts;
    uint64_t can_bus_errors, can_overflows;
    uint64_t can_rx_dropped;
    uint16_t can_tx_err, can_rx_err;
    uint64_t drive_emcy, drive_sdo_aborts, drive_hb_lost;
    uint32_t drive_last_abort;
    double clock_drift_ppm, clock_delay_s;
    uint16_t clock_mode, clock_objects;
} mbmap_daemon_t;

typedef struct {
    engine_setpoint_t sp;       /* the setpoint of this tick */
    engine_status_t st;         /* the engine's status after this tick */
    uint64_t lost;
    uint64_t mb_rejected;
    uint32_t late_p99_us, late_max_us;
    uint16_t can_state, can_load_permille;
    uint64_t uptime_s;
    uint64_t out_lost;          /* lines lost by this object's outputs */
    uint16_t out_fault;
    uint64_t seq_jumps;
    int absent;                 /* no object has this id: the block stays all 0 (GEN 0) */
    /* CiA 402 drives (STATUS2 page 4 on CAN); states 0x0FFF, nmt 0xFF without drives */
    uint16_t drive_states, drive_statusword, drive_nmt, drive_emcy;
    uint16_t clocked;           /* on the daemon's clock (the age is sp.age_s) */
    double delay_s;             /* the play-out delay D of a clocked object (stale: age > D + 1 s) */
    uint16_t clock_unsync;      /* the system clock is not synchronised (adjtimex TIME_ERROR) */
    uint16_t held;              /* feed hold until clear */
    uint16_t fault_held;        /* the lifecycle holds it for a fault (monitor, drive) until clear */
    uint16_t latched;           /* a stop latched until start or clear (lifecycle stopping/stopped) */
    double lat_deg, lon_deg, alt_m; /* the setpoint as WGS84 geodetic (NaN: none) */
    double heading_deg, heading_unwrapped_deg; /* heading axis (NaN: none) */
    uint64_t tx_clamped;        /* CAN setpoints with a value clipped to its field */
    uint64_t resyncs;           /* its CAN sender restarted its numbering, followed */
    double play_delay_s;        /* the play-out delay D its output holds (NaN: none yet) */
    uint16_t mb_worst_addr[MBMAP_X_MB_WORST_ADDR_GROUPS]; /* daemon-wide (mbmap_daemon_t's) */
} mbmap_object_t;

/* The health bits of object o (MBMAP_HEALTH_*). */
uint16_t mbmap_health(const mbmap_object_t *o);

/* Write the daemon block into regs[0 .. MBMAP_BLOCK-1]. */
void mbmap_encode_daemon(uint16_t *regs, const mbmap_daemon_t *d);

/*
 * Write object k's block into regs (the whole input table, MBMAP_REGS(n)
 * registers), stamped with generation gen.  Returns 0, or -MBMAP_EADDRESS if
 * k >= MBMAP_MAX_OBJECTS (nothing written).
 */
int mbmap_encode_object(uint16_t *regs, unsigned k, uint32_t gen, const mbmap_object_t *o);

/*
 * Word order of the values of more than one register ([modbus] word_order).
 * The letters name the bytes of a 32-bit value, A most significant, in the
 * order they go on the wire: ABCD big-endian words (the default), CDAB words
 * swapped, BADC bytes swapped in each word, DCBA both.  A 64-bit value
 * follows the same rule over its 8 bytes: CDAB and DCBA reverse its 4 words
 * (pymodbus wordorder=Endian.Little), BADC and DCBA swap the bytes of each
 * word (byteorder=Endian.Little).  Both operations are their own inverse.
 */
typedef enum { MBMAP_ORDER_ABCD = 0, MBMAP_ORDER_CDAB = 1, MBMAP_ORDER_BADC = 2, MBMAP_ORDER_DCBA = 3 } mbmap_order_t;

/* "ABCD", "CDAB", "BADC", "DCBA" (case-insensitive) -> the order, else -1. */
int mbmap_order_parse(const char *s);
const char *mbmap_order_name(mbmap_order_t o);
/* Reorder one value of count registers (2 or 4) from ABCD to o, or back. */
void mbmap_order_value(uint16_t *r, unsigned count, mbmap_order_t o);
/* Reorder every u32/f32/f64 field of an input table for n objects (the
 * daemon block and the object blocks, from mbmap_fields()), ABCD -> o. */
void mbmap_order_image(uint16_t *regs, unsigned n, mbmap_order_t o);
/* The same for the n diagnostics blocks of a table of MBMAP_TABLE_REGS(n). */
void mbmap_order_diag(uint16_t *regs, unsigned n, mbmap_order_t o);

/*
 * Write object k's diagnostics block into regs (the whole input table,
 * MBMAP_TABLE_REGS(n) registers), stamped with generation gen.  Returns 0,
 * or -MBMAP_EADDRESS if k >= MBMAP_MAX_OBJECTS (nothing written).
 */
int mbmap_encode_diag(uint16_t *regs, unsigned k, uint32_t gen, const mbmap_object_t *o);

/* Word helpers (ABCD).  Exposed for the tests and the daemon. */
void mbmap_put_u32(uint16_t *r, uint32_t v);
void mbmap_put_f32(uint16_t *r, float v);
void mbmap_put_f64(uint16_t *r, double v);
uint32_t mbmap_get_u32(const uint16_t *r);
float mbmap_get_f32(const uint16_t *r);
double mbmap_get_f64(const uint16_t *r);

/* ---- requests ------------------------------------------------------------ */

/*
 * Check a request PDU (function code + data, no MBAP/address/CRC) against the
 * map for n objects, in the order the standard gives (function, then count
 * and length, then address).  writes_enabled 0 refuses FC 06 and 16.
 * Returns 0 if the request may be answered (reads: by modbus_reply on the
 * mapping; writes: after mbmap_decode_write_order), or -MBMAP_EFUNCTION,
 * -MBMAP_EVALUE (count 0 or above the limit, byte count or PDU length
 * inconsistent), -MBMAP_EADDRESS (range outside the table).
 * A PDU shorter than 1 byte returns -MBMAP_EVALUE.
 */
int mbmap_check_request(unsigned n, int writes_enabled, const uint8_t *pdu, size_t len);

typedef enum { MBMAP_WRITE_COMMAND = 1, MBMAP_WRITE_WAYPOINT = 2, MBMAP_WRITE_OVERRIDE = 3 } mbmap_write_kind_t;
/* (a float32 waypoint block decodes to MBMAP_WRITE_WAYPOINT like the float64 one) */

typedef struct {
    mbmap_write_kind_t kind;
    unsigned object;            /* 0-based */
    unsigned command;           /* MBMAP_CMD_*, for MBMAP_WRITE_COMMAND */
    unsigned override_pct;      /* for MBMAP_WRITE_OVERRIDE: 0 .. MBMAP_OVERRIDE_MAX_PCT */
    engine_waypoint_t wp;       /* for MBMAP_WRITE_WAYPOINT */
} mbmap_write_t;

/*
 * Decode a write PDU that passed mbmap_check_request (FC 06 or 16) into one
 * command, one feed override or one waypoint.  Writable: MBMAP_H_COMMAND and
 * MBMAP_H_OVERRIDE of an object (one register each; an override above
 * MBMAP_OVERRIDE_MAX_PCT is -MBMAP_EVALUE) and the waypoint block of an object (exactly MBMAP_H_WP ..
 * +MBMAP_H_WP_COUNT-1 in one FC 16, so it is applied whole or not at all).
 * Returns 0, -MBMAP_EADDRESS (anything else, including a part of the
 * waypoint block or a write spanning two fields), -MBMAP_EVALUE (unknown
 * command; NaN or infinite time, coordinate or velocity: then out->kind is
 * MBMAP_WRITE_WAYPOINT and out->wp holds every field as written, the only
 * refusal that leaves a waypoint decoded), -MBMAP_EFUNCTION (not a
 * write).  Time order and ranges are the engine's to check (engine_push).
 * o: the word order the client writes u32/f32/f64 values in (ABCD: as the map).
 */
int mbmap_decode_write_order(unsigned n, mbmap_order_t o, const uint8_t *pdu, size_t len,
                             mbmap_write_t *out);

/* The exception for an engine_push / command result (negated engine_error):
 * ENGINE_EFULL -> -MBMAP_EBUSY, any other error -> -MBMAP_EVALUE, 0 and
 * ENGINE_DUPLICATE -> 0. */
int mbmap_from_engine(int engine_result);

/* ---- RTU framing ------------------------------------------------------- */

/* CRC-16/MODBUS (poly 0xA001 reflected, init 0xFFFF) of buf. */
uint16_t mbmap_crc16(const uint8_t *buf, size_t len);

/*
 * Length of the RTU request frame at the start of buf (address, PDU, CRC),
 * from its function code: > 0 the frame length (may exceed len: wait for
 * more), 0 not enough bytes yet to tell, -1 a function code whose request
 * length cannot be known from its header (the caller delimits it by line
 * silence instead).
 */
int mbmap_rtu_frame_len(const uint8_t *buf, size_t len);

/* ---- documentation ------------------------------------------------------ */

typedef enum { MBMAP_T_U16 = 1, MBMAP_T_U32 = 2, MBMAP_T_F32 = 3, MBMAP_T_F64 = 4 } mbmap_type_t;

typedef struct {
    const char *table;      /* "input daemon", "input object", "holding object" */
    uint16_t offset;        /* absolute for the daemon block, else from MBMAP_OBJ_BASE(k) */
    uint16_t count;         /* registers */
    mbmap_type_t type;
    const char *name;
    const char *unit;
    const char *doc;
} mbmap_field_t;

/* The map as a table (for config/PROTOCOL.md and the tests); *n receives its length. */
const mbmap_field_t *mbmap_fields(size_t *n);

/* Name of a type: "u16", "u32", "f32", "f64". */
const char *mbmap_type_name(mbmap_type_t t);

/* clang-format on */
#endif
