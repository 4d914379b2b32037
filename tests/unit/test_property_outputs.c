/*
 * test_property_outputs.c - issues 10 item 6 and 16 item 5: a property over
 * the engine and every output.
 *
 * Random sequences (seeded, reproducible) drive one engine: a sender in real
 * time whose waypoints come late (sent on half of the ticks only) and stalls
 * of up to 6 s, after which it sends what it owes at once; gaps (a new
 * trajectory, reached by a transfer), clear, stop, reload (as
 * daemon/core/core.c does it: a moving old engine brakes to rest, then a new
 * one starts where it rests), outliers (refused), random feed overrides
 * (0 .. 1) and skipped ticks.  Each setpoint then passes the safety monitor
 * with the daemon's default speed bound (it must never have to refuse) and is
 * encoded by every output (own CAN frames classic and FD, CiA 402 RPDO, CSV,
 * Modbus registers) and decoded back here.  Asserted on every tick, with no
 * exemption, dt the time since the previous output:
 *   |delta position| <= speed_limit dt + quantum           (every output)
 *   |delta velocity| <= accel_limit dt                     (the engine's
 *       setpoint; and by finite differences of the decoded positions of the
 *       CSV and CiA 402 outputs, + their quantisation)
 *   (+ 1e-9), no output ever carries a position before one exists, and none
 *   loses it.
 * The limits are the engine's output bounds for this object
 * (lib/engine/TIMESCALE.md, "Bounds on every output"), with a_w =
 * max_accel_m_s2 (the largest implied acceleration the engine accepts), v_w =
 * max_speed_m_s and h the waypoint interval:
 *   speed_limit = 2 v_w (the safety monitor's default)
 *   accel_limit = 3 max(a_w, v_w / h) + scale_accel_m_s2
 * (the curve has |k''| <= 3 a_w inside a trajectory by diagonal dominance,
 * but a REST end, every trajectory's start and end, has |k''| up to 3 v / h
 * there: its end row reads 2 M0 + M1 = 6 v / h);
 * and the jerk limit in the same terms (the curve's |k'''| <= 6 a_w / h
 * inside a trajectory, k''' = delta M / h with |M| <= 3 a_w):
 *   |delta acceleration| <= jerk_limit dt, jerk_limit = 6 a_w / h
 *       + 9 a_w scale_accel_m_s2 / (1 m/s) + max(scale_jerk_m_s3, scale_accel_m_s2 / T)
 *   (the last term the stop's jerk, TIMESCALE.md "Stop distance") on every
 *   output that carries an acceleration (engine, CSV, Modbus, float32
 *   rounding allowed), and |jerk| <= jerk_limit by the third divided
 *   difference of the CSV's exact positions (CAN and CiA 402 carry positions
 *   quantised to 0.1 mm: their third difference is noise at 10 ms).
 * It held only once every transfer and trajectory was entered and left at
 * rate 0 (TIMESCALE.md "Handovers"): before, a transfer handing over to a
 * REST start stepped the acceleration from -6 D / T_x^2 to k''(0) in one
 * tick, up to 8.3 x jerk_limit T here.  PROP_DEBUG=1 prints every tick above
 * a bound, PROP_TRACE=seed PROP_TICK=k the setpoints around one.
 */
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "canproto.h"
#include "csv_format.h"
#include "engine.h"
#include "mbmap.h"
#include "safety.h"

#define T_NS 10000000LL
#define T_S 0.01
#define H_S 0.2 /* waypoint interval */
#define SEEDS 40

enum { OUT_ENGINE, OUT_CAN, OUT_CANFD, OUT_CIA402, OUT_CSV, OUT_MODBUS, OUT_N };
static const char *const out_name[OUT_N] = {"engine", "can", "canfd", "cia402", "csv", "modbus"};
/* position quantum of each output (m): field LSB, float32 at <= 2^12 m */
static const double out_quantum[OUT_N] = {0, 1e-4, 1e-4, 1e-4, 0, 5e-4};

