/*
 * csv_fixed.h - fast fixed-notation formatting of a double, exactly what
 * printf("%.*f", prec, x) writes in the C locale.
 *
 * Fast path: x * 10^prec is formed exactly as a double-double (Dekker's
 * two-product: no FMA needed), rounded to the nearest integer with the
 * remainder compared exactly against one half, and the integer written with a
 * two-digit table.  Where that cannot be exact - |x| * 10^prec >= 2^53
 * (|x| >= 9e6 at 9 decimals), a tie or a remainder within a rounding of one
 * half, NaN, infinity, prec > 17 - it
 * falls back to snprintf, so the output is printf's in every case
 * (tests/unit/test_csv_fixed.c checks it over millions of random values and
 * the edge cases).  Negative zero and negative values that round to zero keep
 * their '-' as printf does.
 */
#ifndef TRAJD_CSV_FIXED_H
#define TRAJD_CSV_FIXED_H

#include <stddef.h>

/* Largest precision the fast path takes (10^prec exact in a double and an
 * integer part left for positions); more goes to snprintf. */
#define CSV_FIXED_PREC_MAX 17
/* printf("%.40f", -DBL_MAX) is 1 + 309 + 1 + 40 characters. */
#define CSV_FIXED_MAX 352

/* Write printf("%.*f", prec, x) into out (at least CSV_FIXED_MAX bytes, no
 * terminating NUL written).  prec in 0..40.  Returns the length. */
int csv_fixed(char *out, double x, int prec);

#endif
