/* frag.c - sliding window of overlapping fragments; see frag.h. */
#include "frag.h"

#include <stdlib.h>

frag_t *frag_new(unsigned f, unsigned o, unsigned delta, size_t ring)
{
    frag_t *fw;
    size_t i, per_slot, total;

    if (f < 4 || o < 2 || o % 2 || o >= f || ring < f || delta > frag_delta_max(f, o))
        return NULL;
    fw = calloc(1, sizeof(*fw));
    if (!fw)
        return NULL;
    fw->f = f;
    fw->o = o;
    fw->s = f - o;
    fw->delta = delta;
    /* Fragment k is open from row kS - D (at least 0) to row kS+F-1-D: at
     * most ceil(F/S) fragments hold a row, one more may be opening on it;
     * fragments cut at row 0 (kS <= D) are shorter, so no more of them. */
    fw->nslots = (f + fw->s - 1) / fw->s + 1;
    fw->ring = ring;
    per_slot = (size_t)f * (1 + FRAG_AXES);
    total = per_slot * fw->nslots + (size_t)f * FRAG_AXES + ring * FRAG_AXES;
    fw->slot = calloc(fw->nslots, sizeof(*fw->slot));
    fw->mem = calloc(total, sizeof(double));
    if (!fw->slot || !fw->mem) {
        frag_free(fw);
        return NULL;
    }
    for (i = 0; i < fw->nslots; i++) {
        double *base = fw->mem + i * per_slot;
        tridiag_sweep_init(&fw->slot[i].sw, base, base + f, f, FRAG_AXES);
    }
    fw->xs = fw->mem + per_slot * fw->nslots;
    fw->x = fw->xs + (size_t)f * FRAG_AXES;
    frag_reset(fw);
    return fw;
}

void frag_free(frag_t *fw)
{
    if (!fw)
        return;
    free(fw->slot);
    free(fw->mem);
    free(fw);
}

void frag_reset(frag_t *fw)
{
    unsigned i;

    fw->rows = 0;
    fw->final_rows = 0;
    fw->next_frag = 0;
    fw->next_solve = 0;
    fw->done = 0;
    for (i = 0; i < fw->nslots; i++) {
        fw->slot[i].open = 0;
        tridiag_sweep_reset(&fw->slot[i].sw);
    }
}

static frag_slot_t *slot_of(frag_t *fw, uint64_t k)
{
    return &fw->slot[k % fw->nslots];
}

/* first and last row of fragment k (fragments with kS <= D are cut at row 0) */
static uint64_t frag_first(const frag_t *fw, uint64_t k)
{
    return k * fw->s > fw->delta ? k * fw->s - fw->delta : 0;
}

static uint64_t frag_last(const frag_t *fw, uint64_t k)
{
    return k * fw->s + fw->f - 1 - fw->delta;
}

static void put_x(frag_t *fw, uint64_t j, const double *v)
{
    double *dst = fw->x + (size_t)(j % fw->ring) * FRAG_AXES;
    for (int k = 0; k < FRAG_AXES; k++)
        dst[k] = v[k];
}

/*
 * Back-substitute fragment k (its rows are all in) and make its share of x
 * final.  Returns 0 or a negated tridiag_error.
 */
static int solve_fragment(frag_t *fw, uint64_t k, int to_end)
{
    frag_slot_t *sl = slot_of(fw, k);
    uint64_t first = sl->first, last = first + sl->sw.n - 1;
    uint64_t jprev = k * fw->s - fw->delta + fw->o / 2;    /* J(k-1), k > 0 */
    uint64_t jk = (k + 1) * fw->s - fw->delta + fw->o / 2; /* J(k) */
    uint64_t j, lo = 0;
    int rc, m;

    sl->open = 0;
    fw->next_solve = k + 1;
    if (k > 0 && jprev > last)
        return 0; /* closed before reaching its share: the previous one covers it */
    rc = tridiag_sweep_solve(&sl->sw, fw->xs);
    if (rc < 0)
        return rc;
    if (k > 0) {
        double avg[FRAG_AXES];
        const double *mine = fw->xs + (size_t)(jprev - first) * FRAG_AXES;
        for (m = 0; m < FRAG_AXES; m++)
            avg[m] = 0.5 * (fw->junction[m] + mine[m]);
        put_x(fw, jprev, avg);
        lo = jprev + 1;
    }
    if (jk <= last && !to_end) {
        for (j = lo; j < jk; j++)
            put_x(fw, j, fw->xs + (size_t)(j - first) * FRAG_AXES);
        for (m = 0; m < FRAG_AXES; m++)
            fw->junction[m] = fw->xs[(size_t)(jk - first) * FRAG_AXES + m];
        fw->final_rows = jk;
    } else {
        for (j = lo; j <= last; j++)
            put_x(fw, j, fw->xs + (size_t)(j - first) * FRAG_AXES);
        fw->final_rows = last + 1;
    }
    return 0;
}

