/* csv_fixed.c - fast printf("%.*f") for doubles; see csv_fixed.h. */
#include "csv_fixed.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static unsigned long slow_calls;

unsigned long csv_fixed_slow_calls(void)
{
    return slow_calls;
}

static const double pow10_tab[CSV_FIXED_PREC_MAX + 1] = {
    1e0, 1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,
    1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17,
};

static const char digits2[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* Dekker/Veltkamp: a * b = p + e exactly (no overflow for the magnitudes
 * the fast path takes). */
static void two_product(double a, double b, double *p, double *e)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double t = split * a, ah = t - (t - a), al = a - ah;
    t = split * b;
    double bh = t - (t - b), bl = b - bh;
    *p = a * b;
    *e = ((ah * bh - *p) + ah * bl + al * bh) + al * bl;
}

static int slow(char *out, double x, int prec)
{
    char tmp[CSV_FIXED_MAX + 8];
    slow_calls++;
    int n = snprintf(tmp, sizeof tmp, "%.*f", prec, x);
    if (n < 0)
        return 0;
    if (n > CSV_FIXED_MAX)
        n = CSV_FIXED_MAX;
    memcpy(out, tmp, (size_t)n);
    return n;
}

/* Write v (< 10^20) in decimal, at least mindig digits (zero padded). */
static int write_u64(char *out, uint64_t v, int mindig)
{
    char tmp[24];
    int i = 24;
    while (v >= 100) {
        unsigned r = (unsigned)(v % 100);
        v /= 100;
        i -= 2;
        memcpy(tmp + i, digits2 + 2 * r, 2);
    }
    if (v >= 10) {
        i -= 2;
        memcpy(tmp + i, digits2 + 2 * v, 2);
    } else {
        tmp[--i] = (char)('0' + v);
    }
    while (24 - i < mindig)
        tmp[--i] = '0';
    memcpy(out, tmp + i, (size_t)(24 - i));
    return 24 - i;
}

int csv_fixed(char *out, double x, int prec)
{
    if (prec < 0 || prec > CSV_FIXED_PREC_MAX || !isfinite(x))
        return slow(out, x, prec < 0 ? 0 : prec);
    int neg = signbit(x) != 0;
    double a = fabs(x);
    double p, e;
    two_product(a, pow10_tab[prec], &p, &e);
    /* Below 2^53 p - r is exact (from 2^52 on p is an integer and r = p)
     * and r + 1 is a double. */
    if (!(p < 9007199254740992.0))
        return slow(out, x, prec);
    double r = nearbyint(p); /* any integer within 0.5 of p will do */
    double d = (p - r) + e;  /* p - r exact; d is the rounded remainder */
    /* The exact remainder (p - r) + e is within a rounding of d: a d equal to
     * +-0.5 may be a tie or either side of one - printf decides those. */
    if (fabs(d) >= 0.5 && fabs(d) <= 0.5) /* == 0.5, without -Wfloat-equal */
        return slow(out, x, prec);
    if (d > 0.5)
        r += 1;
    else if (d < -0.5)
        r -= 1;
    uint64_t q = (uint64_t)r;
    char *o = out;
    if (neg)
        *o++ = '-';
    if (prec == 0)
        return (int)(o - out) + write_u64(o, q, 1);
    uint64_t scale = (uint64_t)pow10_tab[prec];
    o += write_u64(o, q / scale, 1);
    *o++ = '.';
    o += write_u64(o, q % scale, prec);
    return (int)(o - out);
}
