/*
 * trajd_client.c - the smallest program against the installed libtrajd:
 * push four waypoints of a straight run, tick the engine at 100 Hz on a
 * clock the caller owns (lib/ reads none), print the setpoints as CSV, and
 * check that the output came to rest on the last waypoint.
 *
 *   cc trajd_client.c $(pkg-config --cflags --libs trajd) -o trajd_client
 *
 * Installed under share/doc/trajd/examples (it is documentation, not part of
 * the library); tests/e2e/test_install.sh builds and runs it against a
 * `make install DESTDIR=...` tree.  Exit 0 when the run ended as expected.
 */
#include <math.h>
#include <stdio.h>

#include "engine.h"

#define RATE_HZ 100
#define TICKS_MAX 2000

int main(void)
{
    engine_config_t cfg;
    engine_setpoint_t sp = {0};
    engine_t *e;
    int err = 0, k;
    static const double x_m[] = {0.0, 1.0, 2.0, 3.0};

    engine_config_default(&cfg);
    e = engine_new(&cfg, &err);
    if (!e) {
        fprintf(stderr, "engine_new: %s\n", engine_strerror(err));
        return 1;
    }
    for (k = 0; k < 4; k++) {
        engine_waypoint_t wp = {.t_s = k, .pos_m = {x_m[k], 0.0, 0.0}, .seq = (uint32_t)k};
        int rc = engine_push(e, &wp);
        if (rc < 0) {
            fprintf(stderr, "engine_push %d: %s\n", k, engine_strerror(rc));
            engine_free(e);
            return 1;
        }
    }
    engine_finish(e);
    printf("now_ns,x_m,vx_m_s,state\n");
    for (k = 0; k < TICKS_MAX; k++) {
        engine_tick(e, (int64_t)k * (1000000000 / RATE_HZ), &sp);
        if (k % 25 == 0)
            printf("%lld,%.6f,%.6f,%s\n", (long long)sp.now_ns, sp.pos_m[0], sp.vel_m_s[0],
                   engine_state_name(sp.state));
        if (sp.state == ENGINE_STATE_FINISHED)
            break;
    }
    engine_free(e);
    if (sp.state != ENGINE_STATE_FINISHED || fabs(sp.pos_m[0] - x_m[3]) > 1e-9) {
        fprintf(stderr, "not at rest on x = %g after %d ticks (x = %g, %s)\n", x_m[3], k,
                sp.pos_m[0], engine_state_name(sp.state));
        return 1;
    }
    printf("finished at x = %.6f m after %d ticks\n", sp.pos_m[0], k);
    return 0;
}
