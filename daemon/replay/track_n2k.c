/* track_n2k.c - NMEA 2000 positions from a candump log (PGN 129025 Position
 * Rapid Update, PGN 129029 GNSS Position Data over fast packets; decoders in
 * lib/proto/nmea2000.h), each with the velocity of the PGN 129026 COG & SOG
 * of its own epoch where there is one (issue 31): for 129029 the same source
 * and SID within N2K_EPOCH_US of log time, for 129025 (no SID) the same
 * source within N2K_SAME_STAMP_US; COG true only.  See track.h. */
#include "track_loader.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "candump.h"
#include "geo.h"
#include "nmea2000.h"

/* 129026 of a 129029's epoch: its SID within this much log time (SIDs wrap
 * at 252, and an epoch's messages go out within a period) */
#define N2K_EPOCH_US 1000000
/* 129026 of a 129025's epoch (no SID): logged at the same time, to this */
#define N2K_SAME_STAMP_US 1000

/* One PGN 129026 as read. */
typedef struct {
    int64_t ts_us;
    double cog_deg, sog_m_s;
    uint8_t src, sid;
} cogsog_t;

/* One position as read, of any stream. */
typedef struct {
    int64_t sec; /* whole seconds (log stamp, or 129029 date and time) */
    double frac; /* and the fraction, kept apart so differences are exact */
    double lat, lon, alt;
    uint32_t line;
    uint32_t pgn;
    uint8_t src;
    uint8_t sid;   /* 129029's */
    int64_t ts_us; /* log time */
} fix_t;

typedef struct {
    track_loader_t *L;
    n2k_fast_t *fast[256]; /* one 129029 message in progress per source, made on its first frame */
    uint8_t fast_src[256]; /* the sources that have one, nfast of them */
    int nfast;
    fix_t *fix;
    size_t n, cap;
    cogsog_t *cs; /* the 129026 messages with COG true, in log order */
    size_t ncs, capcs;
    size_t frames; /* candump frames read */
} n2k_t;

static int add_cogsog(n2k_t *N, const cogsog_t *c)
{
    if (N->ncs == N->capcs) {
        size_t cap = N->capcs ? 2 * N->capcs : 256;
        cogsog_t *nc = realloc(N->cs, cap * sizeof *nc);
        if (!nc) {
            track_loader_fatal(N->L, 0, "out of memory");
            return -1;
        }
        N->cs = nc;
        N->capcs = cap;
    }
    N->cs[N->ncs++] = *c;
    return 0;
}

static int add_fix(n2k_t *N, const fix_t *f)
{
    if (N->n == N->cap) {
        size_t cap = N->cap ? 2 * N->cap : 256;
        fix_t *nf = realloc(N->fix, cap * sizeof *nf);
        if (!nf) {
            track_loader_fatal(N->L, 0, "out of memory");
            return -1;
        }
        N->fix = nf;
        N->cap = cap;
    }
    N->fix[N->n++] = *f;
    return 0;
}

/* A decoded position of a frame at log time ts_us.  Returns 0 or -1. */
static int position(n2k_t *N, int rc, const n2k_position_t *p, const n2k_id_t *id, int64_t ts_us,
                    unsigned long lineno)
{
    if (rc == 0 && geo_check(p->lat_deg, p->lon_deg, isnan(p->alt_m) ? 0.0 : p->alt_m))
        rc = -N2K_ERANGE;
    if (rc < 0 || (id->pgn == N2K_PGN_GNSS_POSITION && !p->has_time)) {
        N->L->ignored++; /* a record without a usable fix: not a bad line */
        return 0;
    }
    fix_t f = {.lat = p->lat_deg,
               .lon = p->lon_deg,
               .alt = p->alt_m,
               .pgn = id->pgn,
               .src = id->source,
               .sid = p->sid,
               .ts_us = ts_us,
               .line = lineno > UINT32_MAX ? UINT32_MAX : (uint32_t)lineno};
    if (id->pgn == N2K_PGN_GNSS_POSITION) {
        double whole = floor(p->tod_s);
        f.sec = p->days * 86400 + (int64_t)whole;
        f.frac = p->tod_s - whole;
    } else {
        f.sec = ts_us / 1000000;
        f.frac = (double)(ts_us % 1000000) * 1e-6;
    }
    return add_fix(N, &f);
}

