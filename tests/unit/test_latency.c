/* test_latency.c - lateness histogram against an exact reference: the samples
 * kept, sorted with qsort, and the nearest-rank quantile read off directly.
 * The histogram is read as the daemon reads it, through lat_summarize (p50,
 * p99, p99.9, max, mean); any other rank through its p50, the histogram
 * padded so that the rank asked for is the middle one (rank_of). */
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "latency.h"

#define NSAMP 20000

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Exact nearest-rank quantile of sorted v[0..n-1]. */
static uint64_t exact_q(const uint64_t *v, size_t n, double q)
{
    size_t rank = (size_t)ceil(q * (double)n);
    if (rank < 1)
        rank = 1;
    return v[rank - 1];
}

static uint64_t rnd(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static lat_summary_t summary(const lat_hist_t *h)
{
    lat_summary_t sm;
    lat_summarize(h, &sm);
    return sm;
}

/* Sample r (1 .. count, nearest rank) of h as its p50 reads it: h padded
 * with count - 2r samples of 0, which sort below every sample, or with
 * 2r - count copies of its maximum, which sort above (neither changes the
 * maximum a quantile is clipped to), so that sample r is the middle one. */
static uint64_t rank_of(const lat_hist_t *h, uint64_t r)
{
    static lat_hist_t p;
    p = *h;
    for (uint64_t k = 2 * r; k < h->count; k++)
        lat_add(&p, 0);
    for (uint64_t k = h->count; k < 2 * r; k++)
        lat_add(&p, h->max_us);
    return summary(&p).p50_us;
}

/* The nearest-rank quantile q of h as the daemon's would be at that q: the
 * sample of rank ceil(q count), at least 1 (rank_of). */
static uint64_t quantile(const lat_hist_t *h, double q)
{
    uint64_t r = (uint64_t)ceil(q * (double)h->count);
    return rank_of(h, r < 1 ? 1 : r);
}

/* The upper edge of the bucket that holds us, read through the API: one
 * sample's p50, with the exact maximum lifted out of the way, is its bucket's
 * upper edge (UINT64_MAX for the last bucket, which the summary saturates to
 * UINT32_MAX: every other edge lies below LAT_MAX_US). */
static uint64_t upper_edge(uint64_t us)
{
    static lat_hist_t h;
    memset(&h, 0, sizeof h);
    lat_add(&h, us);
    h.max_us = UINT64_MAX;
    uint32_t hi = summary(&h).p50_us;
    return hi == UINT32_MAX ? UINT64_MAX : hi;
}

/* The [lo, hi] range of the bucket that holds us: hi its upper edge, lo the
 * least value with the same upper edge (a bisection: upper edges never go
 * down as the value goes up, which test_buckets_tile sees). */
static void range_of(uint64_t us, uint64_t *lo, uint64_t *hi)
{
    *hi = upper_edge(us);
    uint64_t a = 0, b = us; /* lo in [a, b] */
    while (a < b) {
        uint64_t m = a + (b - a) / 2;
        if (upper_edge(m) == *hi)
            b = m;
        else
            a = m + 1;
    }
    *lo = a;
}

/* Given the buckets read from 0 up, each from the value after the last one's
 * upper edge, then they tile the values without gap or overlap (a bucket's
 * upper edge lies in it too), 1 us wide below LAT_LINEAR_US and at most
 * 1/LAT_SUB of their lower edge wide above, LAT_BUCKETS of them, the last
 * holding everything up to UINT64_MAX. */
static void test_buckets_tile(void **state)
{
    (void)state;
    uint64_t next = 0;
    unsigned b = 0;
    for (;; b++) {
        uint64_t lo, hi, lo2, hi2;
        range_of(next, &lo, &hi);
        assert_int_equal(lo, next);
        assert_true(hi >= lo);
        range_of(hi, &lo2, &hi2);
        assert_int_equal(lo2, lo);
        assert_int_equal(hi2, hi);
        if (hi == UINT64_MAX)
            break;
        if (lo < LAT_LINEAR_US)
            assert_int_equal(hi, lo);
        else
            assert_true((double)(hi - lo + 1) <= (double)lo / LAT_SUB + 1e-9);
        next = hi + 1;
    }
    assert_int_equal(b, LAT_BUCKETS - 1);
}

/* Given 20000 samples mixing a tight core (0-200 us), a tail (1-50 ms) and a
 * few huge outliers, when summarised, then p50/p99/p99.9 are never below the
 * exact quantile and above it by at most one bucket width (0 below 1024 us,
 * <= 1/LAT_SUB relative above), and max and mean are exact. */
static void test_quantiles_match_sorted(void **state)
{
    (void)state;
    static uint64_t v[NSAMP];
    static lat_hist_t h;
    uint64_t s = 88172645463325252ull, sum = 0;
    memset(&h, 0, sizeof h);
    for (int i = 0; i < NSAMP; i++) {
        uint64_t r = rnd(&s) % 1000;
        if (r < 980)
            v[i] = rnd(&s) % 200;
        else if (r < 998)
            v[i] = 1000 + rnd(&s) % 49000;
        else
            v[i] = rnd(&s) % 200000000; /* beyond LAT_MAX_US too */
        lat_add(&h, v[i]);
        sum += v[i];
    }
    qsort(v, NSAMP, sizeof v[0], cmp_u64);
    lat_summary_t sm = summary(&h);
    const double qs[] = {0.01, 0.5, 0.9, 0.98, 0.99, 0.995, 0.999, 1.0};
    for (size_t k = 0; k < sizeof qs / sizeof qs[0]; k++) {
        uint64_t ex = exact_q(v, NSAMP, qs[k]), got = quantile(&h, qs[k]);
        /* the daemon's own three (qs[1], qs[4], qs[6]), as lat_summarize gives them */
        if (k == 1 || k == 4 || k == 6)
            assert_int_equal(got, k == 1 ? sm.p50_us : k == 4 ? sm.p99_us : sm.p999_us);
        assert_true(got >= ex);
        if (ex < LAT_LINEAR_US)
            assert_int_equal(got, ex);
        else if (ex < LAT_MAX_US)
            assert_true((double)got <= (double)ex * (1.0 + 1.0 / LAT_SUB) + 1);
        else
            assert_true(got <= v[NSAMP - 1]);
    }
    assert_int_equal(sm.count, NSAMP);
    assert_int_equal(sm.max_us, v[NSAMP - 1] > UINT32_MAX ? UINT32_MAX : v[NSAMP - 1]);
    assert_int_equal(sm.mean_us, sum / NSAMP);
    assert_int_equal(sm.p50_us, exact_q(v, NSAMP, 0.5)); /* in the 1 us range */
}

/* Given an empty histogram, then every number is 0. */
static void test_empty(void **state)
{
    (void)state;
    static lat_hist_t h;
    lat_summary_t sm;
    memset(&h, 0, sizeof h);
    lat_summarize(&h, &sm);
    assert_int_equal(sm.count, 0);
    assert_int_equal(sm.p99_us, 0);
    assert_int_equal(sm.max_us, 0);
    assert_int_equal(sm.p50_us, 0);
    assert_int_equal(sm.p999_us, 0);
    assert_int_equal(sm.mean_us, 0);
}

/* Given small sample counts, where q * n is not a whole number (20000
 * samples above hide that: every q there gives an integer rank), then the
 * quantile is the nearest-rank one, rank ceil(q n), exactly (values in the
 * 1 us linear range): p99 of 10 samples is the largest, p50 of 7 the 4th. */
static void test_quantile_rank_rounds_up(void **state)
{
    (void)state;
    static const size_t ns[] = {1, 2, 3, 7, 10, 13, 99, 101};
    static const double qs[] = {0.1, 0.25, 0.5, 0.9, 0.95, 0.99, 0.999, 1.0};
    uint64_t s = 2463534242ull;
    for (size_t i = 0; i < sizeof ns / sizeof ns[0]; i++) {
        uint64_t v[128];
        lat_hist_t h;
        memset(&h, 0, sizeof h);
        for (size_t j = 0; j < ns[i]; j++) {
            v[j] = rnd(&s) % LAT_LINEAR_US;
            lat_add(&h, v[j]);
        }
        /* cppcheck-suppress uninitvar ; ns[i] >= 1: the loop above set v[0 .. ns[i] - 1] */
        qsort(v, ns[i], sizeof v[0], cmp_u64);
        for (size_t k = 0; k < sizeof qs / sizeof qs[0]; k++)
            assert_int_equal(quantile(&h, qs[k]), exact_q(v, ns[i], qs[k]));
        /* and the daemon's three straight from lat_summarize */
        lat_summary_t sm = summary(&h);
        assert_int_equal(sm.p50_us, exact_q(v, ns[i], 0.5));
        assert_int_equal(sm.p99_us, exact_q(v, ns[i], 0.99));
        assert_int_equal(sm.p999_us, exact_q(v, ns[i], 0.999));
    }
    /* the cases spelled out: 10 distinct samples 0..9 */
    lat_hist_t h10;
    memset(&h10, 0, sizeof h10);
    for (uint64_t j = 0; j < 10; j++)
        lat_add(&h10, j);
    assert_int_equal(summary(&h10).p99_us, 9);
    assert_int_equal(summary(&h10).p50_us, 4);
    assert_int_equal(quantile(&h10, 0.55), 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_buckets_tile),
        cmocka_unit_test(test_quantiles_match_sorted),
        cmocka_unit_test(test_quantile_rank_rounds_up),
        cmocka_unit_test(test_empty),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
