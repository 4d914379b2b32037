/* csv_fixed.c - fast printf("%.*f") for doubles; see csv_fixed.h. */
#include "csv_fixed.h"
#include "csv_shortest.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

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

/* The last n (1..8) of the 8 padded digits of v < 10^8 at out. */
static void put_last(char *out, uint32_t v, int n)
{
    uint64_t d = csv_digits8(v) >> (8 * (8 - n));
    memcpy(out, &d, (size_t)n);
}

/* Decimal digits of v < 10^8 (1 for 0). */
static int ndigits8(uint32_t v)
{
    return v < 10000 ? (v < 100 ? (v < 10 ? 1 : 2) : (v < 1000 ? 3 : 4))
                     : (v < 1000000 ? (v < 100000 ? 5 : 6) : (v < 10000000 ? 7 : 8));
}

/* q = ip * 10^prec + fr, prec 1..17, with constant divisors (a division by a
 * variable 64-bit divisor costs tens of cycles, by a constant a multiply). */
static uint64_t split_pow10(uint64_t q, int prec, uint64_t *fr)
{
    uint64_t ip;
    switch (prec) {
#define P(n, p10)                                                                                  \
    case n:                                                                                        \
        ip = q / p10##ull;                                                                         \
        *fr = q % p10##ull;                                                                        \
        return ip;
        P(1, 10)
        P(2, 100)
        P(3, 1000)
        P(4, 10000)
        P(5, 100000)
        P(6, 1000000)
        P(7, 10000000)
        P(8, 100000000)
        P(9, 1000000000)
        P(10, 10000000000)
        P(11, 100000000000)
        P(12, 1000000000000)
        P(13, 10000000000000)
        P(14, 100000000000000)
        P(15, 1000000000000000)
        P(16, 10000000000000000)
#undef P
    default:
        ip = q / 100000000000000000ull;
        *fr = q % 100000000000000000ull;
        return ip;
    }
}

/* ip "." fr with prec digits of fraction (1..17), by 8-digit blocks. */
static int put_fixed(char *o, uint64_t ip, uint64_t fr, int prec)
{
    char *p = o;
    if (ip < 100000000) {
        int n = ndigits8((uint32_t)ip);
        put_last(p, (uint32_t)ip, n);
        p += n;
    } else {
        p += write_u64(p, ip, 1);
    }
    *p++ = '.';
    if (prec <= 8) {
        put_last(p, (uint32_t)fr, prec);
    } else if (prec <= 16) {
        put_last(p, (uint32_t)(fr / 100000000), prec - 8);
        put_last(p + prec - 8, (uint32_t)(fr % 100000000), 8);
    } else {
        write_u64(p, fr, prec);
    }
    return (int)(p + prec - o);
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
    uint64_t fr, ip = split_pow10(q, prec, &fr);
    return (int)(o - out) + put_fixed(o, ip, fr, prec);
}
