/* latency.c - fixed lateness histogram (see latency.h). */
#include "latency.h"

/* Index of the highest set bit of v > 0. */
static unsigned msb(uint64_t v)
{
    return 63u - (unsigned)__builtin_clzll(v);
}

/* Bucket index of a value. */
static unsigned lat_bucket_of(uint64_t us)
{
    if (us < LAT_LINEAR_US)
        return (unsigned)us;
    if (us >= LAT_MAX_US)
        return LAT_BUCKETS - 1;
    /* octave o: [1024 << o, 1024 << (o+1)), split into LAT_SUB equal parts */
    unsigned o = msb(us) - msb(LAT_LINEAR_US);
    uint64_t lo = (uint64_t)LAT_LINEAR_US << o;
    uint64_t width = lo / LAT_SUB; /* >= 32: LAT_LINEAR_US / LAT_SUB */
    return LAT_LINEAR_US + o * LAT_SUB + (unsigned)((us - lo) / width);
}

/* The [lo, hi] range of values bucket b holds. */
static void lat_bucket_range(unsigned b, uint64_t *lo_us, uint64_t *hi_us)
{
    if (b < LAT_LINEAR_US) {
        *lo_us = *hi_us = b;
        return;
    }
    if (b >= LAT_BUCKETS)
        b = LAT_BUCKETS - 1;
    unsigned o = (b - LAT_LINEAR_US) / LAT_SUB, s = (b - LAT_LINEAR_US) % LAT_SUB;
    uint64_t base = (uint64_t)LAT_LINEAR_US << o, width = base / LAT_SUB;
    *lo_us = base + s * width;
    *hi_us = *lo_us + width - 1;
    if (b == LAT_BUCKETS - 1)
        *hi_us = UINT64_MAX; /* overflow bucket: everything above */
}

void lat_add(lat_hist_t *h, uint64_t us)
{
    unsigned b = lat_bucket_of(us);
    if (h->bucket[b] != UINT32_MAX)
        h->bucket[b]++;
    h->count++;
    h->sum_us += us;
    if (us > h->max_us)
        h->max_us = us;
}

/* Quantile q in (0, 1] of h by nearest rank (latency.h: lat_summarize). */
static uint64_t quantile(const lat_hist_t *h, double q)
{
    if (h->count == 0)
        return 0;
    /* Nearest rank: the smallest value v with #(samples <= v) >= ceil(q n). */
    double r = q * (double)h->count;
    uint64_t rank = (uint64_t)r;
    if ((double)rank < r)
        rank++;
    if (rank < 1)
        rank = 1;
    if (rank > h->count)
        rank = h->count;
    uint64_t seen = 0;
    for (unsigned b = 0; b < LAT_BUCKETS; b++) {
        seen += h->bucket[b];
        if (seen >= rank) {
            uint64_t lo, hi;
            lat_bucket_range(b, &lo, &hi);
            return hi < h->max_us ? hi : h->max_us;
        }
    }
    return h->max_us; /* only if buckets saturated */
}

static uint32_t sat32(uint64_t v)
{
    return v > UINT32_MAX ? UINT32_MAX : (uint32_t)v;
}

void lat_summarize(const lat_hist_t *h, lat_summary_t *s)
{
    s->count = h->count;
    s->p50_us = sat32(quantile(h, 0.50));
    s->p99_us = sat32(quantile(h, 0.99));
    s->p999_us = sat32(quantile(h, 0.999));
    s->max_us = sat32(h->max_us);
    s->mean_us = h->count ? sat32(h->sum_us / h->count) : 0;
}
