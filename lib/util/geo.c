/* geo.c - WGS84 geodetic -> ECEF -> local ENU.  See geo.h. */
#include "geo.h"

#include <math.h>

#define DEG_TO_RAD (3.14159265358979323846 / 180.0)

const char *geo_strerror(int err)
{
    switch (err < 0 ? -err : err) {
    case GEO_OK: return "success";
    case GEO_ENOTFINITE: return "latitude, longitude or height is not a finite number";
    case GEO_ELAT: return "latitude outside [-90, 90] degrees";
    case GEO_ELON: return "longitude outside [-360, 360] degrees";
    case GEO_EALT: return "height outside [-12000, 1000000] metres";
    default: return "unknown geo error";
    }
}

int geo_check(double lat_deg, double lon_deg, double alt_m)
{
    if (!isfinite(lat_deg) || !isfinite(lon_deg) || !isfinite(alt_m))
        return -GEO_ENOTFINITE;
    if (lat_deg < -90.0 || lat_deg > 90.0)
        return -GEO_ELAT;
    if (lon_deg < -360.0 || lon_deg > 360.0)
        return -GEO_ELON;
    if (alt_m < GEO_ALT_MIN_M || alt_m > GEO_ALT_MAX_M)
        return -GEO_EALT;
    return 0;
}

int geo_to_ecef(double lat_deg, double lon_deg, double alt_m, double ecef_m[3])
{
    int rc = geo_check(lat_deg, lon_deg, alt_m);
    if (rc)
        return rc;
    const double f = 1.0 / GEO_WGS84_INV_F;
    const double e2 = f * (2.0 - f); /* first eccentricity squared */
    double sl = sin(lat_deg * DEG_TO_RAD), cl = cos(lat_deg * DEG_TO_RAD);
    double so = sin(lon_deg * DEG_TO_RAD), co = cos(lon_deg * DEG_TO_RAD);
    /* Prime-vertical radius of curvature.  1 - e2*sl^2 >= 1 - e2 > 0.99,
     * so the square root and the division are always well defined. */
    double n_m = GEO_WGS84_A_M / sqrt(1.0 - e2 * sl * sl);
    ecef_m[0] = (n_m + alt_m) * cl * co;
    ecef_m[1] = (n_m + alt_m) * cl * so;
    ecef_m[2] = (n_m * (1.0 - e2) + alt_m) * sl;
    return 0;
}

int geo_enu_init(double lat0_deg, double lon0_deg, double alt0_m, geo_enu_t *frame)
{
    double ecef[3];
    int rc = geo_to_ecef(lat0_deg, lon0_deg, alt0_m, ecef);
    if (rc)
        return rc;
    frame->lat0_deg = lat0_deg;
    frame->lon0_deg = lon0_deg;
    frame->alt0_m = alt0_m;
    frame->ecef0_m[0] = ecef[0];
    frame->ecef0_m[1] = ecef[1];
    frame->ecef0_m[2] = ecef[2];
    frame->sin_lat = sin(lat0_deg * DEG_TO_RAD);
    frame->cos_lat = cos(lat0_deg * DEG_TO_RAD);
    frame->sin_lon = sin(lon0_deg * DEG_TO_RAD);
    frame->cos_lon = cos(lon0_deg * DEG_TO_RAD);
    return 0;
}

int geo_to_enu(const geo_enu_t *frame, double lat_deg, double lon_deg, double alt_m,
               double enu_m[3])
{
    double p[3];
    int rc = geo_to_ecef(lat_deg, lon_deg, alt_m, p);
    if (rc)
        return rc;
    const double d[3] = {p[0] - frame->ecef0_m[0], p[1] - frame->ecef0_m[1],
                         p[2] - frame->ecef0_m[2]};
    geo_vec_to_enu(frame, d, enu_m);
    return 0;
}

void geo_vec_to_enu(const geo_enu_t *frame, const double ecef[3], double enu[3])
{
    const double dx = ecef[0], dy = ecef[1], dz = ecef[2];
    const double sl = frame->sin_lat, cl = frame->cos_lat;
    const double so = frame->sin_lon, co = frame->cos_lon;
    /* Rows of the ECEF -> ENU rotation: east, north, up unit vectors. */
    enu[0] = -so * dx + co * dy;
    enu[1] = -sl * co * dx - sl * so * dy + cl * dz;
    enu[2] = cl * co * dx + cl * so * dy + sl * dz;
}

