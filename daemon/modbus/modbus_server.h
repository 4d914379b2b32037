/*
 * modbus_server.h - trajd's Modbus server (libmodbus), TCP and RTU, inside the
 * daemon's one event loop.  The register map is lib/proto/mbmap.h; the
 * connection policy, RTU framing and counters are config/PROTOCOL.md "Modbus".
 *
 * Loop: the server keeps its sockets, serial port and timers in an epoll set
 * of its own, exposed as ONE descriptor (modbus_server_fd) for EPOLLIN; the
 * daemon calls modbus_server_process() when it is readable, which never
 * blocks and handles at most MODBUS_SERVER_EVENTS_PER_CALL events.
 * Requests: assembled without blocking (framing: modbus_framing.c), checked
 * by mbmap_check_request and mbmap_decode_write_order, answered by libmodbus
 * (modbus_reply / modbus_reply_exception), which is never used to receive.
 * Snapshot: modbus_server_publish() rewrites the input registers once per
 * tick in the same thread, so every request is answered from one tick's image.
 * RTU: a request ends where its function code says, else at
 * MODBUS_SERVER_RTU_SILENCE_MS of line silence; other unit ids and broadcasts
 * are not answered.
 * TCP: a request must be whole within request_timeout_ms of its first byte
 * (slow), an idle client is closed after idle_timeout_ms (dropped); at
 * max_clients a newcomer evicts the stalest client connected for at least
 * MODBUS_SERVER_EVICT_GRACE_MS (evicted), else it is refused; out of file
 * descriptors the listener backs off (modbus_accept.h).  Client notices: at
 * most MODBUS_SERVER_LOG_PER_S lines a second.
 */
#ifndef TRAJD_MBSRV_H
#define TRAJD_MBSRV_H

#include <stddef.h>
#include <stdint.h>
#include "engine.h"
#include "mbmap.h"

#define MODBUS_SERVER_DEFAULT_ADDRESS "127.0.0.1"
#define MODBUS_SERVER_DEFAULT_PORT 1502
#define MODBUS_SERVER_DEFAULT_MAX_CLIENTS 16
#define MODBUS_SERVER_MAX_CLIENTS_LIMIT 1024
#define MODBUS_SERVER_DEFAULT_IDLE_MS 60000
#define MODBUS_SERVER_DEFAULT_REQUEST_MS 2000 /* a whole request, from its first byte */
#define MODBUS_SERVER_EVICT_GRACE_MS 250      /* a client this new is never evicted */
#define MODBUS_SERVER_LOG_PER_S 5             /* client messages per second at most */
#define MODBUS_SERVER_EVENTS_PER_CALL 8
#define MODBUS_SERVER_RTU_SILENCE_MS 20
#define MODBUS_SERVER_ALLOW_MAX 32        /* entries in the allow-list */
#define MODBUS_SERVER_HOUSEKEEPING_MS 100 /* idle-timeout resolution */
/* Client addresses (host, without the port) whose counters are kept across
 * their connections: the least recently seen is forgotten for a new one. */
#define MODBUS_SERVER_PEERS 32
#define MODBUS_SERVER_DEFAULT_PEER_LOG_S 60 /* per-client summary lines, at most this often */
/* Largest forward step of a waypoint sequence number counted as lost
 * waypoints; a bigger one is a jump (see modbus_server_publish). */
#define MODBUS_SERVER_SEQ_WINDOW 65536u

