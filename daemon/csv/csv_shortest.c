/* csv_shortest.c - shortest round-trip double in repr() form; see csv_shortest.h. */
#include "csv_shortest.h"

#include <math.h>
#include <string.h>

static const char digits2[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/*
 * The eight ASCII digits of v < 10^8, zero padded, the first in the lowest
 * byte (little-endian memory order), computed in a register: v is split into
 * two 4-digit halves in the two 32-bit lanes, each into two 2-digit halves in
 * 16-bit lanes, each into two digits in bytes, by multiplications with
 * reciprocals exact in these ranges (tests/unit/test_csv_shortest.c checks
 * every v < 10^8).  x86-64 is little-endian, as the byte swap assumes.
 */
uint64_t csv_digits8(uint32_t v)
{
    uint64_t x = v + (((uint64_t)1 << 32) - 10000) * (((uint64_t)v * 109951163) >> 40);
    x += (((uint64_t)1 << 16) - 100) * (((x * 5243) >> 19) & 0x0000007F0000007Full);
    x += (((uint64_t)1 << 8) - 10) * (((x * 103) >> 10) & 0x000F000F000F000Full);
    return __builtin_bswap64(x) + 0x3030303030303030ull;
}

/*
 * A number's digits are written with 8- and 16-byte stores of register
 * values, each in its final place, the line's later bytes overwriting the
 * zero bytes a store leaves past its digits.  A first version built the
 * digits in a scratch buffer with 2-byte stores and copied them: the 16-byte
 * load of freshly stored bytes cannot be forwarded from the store buffer
 * (a store-forwarding stall, the hottest instruction in perf annotate), and
 * a chain of divisions by 100 came next.
 */
typedef struct {
    char first;          /* padded digit 0 ('0' + sig / 10^16) */
    unsigned __int128 x; /* padded digits 1..16, digit 1 in the lowest byte */
} digits17_t;

static digits17_t digits17(uint64_t sig) /* sig < 10^17 */
{
    digits17_t d;
    uint64_t r = sig % 10000000000000000ull;
    d.first = (char)('0' + sig / 10000000000000000ull);
    d.x = csv_digits8((uint32_t)(r / 100000000)) |
          (unsigned __int128)csv_digits8((uint32_t)(r % 100000000)) << 64;
    return d;
}

/* Padded digits p..16 at o (p 0..16), and zero bytes up to o + 17 - p + 16. */
static void put_from(char *o, const digits17_t *d, int p)
{
    unsigned __int128 v = d->x;
    if (p == 0)
        *o++ = d->first;
    else
        v >>= 8 * (p - 1);
    memcpy(o, &v, 16);
}

static const uint64_t pow10_u64[18] = {1ull,
                                       10ull,
                                       100ull,
                                       1000ull,
                                       10000ull,
                                       100000ull,
                                       1000000ull,
                                       10000000ull,
                                       100000000ull,
                                       1000000000ull,
                                       10000000000ull,
                                       100000000000ull,
                                       1000000000000ull,
                                       10000000000000ull,
                                       100000000000000ull,
                                       1000000000000000ull,
                                       10000000000000000ull,
                                       100000000000000000ull};

/* Decimal digits of v, 1 <= v < 10^17. */
static int count_digits(uint64_t v)
{
    /* log10(2) ~ 1233 / 4096: the count from the bit length, or one less */
    int b = 64 - __builtin_clzll(v);
    int n = (b * 1233 >> 12) + 1;
    return v < pow10_u64[n - 1] ? n - 1 : n;
}

/* sig (n digits) as repr writes it with the point after decpt digits. */
static int put_repr(char *o, uint64_t sig, int n, int decpt)
{
    digits17_t d = digits17(sig);
    int z = 17 - n;                  /* padded index of the first significant digit */
    if (decpt > 16 || decpt <= -4) { /* d.ddde+XX */
        int e = decpt - 1;
        char *p = o;
        put_from(p, &d, z);
        if (n > 1) {
            p[1] = '.';
            put_from(p + 2, &d, z + 1);
            p += n + 1;
        } else {
            p++;
        }
        *p++ = 'e';
        *p++ = e < 0 ? '-' : '+';
        unsigned a = (unsigned)(e < 0 ? -e : e);
        if (a >= 100)
            *p++ = (char)('0' + a / 100);
        memcpy(p, digits2 + 2 * (a % 100), 2);
        return (int)(p + 2 - o);
    }
    if (decpt <= 0) { /* 0.000ddd */
        memcpy(o, "0.000000", 8);
        put_from(o + 2 - decpt, &d, z);
        return 2 - decpt + n;
    }
    put_from(o, &d, z);
    if (decpt >= n) { /* ddd000.0 */
        memset(o + n, '0', 16);
        memcpy(o + decpt, ".0", 2);
        return decpt + 2;
    }
    o[decpt] = '.'; /* ddd.ddd */
    put_from(o + decpt + 1, &d, z + decpt);
    return n + 1;
}

int csv_shortest(char *out, double x)
{
    char *o = out;
    if (isnan(x)) {
        memcpy(out, "nan", 3);
        return 3;
    }
    if (signbit(x))
        *o++ = '-';
    if (isinf(x)) {
        memcpy(o, "inf", 3);
        return (int)(o + 3 - out);
    }
    if (fpclassify(x) == FP_ZERO) {
        memcpy(o, "0.0", 3);
        return (int)(o + 3 - out);
    }
    uint64_t sig;
    int e10;
    csv_dragonbox(x, &sig, &e10);
    int n = count_digits(sig);
    return (int)(o - out) + put_repr(o, sig, n, e10 + n); /* |x| = 0.d * 10^(e10 + n) */
}
