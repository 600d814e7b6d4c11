/*
 * gnss_geom.h - satellite-to-receiver geometry for raw GNSS measurements (issue #20),
 * formed in 64-bit fixed point so that float32 only ever sees small numbers
 * (docs/numeric-design.md, "Raw GNSS ranges").
 *
 * A pseudorange is about 2e7 m and must be compared with the predicted range to a few
 * millimetres: float32 spaces 2e7 by 2 m, and its sin/cos of the latitude are good to
 * 6e-8, 0.4 m of the Earth's radius. So:
 * - the receiver's ECEF position comes from the core's fixed-point geo_pos_t through sine
 *   and cosine in Q62 (Taylor series after an exact quarter-turn reduction) and the prime
 *   vertical radius as a binomial series in e^2 sin^2(lat), products in 128 bits: 0.1 mm
 *   units (int64), exact to well below 0.1 mm;
 * - the satellite (0.02 m units, the ECEF axes of the transmit time) is turned into the
 *   axes of the reception time (the Earth's rotation during the signal's travel, IS-GPS-200
 *   20.3.3.4.3.3.2: a correction of up to 30 m, formed in float32 as it is small);
 * - the range is the square root of a 128-bit sum of squares: a float32 first guess,
 *   corrected by (|d|^2 - r0^2) / (2 r0) with the difference exact in integers;
 * - the pseudorange residual is taken in integers, against a clock bias the caller keeps in
 *   integers too (a receiver clock of 1 ms is 300 km: 3 cm in float32), and only then
 *   converted to float32 metres.
 * Integer arithmetic only but the small corrections; identical in both numeric variants.
 */
#ifndef NAVECU_GNSS_GEOM_H
#define NAVECU_GNSS_GEOM_H

#include <stdint.h>

#include "earth.h"
#include "nav_types.h"

#define GNSS_GEOM_DMM_PER_M 10000    /* the unit of the fixed-point ECEF: 0.1 mm */
#define GNSS_GEOM_DMM_PER_RAW_POS 200 /* GNSS_RawSat*.SatPos* and Pseudorange: 0.02 m */
#define GNSS_C_MPS 299792458.0        /* the speed of light (IS-GPS-200) */

#define geo_to_ecef_dmm NAV_SYM(geo_to_ecef_dmm)
#define gnss_geom_sat NAV_SYM(gnss_geom_sat)
#define gnss_geom_pr_residual_m NAV_SYM(gnss_geom_pr_residual_m)
#define gnss_geom_sin_cos_q62 NAV_SYM(gnss_geom_sin_cos_q62)

/* One satellite seen from the receiver. */
typedef struct {
    int64_t range_dmm;        /* geometric range in the receive-time axes, 0.1 mm, */
    nav_real_t range_frac_dmm; /* plus this fraction of 0.1 mm (|frac| <= 0.5) */
    nav_real_t los_ecef[3];   /* unit vector from the receiver to the satellite, ECEF */
    nav_real_t sat_vel_mps[3]; /* the satellite's velocity in the receive-time axes */
    nav_real_t tau_s;         /* the signal's travel time (range / c) */
} gnss_geom_t;

/* ECEF WGS-84 of a geodetic position, 0.1 mm units. */
void geo_to_ecef_dmm(const geo_pos_t *pos, int64_t ecef_dmm[3]);

/* A GNSS satellite's distance from the Earth's centre: GLONASS's 25,500 km orbit and the
 * MEO constellations above it, up to QZSS's inclined geosynchronous orbit at its apogee
 * (42,164 km x (1 + 0.075) = 45,330 km), with a margin; and its elevation above the
 * receiver's horizon at least -10 deg (a receiver on a mountain sees the horizon dip by
 * 2 deg at 4 km; refraction adds half a degree). */
#define GNSS_GEOM_ORBIT_MIN_M NAV_C(2.0e7)
#define GNSS_GEOM_ORBIT_MAX_M NAV_C(4.7e7)
#define GNSS_GEOM_SIN_EL_MIN NAV_C(-0.17365) /* sin(-10 deg) */

/* The geometry of a satellite at pos_lsb (0.02 m, transmit-time axes) with velocity
 * vel_lsb (0.125 m/s) seen from rx_dmm. NAV_EINVAL for a position that is not a GNSS
 * satellite's (a corrupt or made-up one): closer than 1,000 km or farther than 100,000 km,
 * off the orbits above (GNSS_GEOM_ORBIT_MIN_M..MAX_M from the Earth's centre), or more
 * than 10 deg below the receiver's horizon. */
int gnss_geom_sat(const int64_t rx_dmm[3], const int32_t pos_lsb[3], const int16_t vel_lsb[3],
                  gnss_geom_t *g);

/* Pseudorange (0.02 m units) minus the geometric range and the receiver clock bias
 * clock_dmm (0.1 mm), in metres: the pseudorange's innovation before the filter's own
 * clock and atmosphere terms. */
nav_real_t gnss_geom_pr_residual_m(uint32_t pr_lsb, const gnss_geom_t *g, int64_t clock_dmm);

/* sin and cos of an angle in radians Q61 (|angle| <= pi), in Q62 (exposed for the tests). */
void gnss_geom_sin_cos_q62(int64_t angle_q61, int64_t *sin_q62, int64_t *cos_q62);

#endif /* NAVECU_GNSS_GEOM_H */
