/*
 * test.h - what the C unit tests (tests/unit/) and benchmarks (tests/bench/)
 * share, instead of copies in each file:
 *   - cmocka's include block: cmocka.h needs stdarg.h, stddef.h, stdint.h and
 *     setjmp.h before it;
 *   - urand(), a reproducible pseudo-random number in [0, 1] from a seed the
 *     test owns (an LCG: the same numbers on every machine and libc, so a
 *     failure can be replayed; not for anything but test data);
 *   - now_s(), CLOCK_MONOTONIC in seconds, for the benchmarks only (tests
 *     make no timed assertions);
 *   - test_write_file(), a file of given text in a test's temporary directory.
 * Header-only (static inline): a file that uses none of them pays nothing.
 */
#ifndef TRAJD_TEST_H
#define TRAJD_TEST_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <time.h>

/* Next number of the sequence seeded by *s, uniform in [0, 1] in steps of 1/65535. */
static inline double urand(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return ((*s >> 8) & 0xffff) / 65535.0;
}

/* Write text to the file dir/name (tests that make files in a temporary
 * directory: configurations, tracks); a failure fails the test. */
static inline void test_write_file(const char *dir, const char *name, const char *text)
{
    char path[256];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* Monotonic time in seconds (benchmarks). */
static inline double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

#endif