typedef struct {
    int have, vhave, ahave;
    double p[3], v[3], a[3];
    double vdt; /* the span v was measured over (s) */
    int64_t now;
    int nh; /* positions kept for the third divided difference */
    double ht[4], hp[4][3];
} track_t;

typedef struct {
    double v, a, j;   /* worst ratios to the limits (engine) */
    double fd;        /* worst finite-difference |dv| ratio (CSV, CiA 402) */
    double fj;        /* worst |jerk| by third divided differences of CSV positions */
    unsigned over;    /* ticks above a bound (asserted: none) */
    unsigned reloads; /* reloads while moving */
    unsigned ticks;   /* ticks checked */
    unsigned stops;   /* stop/clear commands given while moving */
    unsigned xfers;   /* transfers */
    unsigned scaled;  /* time-scaled ticks */
} worst_t;

/* The three f32 values at object offset off of sp's Modbus block (encoded,
 * read back); 0 if the first is NaN. */
static int modbus_vec(const engine_setpoint_t *sp, int off, double v[3])
{
    static uint16_t regs[MBMAP_REGS(1)];
    mbmap_object_t o;
    memset(&o, 0, sizeof o);
    o.sp = *sp;
    assert_int_equal(mbmap_encode_object(regs, 0, 1, &o), 0);
    for (int x = 0; x < 3; x++)
        v[x] = mbmap_get_f32(regs + MBMAP_OBJ_BASE(0) + off + 2 * x);
    return !isnan(v[0]);
}

/* Decoded position of sp through output k; 0 if the output has no position. */
static int decode_out(int k, const canproto_ids_t *ids, const engine_setpoint_t *sp, double p[3])
{
    canproto_frame_t f[3];
    canproto_setpoint_t d;
    switch (k) {
    case OUT_ENGINE:
        memcpy(p, sp->pos_m, sizeof(double) * 3);
        return !(sp->flags & ENGINE_SP_NO_POSITION);
    case OUT_CAN:
        canproto_encode_setpoint(0x6A0, sp, f);
        for (int a = 0; a < 3; a++) {
            assert_int_equal(canproto_decode_setpoint(&f[a], &d), 0);
            if (d.flags & ENGINE_SP_NO_POSITION)
                return 0;
            p[a] = d.pos_m[a];
        }
        return 1;
    case OUT_CANFD:
        canproto_encode_setpoint_fd(0x6B0, 0, sp, f);
        assert_int_equal(canproto_decode_setpoint(&f[0], &d), 0);
        if (d.flags & ENGINE_SP_NO_POSITION)
            return 0;
        memcpy(p, d.pos_m, sizeof(double) * 3);
        return 1;
    case OUT_CIA402:
        if (sp->flags & ENGINE_SP_NO_POSITION)
            return 0; /* can_port sends no RPDO (test_can_port checks it) */
        for (int a = 0; a < 3; a++) {
            assert_true(canproto_encode_cia402(ids, (unsigned)a, sp->pos_m[a], &f[0]) >= 0);
            int32_t inc = (int32_t)(f[0].data[0] | f[0].data[1] << 8 | f[0].data[2] << 16 |
                                    (uint32_t)f[0].data[3] << 24);
            p[a] = canproto_cia402_pos_m(ids, (unsigned)a, inc);
        }
        return 1;
    case OUT_CSV: {
        char line[CSV_FORMAT_LINE_MAX];
        assert_true(csv_format_format(line, sizeof line, "o", sp) > 0);
        char *q = strchr(strchr(strchr(line, ',') + 1, ',') + 1, ','); /* after object,now,t */
        for (int a = 0; a < 3; a++)
            p[a] = strtod(q + 1, &q);
        return !isnan(p[0]);
    }
    case OUT_MODBUS: return modbus_vec(sp, MBMAP_O_POS, p);
    }
    return 0;
}

