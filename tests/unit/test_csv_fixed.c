/*
 * test_csv_fixed.c - csv_fixed() against glibc's printf("%.*f") (the
 * reference: exact decimal expansion, round half to even) over random doubles
 * of every magnitude, decimals with ties and their neighbours, and the edge
 * cases; csv_format_format_prec's line against one snprintf of the same
 * fields.
 */
#include "test.h"

#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "csv_fixed.h"
#include "csv_format.h"

static unsigned long checked;

/* csv_fixed's slow path is the C library's snprintf.  This program's own
 * snprintf, to which the linker binds csv_fixed.o's call (and every other),
 * hands each call to vsnprintf and counts those made from inside csv_fixed:
 * how often csv_fixed needed snprintf. */
static int in_csv_fixed;
static unsigned long slow_calls;

int snprintf(char *restrict s, size_t n, const char *restrict fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    slow_calls += (unsigned long)in_csv_fixed;
    int r = vsnprintf(s, n, fmt, ap);
    va_end(ap);
    return r;
}

/* csv_fixed(x, prec) is printf's string. */
static void check(double x, int prec)
{
    char want[CSV_FIXED_MAX + 64], got[CSV_FIXED_MAX + 8];
    int wn = snprintf(want, sizeof want, "%.*f", prec, x);
    in_csv_fixed = 1;
    int gn = csv_fixed(got, x, prec);
    in_csv_fixed = 0;
    got[gn] = '\0';
    if (gn != wn || strcmp(got, want) != 0) {
        print_error("x = %a (%.17g) prec %d: got '%s', printf '%s'\n", x, x, prec, got, want);
        fail();
    }
    checked++;
}

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rnd64(void) /* xorshift64*: reproducible test data */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}

/* Given the edge cases, then printf's output for each precision. */
static void test_edges(void **state)
{
    (void)state;
    static const double xs[] = {
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.5,
        2.5,
        -2.5,
        0.125,
        0.375,
        1e-300,
        -1e-300,
        5e-324,
        DBL_MIN,
        DBL_MAX,
        -DBL_MAX,
        4503599627370495.5,
        4503599627370496.0,
        9007199254740993.0,
        1e15 + 0.5,
        0.05,
        0.15,
        0.25,
        0.35,
        1.005,
        2.675,
        0.0000000005,
        0.0000000015,
        0.0000000025,
        999999.9999999995,
        9.5,
        99.5,
        0.49999999999999994,
        1e22,
        1e23,
        123456789.123456789,
        -1e-10,
        -0.0004,
        6378137.0,
        6378137.123456789,
        1e308,
        1.7976931348623157e308,
    };
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++)
        for (int p = 0; p <= CSV_FIXED_PREC_MAX + 3; p++) {
            check(xs[i], p);
            check(nextafter(xs[i], INFINITY), p);
            check(nextafter(xs[i], -INFINITY), p);
        }
    for (int p = 0; p <= 20; p++) {
        check(NAN, p);
        check(-NAN, p);
        check(INFINITY, p);
        check(-INFINITY, p);
    }
}

/* Given random bit patterns of every exponent, then printf's output. */
static void test_random_bits(void **state)
{
    (void)state;
    for (long i = 0; i < 400000; i++) {
        uint64_t b = rnd64();
        /* exponents spread over 2^-70 .. 2^70 mostly, all of them sometimes */
        if (i % 8) {
            uint64_t e = 1023 - 70 + rnd64() % 141;
            b = (b & 0x800FFFFFFFFFFFFFull) | (e << 52);
        }
        double x;
        memcpy(&x, &b, sizeof x);
        check(x, (int)(rnd64() % (CSV_FIXED_PREC_MAX + 1)));
    }
}

/* Given decimals k / 10^m (ties at precision m - 1 when k ends in 5) and
 * their neighbours one and two ulps away, then printf's output. */
