/*
 * igc.h - IGC flight recorder records (FAI IGC "Technical Specification for
 * IGC-approved GNSS flight recorders", appendix A), pure (no I/O): the date
 * header and the B (fix) record.
 *
 *   HFDTEddmmyy  or  HFDTEDATE:ddmmyy[,nn]      date of the first fix (UTC)
 *   BhhmmssDDMMmmmNDDDMMmmmEVPPPPPGGGGG[ext]    fix: time (UTC), latitude and
 *        longitude in degrees and thousandths of minutes, validity A (3-D) or
 *        V (2-D / no GNSS altitude), pressure altitude and GNSS altitude in
 *        metres (5 characters each, may be negative "-0012")
 * Precision is what the format holds: 0.001' (1.85 m north-south), 1 m, 1 s.
 */
#ifndef TRAJD_IGC_H
#define TRAJD_IGC_H
/* trajd public API: installed as <trajd/igc.h> (make install; pkg-config trajd). */

#include <stdint.h>

enum igc_error {
    IGC_OK = 0,
    IGC_ESYNTAX = 1, /* not a B record / date header, or a field does not parse */
    IGC_ERANGE = 2,  /* time, date, latitude or longitude out of range */
};

const char *igc_strerror(int err);

typedef struct {
    int tod_s; /* time of day, seconds [0, 86400) */
    double lat_deg, lon_deg;
    int valid_3d; /* validity A */
    int pressure_alt_m;
    int gnss_alt_m;
} igc_fix_t;

/* Parse a B record (the whole line; extensions after the 35 characters are
 * allowed).  Returns 0, -IGC_ESYNTAX, -IGC_ERANGE. */
int igc_parse_b(const char *line, igc_fix_t *out);

/* Parse an HFDTE header into days since 1970-01-01 (two-digit years 80..99
 * are 1980..1999, others 2000..2079).  Returns 0, -IGC_ESYNTAX, -IGC_ERANGE. */
int igc_parse_date(const char *line, int64_t *days);

#endif
