/* earth.c - see earth.h for the contracts and sources. */
#include "earth.h"

/* Scales written as the expressions that define them; the compiler folds them in double
 * and NAV_C rounds once to nav_real_t. */
#define PI_D 3.14159265358979323846
#define RAD_PER_LSB NAV_C(PI_D / (1.8e9 * (double)GEO_LSB_PER_DEG_E7))
#define LSB_PER_RAD NAV_C((1.8e9 * (double)GEO_LSB_PER_DEG_E7) / PI_D)
#define M_PER_HLSB NAV_C(1e-3 / (double)GEO_LSB_PER_MM)
#define HLSB_PER_M NAV_C(1e3 * (double)GEO_LSB_PER_MM)

/* geo_lat_rad and geo_h_m out of line (noinline): the link inlined them at their 11 and
 * 13 calls, an __aeabi_l2f call and a multiply each: 280 bytes of the ECU's flash in every
 * image (geo_lon_rad, called less, is 8 bytes smaller inlined) */
__attribute__((noinline)) nav_real_t geo_lat_rad(const geo_pos_t *pos)
{
    return (nav_real_t)pos->lat * RAD_PER_LSB;
}

nav_real_t geo_lon_rad(const geo_pos_t *pos)
{
    return (nav_real_t)pos->lon * RAD_PER_LSB;
}

__attribute__((noinline)) nav_real_t geo_h_m(const geo_pos_t *pos)
{
    return (nav_real_t)pos->h * M_PER_HLSB;
}

/* nearest integer of a value already checked to be well inside the int64 range */
static int64_t round_to_lsb(nav_real_t x)
{
    return (int64_t)(x >= NAV_C(0.0) ? x + NAV_C(0.5) : x - NAV_C(0.5));
}

int geo_pos_add(geo_pos_t *pos, nav_real_t dlat_rad, nav_real_t dlon_rad, nav_real_t dh_m)
{
    if (!(nav_fabs(dlat_rad) <= NAV_C(0.1)) || !(nav_fabs(dlon_rad) <= NAV_C(0.1)) ||
        !(nav_fabs(dh_m) <= NAV_C(1e5))) {
        return NAV_ERANGE; /* also catches NaN, for which every comparison is false */
    }
    if (pos->lat > GEO_LSB_180DEG / 2 || pos->lat < -GEO_LSB_180DEG / 2 ||
        pos->lon > GEO_LSB_180DEG || pos->lon <= -GEO_LSB_180DEG || pos->h > GEO_H_MAX_LSB ||
        pos->h < GEO_H_MIN_LSB) {
        return NAV_ERANGE; /* bounded inputs keep every sum below far from int64 overflow */
    }
    const int64_t h = pos->h + round_to_lsb(dh_m * HLSB_PER_M);
    if (h > GEO_H_MAX_LSB || h < GEO_H_MIN_LSB) {
        return NAV_ERANGE;
    }
    const int64_t lat = pos->lat + round_to_lsb(dlat_rad * LSB_PER_RAD);
    if (lat > GEO_LSB_180DEG / 2 || lat < -GEO_LSB_180DEG / 2) {
        return NAV_ERANGE;
    }
    int64_t lon = pos->lon + round_to_lsb(dlon_rad * LSB_PER_RAD);
    if (lon > GEO_LSB_180DEG) {
        lon -= 2 * GEO_LSB_180DEG;
    } else if (lon <= -GEO_LSB_180DEG) {
        lon += 2 * GEO_LSB_180DEG;
    }
    pos->lat = lat;
    pos->lon = lon;
    pos->h = h;
    return NAV_OK;
}

void earth_radii(nav_real_t sin_lat, nav_real_t *R_M_m, nav_real_t *R_N_m)
{
    const nav_real_t w2 = NAV_C(1.0) - NAV_C(WGS84_E2) * sin_lat * sin_lat;
    const nav_real_t w = nav_sqrt(w2);
    *R_N_m = NAV_C(WGS84_A_M) / w;
    *R_M_m = NAV_C(WGS84_A_M) * (NAV_C(1.0) - NAV_C(WGS84_E2)) / (w2 * w);
}

nav_real_t earth_gravity(nav_real_t sin_lat, nav_real_t h_m)
{
    const nav_real_t s2 = sin_lat * sin_lat;
    const nav_real_t g0 = NAV_C(WGS84_GAMMA_E_MPS2) * (NAV_C(1.0) + NAV_C(WGS84_SOMIGLIANA_K) * s2) /
                          nav_sqrt(NAV_C(1.0) - NAV_C(WGS84_E2) * s2);
    const nav_real_t inv_a = NAV_C(1.0) / NAV_C(WGS84_A_M);
    const nav_real_t k1 = NAV_C(2.0) * inv_a *
                          (NAV_C(1.0) + NAV_C(WGS84_F) + NAV_C(WGS84_M) - NAV_C(2.0) * NAV_C(WGS84_F) * s2);
    const nav_real_t k2 = NAV_C(3.0) * inv_a * inv_a;
    return g0 * (NAV_C(1.0) - k1 * h_m + k2 * h_m * h_m);
}

void earth_eval(nav_real_t lat_rad, nav_real_t h_m, earth_t *e)
{
    e->sin_lat = nav_sin(lat_rad);
    e->cos_lat = nav_cos(lat_rad);
    e->tan_lat = e->sin_lat / e->cos_lat;
    earth_radii(e->sin_lat, &e->R_M_m, &e->R_N_m);
    e->g_mps2 = earth_gravity(e->sin_lat, h_m);
    e->w_ie_n_rps[0] = NAV_C(0.0);
    e->w_ie_n_rps[1] = NAV_C(WGS84_OMEGA_IE_RPS) * e->cos_lat;
    e->w_ie_n_rps[2] = NAV_C(WGS84_OMEGA_IE_RPS) * e->sin_lat;
}

void earth_transport_rate(const earth_t *e, nav_real_t h_m, const nav_real_t v_n_mps[3],
                          nav_real_t w_en_n_rps[3])
{
    const nav_real_t inv_rm = NAV_C(1.0) / (e->R_M_m + h_m);
    const nav_real_t inv_rn = NAV_C(1.0) / (e->R_N_m + h_m);
    w_en_n_rps[0] = -v_n_mps[1] * inv_rm;
    w_en_n_rps[1] = v_n_mps[0] * inv_rn;
    w_en_n_rps[2] = v_n_mps[0] * e->tan_lat * inv_rn;
}
