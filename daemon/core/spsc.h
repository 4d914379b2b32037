/*
 * spsc.h - a bounded single-producer single-consumer ring of fixed-size
 * records (C11 atomics), the meeting point of the tick and a writer thread
 * (issue 28): the tick reserves and fills records and publishes them once per
 * tick, never waits, never allocates (the ring is allocated at its open); a
 * full ring is the producer's to count as a drop.  The consumer reads the
 * records published so far in order and releases them.
 *
 * Producer: spsc_slot() (NULL: full), fill it, spsc_push(); spsc_publish()
 * makes every pushed record visible (store-release of head).  Consumer:
 * spsc_avail() (load-acquire of head), spsc_at(i) for i < avail, then
 * spsc_release(n) (store-release of tail, the slots may be reused).
 */
#ifndef TRAJD_SPSC_H
#define TRAJD_SPSC_H

#include <stdatomic.h>
#include <stddef.h>

typedef struct {
    _Alignas(64) _Atomic size_t head; /* published by the producer */
    size_t head_local;                /* producer: pushed, not yet published */
    size_t tail_seen;                 /* producer: the tail it last read */
    _Alignas(64) _Atomic size_t tail; /* released by the consumer */
    _Alignas(64) size_t mask;         /* capacity - 1 (a power of two) */
    size_t rec;                       /* record size, bytes */
    unsigned char *buf;
} spsc_t;

/* A ring of at least cap records of rec bytes.  0 or -ENOMEM. */
int spsc_init(spsc_t *r, size_t rec, size_t cap);
void spsc_fini(spsc_t *r);

static inline void *spsc_slot(spsc_t *r)
{
    if (r->head_local - r->tail_seen > r->mask) {
        r->tail_seen = atomic_load_explicit(&r->tail, memory_order_acquire);
        if (r->head_local - r->tail_seen > r->mask)
            return NULL;
    }
    return r->buf + (r->head_local & r->mask) * r->rec;
}

static inline void spsc_push(spsc_t *r)
{
    r->head_local++;
}

static inline void spsc_publish(spsc_t *r)
{
    atomic_store_explicit(&r->head, r->head_local, memory_order_release);
}

static inline size_t spsc_avail(spsc_t *r)
{
    return atomic_load_explicit(&r->head, memory_order_acquire) -
           atomic_load_explicit(&r->tail, memory_order_relaxed);
}

static inline void *spsc_at(spsc_t *r, size_t i)
{
    size_t t = atomic_load_explicit(&r->tail, memory_order_relaxed);
    return r->buf + ((t + i) & r->mask) * r->rec;
}

static inline void spsc_release(spsc_t *r, size_t n)
{
    size_t t = atomic_load_explicit(&r->tail, memory_order_relaxed);
    atomic_store_explicit(&r->tail, t + n, memory_order_release);
}

#endif