static int frame(n2k_t *N, const candump_line_t *cl, unsigned long lineno)
{
    const canproto_frame_t *fr = &cl->frame;
    n2k_id_t id;
    n2k_position_t p;
    N->frames++;
    if (!(fr->flags & CANPROTO_F_EFF) || (fr->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR)))
        return 0; /* NMEA 2000 uses 29-bit data frames only */
    n2k_id_decode(fr->id, &id);
    if (id.pgn == N2K_PGN_POSITION_RAPID)
        return position(N, n2k_decode_position_rapid(fr->data, fr->len, &p), &p, &id, cl->ts_us,
                        lineno);
    if (id.pgn == N2K_PGN_COG_SOG_RAPID) {
        n2k_cog_sog_t v;
        if (n2k_decode_cog_sog(fr->data, fr->len, &v) < 0 || v.ref != 0)
            return 0; /* not available, or magnetic: no velocity from it */
        cogsog_t c = {.ts_us = cl->ts_us,
                      .cog_deg = v.cog_deg,
                      .sog_m_s = v.sog_m_s,
                      .src = id.source,
                      .sid = v.sid};
        return add_cogsog(N, &c);
    }
    if (id.pgn != N2K_PGN_GNSS_POSITION)
        return 0;
    n2k_fast_t *f = N->fast[id.source];
    if (!f) {
        if (!(f = N->fast[id.source] = calloc(1, sizeof *f))) {
            track_loader_fatal(N->L, 0, "out of memory");
            return -1;
        }
        N->fast_src[N->nfast++] = id.source;
    }
    int rc = n2k_fast_push(f, fr->data, fr->len);
    if (rc < 0) {
        N->L->ignored++; /* a message lost to a missing frame */
        return 0;
    }
    if (rc == 0)
        return 0;
    return position(N, n2k_decode_gnss_position(f->data, f->len, &p), &p, &id, cl->ts_us, lineno);
}

/* The stream kept: 129029 if any (fix time, 1e-16 deg, altitude), else
 * 129025; of that PGN the source with the most fixes (the first seen on a
 * tie).  Streams are counted in a short list: a log has a few sources. */
static void choose(const n2k_t *N, uint32_t *pgn, int *src)
{
    struct {
        uint32_t pgn;
        uint8_t src;
        size_t n;
    } st[512];
    size_t ns = 0, best = 0;
    for (size_t i = 0; i < N->n; i++) {
        size_t k = 0;
        while (k < ns && (st[k].pgn != N->fix[i].pgn || st[k].src != N->fix[i].src))
            k++;
        if (k == ns) { /* at most 2 PGNs x 256 sources: always fits */
            st[k].pgn = N->fix[i].pgn;
            st[k].src = N->fix[i].src;
            st[k].n = 0;
            ns++;
        }
        st[k].n++;
    }
    *src = -1;
    *pgn = N2K_PGN_POSITION_RAPID;
    for (size_t k = 0; k < ns; k++) {
        int gnss = st[k].pgn == N2K_PGN_GNSS_POSITION, had_gnss = *pgn == N2K_PGN_GNSS_POSITION;
        if (*src < 0 || (gnss && !had_gnss) || (gnss == had_gnss && st[k].n > best)) {
            *pgn = st[k].pgn;
            *src = st[k].src;
            best = st[k].n;
        }
    }
}

/* The 129026 of fix f's epoch (see the top), NULL if none; *j: where the
 * search of the next fix (later in the log) may start. */
