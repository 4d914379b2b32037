/*
 * bench_csv.c - ns per setpoint line of each CSV number form, formatting
 * only (no engine, no write), in one run: the former default printf %.17g
 * (kept as trajreplay --precision g17), the default shortest round-trip form
 * (csv_shortest.h, Dragonbox) and --precision 9 (csv_fixed.h).  The lines
 * are the setpoints of a real replay (the figure-eight at 100 Hz), formatted
 * again and again; best of 5 repetitions, the least disturbed by other
 * processes.  Prints a table; asserts nothing.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "csv_format.h"
#include "engine.h"

enum { NSP = 20000, REPS = 5 };
static engine_setpoint_t sps[NSP];
static volatile size_t sink;

/* A stream of varied setpoints: a walk through the engine at 100 Hz. */
static size_t make_setpoints(void)
{
    engine_config_t c;
    engine_config_default(&c);
    engine_t *e = engine_new(&c, NULL);
    unsigned seed = 7;
    double pos[3] = {1234.5, -250.25, 12.0};
    size_t n = 0;
    for (long i = 0; i < 400; i++) {
        engine_waypoint_t w = {.t_s = 0.5 * (double)i, .seq = (uint32_t)i};
        for (int k = 0; k < 3; k++) {
            pos[k] += (urand(&seed) - 0.5) * 3.0;
            w.pos_m[k] = pos[k];
        }
        engine_push(e, &w);
    }
    engine_finish(e);
    for (int64_t k = 0; n < NSP; k++) {
        engine_tick(e, k * c.period_ns, &sps[n]);
        if (sps[n].state == ENGINE_STATE_FINISHED)
            break;
        n++;
    }
    engine_free(e);
    return n;
}

static double ns_per_line(size_t n, int prec)
{
    static char buf[CSV_FORMAT_LINE_MAX];
    double best = 1e30;
    for (int r = 0; r < REPS; r++) {
        double t0 = now_s();
        size_t bytes = 0;
        for (size_t i = 0; i < n; i++) {
            int len = csv_format_format_prec(buf, sizeof buf, "replay", &sps[i], prec);
            bytes += (size_t)len;
        }
        double t = now_s() - t0;
        sink += bytes;
        if (t < best)
            best = t;
    }
    return best * 1e9 / (double)n;
}

int main(void)
{
    size_t n = make_setpoints();
    if (getenv("BENCH_CSV_SHOW")) {
        char b[CSV_FORMAT_LINE_MAX];
        for (size_t i = 0; i < n; i += n / 8) {
            csv_format_format(b, sizeof b, "replay", &sps[i]);
            fputs(b, stdout);
        }
    }
    struct {
        const char *name;
        int prec;
    } forms[] = {
        {"former default printf %.17g (--precision g17)", CSV_PREC_G17},
        {"default shortest round trip (Dragonbox)", CSV_PREC_SHORTEST},
        {"--precision 9 (csv_fixed)", 9},
    };
    double ref = 0;
    printf("setpoint CSV line formatting, %zu lines of a 100 Hz replay, best of %d, same run:\n", n,
           REPS);
    printf("| form | ns/line | M lines/s | x %%.17g |\n|---|---|---|---|\n");
    for (size_t f = 0; f < sizeof forms / sizeof forms[0]; f++) {
        double ns = ns_per_line(n, forms[f].prec);
        if (f == 0)
            ref = ns;
        printf("| %s | %.0f | %.2f | %.2f |\n", forms[f].name, ns, 1e3 / ns, ref / ns);
    }
    return 0;
}
