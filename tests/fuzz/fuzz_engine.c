/*
 * fuzz_engine.c - libFuzzer target: arbitrary sequences of pushes (any bit
 * patterns for time and position, NaN and infinities included), ticks (also
 * skipping and going backwards), finish, stop, clear and counter resets, on
 * several configurations.  Checks: no crash, no sanitizer finding, and no
 * setpoint is ever NaN or infinite.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static double take_double(const uint8_t **p, const uint8_t *end)
{
    double d = 0;
    if (end - *p >= (long)sizeof(d)) {
        memcpy(&d, *p, sizeof(d));
        *p += sizeof(d);
    }
    return d;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *p = data, *end = data + size;
    engine_config_t c;
    engine_setpoint_t sp;
    engine_status_t st;
    int64_t now = 0;
    double t = 0;

    if (size < 1)
        return 0;
    engine_config_default(&c);
    switch (*p++ % 4) {
    case 1:
        c.method = ENGINE_METHOD_BSPLINE;
        c.param = ENGINE_PARAM_UNIFORM;
        c.ends = ENGINE_ENDS_MULTIPLE;
        c.fragment = 8;
        c.overlap = 4;
        break;
    case 2:
        c.ends = ENGINE_ENDS_NATURAL;
        c.fragment = 6;
        c.overlap = 2;
        c.start_slack = 0;
        c.max_speed_m_s = 0;
        break;
    case 3:
        c.method = ENGINE_METHOD_BSPLINE;
        c.param = ENGINE_PARAM_UNIFORM;
        c.ends = ENGINE_ENDS_HELD;
        c.capacity = 96; /* near the minimum (lookahead + F + 8): EFULL often */
        break;
    default:
        break;
    }
    c.max_gap_s = 5;
    engine_t *e = engine_new(&c, NULL);
    if (!e)
        abort();
    while (p < end) {
        uint8_t op = *p++;
        switch (op % 8) {
        case 0: case 1: case 2: { /* push: small steps mostly, raw doubles sometimes */
            engine_waypoint_t w = {0};
            if (op & 0x80) {
                w.t_s = take_double(&p, end);
                for (int k = 0; k < 3; k++)
                    w.pos_m[k] = take_double(&p, end);
            } else {
                t += (op >> 3) * 0.05;
                w.t_s = t;
                for (int k = 0; k < 3 && p < end; k++)
                    w.pos_m[k] = (double)(int8_t)*p++;
            }
            (void)engine_push(e, &w);
            break;
        }
        case 3: case 4: case 5:
            now += (int64_t)((op >> 3) + 1) * c.period_ns;
            (void)engine_tick(e, now, &sp);
            for (int k = 0; k < 3; k++)
                if (!isfinite(sp.pos_m[k]) || !isfinite(sp.vel_m_s[k]) ||
                    !isfinite(sp.acc_m_s2[k]))
                    abort();
            break;
        case 6:
            if (op & 0x40)
                engine_clear(e);
            else if (op & 0x20)
                (void)engine_stop(e);
            else
                (void)engine_finish(e);
            break;
        default:
            if (op & 0x80)
                (void)engine_tick(e, now - c.period_ns, &sp); /* backwards: refused */
            else if (op & 0x40)
                engine_reset_counters(e);
            engine_status(e, &st);
            break;
        }
    }
    engine_free(e);
    return 0;
}
