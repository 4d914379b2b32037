/* test_delay_robust.c - the interval D grows to (engine_interval_robust,
 * lib/engine/delay_run.c) against the computation it replaced, kept here as
 * the reference: the median by a selection of the smallest half, each window
 * of the ring read through its modulo, summed from 0 and its longest taken by
 * fmax.  Bit for bit, on random rings of every fill, write position and window
 * length, with intervals drawn from a few values (ties) or spread, and on
 * the real track's 5 Hz intervals (0.199 and 0.201 s among 0.2 s); and a regular
 * sender's holes (engine_interval_holes). */
#include "test.h"

#include <math.h>
#include <string.h>

#include "engine_int.h"

/* The computation as it was (delay_run.c interval_robust before it was
 * made linear in the median and free of the modulo in the windows). */
static double reference(const double *iv, unsigned n, unsigned next, unsigned w)
{
    double v[ENGINE_IV_RING], med;
    unsigned k = n / 2;
    if (n < w || w > ENGINE_IV_RING)
        return 0.0;
    /* the first n slots: the n written while the ring fills (next == n),
     * every slot once it is full */
    memcpy(v, iv, n * sizeof v[0]);
    for (unsigned i = 0; i <= k; i++)
        for (unsigned j = i + 1; j < n; j++)
            if (v[j] < v[i]) {
                double x = v[i];
                v[i] = v[j];
                v[j] = x;
            }
    med = v[k];
    double best = 0.0;
    for (unsigned s = 0; s + w <= n; s++) {
        double sum = 0.0, mx = 0.0;
        for (unsigned i = 0; i < w; i++) {
            double x = iv[(next + ENGINE_IV_RING - n + s + i) % ENGINE_IV_RING];
            sum += x;
            mx = fmax(mx, x);
        }
        best = fmax(best, sum - mx + med);
    }
    return best / w;
}

static void same_bits(double a, double b)
{
    if (memcmp(&a, &b, sizeof a) != 0)
        fail_msg("%.17g against the reference's %.17g", a, b);
}

/* A ring as measure_input leaves it: n intervals written up to next
 * (exclusive; next == n until it is full), the slots not written left at a
 * value never read. */
static void fill(double *iv, unsigned n, unsigned next, unsigned *seed, int kind)
{
    static const double few[] = {0.199, 0.2, 0.201, 0.4, 1.0};
    for (unsigned i = 0; i < ENGINE_IV_RING; i++)
        iv[i] = -12345.0;
    for (unsigned i = 0; i < n; i++) {
        double x;
        if (kind == 0)
            x = few[(unsigned)(urand(seed) * 4.999)];
        else if (kind == 1)
            x = 1e-3 + urand(seed) * 10.0;
        else
            x = 0.2 + (urand(seed) - 0.5) * 1e-3; /* jitter */
        iv[(next + ENGINE_IV_RING - n + i) % ENGINE_IV_RING] = x;
    }
}

static void test_random_rings(void **state)
{
    (void)state;
    unsigned seed = 28;
    double iv[ENGINE_IV_RING];
    unsigned cases = 0;
    for (unsigned w = 1; w <= ENGINE_IV_RING; w++)
        for (unsigned n = 0; n <= ENGINE_IV_RING; n++)
            for (int kind = 0; kind < 3; kind++) {
                unsigned next = n == ENGINE_IV_RING ? (unsigned)(urand(&seed) * 63.999) : n;
                fill(iv, n, next, &seed, kind);
                same_bits(engine_interval_robust(iv, n, next, w), reference(iv, n, next, w));
                cases++;
            }
    assert_true(cases > 10000);
}

/* The full ring, written round more than once (next anywhere), the
 * engine's window of the default settings and a few others. */
static void test_full_ring_any_position(void **state)
{
    (void)state;
    unsigned seed = 5;
    double iv[ENGINE_IV_RING];
    static const unsigned ws[] = {1, 2, 3, 4, 5, 8, 16, 17, 33, 63, 64};
    for (unsigned next = 0; next < ENGINE_IV_RING; next++)
        for (size_t k = 0; k < sizeof ws / sizeof ws[0]; k++)
            for (int kind = 0; kind < 3; kind++) {
                fill(iv, ENGINE_IV_RING, next, &seed, kind);
                same_bits(engine_interval_robust(iv, ENGINE_IV_RING, next, ws[k]),
                          reference(iv, ENGINE_IV_RING, next, ws[k]));
            }
}

/* All equal, one long hole, sorted up and down: the selection's worst orders. */
static void test_orders(void **state)
{
    (void)state;
    double iv[ENGINE_IV_RING];
    for (unsigned w = 1; w <= 20; w++) {
        for (unsigned i = 0; i < ENGINE_IV_RING; i++)
            iv[i] = 0.2;
        same_bits(engine_interval_robust(iv, 64, 0, w), reference(iv, 64, 0, w));
        iv[17] = 3.0;
        same_bits(engine_interval_robust(iv, 64, 5, w), reference(iv, 64, 5, w));
        for (unsigned i = 0; i < ENGINE_IV_RING; i++)
            iv[i] = 0.1 + 0.01 * i;
        same_bits(engine_interval_robust(iv, 64, 0, w), reference(iv, 64, 0, w));
        for (unsigned i = 0; i < ENGINE_IV_RING; i++)
            iv[i] = 1.0 - 0.01 * i;
        same_bits(engine_interval_robust(iv, 64, 31, w), reference(iv, 64, 31, w));
    }
    same_bits(engine_interval_robust(iv, 3, 3, 4), 0.0); /* fewer than w */
}

/* A regular sender's ring (engine_interval_holes): intervals of 0.5 s with
 * fixes lost (1.0, 1.5 s) give 0.5 s, its holes filled in, where the
 * longest-removed window counts all but one of them; a few ms of jitter
 * keeps it regular; a sender whose timing varies (0.7 s among 0.5 s, or the
 * spread intervals) is none (0). */
static void test_holes(void **state)
{
    (void)state;
    double iv[ENGINE_IV_RING];
    for (unsigned i = 0; i < ENGINE_IV_RING; i++)
        iv[i] = 0.5;
    iv[10] = 1.0;
    iv[14] = 1.5;
    iv[20] = 1.0;
    assert_true(fabs(engine_interval_holes(iv, 64, 0, 19) - 0.5) < 1e-12);
    assert_true(engine_interval_robust(iv, 64, 0, 19) > 0.5 + 1.0 / 19); /* two holes count */
    for (unsigned i = 0; i < ENGINE_IV_RING; i++)
        iv[i] += 0.004 * sin(i); /* 20..80 ms late arrivals are not the stamps: a few ms */
    double h = engine_interval_holes(iv, 64, 0, 19);
    assert_true(h > 0.49 && h < 0.51);
    iv[30] = 0.7;
    assert_true(!(engine_interval_holes(iv, 64, 0, 19) > 0.0));
    unsigned seed = 9;
    fill(iv, 64, 64, &seed, 1);
    assert_true(!(engine_interval_holes(iv, 64, 0, 19) > 0.0));
    assert_true(!(engine_interval_holes(iv, 10, 10, 19) > 0.0)); /* fewer than w */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_rings),
        cmocka_unit_test(test_full_ring_any_position),
        cmocka_unit_test(test_orders),
        cmocka_unit_test(test_holes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