/* Decoded acceleration of sp through output k; 0 if the output carries none
 * (CAN and CiA 402 carry positions and velocities only). */
static int decode_acc(int k, const engine_setpoint_t *sp, double a[3])
{
    switch (k) {
    case OUT_ENGINE: memcpy(a, sp->acc_m_s2, sizeof(double) * 3); return 1;
    case OUT_CSV: {
        char line[CSV_FORMAT_LINE_MAX], *q = line;
        assert_true(csv_format_format(line, sizeof line, "o", sp) > 0);
        for (int c = 0; c < 9; c++) /* object,now,t,x,y,z,vx,vy,vz */
            q = strchr(q, ',') + 1;
        for (int x = 0; x < 3; x++) {
            a[x] = strtod(q, &q);
            q++;
        }
        return !isnan(a[0]);
    }
    case OUT_MODBUS: return modbus_vec(sp, MBMAP_O_ACC, a);
    }
    return 0;
}

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

typedef struct {
    double speed, accel, jerk;
} limits_t;

static void limits_of(const engine_config_t *c, limits_t *l)
{
    double aw = c->max_accel_m_s2, as = c->scale_accel_m_s2, vw = c->max_speed_m_s;
    l->speed = 2.0 * vw;
    /* interior: |k''| <= 3 a_w; a REST end (every trajectory's start and end)
     * has |k''| <= 3 v_w / h there (its first row, 2 M0 + M1 = 6 v / h) */
    l->accel = 3.0 * fmax(aw, vw / H_S) + as;
    l->jerk = 6.0 * aw / H_S + 9.0 * aw * as / 1.0 +
              fmax(c->scale_jerk_m_s3, as / ((double)c->period_ns * 1e-9));
}

/* Judge one ratio; count and (PROP_DEBUG) print it when above 1. */
static const char *cause = "";
static void judge(worst_t *w, double *worst, double value, double bound, const char *what,
                  unsigned seed, int k, const char *out, const engine_setpoint_t *sp)
{
    double r = value / bound;
    *worst = fmax(*worst, r);
    if (value > bound + 1e-9) {
        w->over++;
        if (getenv("PROP_DEBUG"))
            print_message("seed %u tick %d %s %s: %.4g x (state %d flags 0x%x) %s\n", seed, k, out,
                          what, r, sp->state, sp->flags, cause);
    }
}

