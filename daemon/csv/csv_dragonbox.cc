// csv_dragonbox.cc - the one C++ file: Debian's libdragonbox-dev (header-only,
// Junekey Jeon's Dragonbox) behind a C function, for csv_shortest.h.
#include <cstdint>

#include <dragonbox/dragonbox.h>

extern "C" void csv_dragonbox(double x, uint64_t *sig, int *exp10);

// x finite and nonzero, either sign: |x| = sig * 10^exp10 with the fewest
// digits that read back to x (round to nearest, ties to even, as strtod does),
// the closest such when several have that many, and no trailing zeros in sig.
extern "C" void csv_dragonbox(double x, uint64_t *sig, int *exp10)
{
    auto d = jkj::dragonbox::to_decimal(x, jkj::dragonbox::policy::sign::ignore);
    *sig = d.significand;
    *exp10 = d.exponent;
}
