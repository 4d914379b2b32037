/*
 * csv_shortest.h - the default text form of a double in the setpoint CSV:
 * the shortest decimal that reads back to the same double, written as
 * Python's repr() writes it (so a value printed by trajd reads back bit for
 * bit with strtod, float() or numpy, and equals repr(float(field))).
 *
 * The digits come from Dragonbox (Debian libdragonbox-dev, through
 * csv_dragonbox.cc): the fewest significant digits that round to x under
 * round-to-nearest-even, the closest to x of those.  The layout is repr's:
 * fixed notation when the decimal exponent is -4 < decpt <= 16 (with ".0"
 * added to an integer, "0.0001", "1234.5", "1e+16" is the first in exponent
 * form), else d.ddde+XX / e-XX with at least two exponent digits; "-0.0"
 * for negative zero; "inf", "-inf" and "nan" (repr drops NaN's sign).
 *
 * tests/unit/test_csv_shortest.c checks the round trip (strtod) over millions
 * of random doubles and the edge cases, and that it never has more digits
 * than %.17g; tests/oracle/test_csv_shortest.py compares with Python's repr.
 */
#ifndef TRAJD_CSV_SHORTEST_H
#define TRAJD_CSV_SHORTEST_H

#include <stdint.h>

/* The longest output: "-1.2345678901234567e-308" is 24 characters,
 * "-0.00012345678901234567" 23. */
#define CSV_SHORTEST_LEN 24
/* Room out must have: the writer copies fixed-size blocks and may write
 * bytes past the returned length (never past out + CSV_SHORTEST_MAX). */
#define CSV_SHORTEST_MAX 48

/* Write x into out (at least CSV_SHORTEST_MAX bytes, no terminating NUL).
 * Returns the length, at most CSV_SHORTEST_LEN. */
int csv_shortest(char *out, double x);

/* The 8 ASCII digits of v < 10^8, zero padded, first digit in the lowest byte. */
uint64_t csv_digits8(uint32_t v);

/* Dragonbox (csv_dragonbox.cc): |x| = sig * 10^exp10, x finite and nonzero. */
void csv_dragonbox(double x, uint64_t *sig, int *exp10);

#endif
