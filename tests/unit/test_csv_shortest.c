/*
 * test_csv_shortest.c - csv_shortest(), the default number form of the
 * setpoint CSV, against the C library:
 *   - strtod reads every output back to the same double, bit for bit, over
 *     millions of random bit patterns and of values in the ranges setpoints
 *     take (the round trip printf("%.17g") -> strtod also gives, checked on
 *     the same values as the reference);
 *   - it never has more significant digits than the fewest N for which
 *     printf("%.Ng") reads back (glibc's correctly rounded digits);
 *   - the layout: repr's fixed/exponent switch, ".0", signs, inf and nan.
 * tests/oracle/test_csv_shortest.py compares the same function with
 * Python's repr, through this program's --print mode (hex bit patterns on
 * stdin, one output per line).
 */
#include "test.h"

#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "csv_format.h"
#include "csv_shortest.h"

static unsigned long checked;

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static uint64_t rnd64(void) /* xorshift64*: reproducible test data */
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 0x2545F4914F6CDD1Dull;
}

static double from_bits(uint64_t b)
{
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

static int same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* Significant digits of a decimal string (mantissa digits, leading zeros not counted). */
static int sig_count(const char *s)
{
    int n = 0, started = 0, trailing = 0;
    for (; *s && *s != 'e'; s++) {
        if (*s < '0' || *s > '9')
            continue;
        if (*s != '0')
            started = 1;
        if (started) {
            n++;
            trailing = *s == '0' ? trailing + 1 : 0;
        }
    }
    return n - trailing;
}

/* x (finite) round-trips through csv_shortest and through %.17g. */
static void check_roundtrip(double x)
{
    char got[CSV_SHORTEST_MAX + 1], ref[40];
    int n = csv_shortest(got, x);
    assert_true(n > 0 && n <= CSV_SHORTEST_MAX);
    got[n] = '\0';
    double back = strtod(got, NULL);
    snprintf(ref, sizeof ref, "%.17g", x);
    if (!same_bits(back, x) || !same_bits(strtod(ref, NULL), x)) {
        print_error("x = %a: csv_shortest '%s' reads back as %a (%%.17g '%s')\n", x, got, back,
                    ref);
        fail();
    }
    checked++;
}

/* No more digits than the shortest %.Ng that reads back. */
static void check_shortest(double x)
{
    char got[CSV_SHORTEST_MAX + 1], ref[40];
    int n = csv_shortest(got, x);
    got[n] = '\0';
    int p;
    for (p = 1; p < 17; p++) {
        snprintf(ref, sizeof ref, "%.*g", p, x);
        if (same_bits(strtod(ref, NULL), x))
            break;
    }
    if (sig_count(got) > p) {
        print_error("x = %a: '%s' has %d digits, printf's %%.%dg reads back\n", x, got,
                    sig_count(got), p);
        fail();
    }
}

static void test_random_bits(void **state)
{
    (void)state;
    for (long i = 0; i < 2000000; i++) {
        double x = from_bits(rnd64());
        if (isfinite(x))
            check_roundtrip(x);
        if (i % 10 == 0 && isfinite(x))
            check_shortest(x);
    }
}

/* Values as setpoints have them: metres to thousands of km, speeds,
 * accelerations, times, and short decimals (waypoints typed by hand). */
static void test_typical(void **state)
{
    (void)state;
    for (long i = 0; i < 2000000; i++) {
        double mag = ldexp(1.0, (int)(rnd64() % 60) - 30);
        double x = mag * ((double)(rnd64() >> 11) * 0x1p-53 - 0.5);
        check_roundtrip(x);
        double d = (double)((int64_t)(rnd64() % 2000001) - 1000000) / 1000.0; /* 3 decimals */
        check_roundtrip(d);
        if (i % 10 == 0) {
            check_shortest(x);
            check_shortest(d);
        }
    }
}

static void expect(double x, const char *want)
{
    char got[CSV_SHORTEST_MAX + 1];
    int n = csv_shortest(got, x);
    got[n] = '\0';
    assert_string_equal(got, want);
}

/* The layout (the strings are what Python 3's repr prints). */
static void test_layout(void **state)
{
    (void)state;
    expect(0.0, "0.0");
    expect(-0.0, "-0.0");
    expect(1.0, "1.0");
    expect(-2.5, "-2.5");
    expect(0.1, "0.1");
    expect(0.0001, "0.0001");
    expect(0.00001, "1e-05");
    expect(0.000123, "0.000123");
    expect(1e15, "1000000000000000.0");
    expect(1e16, "1e+16");
    expect(1.5e16, "1.5e+16");
    expect(9007199254740993.0, "9007199254740992.0");
    expect(123456789.125, "123456789.125");
    expect(6378137.1234567891, "6378137.123456789");
    expect(1e300, "1e+300");
    expect(1e-300, "1e-300");
    expect(DBL_MAX, "1.7976931348623157e+308");
    expect(-DBL_MIN, "-2.2250738585072014e-308");
    expect(4.9406564584124654e-324, "5e-324");
    expect(0.3, "0.3");
    expect(0.1 + 0.2, "0.30000000000000004");
    expect(2.0 / 3.0, "0.6666666666666666");
    expect(INFINITY, "inf");
    expect(-INFINITY, "-inf");
    expect(NAN, "nan");
    expect(-NAN, "nan");
    /* every power of two and of ten (the asymmetric rounding interval at 2^k) */
    for (int e = -1074; e <= 1023; e++)
        check_roundtrip(ldexp(1.0, e));
    for (int e = -323; e <= 308; e++)
        check_roundtrip(pow(10.0, e));
}

/* csv_digits8 against division for every v < 10^8 (the sanitizer pass, which
 * looks for memory faults an arithmetic loop cannot make, every 97th: the
 * whole range took 26 s of make check's sanitizer pass). */
#if defined(__SANITIZE_ADDRESS__)
#define DIGITS8_STRIDE 97u
#else
#define DIGITS8_STRIDE 1u
#endif
static void test_digits8(void **state)
{
    (void)state;
    unsigned long bad = 0;
    for (uint32_t v = 0; v < 100000000u; v += DIGITS8_STRIDE) {
        uint64_t got = csv_digits8(v), want = 0;
        uint32_t u = v;
        for (int i = 7; i >= 0; i--) {
            want |= (uint64_t)('0' + u % 10) << (8 * i);
            u /= 10;
        }
        if (got != want && bad++ < 5)
            print_error("csv_digits8(%" PRIu32 ") = %016" PRIx64 ", want %016" PRIx64 "\n", v, got,
                        want);
    }
    assert_int_equal(bad, 0);
}

/* The default CSV line is the shortest form of each field. */
static void test_line(void **state)
{
    (void)state;
    engine_setpoint_t sp = {
        .now_ns = -123456789012345,
        .t_s = 1234.5,
        .pos_m = {-0.0, 6378137.1234567891, -1e-12},
        .vel_m_s = {2.5, -2.5, 1e300},
        .acc_m_s2 = {NAN, -INFINITY, 0.1},
        .state = ENGINE_STATE_STREAMING,
        .flags = 9,
        .cycle = 4294967295u,
        .track = 7,
    };
    char got[CSV_FORMAT_LINE_MAX];
    const char *want = "obj,-123456789012345,1234.5,-0.0,6378137.123456789,-1e-12,2.5,-2.5,"
                       "1e+300,nan,-inf,0.1,streaming,9,4294967295,7\n";
    int n = csv_format_format(got, sizeof got, "obj", &sp);
    assert_int_equal(n, (int)strlen(want));
    assert_string_equal(got, want);
    assert_int_equal(csv_format_format(got, (size_t)n, "obj", &sp), -1); /* one byte short */
    /* the former default, kept as --precision g17 */
    char g17[1024], ref[1024];
    snprintf(ref, sizeof ref,
             "obj,-123456789012345,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
             "streaming,9,4294967295,7\n",
             sp.t_s, sp.pos_m[0], sp.pos_m[1], sp.pos_m[2], sp.vel_m_s[0], sp.vel_m_s[1],
             sp.vel_m_s[2], sp.acc_m_s2[0], sp.acc_m_s2[1], sp.acc_m_s2[2]);
    assert_int_equal(csv_format_format_prec(g17, sizeof g17, "obj", &sp, CSV_PREC_G17),
                     (int)strlen(ref));
    assert_string_equal(g17, ref);
    assert_int_equal(csv_format_format_prec(g17, sizeof g17, "obj", &sp, -3), -1);
}

/* --print: hex bit patterns on stdin, csv_shortest of each on stdout. */
static int print_mode(void)
{
    char line[64], out[CSV_SHORTEST_MAX + 1];
    while (fgets(line, sizeof line, stdin)) {
        int n = csv_shortest(out, from_bits(strtoull(line, NULL, 16)));
        out[n] = '\0';
        puts(out);
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--print") == 0)
        return print_mode();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout),      cmocka_unit_test(test_digits8),
        cmocka_unit_test(test_line),        cmocka_unit_test(test_typical),
        cmocka_unit_test(test_random_bits),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    print_message("%lu values read back with strtod\n", checked);
    return rc;
}
