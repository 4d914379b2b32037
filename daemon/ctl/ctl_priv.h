/*
 * ctl_priv.h - the control socket's insides, shared by ctl.c (socket,
 * clients, I/O) and ctl_cmd.c (requests, replies, the command gate).
 */
#ifndef TRAJD_CTL_PRIV_H
#define TRAJD_CTL_PRIV_H

#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "acceptguard.h"
#include "ctl.h"

#define CTL_IN_BYTES 1024   /* a request line, with its '\n', at most */
#define CTL_OUT_BYTES 65536 /* replies queued per client */
#define CTL_REPLY_MAX 4096  /* room one reply line needs (a status line of one object) */
#define CTL_PEER_MAX 64

/* A text buffer (JSON lines are built in it): over is set once something did not fit. */
typedef struct {
    char *b;
    size_t len, cap;
    int over;
} ctl_sb_t;

void ctl_sb_printf(ctl_sb_t *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A JSON string, quoted and escaped. */
void ctl_sb_str(ctl_sb_t *s, const char *str);

/* One setpoint in a subscriber's ring. */
typedef struct {
    engine_setpoint_t sp;
    int64_t period_ns;    /* of the core that made it: tick = now_ns / period_ns */
    uint64_t lost_before; /* setpoints dropped just before this one (ring full) */
} ctl_sp_t;

typedef struct {
    struct ctl *owner;
    int fd; /* -1: free slot */
    uint64_t id;
    pid_t pid;
    uid_t uid;
    gid_t gid;
    char peer[CTL_PEER_MAX]; /* "pid P uid U gid G" */
    char in[CTL_IN_BYTES];
    size_t inlen;
    char *out; /* CTL_OUT_BYTES */
    size_t outlen, outoff;
    uint32_t events; /* what the loop watches */
    int closing;     /* close once out is written */
    int eof;         /* the peer shut its side: no more requests (a watcher watches on) */
    int status_next; /* a status reply under way: next object index, else -1 */
    /* subscription: object index in the running core, or -1 */
    int sub_obj;
    char sub_name[CFG_NAME_MAX];
    ctl_sp_t *ring; /* CTL_RING entries while subscribed */
    uint32_t head, tail;
    uint64_t pending_lost; /* dropped since the last one queued */
    uint64_t sent, lost, lost_logged;
} ctl_client_t;

struct ctl {
    loop_t *loop;
    core_t *core;
    const cfg_t *cfg;
    int fd;
    char path[108];
    dev_t dev;
    ino_t ino;
    ctl_reload_fn reload;
    void *reload_ctx;
    ctl_client_t cl[CTL_CLIENTS_MAX];
    uint64_t next_id;
    uint64_t reload_waiter; /* the client whose reload is being read (0: none) */
    int flush_fd;           /* the CTL_FLUSH_NS timer while someone watches, else -1 */
    unsigned watchers;
    uint64_t busy_refused;
    uint64_t watch_lost; /* setpoints dropped from watchers' full rings, since start */
    acceptguard_t ag;    /* out of fds: clients told why, the listener paused */
};

/* Handle one request line (no '\n'): replies are appended to cl->out. */
void ctl_request(ctl_t *t, ctl_client_t *cl, char *line);

/* Append status lines while room remains (cl->status_next advances). */
void ctl_status_more(ctl_t *t, ctl_client_t *cl);

/* Append setpoint lines from the ring while room remains. */
void ctl_sub_more(ctl_t *t, ctl_client_t *cl);

/* Send what cl->out holds (a reply made outside a request: ctl_reload_done),
 * then watch for what comes next; cl may be closed (fd -1) after it. */
void ctl_client_pump(ctl_t *t, ctl_client_t *cl);

/* Room left in cl->out for appending. */
ctl_sb_t ctl_out_sb(ctl_client_t *cl);
/* Keep what was appended through sb (unless it overflowed: then nothing). */
int ctl_out_commit(ctl_client_t *cl, const ctl_sb_t *sb);

/* Start a subscription (allocation and the flush timer; ctl.c ends it). */
int ctl_sub_start(ctl_t *t, ctl_client_t *cl, int obj_index, const char *name);

#endif