static double norm3(const double *a)
{
    return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

/* The jerk of the CSV's positions (exact doubles), by the third divided
 * difference over the last four ticks (any spacing: skipped ticks): six
 * times it is the jerk somewhere in the window, so it is bounded by the
 * jerk limit wherever the motion has no step of acceleration. */
static void third_difference(worst_t *w, const limits_t *l, track_t *tr, const double *p,
                             const engine_setpoint_t *sp, unsigned seed, int k)
{
    if (tr->nh == 4) {
        memmove(tr->ht, tr->ht + 1, 3 * sizeof tr->ht[0]);
        memmove(tr->hp, tr->hp + 1, 3 * sizeof tr->hp[0]);
        tr->nh = 3;
    }
    tr->ht[tr->nh] = (double)sp->now_ns * 1e-9;
    memcpy(tr->hp[tr->nh], p, sizeof tr->hp[0]);
    if (++tr->nh < 4)
        return;
    const double *t = tr->ht;
    double j[3];
    for (int x = 0; x < 3; x++) {
        double d1[3], d2[2];
        for (int i = 0; i < 3; i++)
            d1[i] = (tr->hp[i + 1][x] - tr->hp[i][x]) / (t[i + 1] - t[i]);
        for (int i = 0; i < 2; i++)
            d2[i] = (d1[i + 1] - d1[i]) / (t[i + 2] - t[i]);
        j[x] = 6.0 * (d2[1] - d2[0]) / (t[3] - t[0]);
    }
    /* rounding: 8 eps |p| / dt^3, times 6 */
    double dt = t[1] - t[0], noise = 48 * 2.3e-16 * (norm3(p) + 1) / (dt * dt * dt);
    judge(w, &w->fj, norm3(j), l->jerk + noise, "jerk (CSV third difference)", seed, k, "csv", sp);
}

/* One output's history: check sp's decoded position p against it. */
static void check_out(worst_t *w, const limits_t *l, track_t *tr, int o, const double *p,
                      const engine_setpoint_t *sp, unsigned seed, int k)
{
    if (tr->have) {
        double dt = (double)(sp->now_ns - tr->now) * 1e-9, v[3];
        double q = out_quantum[o];
        judge(w, &w->v, dist3(p, tr->p), l->speed * dt + 2 * q * sqrt(3.0), "step", seed, k,
              out_name[o], sp);
        for (int a = 0; a < 3; a++)
            v[a] = (p[a] - tr->p[a]) / dt;
        /* the two velocities' windows are the mean of their spans apart (a
         * skipped tick makes one longer), as the safety monitor judges them */
        if ((o == OUT_CSV || o == OUT_CIA402) && tr->vhave)
            judge(w, &w->fd, dist3(v, tr->v),
                  l->accel * 0.5 * (dt + tr->vdt) + 4 * q * sqrt(3.0) / fmin(dt, tr->vdt),
                  "finite-difference dv", seed, k, out_name[o], sp);
        memcpy(tr->v, v, sizeof v);
        tr->vdt = dt;
        tr->vhave = 1;
    }
    double a[3];
    if (decode_acc(o, sp, a)) {
        if (tr->ahave) {
            /* float32 (Modbus) rounds each value to 2^-24 relative */
            double dt = (double)(sp->now_ns - tr->now) * 1e-9;
            double q = o == OUT_MODBUS ? (norm3(a) + norm3(tr->a)) * ldexp(1.0, -23) : 0;
            judge(w, &w->j, dist3(a, tr->a), l->jerk * dt + q, "da", seed, k, out_name[o], sp);
        }
        memcpy(tr->a, a, sizeof a);
        tr->ahave = 1;
    }
    if (o == OUT_CSV)
        third_difference(w, l, tr, p, sp, seed, k);
    tr->have = 1;
    memcpy(tr->p, p, sizeof tr->p);
    tr->now = sp->now_ns;
}

/* cap: the caller's acceleration cap (engine.h cap_accel_m_s2, trajd's from a
 * configured safety_max_accel_m_s2), the acceleration bound judged; 0: none */
static void run_seed(unsigned seed, worst_t *w, double cap)
{
    engine_config_t c;
    engine_config_default(&c);
    /* default F = 32, O = 16: the junction error ~rho^8 is far below the bound */
    c.start_slack = 2;
    c.max_speed_m_s = 10.0;
    c.max_accel_m_s2 = 5.0;
    c.max_gap_s = 3.0;
    c.cap_accel_m_s2 = cap;
    limits_t l;
    limits_of(&c, &l);
    if (cap > 0)
        l.accel = cap;
    int err;
    engine_t *e = engine_new(&c, &err);
    assert_non_null(e);
    safety_t sf;
    safety_limits_t slim = {.max_speed_m_s = l.speed, .tol_m = SAFETY_TOL_M_DEFAULT};
    safety_init(&sf, &slim);
    canproto_ids_t ids;
    canproto_ids_default(&ids, 0);
    ids.cia402 = CANPROTO_CIA402_TARGETS;
    ids.cia402_invert[1] = 1;
    ids.cia402_offset[2] = 1234;
    track_t tr[OUT_N];
    memset(tr, 0, sizeof tr);
    unsigned s = seed;
    double t_wp = 0, due = 0, pos[3] = {0, 0, 0}, vel[3] = {1, 0.5, 0};
    double pause_until = 0;
    int64_t now = 0;
    uint32_t seq = 0;
    int ticks = 3000 + (int)(urand(&s) * 3000);
    int had_pos = 0;
    engine_setpoint_t prev;
    memset(&prev, 0, sizeof prev);
    int have_prev = 0;
    engine_t *retiring = NULL;
    for (int k = 0; k < ticks; k++) {
        double now_s = (double)now * 1e-9;
        /* the sender: one waypoint every H_S of its clock, sent when due
         * (late by up to 0.3 s), unless stalled; then all it owes at once */
        if (now_s >= pause_until && urand(&s) < 0.5) {
            while (due <= now_s) {
                double dt = H_S;
                if (urand(&s) < 0.004)
                    dt = 3.5; /* a gap: a new trajectory, reached by a transfer */
                for (int a = 0; a < 3; a++) {
                    vel[a] += (urand(&s) - 0.5) * 0.4;
                    vel[a] = fmax(-4, fmin(4, vel[a]));
                    pos[a] += vel[a] * dt;
                }
                t_wp += dt;
                due += dt;
                seq++;
                engine_waypoint_t wp = {.t_s = t_wp, .seq = seq};
                memcpy(wp.pos_m, pos, sizeof pos);
                if (urand(&s) < 0.02)
                    wp.pos_m[0] += 500; /* an outlier: refused by the engine */
                (void)engine_push(e, &wp);
            }
            if (urand(&s) < 0.002)
                pause_until = now_s + 6.0 * urand(&s); /* a stall */
        }
        /* commands */
        double r = urand(&s);
        int moving = have_prev && !(prev.flags & ENGINE_SP_HOLD);
        static int last_ev = -1000;
        static const char *ev = "";
        if (k - last_ev > 400)
            ev = "";
        static char cbuf[64];
        snprintf(cbuf, sizeof cbuf, "%s %d ago, track %u", ev, k - last_ev, prev.track);
        cause = cbuf;
        if (r < 0.0029)
            last_ev = k;
        if (r < 0.0007) {
            ev = "clear";
            engine_clear(e);
            w->stops += (unsigned)moving;
        } else if (r < 0.0014) {
            ev = "stop";
            engine_stop(e);
            w->stops += (unsigned)moving;
        } else if (r < 0.0024) {
            ev = "override";
            assert_int_equal(engine_set_override(e, urand(&s) < 0.5 ? 1.0 : urand(&s)), 0);
        } else if (r < 0.0029 && engine_has_position(e) && !retiring) {
            /* reload with other settings, as daemon/core/core.c does it: a new
             * engine; a moving old one brakes to rest first (engine_stop), and
             * the new one starts where the output rests */
            ev = "reload";
            w->reloads += (unsigned)moving;
            retiring = e;
            engine_stop(retiring);
            e = engine_new(&c, &err);
            assert_non_null(e);
        }
        /* skipped ticks */
        now += urand(&s) < 0.01 ? 3 * T_NS : T_NS;
        engine_setpoint_t sp;
        if (retiring) {
            assert_int_equal(engine_tick(retiring, now, &sp), 0);
            if ((sp.flags & ENGINE_SP_HOLD) && sp.state != ENGINE_STATE_STREAMING &&
                sp.state != ENGINE_STATE_UNDERRUN) {
                if (!(sp.flags & ENGINE_SP_NO_POSITION))
                    assert_int_equal(engine_set_position(e, sp.pos_m), 0);
                engine_free(retiring);
                retiring = NULL;
            }
        } else {
            assert_int_equal(engine_tick(e, now, &sp), 0);
        }
        assert_int_equal(safety_check(&sf, &sp), SAFETY_OK); /* never needed */
        if (!(sp.flags & ENGINE_SP_NO_POSITION))
            had_pos = 1;
        else
            assert_false(had_pos); /* a position, once there, is never lost */
        w->xfers += (sp.flags & ENGINE_SP_TRANSFER) && (sp.flags & ENGINE_SP_NEW_TRACK);
        w->scaled += (sp.flags & ENGINE_SP_SCALED) != 0;
        if (have_prev && !(sp.flags & ENGINE_SP_NO_POSITION)) {
            double dt = (double)(sp.now_ns - prev.now_ns) * 1e-9;
            judge(w, &w->a, dist3(sp.vel_m_s, prev.vel_m_s), l.accel * dt, "dv", seed, k, "engine",
                  &sp);
        }
        for (int o = 0; o < OUT_N; o++) {
            double p[3];
            if (!decode_out(o, &ids, &sp, p)) {
                assert_false(tr[o].have);
                continue;
            }
            check_out(w, &l, &tr[o], o, p, &sp, seed, k);
        }
        if (getenv("PROP_TRACE") && seed == (unsigned)atoi(getenv("PROP_TRACE")) &&
            abs(k - atoi(getenv("PROP_TICK"))) < 6) {
            engine_status_t st;
            engine_status(e, &st);
            print_message("  k %d t_s %.4f state %d flags 0x%x |v| %.4f a %.3f %.3f %.3f rate %.4f "
                          "ahead %.3f buf %u\n",
                          k, sp.t_s, sp.state, sp.flags,
                          sqrt(sp.vel_m_s[0] * sp.vel_m_s[0] + sp.vel_m_s[1] * sp.vel_m_s[1] +
                               sp.vel_m_s[2] * sp.vel_m_s[2]),
                          sp.acc_m_s2[0], sp.acc_m_s2[1], sp.acc_m_s2[2], st.rate, st.ahead_s,
                          st.buffered);
        }
        prev = sp;
        have_prev = !(sp.flags & ENGINE_SP_NO_POSITION);
    }
    w->ticks += (unsigned)ticks;
    engine_free(retiring);
    engine_free(e);
}

static void test_random_sequences(void **state)
{
    (void)state;
    worst_t w;
    memset(&w, 0, sizeof w);
    for (unsigned seed = 1; seed <= SEEDS; seed++)
        run_seed(seed, &w, 0.0);
    print_message("%d random sequences, %u ticks x %d outputs, %u stops/clears and %u reloads "
                  "while moving, %u transfers, %u scaled ticks; worst ratios to the limits: step "
                  "%.3f, dv %.3f, finite-difference dv %.3f, da %.3f, CSV jerk by third "
                  "differences %.3f (asserted: %u ticks above)\n",
                  SEEDS, w.ticks, OUT_N, w.stops, w.reloads, w.xfers, w.scaled, w.v, w.a, w.fd, w.j,
                  w.fj, w.over);
    /* the property was exercised */
    assert_true(w.stops > 20 && w.reloads > 10 && w.xfers > 20 && w.scaled > 1000);
    assert_int_equal(w.over, 0);
}

/* The same sequences with an acceleration cap well below what the curve and
 * the time scaling ask (trajd's 95 % of a configured safety_max_accel_m_s2):
 * every output's finite-difference acceleration within the cap, on every
 * tick of every stop, clear, reload, transfer and override (before the cap,
 * the engine planned its ramps at scale_accel_m_s2, 5 m/s^2, and the curve at
 * up to 3 x max_accel_m_s2, and the monitor held the object). */
static void test_random_sequences_accel_cap(void **state)
{
    (void)state;
    worst_t w;
    memset(&w, 0, sizeof w);
    for (unsigned seed = 1; seed <= SEEDS; seed++)
        run_seed(seed, &w, 2.0);
    print_message("acceleration cap 2 m/s^2, the same %d sequences: %u ticks, %u stops/clears, %u "
                  "reloads, %u transfers; worst finite-difference dv %.3f of the cap "
                  "(asserted: %u ticks above any bound)\n",
                  SEEDS, w.ticks, w.stops, w.reloads, w.xfers, w.fd, w.over);
    assert_true(w.stops > 20 && w.reloads > 10 && w.xfers > 20);
    assert_int_equal(w.over, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_sequences),
        cmocka_unit_test(test_random_sequences_accel_cap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