void geo_vec_from_enu(const geo_enu_t *frame, const double enu[3], double ecef[3])
{
    const double e = enu[0], n = enu[1], u = enu[2];
    const double sl = frame->sin_lat, cl = frame->cos_lat;
    const double so = frame->sin_lon, co = frame->cos_lon;
    /* the transpose of geo_vec_to_enu's rotation */
    ecef[0] = -so * e - sl * co * n + cl * co * u;
    ecef[1] = co * e - sl * so * n + cl * so * u;
    ecef[2] = cl * n + sl * u;
}

int geo_from_ecef(const double ecef_m[3], double *lat_deg, double *lon_deg, double *alt_m)
{
    const double x = ecef_m[0], y = ecef_m[1], z = ecef_m[2];
    if (!isfinite(x) || !isfinite(y) || !isfinite(z))
        return -GEO_ENOTFINITE;
    const double a = GEO_WGS84_A_M, f = 1.0 / GEO_WGS84_INV_F;
    const double b = a * (1.0 - f), e2 = f * (2.0 - f), ep2 = e2 / (1.0 - e2);
    double p = hypot(x, y);
    double lon = atan2(y, x);
    /* parametric latitude beta, then geodetic latitude from it, to a fixed point */
    double beta = atan2(z, (1.0 - f) * p), lat = 0.0;
    for (int i = 0; i < 8; i++) {
        double sb = sin(beta), cb = cos(beta);
        double nl = atan2(z + ep2 * b * sb * sb * sb, p - e2 * a * cb * cb * cb);
        double nb = atan2((1.0 - f) * sin(nl), cos(nl));
        int done = fabs(nl - lat) < 1e-15;
        lat = nl;
        beta = nb;
        if (done && i > 0)
            break;
    }
    double sl = sin(lat), cl = cos(lat);
    double n_m = a / sqrt(1.0 - e2 * sl * sl);
    /* the better-conditioned of the two height forms */
    double h = fabs(cl) > 0.7 ? p / cl - n_m : z / sl - n_m * (1.0 - e2);
    *lat_deg = lat / DEG_TO_RAD;
    *lon_deg = lon / DEG_TO_RAD;
    *alt_m = h;
    return 0;
}

int geo_from_enu(const geo_enu_t *frame, const double enu_m[3], double *lat_deg, double *lon_deg,
                 double *alt_m)
{
    if (!isfinite(enu_m[0]) || !isfinite(enu_m[1]) || !isfinite(enu_m[2]))
        return -GEO_ENOTFINITE;
    double p[3];
    geo_vec_from_enu(frame, enu_m, p);
    for (int k = 0; k < 3; k++)
        p[k] += frame->ecef0_m[k];
    return geo_from_ecef(p, lat_deg, lon_deg, alt_m);
}

int geo_from_enu_track(const geo_enu_t *frame, const double enu_m[3], int no_alt, double out[3])
{
    int rc;
    if (no_alt) {
        out[2] = NAN; /* no altitude came in, none goes out */
        rc = geo_from_enu_at(frame, enu_m[0], enu_m[1], frame->alt0_m, &out[0], &out[1]);
    } else {
        rc = geo_from_enu(frame, enu_m, &out[0], &out[1], &out[2]);
    }
    if (rc < 0)
        out[0] = out[1] = out[2] = NAN;
    return rc;
}

int geo_from_enu_at(const geo_enu_t *frame, double east_m, double north_m, double alt_m,
                    double *lat_deg, double *lon_deg)
{
    if (!isfinite(east_m) || !isfinite(north_m) || !isfinite(alt_m))
        return -GEO_ENOTFINITE;
    /* along the frame's up until the height is alt_m: the frame's up leans
     * from the normal there by the angle between them (d / R), so each round
     * takes the error down by about (d / R)^2 / 2 */
    double enu[3] = {east_m, north_m, 0.0}, h = 0.0;
    for (int i = 0; i < 8; i++) {
        int rc = geo_from_enu(frame, enu, lat_deg, lon_deg, &h);
        if (rc < 0)
            return rc;
        double d = alt_m - h;
        if (!(fabs(d) > 1e-9))
            break;
        enu[2] += d;
    }
    return 0;
}
