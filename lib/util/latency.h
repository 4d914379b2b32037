/*
 * latency.h - fixed histogram of tick lateness in microseconds, for the
 * daemon's p50/p99/p99.9/max.  Pure and allocation-free: the histogram is a
 * plain struct the caller owns, adding a sample is O(1) and never fails, so
 * it can run in the periodic tick.
 *
 * Buckets: 1 us wide below LAT_LINEAR_US (where a real-time tick lives), then
 * LAT_SUB buckets per power of two up to LAT_MAX_US (relative width at most
 * 1/LAT_SUB, about 3 %).  Larger samples go in the last bucket; the exact
 * maximum is kept apart, so max is never rounded.
 *
 * Limit: a quantile is reported as the upper edge of the bucket that holds
 * it (clipped to the exact max), i.e. exact below LAT_LINEAR_US and at most
 * ~3 % high above it: conservative, never optimistic.
 */
#ifndef TRAJD_LATENCY_H
#define TRAJD_LATENCY_H

#include <stdint.h>

#define LAT_LINEAR_US 1024u /* 1 us buckets for 0 .. 1023 us */
#define LAT_SUB 32u         /* buckets per octave above */
#define LAT_OCTAVES 16u     /* 1024 us .. 67 s */
#define LAT_MAX_US (LAT_LINEAR_US << LAT_OCTAVES)
#define LAT_BUCKETS (LAT_LINEAR_US + LAT_SUB * LAT_OCTAVES)

typedef struct {
    uint64_t count;               /* samples added */
    uint64_t sum_us;              /* for the mean */
    uint64_t max_us;              /* exact largest sample */
    uint32_t bucket[LAT_BUCKETS]; /* sample counts (saturate at UINT32_MAX) */
} lat_hist_t;

/* The four numbers the daemon logs and publishes (all 0 when empty). */
typedef struct {
    uint64_t count;
    uint32_t p50_us, p99_us, p999_us, max_us;
    uint32_t mean_us;
} lat_summary_t;

/* A histogram all zero (static, calloc, memset) is empty. */

/* Add one sample (us).  Never fails; values >= LAT_MAX_US land in the last bucket. */
void lat_add(lat_hist_t *h, uint64_t us);

/* p50, p99, p99.9, max and mean of h.  A quantile q is by nearest rank: the
 * smallest bucket upper edge below which at least ceil(q * count) samples
 * lie, clipped to max_us.  An empty histogram gives all 0.  Values above
 * UINT32_MAX saturate. */
void lat_summarize(const lat_hist_t *h, lat_summary_t *s);

#endif