static void test_near_ties(void **state)
{
    (void)state;
    for (long i = 0; i < 300000; i++) {
        int m = 1 + (int)(rnd64() % 17);
        double k = (double)(rnd64() % 100000000000ull);
        if (i % 2)
            k = floor(k / 10) * 10 + 5; /* ...5: a decimal tie one place up */
        double x = k / pow(10, m);
        if (i % 3 == 1)
            x = nextafter(x, INFINITY);
        else if (i % 3 == 2)
            x = nextafter(nextafter(x, -INFINITY), -INFINITY);
        if (i % 5 == 0)
            x = -x;
        check(x, m - 1);
        check(x, m);
    }
}

/* Given positions, speeds and accelerations as the engine writes them
 * (|x| < 9e6 m, prec 9), then exact, and snprintf is rarely needed. */
static void test_typical_fast(void **state)
{
    (void)state;
    unsigned long slow0 = slow_calls;
    long n = 300000;
    for (long i = 0; i < n; i++) {
        double x = ((double)(rnd64() >> 11) / 9007199254740992.0 - 0.5) * 1.8e7; /* +-9e6 m */
        x /= (double)(1u << (rnd64() % 30));
        check(x, 9);
    }
    unsigned long slow = slow_calls - slow0;
    print_message("%lu of %ld typical values needed snprintf\n", slow, n);
    assert_true(slow * 1000 < (unsigned long)n);
    /* the count sees a call: a precision beyond the fast path's takes snprintf */
    slow0 = slow_calls;
    check(0.1, CSV_FIXED_PREC_MAX + 1);
    assert_int_equal(slow_calls - slow0, 1);
}

/* Given a setpoint, then the --precision line is the %.Nf of each field. */
static void test_line(void **state)
{
    (void)state;
    engine_setpoint_t sp = {
        .now_ns = 123456789012345,
        .t_s = 1234.5678901234,
        .pos_m = {-0.0, 6378137.1234567891, -1e-12},
        .vel_m_s = {2.5, -2.5, 1e300},
        .acc_m_s2 = {NAN, -INFINITY, 0.1},
        .state = ENGINE_STATE_STREAMING,
        .flags = 9,
        .cycle = 4294967295u,
        .track = 7,
    };
    for (int p = 0; p <= CSV_FIXED_PREC_MAX; p++) {
        char want[8192], got[8192];
        snprintf(want, sizeof want,
                 "obj,%" PRId64 ",%.*f,%.*f,%.*f,%.*f,%.*f,%.*f,%.*f,%.*f,%.*f,%.*f,streaming,9,"
                 "4294967295,7\n",
                 sp.now_ns, p, sp.t_s, p, sp.pos_m[0], p, sp.pos_m[1], p, sp.pos_m[2], p,
                 sp.vel_m_s[0], p, sp.vel_m_s[1], p, sp.vel_m_s[2], p, sp.acc_m_s2[0], p,
                 sp.acc_m_s2[1], p, sp.acc_m_s2[2]);
        int n = csv_format_format_prec(got, sizeof got, "obj", &sp, p);
        assert_int_equal(n, (int)strlen(want));
        assert_string_equal(got, want);
        /* a buffer one byte short of the line: refused, not cut */
        assert_int_equal(csv_format_format_prec(got, (size_t)n, "obj", &sp, p), -1);
    }
    sp.now_ns = -5;
    char a[1024], b[1024];
    /* negative now_ns and the default form */
    assert_true(csv_format_format_prec(a, sizeof a, "o", &sp, 3) > 0);
    assert_true(strncmp(a, "o,-5,1234.568,", 14) == 0);
    assert_int_equal(csv_format_format_prec(a, sizeof a, "o", &sp, CSV_PREC_SHORTEST),
                     csv_format_format(b, sizeof b, "o", &sp));
    assert_string_equal(a, b);
    assert_int_equal(csv_format_format_prec(a, sizeof a, "o,x", &sp, 3), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edges),     cmocka_unit_test(test_random_bits),
        cmocka_unit_test(test_near_ties), cmocka_unit_test(test_typical_fast),
        cmocka_unit_test(test_line),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    print_message("%lu values compared with printf\n", checked);
    return rc;
}
