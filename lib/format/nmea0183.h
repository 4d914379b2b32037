/*
 * nmea0183.h - NMEA 0183 position sentences, pure (no I/O): the checksum and
 * the GGA and RMC sentences of any talker ($GPGGA, $GNRMC, ...), and VTG's
 * course and speed.
 *
 *   $--GGA,hhmmss.ss,ddmm.mmmm,N,dddmm.mmmm,E,q,nn,hdop,alt,M,sep,M,age,ref*hh
 *   $--RMC,hhmmss.ss,A,ddmm.mmmm,N,dddmm.mmmm,E,sog,cog,ddmmyy,var,E[,mode]*hh
 *   $--VTG,cog,T,cogm,M,sog,N,kmh,K[,mode]*hh     (no time: of the epoch it follows)
 *
 * The checksum ("*hh", the XOR of every byte between '$' and '*') is
 * required and verified.  GGA altitude is above mean sea level (the geoid);
 * the separation field is kept apart.  A GGA with quality 0 or an RMC with
 * status V carries no valid fix (valid = 0).
 */
#ifndef TRAJD_NMEA0183_H
#define TRAJD_NMEA0183_H
/* trajd public API: installed as <trajd/nmea0183.h> (make install; pkg-config trajd). */

#include <stdint.h>

enum nmea0183_error {
    NMEA0183_OK = 0,
    NMEA0183_ESYNTAX = 1,   /* not a sentence, or a field that does not parse */
    NMEA0183_ECHECKSUM = 2, /* missing or wrong checksum */
    NMEA0183_ERANGE = 3,    /* time, date, latitude or longitude out of range */
};

const char *nmea0183_strerror(int err);

typedef enum { NMEA0183_OTHER = 0, NMEA0183_GGA, NMEA0183_RMC, NMEA0183_VTG } nmea0183_kind_t;

typedef struct {
    nmea0183_kind_t kind;
    int valid;    /* GGA quality > 0, RMC status A */
    int has_pos;  /* latitude and longitude present */
    double tod_s; /* time of day, [0, 86400) */
    double lat_deg, lon_deg;
    double alt_m;   /* GGA altitude above MSL, NaN if empty or RMC */
    double sep_m;   /* GGA geoid separation, NaN if empty */
    int has_date;   /* RMC */
    int64_t days;   /* RMC date, days since 1970-01-01 (years 1980-2079) */
    int has_vel;    /* RMC, VTG: speed over ground given, and the course (or a speed of 0);
                     VTG mode N (not valid): 0 */
    double sog_m_s; /* speed over ground, m/s (knots x 1852 / 3600; VTG: km/h if no knots) */
    double cog_deg; /* course over ground, degrees true, [0, 360] (0 with a speed of 0) */
} nmea0183_fix_t;

/*
 * Parse one sentence (a NUL-terminated line, leading/trailing blanks and
 * '\r' allowed).  Sentences other than GGA and RMC with a good checksum give
 * kind NMEA0183_OTHER.  Returns 0, -NMEA0183_ESYNTAX, -NMEA0183_ECHECKSUM,
 * -NMEA0183_ERANGE.
 */
int nmea0183_parse(const char *line, nmea0183_fix_t *out);

#endif
