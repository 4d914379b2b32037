/*
 * geo.h - WGS84 geodetic coordinates to local east/north/up metres.
 *
 * Pure (no I/O, no allocation).  The route is the exact one, not a flat
 * approximation: geodetic (lat, lon, h) -> Earth-centred Earth-fixed (ECEF)
 * on the WGS84 ellipsoid -> rotation into the east/north/up frame tangent
 * to the ellipsoid at an origin.  "Up" is along the ellipsoid normal at the
 * origin, so a point at the origin's height 1 km away has up ~ -8 cm (the
 * Earth curves away); that is correct, not an error.
 *
 * Precision: ECEF coordinates are ~6.4e6 m, so one ulp is ~1e-9 m; the
 * difference and the rotation lose nothing at the millimetre level for any
 * distance on Earth (tests/unit/test_geo.c checks it against pyproj).
 */
#ifndef TRAJD_GEO_H
#define TRAJD_GEO_H
/* trajd public API: installed as <trajd/geo.h> (make install; pkg-config trajd). */

/* WGS84 defining constants (NIMA TR8350.2, table 3.1). */
#define GEO_WGS84_A_M 6378137.0       /* semi-major axis */
#define GEO_WGS84_INV_F 298.257223563 /* inverse flattening */

/* Heights accepted, metres: from the deepest ocean trench to low orbit.
 * Anything outside is a data error (a wrong column or unit), not a place. */
#define GEO_ALT_MIN_M (-12000.0)
#define GEO_ALT_MAX_M 1.0e6

enum geo_error {
    GEO_OK = 0,
    GEO_ENOTFINITE = 1, /* NaN or infinite latitude, longitude or height */
    GEO_ELAT = 2,       /* latitude outside [-90, 90] degrees */
    GEO_ELON = 3,       /* longitude outside [-360, 360] degrees */
    GEO_EALT = 4,       /* height outside [GEO_ALT_MIN_M, GEO_ALT_MAX_M] */
};

/* Human-readable text for a geo_error (positive or negated). */
const char *geo_strerror(int err);

/* An ENU frame: its origin in ECEF and the rotation, computed once. */
typedef struct {
    double lat0_deg, lon0_deg, alt0_m;
    double ecef0_m[3];
    double sin_lat, cos_lat, sin_lon, cos_lon;
} geo_enu_t;

/*
 * Check a geodetic position.  Returns 0 or a negated geo_error
 * (-GEO_ENOTFINITE, -GEO_ELAT, -GEO_ELON, -GEO_EALT).
 */
int geo_check(double lat_deg, double lon_deg, double alt_m);

/*
 * Geodetic (degrees, degrees, metres above the ellipsoid) to ECEF metres.
 * Returns 0, or the error of geo_check (ecef_m then untouched).
 */
int geo_to_ecef(double lat_deg, double lon_deg, double alt_m, double ecef_m[3]);

/*
 * Set up an ENU frame about an origin.  Returns 0, or the error of
 * geo_check (frame then untouched).
 */
int geo_enu_init(double lat0_deg, double lon0_deg, double alt0_m, geo_enu_t *frame);

/*
 * Position in the frame: enu_m[0] east, [1] north, [2] up, metres.
 * Returns 0, or the error of geo_check (enu_m then untouched).
 */
int geo_to_enu(const geo_enu_t *frame, double lat_deg, double lon_deg, double alt_m,
               double enu_m[3]);

/* A vector (a velocity, a difference of positions) between ECEF axes and the
 * frame's east/north/up axes: the rotation geo_to_enu applies, and back. */
void geo_vec_to_enu(const geo_enu_t *frame, const double ecef[3], double enu[3]);
void geo_vec_from_enu(const geo_enu_t *frame, const double enu[3], double ecef[3]);

/*
 * ECEF metres to geodetic (degrees in [-90, 90] and (-180, 180], metres
 * above the ellipsoid): Bowring's parametric-latitude iteration (B. R.
 * Bowring, "Transformation from spatial to geographical coordinates",
 * Survey Review 23(181), 1976), run to a fixed point; converges to
 * ~1e-12 degrees within a few rounds anywhere within GEO_ALT_MAX_M of the
 * ellipsoid.  Returns 0, or -GEO_ENOTFINITE.
 */
int geo_from_ecef(const double ecef_m[3], double *lat_deg, double *lon_deg, double *alt_m);

/* The inverse of geo_to_enu: east/north/up metres about frame's origin to
 * geodetic.  Returns 0, or -GEO_ENOTFINITE. */
int geo_from_enu(const geo_enu_t *frame, const double enu_m[3], double *lat_deg, double *lon_deg,
                 double *alt_m);

/* The geodetic latitude and longitude of the point at height alt_m whose
 * east and north in frame are east_m, north_m: the inverse of geo_to_enu's
 * first two coordinates at a known height.  A track with no altitude is
 * expressed at the frame origin's height with up taken as 0; its setpoints
 * go back to WGS84 this way (geo_from_enu of up = 0 is a point on the
 * tangent plane, 784 m above the ellipsoid and 12 m off in latitude 100 km
 * from the origin).  Returns 0, or -GEO_ENOTFINITE. */
int geo_from_enu_at(const geo_enu_t *frame, double east_m, double north_m, double alt_m,
                    double *lat_deg, double *lon_deg);

/* A setpoint of a track expressed about frame back to geodetic: out = lat,
 * lon (degrees), alt (metres).  no_alt: the track had no altitude (up 0 at
 * the frame origin's height): at that height, alt NaN (geo_from_enu_at);
 * else geo_from_enu.  Returns 0, or -GEO_ENOTFINITE (out then all NaN). */
int geo_from_enu_track(const geo_enu_t *frame, const double enu_m[3], int no_alt, double out[3]);

#endif
