/*
 * frag.h - sliding window of overlapping fragments (maths notes: lib/engine/DESIGN.md).
 *
 * One tridiagonal system per coordinate, rows arriving one at a time (one per
 * node), is solved in fragments of F rows overlapping by O (S = F - O):
 * fragment k holds rows [max(0, kS - D), kS - D + F - 1]: the fragments
 * with kS <= D are cut at row 0 (fragment 0 has F - D rows and ends, and is
 * solved, D rows earlier: the start offset D <= S + O/2 - 1 shortens the
 * wait before the first segment down to O/2 + 1 rows, so that the start
 * needs no more than the steady state; D = 0 is the plain grid).  A fragment
 * cut at row 0 has the true start condition there, and still ends at least
 * O/2 rows after its junction J(k) >= 1.  Each fragment's forward sweep
 * advances one row per pushed row; when its last row is in, it is
 * back-substituted (F rows) and its values become final:
 *
 *   x[j] from fragment k           for J(k-1) < j < J(k)
 *   x[J(k)] = (x_k[J(k)] + x_{k+1}[J(k)]) / 2   the junction, averaged
 *
 * with J(k) = (k+1) S - D + O/2, the middle of the overlap of k and k+1 (O/2
 * rows from k+1's first row, O/2 - 1 from k's last).  A fragment's artificial
 * ends (its first row for k > 0, its last unless it is the true end) are "pinned" rows x = pin (the caller's natural end value);
 * their error decays by about 2 - sqrt(3) = 0.268 per row inward, so the
 * value taken at the junction, O/2 rows from either fragment's end, is off by
 * about 0.268^(O/2) of the local curvature scale.
 *
 * Work per pushed row: one forward-sweep row in each of the ceil(F/S)
 * fragments that hold it, plus F back-substitution rows every S rows:
 * bounded by F and O, independent of the track length.  No allocation after
 * frag_new.  x values live in a ring of `ring` rows indexed by row number.
 */
#ifndef TRAJD_FRAG_H
#define TRAJD_FRAG_H

#include <stddef.h>
#include <stdint.h>

#include "tridiag.h"

#define FRAG_AXES 3

/* One row of the system: a x[j-1] + b x[j] + c x[j+1] = d (per axis). */
typedef struct {
    double a, b, c;
    double d[FRAG_AXES];
} frag_row_t;

typedef struct {
    tridiag_sweep_t sw;
    uint64_t first; /* global row of the fragment's first row */
    int open;
} frag_slot_t;

typedef struct {
    unsigned f, o, s;           /* F, O, S = F - O */
    unsigned delta;             /* D: start offset of the fragment grid */
    unsigned nslots;            /* fragments open at once at most */
    size_t ring;                /* rows of x kept */
    uint64_t rows;              /* rows pushed so far (the next row's number) */
    uint64_t final_rows;        /* x[0 .. final_rows-1] are final */
    uint64_t next_frag;         /* next fragment to open */
    uint64_t next_solve;        /* next fragment to solve (they solve in order) */
    int done;                   /* closed: no more rows until frag_reset */
    double junction[FRAG_AXES]; /* fragment k's value at J(k), waiting for k+1 */
    frag_slot_t *slot;
    double *mem; /* all doubles, one allocation */
    double *xs;  /* F x AXES back-substitution scratch */
    double *x;   /* ring x AXES final values */
} frag_t;

/* Largest start offset D for F, O: S + O/2 - 1 (J(0) = 1). */
unsigned frag_delta_max(unsigned f, unsigned o);

/*
 * Allocate a window for F, O (O even, 2 <= O < F), start offset
 * D <= frag_delta_max(F, O),
 * keeping ring final rows (ring >= F).  Returns NULL on bad sizes or no memory.
 */
frag_t *frag_new(unsigned f, unsigned o, unsigned delta, size_t ring);

/* Free; NULL is a no-op. */
void frag_free(frag_t *fw);

/* Forget every row: a new system starts at row 0. */
void frag_reset(frag_t *fw);

/*
 * Push row number fw->rows.  row is its full row (for row 0 the true start
 * condition; a is ignored there).  pin: the value used when this row is an
 * artificial fragment end.  Returns 0 or a negated tridiag_error
 * (-TRIDIAG_ESINGULAR: not finite or singular; the window is then unusable
 * until frag_reset).
 */
int frag_push(frag_t *fw, const frag_row_t *row, const double *pin);

/*
 * Push the last row (the true end condition: c ignored) and close: every
 * value up to it becomes final.  The oldest open fragment takes the end row
 * and covers everything from its junction to the end (its only artificial
 * end is gone); younger open fragments are dropped.
 * Returns 0 or a negated tridiag_error.
 */
int frag_finish(frag_t *fw, const frag_row_t *row);

/* Final value of row j (j < fw->final_rows and within the ring). */
static inline const double *frag_x(const frag_t *fw, uint64_t j)
{
    return fw->x + (size_t)(j % fw->ring) * FRAG_AXES;
}

/*
 * Rows of delay: after row r is pushed, every row below
 * frag_final_after(f, o, delta, r) is final.  Used to derive the lookahead.
 */
uint64_t frag_final_after(unsigned f, unsigned o, unsigned delta, uint64_t r);

#endif