static const cogsog_t *epoch_velocity(const n2k_t *N, const fix_t *f, size_t *j)
{
    int64_t win = f->pgn == N2K_PGN_GNSS_POSITION ? N2K_EPOCH_US : N2K_SAME_STAMP_US;
    const cogsog_t *best = NULL;
    while (*j < N->ncs && N->cs[*j].ts_us < f->ts_us - N2K_EPOCH_US)
        (*j)++;
    for (size_t k = *j; k < N->ncs && N->cs[k].ts_us <= f->ts_us + win; k++) {
        const cogsog_t *c = &N->cs[k];
        int64_t d = c->ts_us > f->ts_us ? c->ts_us - f->ts_us : f->ts_us - c->ts_us;
        if (c->src != f->src || d > win || (f->pgn == N2K_PGN_GNSS_POSITION && c->sid != f->sid))
            continue;
        if (!best || d < (best->ts_us > f->ts_us ? best->ts_us - f->ts_us : f->ts_us - best->ts_us))
            best = c;
    }
    return best;
}

static int rows(n2k_t *N)
{
    uint32_t pgn;
    int src;
    size_t j = 0;
    choose(N, &pgn, &src);
    const fix_t *f0 = NULL;
    for (size_t i = 0; i < N->n; i++) {
        const fix_t *f = &N->fix[i];
        if (f->pgn != pgn || f->src != src) {
            N->L->ignored++; /* another source or the other PGN */
            continue;
        }
        if (!f0)
            f0 = f;
        double t = (double)(f->sec - f0->sec) + (f->frac - f0->frac);
        if (track_loader_add_row(N->L, t, f->lat, f->lon, f->alt, f->line))
            return -1;
        const cogsog_t *v = epoch_velocity(N, f, &j);
        if (v)
            track_loader_course_speed(N->L, v->cog_deg, v->sog_m_s);
    }
    return 0;
}

int track_n2k_parse(track_loader_t *L, const char *buf, size_t len)
{
    n2k_t N = {.L = L};
    track_lines_t *it = malloc(sizeof *it);
    int rc = -1, r;
    if (!it) {
        track_loader_fatal(L, 0, "out of memory");
        goto out;
    }
    track_lines_init(it, buf, len);
    while ((r = track_lines_next(L, it)) > 0) {
        candump_line_t cl;
        int prc = candump_parse_line(it->line, &cl);
        if (prc == -CANDUMP_ESKIP)
            continue;
        if (prc < 0) {
            /* (the error's own text is "not a candump frame": not said twice) */
            if (prc == -CANDUMP_ESYNTAX
                    ? track_loader_bad(L, it->lineno,
                                       "not a candump -l frame, \"(SECONDS) IFACE ID#DATA\" (a "
                                       "log without its time stamps, as candump prints by "
                                       "default, cannot be replayed: record it with candump -l)")
                    : track_loader_bad(L, it->lineno, "candump frame: %s", candump_strerror(prc)))
                goto out;
            continue;
        }
        if (frame(&N, &cl, it->lineno) < 0)
            goto out;
    }
    if (r == 0)
        rc = rows(&N);
    if (rc == 0 && L->n == 0) { /* nothing usable: say what the log held */
        track_loader_fatal(L, 0,
                           "no waypoints: no NMEA 2000 position with a usable fix (PGN 129029 or "
                           "129025) among its %zu frames (%zu positions without one, %zu bad "
                           "lines); a log of trajd's own WAYPOINT frames is replayed by trajd "
                           "([can] log_in)",
                           N.frames, L->ignored, L->skipped);
        rc = -1;
    }
out:
    free(it);
    for (int k = 0; k < N.nfast; k++)
        free(N.fast[N.fast_src[k]]);
    free(N.fix);
    free(N.cs);
    return rc;
}

int track_n2k_sniff(const char *buf, size_t len)
{
    /* the first line that is not blank or a comment is a stamped candump frame */
    size_t i = 0;
    while (i < len) {
        size_t e = i;
        while (e < len && buf[e] != '\n')
            e++;
        size_t k = i;
        while (k < e && (buf[k] == ' ' || buf[k] == '\t' || buf[k] == '\r'))
            k++;
        if (k < e && buf[k] != '#') {
            char line[256];
            size_t n = e - k < sizeof line - 1 ? e - k : sizeof line - 1;
            candump_line_t cl;
            memcpy(line, buf + k, n);
            line[n] = '\0';
            return buf[k] == '(' && candump_parse_line(line, &cl) == 0;
        }
        i = e + 1;
    }
    return 0;
}