typedef struct {
    int enabled; /* [modbus] enabled: the daemon starts a server only if 1 */
    /* TCP: tcp_address "" disables TCP.  tcp_port 0 picks a free
     * port (read it back with modbus_server_tcp_port; used by the tests). */
    char tcp_address[64];
    int tcp_port;
    /* 1: if systemd passed a listening stream socket (sd_listen_fds), use the
     * first one instead of binding (so port 502 needs no privilege). */
    int systemd_socket;
    /* RTU: rtu_device "" disables RTU. */
    char rtu_device[256];
    int rtu_baud;
    char rtu_parity; /* 'N', 'E', 'O' */
    int rtu_data_bits;
    int rtu_stop_bits;
    int unit_id;        /* RTU slave address 1..247 (TCP answers any) */
    int writes_enabled; /* 0: FC 06/16 answered with exception 01 */
    /* Comma- or space-separated CIDR list ("127.0.0.1/32, ::1, 10.0.0.0/8");
     * "" allows every client. */
    char allow[512];
    /* Clients that may write when writes_enabled (same syntax); "" = every
     * allowed client.  Others get exception 01 for FC 06/16, as with writes
     * off.  RTU has no address: writes_enabled alone decides there. */
    char write_allow[512];
    unsigned max_clients;        /* TCP clients at once; a newcomer evicts one (policy above) */
    unsigned idle_timeout_ms;    /* close a TCP client silent this long (0 = never) */
    unsigned request_timeout_ms; /* close a TCP client whose request is not whole this long
                                  * after its first byte */
    unsigned peer_log_s;         /* a notice line per client address that had exceptions or
                                  * drops, at most every this many seconds (0 = none) */
    unsigned n_objects;          /* 1..MBMAP_MAX_OBJECTS */
    int word_order;              /* mbmap_order_t of u32/f32/f64 values (ABCD default) */
} modbus_server_config_t;

/*
 * What a write does: the daemon applies it to the object's engine.
 * waypoint: engine_push semantics, returns 0, ENGINE_DUPLICATE or a negated
 * engine_error.  command: MBMAP_CMD_*, returns 0 or a negated engine_error.
 * Either may return MODBUS_SERVER_HOOK_EADDRESS: not writable for this object
 * (answered with exception 02).  A NULL hook refuses the write with 03.
 */
#define MODBUS_SERVER_HOOK_EADDRESS (-1000)
typedef struct {
    int (*waypoint)(void *ctx, unsigned object, const engine_waypoint_t *wp);
    int (*command)(void *ctx, unsigned object, unsigned command);
    void *ctx;
    /* A feed override (percent, 0 .. MBMAP_OVERRIDE_MAX_PCT) was written;
     * NULL: refused with 03.  Returns 0 or a negated engine_error. */
    int (*override)(void *ctx, unsigned object, unsigned percent);
    /* A command or override refused for its value (exception 03: an unknown
     * command code, an override above MBMAP_OVERRIDE_MAX_PCT), for the log
     * and the object's refused commands; NULL: only counted (mb_rejected). */
    void (*refused)(void *ctx, unsigned object, const mbmap_write_t *w);
} modbus_server_hooks_t;

typedef struct {
    uint64_t requests; /* answered (normal or exception) */
    uint64_t exceptions;
    uint64_t refused;     /* connections refused: allow-list, max_clients or out of fds */
    uint64_t dropped;     /* connections closed for bad framing, idleness, or answers
                                 * not read; and slow ones (also counted in slow) */
    uint64_t slow;        /* closed: a request not whole within request_timeout_ms */
    uint64_t evicted;     /* closed at max_clients to admit a newcomer */
    uint64_t connections; /* TCP connections accepted */
    uint64_t rtu_crc_errors;
    int rtu_down;           /* 1 once the serial line failed (not reopened) */
    unsigned clients;       /* TCP clients connected now */
    uint64_t process_calls; /* modbus_server_process calls that handled events */
    uint64_t
        process_max_ns; /* longest modbus_server_process call: the most a tick can wait on Modbus */
    uint64_t process_total_ns; /* time spent in modbus_server_process, for the mean */
} modbus_server_stats_t;

typedef struct modbus_server modbus_server_t;

/* Defaults: not enabled, 127.0.0.1:1502, systemd socket if passed, no RTU
 * (9600 8N1, unit 1 when set), writes off, no allow-list,
 * MODBUS_SERVER_DEFAULT_MAX_CLIENTS, MODBUS_SERVER_DEFAULT_IDLE_MS,
 * MODBUS_SERVER_DEFAULT_REQUEST_MS, 1 object. */