int frag_push(frag_t *fw, const frag_row_t *row, const double *pin)
{
    uint64_t r = fw->rows, k;
    int rc;

    if (fw->done)
        return -TRIDIAG_ESIZE;
    /* rows of fragments already open (oldest first: the oldest may end here) */
    for (k = fw->next_solve; k < fw->next_frag; k++) {
        frag_slot_t *sl = slot_of(fw, k);
        if (!sl->open)
            continue;
        if (r == frag_last(fw, k)) {
            /* artificial end: pinned */
            rc = tridiag_sweep_push(&sl->sw, 0.0, 1.0, 0.0, pin);
            if (rc == 0)
                rc = solve_fragment(fw, k, 0);
        } else {
            rc = tridiag_sweep_push(&sl->sw, row->a, row->b, row->c, row->d);
        }
        if (rc < 0)
            return rc;
    }
    /* open the fragments starting here (several at row 0 when D >= S) */
    while (r == frag_first(fw, fw->next_frag)) {
        frag_slot_t *sl = slot_of(fw, fw->next_frag);
        if (sl->open)
            return -TRIDIAG_ESIZE; /* cannot happen with nslots as sized */
        sl->open = 1;
        sl->first = r;
        tridiag_sweep_reset(&sl->sw);
        if (r == 0)
            rc = tridiag_sweep_push(&sl->sw, 0.0, row->b, row->c, row->d);
        else
            rc = tridiag_sweep_push(&sl->sw, 0.0, 1.0, 0.0, pin); /* artificial start */
        fw->next_frag++;
        if (rc < 0)
            return rc;
    }
    fw->rows = r + 1;
    return 0;
}

int frag_finish(frag_t *fw, const frag_row_t *row)
{
    uint64_t r = fw->rows, k;
    int rc;

    if (fw->done)
        return -TRIDIAG_ESIZE;
    if (r == 0) {
        /* a one-row system: the row alone (a and c ignored) */
        frag_slot_t *sl = slot_of(fw, 0);
        sl->open = 1;
        sl->first = 0;
        tridiag_sweep_reset(&sl->sw);
        rc = tridiag_sweep_push(&sl->sw, 0.0, row->b, 0.0, row->d);
        fw->next_frag = 1;
        if (rc < 0)
            return rc;
    } else {
        /* The oldest open fragment takes the true end row and covers every
         * row up to it: its only artificial end is gone, so near the end it
         * is better than the younger ones (pinned O/2 rows before their
         * junction), and the true end condition holds exactly.  The younger
         * open fragments are dropped. */
        for (k = fw->next_solve; k < fw->next_frag && !slot_of(fw, k)->open; k++)
            ;
        if (k == fw->next_frag)
            return -TRIDIAG_ESIZE; /* cannot happen: some fragment holds row r-1 */
        rc = tridiag_sweep_push(&slot_of(fw, k)->sw, row->a, row->b, 0.0, row->d);
        if (rc < 0)
            return rc;
    }
    for (k = fw->next_solve; k < fw->next_frag; k++) {
        if (!slot_of(fw, k)->open)
            continue;
        rc = solve_fragment(fw, k, 1);
        if (rc < 0)
            return rc;
        break;
    }
    for (; k < fw->next_frag; k++)
        slot_of(fw, k)->open = 0;
    fw->rows = r + 1;
    fw->done = 1;
    return 0;
}

unsigned frag_delta_max(unsigned f, unsigned o)
{
    return f - o + o / 2 - 1;
}

uint64_t frag_final_after(unsigned f, unsigned o, unsigned delta, uint64_t r)
{
    unsigned s = f - o;
    uint64_t k;

    /* the newest fragment solved: largest k with kS + F - 1 - delta <= r */
    if (r + 1 + delta < f)
        return 0;
    k = (r + 1 + delta - f) / s;
    return (k + 1) * s - delta + o / 2;
}
