/*
 * earth.h - the WGS-84 Earth model and the fixed-point geodetic position.
 *
 * Constants: NIMA TR8350.2 (3rd ed., 2000), "Department of Defense World Geodetic
 * System 1984", Tables 3.1-3.4; normal gravity: eq. (4-1) (Somigliana) and (4-3)
 * (height series). Radii of curvature: standard ellipsoid geometry (Groves,
 * "Principles of GNSS, Inertial, and Multisensor Integrated Navigation", 2nd ed.,
 * eqs. 2.105-2.106). Frame rates: seed 001 eq. (7), ENU navigation frame.
 */
#ifndef NAVECU_EARTH_H
#define NAVECU_EARTH_H

#include "nav_types.h"

#define WGS84_A_M 6378137.0                 /* semi-major axis */
#define WGS84_F (1.0 / 298.257223563)       /* flattening */
#define WGS84_E2 6.69437999014e-3           /* first eccentricity squared */
#define WGS84_OMEGA_IE_RPS 7.292115e-5      /* Earth rotation rate, rad/s */
#define WGS84_GM_M3PS2 3.986004418e14       /* geocentric gravitational constant */
#define WGS84_GAMMA_E_MPS2 9.7803253359     /* normal gravity at the equator */
#define WGS84_GAMMA_P_MPS2 9.8321849378     /* normal gravity at the poles */
#define WGS84_SOMIGLIANA_K 0.00193185265241 /* (b*gamma_p)/(a*gamma_e) - 1 */
#define WGS84_M 0.00344978650684            /* omega^2 a^2 b / GM */
#define STD_GRAVITY_MPS2 9.80665           /* standard acceleration of gravity (CGPM 1901) */

/*
 * Geodetic position in 64-bit fixed point, so that it accumulates without loss on a
 * float-only FPU (docs/numeric-design.md). The unit is 1e-7 degree (as GNSS receivers and
 * the CAN protocol carry it) divided by 2^24, so converting to or from 1e-7 degree is an
 * exact shift: angle LSB = 5.96e-15 deg (0.66 nm on the ground), height LSB = 1 mm / 2^24.
 */
#define GEO_LSB_PER_DEG_E7 16777216LL /* 2^24 */
#define GEO_LSB_PER_MM 16777216LL     /* 2^24 */
#define GEO_LSB_180DEG (1800000000LL * GEO_LSB_PER_DEG_E7)
/* Heights the Earth model is valid for (normal gravity series, TR8350.2 eq. 4-3): from
 * below the Dead Sea to far above any road. */
#define GEO_H_MIN_LSB (-1000000LL * GEO_LSB_PER_MM)  /* -1 km */
#define GEO_H_MAX_LSB (20000000LL * GEO_LSB_PER_MM)  /* +20 km */

typedef struct {
    int64_t lat;  /* geodetic latitude, north positive, GEO_LSB_PER_DEG_E7 per 1e-7 deg */
    int64_t lon;  /* longitude, east positive, wrapped to (-180, 180] deg, same unit */
    int64_t h;    /* height above the ellipsoid, GEO_LSB_PER_MM per mm */
} geo_pos_t;

/* Earth quantities at one position, all in the ENU navigation frame. */
typedef struct {
    nav_real_t sin_lat, cos_lat, tan_lat;
    nav_real_t R_M_m;         /* meridian radius of curvature (no height) */
    nav_real_t R_N_m;         /* prime-vertical radius of curvature (no height) */
    nav_real_t g_mps2;        /* magnitude of normal gravity, g_n = (0, 0, -g) */
    nav_real_t w_ie_n_rps[3]; /* Earth rate: (0, U cos(lat), U sin(lat)) */
} earth_t;

#define geo_lat_rad NAV_SYM(geo_lat_rad)
#define geo_lon_rad NAV_SYM(geo_lon_rad)
#define geo_h_m NAV_SYM(geo_h_m)
#define geo_pos_add NAV_SYM(geo_pos_add)
#define earth_radii NAV_SYM(earth_radii)
#define earth_gravity NAV_SYM(earth_gravity)
#define earth_eval NAV_SYM(earth_eval)
#define earth_transport_rate NAV_SYM(earth_transport_rate)

/* latitude, longitude (rad) and height (m) of a fixed-point position, rounded to nav_real_t */
nav_real_t geo_lat_rad(const geo_pos_t *pos);
nav_real_t geo_lon_rad(const geo_pos_t *pos);
nav_real_t geo_h_m(const geo_pos_t *pos);

/*
 * pos += (dlat_rad, dlon_rad, dh_m). pos must be valid: |lat| <= 90 deg, lon in
 * (-180, 180] deg, height within [GEO_H_MIN_LSB, GEO_H_MAX_LSB]. Increments are rounded to
 * the nearest LSB; longitude wraps to (-180, 180] degrees. Returns NAV_OK, or NAV_ERANGE
 * (pos unchanged) if pos is not valid, an increment is not finite or larger than 0.1 rad /
 * 100 km, or the result would leave the valid latitudes or heights.
 */
int geo_pos_add(geo_pos_t *pos, nav_real_t dlat_rad, nav_real_t dlon_rad, nav_real_t dh_m);

/* Meridian R_M and prime-vertical R_N radii of curvature (m) at sin(lat). */
void earth_radii(nav_real_t sin_lat, nav_real_t *R_M_m, nav_real_t *R_N_m);

/* Normal gravity magnitude (m/s^2) at sin(lat), height h_m (TR8350.2 eqs. 4-1, 4-3). */
nav_real_t earth_gravity(nav_real_t sin_lat, nav_real_t h_m);

/* All of earth_t at latitude lat_rad, height h_m. |lat| must stay below 90 deg. */
void earth_eval(nav_real_t lat_rad, nav_real_t h_m, earth_t *e);

/*
 * Transport rate w_en_n (rad/s) of the ENU frame moving with velocity v_n_mps at height
 * h_m: (-v_N/(R_M+h), v_E/(R_N+h), v_E tan(lat)/(R_N+h)), seed 001 eq. (7).
 */
void earth_transport_rate(const earth_t *e, nav_real_t h_m, const nav_real_t v_n_mps[3],
                          nav_real_t w_en_n_rps[3]);

#endif /* NAVECU_EARTH_H */