void modbus_server_config_default(modbus_server_config_t *cfg);

/*
 * Set one key of the [modbus] config section (the daemon's ini handler calls
 * this for each key of the section; n_objects is the daemon's to set).
 * Keys: enabled, address, port, systemd_socket, rtu_device, rtu_baud,
 * rtu_parity (N|E|O|none|even|odd), rtu_data_bits, rtu_stop_bits, unit_id,
 * writes, allow, write_allow, max_clients, idle_timeout_ms, request_timeout_ms (100 ..
 * 600000), peer_log_s (0 .. 86400).  Booleans: yes/no/true/false/1/0.
 * Returns 0, -ENOENT for an unknown key, -EINVAL for a bad value (with the
 * reason in err if not NULL).
 */
int modbus_server_config_set(modbus_server_config_t *cfg, const char *key, const char *value,
                             char *err, size_t errlen);

/*
 * Open the listening socket and/or the serial port and allocate everything
 * the server will use (no allocation afterwards).  hooks may be NULL (writes
 * refused).  Returns NULL on failure with a message in err (if not NULL).
 */
modbus_server_t *modbus_server_new(const modbus_server_config_t *cfg,
                                   const modbus_server_hooks_t *hooks, char *err, size_t errlen);

/* Close everything; NULL is a no-op. */
void modbus_server_free(modbus_server_t *s);

/* One object's Modbus counters and sequence numbering (block k), which a
 * reload carries over to the server it opens (modbus_transport.c). */
typedef struct {
    uint64_t mb_rejected, lost, seq_jumps, missing;
    uint32_t last_seq, alt_seq;
} modbus_server_obj_seq_t;
void modbus_server_obj_seq(const modbus_server_t *s, unsigned k, modbus_server_obj_seq_t *out);
void modbus_server_set_obj_seq(modbus_server_t *s, unsigned k, const modbus_server_obj_seq_t *in);

/* The one descriptor to watch for EPOLLIN in the daemon's loop. */
int modbus_server_fd(const modbus_server_t *s);

/* Inside a hook: the peer whose request is being served (TCP "address:port",
 * RTU "rtu DEVICE unit N"); "" outside a request. */
const char *modbus_server_peer(const modbus_server_t *s);

/* The TCP port listened on (after tcp_port 0), or -1 without TCP. */
int modbus_server_tcp_port(const modbus_server_t *s);

/* 1 if the listening socket came from systemd (sd_listen_fds), else 0. */
int modbus_server_tcp_from_systemd(const modbus_server_t *s);

/*
 * Handle what is ready: accept, read, answer, time out idle clients, RTU
 * silence.  Never blocks; at most MODBUS_SERVER_EVENTS_PER_CALL events.  Returns 0,
 * or -errno if the server's own epoll set failed (clients' errors are
 * handled by closing them, never returned).
 */
int modbus_server_process(modbus_server_t *s);

/*
 * Publish a tick's snapshot: generation +1, daemon block and every object's
 * block rewritten.  d and objs[0..n_objects-1] are the daemon's view; the
 * server fills its own fields (Modbus counters, clients, writes_enabled,
 * objects, per-object mb_rejected and lost by sequence gaps of Modbus
 * waypoints, added to objs[k].lost).  No allocation, no system call.
 */
void modbus_server_publish(modbus_server_t *s, const mbmap_daemon_t *d, const mbmap_object_t *objs);

void modbus_server_stats(const modbus_server_t *s, modbus_server_stats_t *st);

/*
 * Parse an allow-list (see modbus_server_config_t.allow) to check it at config load.
 * Returns the number of entries, or -EINVAL with the offending entry in err.
 */
int modbus_server_allow_check(const char *allow, char *err, size_t errlen);

#endif
