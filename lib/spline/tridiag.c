/* tridiag.c - Thomas algorithm; see tridiag.h. */
#include "tridiag.h"

#include <math.h>

/* A pivot is usable if it is finite and not negligible against its row. */
static int pivot_ok(double piv, double a, double b, double c)
{
    double scale = fabs(a) + fabs(b) + fabs(c);
    return isfinite(piv) && fabs(piv) > TRIDIAG_PIVOT_REL_MIN * scale;
}

void tridiag_sweep_init(tridiag_sweep_t *s, double *cp, double *dp, size_t cap, size_t nrhs)
{
    s->n = 0;
    s->cap = cap;
    s->nrhs = nrhs;
    s->cp = cp;
    s->dp = dp;
}

void tridiag_sweep_reset(tridiag_sweep_t *s)
{
    s->n = 0;
}

int tridiag_sweep_push(tridiag_sweep_t *s, double a, double b, double c, const double *d)
{
    size_t i = s->n, k, m = s->nrhs;
    double piv, inv;

    if (i >= s->cap)
        return -TRIDIAG_ESIZE;
    if (i == 0) {
        a = 0.0;
        piv = b;
    } else {
        piv = b - a * s->cp[i - 1];
    }
    if (!pivot_ok(piv, a, b, c))
        return -TRIDIAG_ESINGULAR;
    /* one division per row, whatever the number of right-hand sides */
    inv = 1.0 / piv;
    s->cp[i] = c * inv;
    for (k = 0; k < m; k++) {
        double prev = i ? s->dp[(i - 1) * m + k] : 0.0;
        s->dp[i * m + k] = (d[k] - a * prev) * inv;
    }
    s->n = i + 1;
    return 0;
}

int tridiag_sweep_solve(const tridiag_sweep_t *s, double *x)
{
    size_t n = s->n, m = s->nrhs, i, k;

    if (n == 0)
        return -TRIDIAG_ESIZE;
    for (k = 0; k < m; k++)
        x[(n - 1) * m + k] = s->dp[(n - 1) * m + k];
    for (i = n - 1; i-- > 0;)
        for (k = 0; k < m; k++)
            x[i * m + k] = s->dp[i * m + k] - s->cp[i] * x[(i + 1) * m + k];
    return 0;
}

int tridiag_solve(size_t n, size_t nrhs, const double *a, const double *b, const double *c,
                  const double *d, double *x, double *scratch)
{
    tridiag_sweep_t s;
    size_t i;
    int rc;

    if (n == 0 || nrhs == 0)
        return -TRIDIAG_ESIZE;
    /* x doubles as d' storage: row i of d is read before row i of x is written. */
    tridiag_sweep_init(&s, scratch, x, n, nrhs);
    for (i = 0; i < n; i++) {
        rc = tridiag_sweep_push(&s, a[i], b[i], i + 1 < n ? c[i] : 0.0, d + i * nrhs);
        if (rc < 0)
            return rc;
    }
    return tridiag_sweep_solve(&s, x);
}
