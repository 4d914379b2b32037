/* bench_can_busload.c - prints (no assertions): worst-case bus load of trajd's CAN
 * configurations at common bit rates (computed, lib/proto/canproto.h), and the
 * codec's cost per frame. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "test.h"
#include "canproto.h"

typedef struct {
    const char *name;
    unsigned nobj;
    double rate_hz;
    int sync, fd, brs, cia402, own;
} variant_t;

int main(void)
{
    static const variant_t v[] = {
        {"default: 1 object, 100 Hz, classic own frames", 1, 100, 0, 0, 0, 0, 1},
        {"1 object, 100 Hz, SYNC + own + CiA 402 x3", 1, 100, 1, 0, 0, 1, 1},
        {"1 object, 1 kHz, SYNC + CiA 402 x3 only", 1, 1000, 1, 0, 0, 1, 0},
        {"1 object, 1 kHz, classic own frames", 1, 1000, 0, 0, 0, 0, 1},
        {"1 object, 1 kHz, FD own frame, BRS x4", 1, 1000, 0, 1, 1, 0, 1},
        {"4 objects, 250 Hz, SYNC + own", 4, 250, 1, 0, 0, 0, 1},
    };
    static const double br[] = {125e3, 250e3, 500e3, 1e6};
    canproto_traffic_t tr = {.status_hz = 10, .waypoint_hz = 10};

    printf("Worst-case frame lengths (bits incl. stuffing and IFS), 11-bit ids:\n");
    printf("  classic DLC 0: %.0f, DLC 4: %.0f, DLC 8: %.0f; FD 32 bytes no BRS: %.0f\n",
           canproto_frame_bits(0, 0, 0, 0, 500e3, 0), canproto_frame_bits(4, 0, 0, 0, 500e3, 0),
           canproto_frame_bits(8, 0, 0, 0, 500e3, 0), canproto_frame_bits(32, 1, 0, 0, 500e3, 0));
    printf("\nWorst-case bus load, %% (status 10 Hz, 10 waypoints/s in, per object; FD data phase "
           "4x nominal)\n");
    printf("%-48s %9s %9s %9s %9s\n", "configuration", "125k", "250k", "500k", "1M");
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        canproto_ids_t ids[4];
        for (unsigned n = 0; n < v[i].nobj; n++) {
            canproto_ids_default(&ids[n], n);
            ids[n].fd = v[i].fd;
            ids[n].brs = v[i].brs;
            ids[n].cia402 = v[i].cia402;
            ids[n].own = v[i].own;
        }
        tr.rate_hz = v[i].rate_hz;
        printf("%-48s", v[i].name);
        for (size_t b = 0; b < sizeof br / sizeof br[0]; b++)
            printf(" %9.1f",
                   100 * canproto_busload(ids, v[i].nobj, v[i].sync, 0, &tr, br[b], 4 * br[b]));
        printf("\n");
    }

    /* codec cost */
    enum { N = 2000000 };
    engine_setpoint_t sp;
    memset(&sp, 0, sizeof sp);
    canproto_frame_t f[3];
    canproto_setpoint_t d;
    volatile double sink = 0;
    double t0 = now_s();
    for (int i = 0; i < N; i++) {
        sp.pos_m[0] = i * 1e-4;
        sp.cycle = (uint32_t)i;
        canproto_encode_setpoint(0x6A0, &sp, f);
    }
    double t1 = now_s();
    for (int i = 0; i < N; i++) {
        f[0].data[2] = (uint8_t)i;
        canproto_decode_setpoint(&f[0], &d);
        sink += d.pos_m[0];
    }
    double t2 = now_s();
    canproto_slot_t slots[2];
    canproto_rx_t rx;
    canproto_rx_init(&rx, slots, 2);
    engine_waypoint_t w = {.t_s = 0, .pos_m = {1, 2, 3}, .seq = 0};
    canproto_frame_t wf[4];
    canproto_rx_out_t out;
    double t3 = now_s();
    for (int i = 0; i < N / 4; i++) {
        w.seq = (uint32_t)i;
        w.t_s = i * 0.2;
        canproto_encode_waypoint(0x680, &w, wf);
        for (int k = 0; k < 4; k++)
            if (canproto_rx_frame(&rx, &wf[k], 0, &out) == CANPROTO_RX_WAYPOINT)
                canproto_rx_consume(&rx, &out);
    }
    double t4 = now_s();
    printf("\nCodec: encode 3 setpoint frames %.0f ns, decode one %.0f ns, "
           "encode + reassemble one waypoint (4 frames) %.0f ns\n",
           (t1 - t0) / N * 1e9, (t2 - t1) / N * 1e9, (t4 - t3) / (N / 4) * 1e9);
    (void)sink;
    return 0;
}
