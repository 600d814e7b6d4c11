/* gnss_geom.c - satellite-to-receiver geometry in 64-bit fixed point; see gnss_geom.h. */
#include "gnss_geom.h"


/* Q62 one, and the constants below rounded to the nearest LSB (computed with 60-digit
 * decimal arithmetic: pi by Machin's formula; tests/test_gnss_geom.c checks each against
 * the double value to the double's precision). */
#define Q62_ONE 4611686018427387904LL /* 2^62 */
#define PI_Q61 7244019458077122842LL   /* pi x 2^61 */
#define PI_2_Q61 3622009729038561421LL /* pi/2 x 2^61 */
/* one geo_pos_t angle LSB (1e-7 deg / 2^24) in radians Q61, times 2^55:
 * pi x 2^61 / (180e7 x 2^24) x 2^55 */
#define GEO_LSB_TO_Q61_M 8642451851119134904LL
#define GEO_LSB_TO_Q61_SHIFT 55u
#define E2_Q62 30872378602568713LL             /* WGS-84 e^2 = 6.69437999014e-3 */
#define ONE_MINUS_E2_Q62 4580813639824819191LL /* 1 - e^2 */
#define A_DMM 63781370000LL                    /* WGS-84 a = 6378137 m */

typedef struct {
    uint64_t hi, lo;
} u128_t;

static u128_t mul_u64(uint64_t a, uint64_t b)
{
    const uint64_t a0 = a & 0xFFFFFFFFu, a1 = a >> 32, b0 = b & 0xFFFFFFFFu, b1 = b >> 32;
    const uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    u128_t r;
    r.lo = (mid << 32) | (p00 & 0xFFFFFFFFu);
    r.hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    return r;
}

static u128_t add_u128(u128_t a, u128_t b)
{
    u128_t r;
    r.lo = a.lo + b.lo;
    r.hi = a.hi + b.hi + (r.lo < a.lo ? 1u : 0u);
    return r;
}

static uint64_t abs_u64(int64_t x)
{
    return x < 0 ? (uint64_t)0 - (uint64_t)x : (uint64_t)x;
}

/* (a x b) / 2^s rounded to the nearest (halves away from zero), 1 <= s <= 127; the result
 * must fit int64 (it does for every use here: the magnitudes are in the comments). */
static int64_t mul_shr(int64_t a, int64_t b, unsigned s)
{
    const uint8_t neg = ((a < 0) != (b < 0)) ? 1u : 0u;
    u128_t p = mul_u64(abs_u64(a), abs_u64(b));
    u128_t half = {0u, 0u};
    const uint64_t sh = (uint64_t)s - 1u;
    if (sh < 64u) {
        half.lo = (uint64_t)1 << sh;
    } else {
        const uint64_t sh_hi = sh - 64u;
        half.hi = (uint64_t)1 << sh_hi;
    }
    p = add_u128(p, half);
    uint64_t r;
    if (s >= 64u) {
        r = p.hi >> (s - 64u);
    } else {
        r = (p.hi << (64u - s)) | (p.lo >> s);
    }
    return neg != 0u ? -(int64_t)r : (int64_t)r;
}

static int64_t q62_mul(int64_t a, int64_t b)
{
    return mul_shr(a, b, 62u);
}

/* sin and cos of |x| <= pi/4 in Q62: Taylor series to x^19 / x^18 (the next terms are
 * below 2e-21), Horner's rule */
static void sin_cos_small(int64_t x_q62, int64_t *s, int64_t *c)
{
    const int64_t x2 = q62_mul(x_q62, x_q62);
    int64_t ts = Q62_ONE, tc = Q62_ONE;
    for (int64_t k = 9; k >= 1; k--) {
        ts = Q62_ONE - q62_mul(x2, ts) / ((2 * k) * (2 * k + 1));
        tc = Q62_ONE - q62_mul(x2, tc) / ((2 * k - 1) * (2 * k));
    }
    *s = q62_mul(x_q62, ts);
    *c = tc;
}

void gnss_geom_sin_cos_q62(int64_t angle_q61, int64_t *sin_q62, int64_t *cos_q62)
{
    /* the nearest quarter turn q, and the rest within +-pi/4 */
    const int64_t half = angle_q61 >= 0 ? PI_2_Q61 / 2 : -(PI_2_Q61 / 2);
    const int64_t q = (angle_q61 + half) / PI_2_Q61;
    const int64_t r_q61 = angle_q61 - q * PI_2_Q61;
    int64_t s, c;
    sin_cos_small(r_q61 * 2, &s, &c);
    switch (((q % 4) + 4) % 4) {
    case 0:
        *sin_q62 = s;
        *cos_q62 = c;
        break;
    case 1:
        *sin_q62 = c;
        *cos_q62 = -s;
        break;
    case 2:
        *sin_q62 = -s;
        *cos_q62 = -c;
        break;
    default:
        *sin_q62 = -c;
        *cos_q62 = s;
        break;
    }
}

/* x rounded to the nearest integer, halves away from zero (|x| < 2^62) */
static int64_t round_i64(nav_real_t x)
{
    return (int64_t)(x >= NAV_C(0.0) ? x + NAV_C(0.5) : x - NAV_C(0.5));
}

/* geo_lsb_to_q61 and gnss_geom_pr_residual_m out of line (noinline): the link inlined them
 * at their two calls each, 40 bytes more of the ECU's flash each */
__attribute__((noinline)) static int64_t geo_lsb_to_q61(int64_t lsb)
{
    return mul_shr(lsb, GEO_LSB_TO_Q61_M, GEO_LSB_TO_Q61_SHIFT);
}

/* x / div rounded to the nearest, halves away from zero (div even, > 0); out of line
 * (noinline): inlined at its four calls it took 104 bytes more of the ECU's flash */
__attribute__((noinline)) static int64_t round_div(int64_t x, int64_t div)
{
    const int64_t half = div / 2;
    return (x >= 0 ? x + half : x - half) / div;
}

/* the ECEF's intermediate unit: 0.1 mm / 2^16, so that the products' roundings add up to
 * nothing before the last one; the height's geo_pos_t unit is mm / 2^24, so x 10 / 2^8 */
#define FRAC_SCALE 65536LL    /* 2^16 */
#define H_TO_FRAC_DIV 256LL   /* 2^24 / 2^16 */

void geo_to_ecef_dmm(const geo_pos_t *pos, int64_t ecef_dmm[3])
{
    int64_t s_lat, c_lat, s_lon, c_lon;
    gnss_geom_sin_cos_q62(geo_lsb_to_q61(pos->lat), &s_lat, &c_lat);
    gnss_geom_sin_cos_q62(geo_lsb_to_q61(pos->lon), &s_lon, &c_lon);
    /* N = a (1 - u)^(-1/2), u = e^2 sin^2(lat) <= 0.0067: the binomial series to u^6 (the
     * next term is 1.3e-16 of N), its coefficients dyadic, so exact in Q62 */
    const int64_t u = q62_mul(E2_Q62, q62_mul(s_lat, s_lat));
    static const int64_t coef[6] = {2305843009213693952LL,  /* 1/2 */
                                    1729382256910270464LL,  /* 3/8 */
                                    1441151880758558720LL,  /* 5/16 */
                                    1261007895663738880LL,  /* 35/128 */
                                    1134907106097364992LL,  /* 63/256 */
                                    1040331513922584576LL}; /* 231/1024 */
    int64_t f = coef[5];
    for (int i = 4; i >= 0; i--) {
        f = coef[i] + q62_mul(u, f);
    }
    f = Q62_ONE + q62_mul(u, f);
    /* in 0.1 mm / 2^16: N < 2^53, the height (mm / 2^24 -> 0.1 mm / 2^16: x 10 / 2^8) */
    const int64_t n_q = q62_mul(A_DMM * FRAC_SCALE, f);
    const int64_t h_q = round_div(pos->h * (GNSS_GEOM_DMM_PER_M / 1000), H_TO_FRAC_DIV);
    const int64_t nh_cos = q62_mul(n_q + h_q, c_lat);
    const int64_t nz = q62_mul(n_q, ONE_MINUS_E2_Q62) + h_q;
    ecef_dmm[0] = round_div(q62_mul(nh_cos, c_lon), FRAC_SCALE);
    ecef_dmm[1] = round_div(q62_mul(nh_cos, s_lon), FRAC_SCALE);
    ecef_dmm[2] = round_div(q62_mul(nz, s_lat), FRAC_SCALE);
}

int gnss_geom_sat(const int64_t rx_dmm[3], const int32_t pos_lsb[3], const int16_t vel_lsb[3],
                  gnss_geom_t *g)
{
    int64_t s[3], d[3];
    nav_real_t df[3];
    for (int i = 0; i < 3; i++) {
        s[i] = (int64_t)pos_lsb[i] * GNSS_GEOM_DMM_PER_RAW_POS;
        const int64_t di = s[i] - rx_dmm[i];
        df[i] = (nav_real_t)di;
    }
    /* the travel time from a first range (float32: a relative 1e-7 of it is enough) */
    const nav_real_t r0 = nav_sqrt(df[0] * df[0] + df[1] * df[1] + df[2] * df[2]);
    if (!(r0 >= NAV_C(1e6) * (nav_real_t)GNSS_GEOM_DMM_PER_M &&
          r0 <= NAV_C(1e8) * (nav_real_t)GNSS_GEOM_DMM_PER_M)) {
        return NAV_EINVAL;
    }
    /* a GNSS satellite's orbit (the centre's distance) and above the receiver's horizon
     * (the geocentric one, within 0.2 deg of the ellipsoid's normal): not a corrupt or
     * made-up position that a range 1,000 to 100,000 km away would let through */
    nav_real_t rs2 = NAV_C(0.0), rx2 = NAV_C(0.0), up = NAV_C(0.0);
    for (int i = 0; i < 3; i++) {
        const nav_real_t si = (nav_real_t)s[i], ri = (nav_real_t)rx_dmm[i];
        rs2 += si * si;
        rx2 += ri * ri;
        up += df[i] * ri;
    }
    const nav_real_t lo = GNSS_GEOM_ORBIT_MIN_M * (nav_real_t)GNSS_GEOM_DMM_PER_M;
    const nav_real_t hi = GNSS_GEOM_ORBIT_MAX_M * (nav_real_t)GNSS_GEOM_DMM_PER_M;
    if (!(rs2 >= lo * lo && rs2 <= hi * hi) ||
        !(up >= GNSS_GEOM_SIN_EL_MIN * r0 * nav_sqrt(rx2))) {
        return NAV_EINVAL;
    }
    const nav_real_t tau = r0 / ((nav_real_t)GNSS_GEOM_DMM_PER_M * NAV_C(299792458.0));
    const nav_real_t th = (nav_real_t)WGS84_OMEGA_IE_RPS * tau; /* < 1e-5 rad */
    /* R3(th) s - s = (th y - th^2/2 x, -th x - th^2/2 y, 0): below 400 m, float32 to 0.1 mm */
    const nav_real_t sx = (nav_real_t)s[0], sy = (nav_real_t)s[1];
    const nav_real_t h2 = NAV_C(0.5) * th * th;
    const int64_t dx = round_i64(th * sy - h2 * sx);
    const int64_t dy = round_i64(-th * sx - h2 * sy);
    d[0] = s[0] + dx - rx_dmm[0];
    d[1] = s[1] + dy - rx_dmm[1];
    d[2] = s[2] - rx_dmm[2];
    /* |d|^2 in 128 bits (|d_i| < 2^40), a float32 root, then the exact correction */
    u128_t sum = {0u, 0u};
    for (int i = 0; i < 3; i++) {
        const uint64_t a = abs_u64(d[i]);
        sum = add_u128(sum, mul_u64(a, a));
    }
    const nav_real_t sumf = (nav_real_t)sum.hi * NAV_C(18446744073709551616.0) +
                            (nav_real_t)sum.lo;
    const int64_t r1 = round_i64(nav_sqrt(sumf));
    const u128_t r1sq = mul_u64((uint64_t)r1, (uint64_t)r1);
    /* sum - r1^2: a few times 1e16 at most (r1 is within 1e-7 of the range) */
    const uint64_t diff_lo = sum.lo - r1sq.lo;
    const int64_t diff = (int64_t)diff_lo; /* the high words cancel: |diff| < 2^63 */
    const nav_real_t corr = (nav_real_t)diff / (NAV_C(2.0) * (nav_real_t)r1);
    const int64_t corr_int = round_i64(corr);
    g->range_dmm = r1 + corr_int;
    g->range_frac_dmm = corr - (nav_real_t)corr_int;
    const nav_real_t rf = (nav_real_t)g->range_dmm + g->range_frac_dmm;
    for (int i = 0; i < 3; i++) {
        g->los_ecef[i] = (nav_real_t)d[i] / rf;
    }
    const nav_real_t lsb_v = NAV_C(0.125);
    const nav_real_t vx = (nav_real_t)vel_lsb[0] * lsb_v, vy = (nav_real_t)vel_lsb[1] * lsb_v;
    g->sat_vel_mps[0] = vx + th * vy;
    g->sat_vel_mps[1] = vy - th * vx;
    g->sat_vel_mps[2] = (nav_real_t)vel_lsb[2] * lsb_v;
    g->tau_s = rf / ((nav_real_t)GNSS_GEOM_DMM_PER_M * NAV_C(299792458.0));
    return NAV_OK;
}

__attribute__((noinline)) nav_real_t gnss_geom_pr_residual_m(uint32_t pr_lsb, const gnss_geom_t *g,
                                                        int64_t clock_dmm)
{
    const int64_t pr_dmm = (int64_t)pr_lsb * GNSS_GEOM_DMM_PER_RAW_POS;
    const int64_t z_dmm = pr_dmm - g->range_dmm - clock_dmm;
    return ((nav_real_t)z_dmm - g->range_frac_dmm) / (nav_real_t)GNSS_GEOM_DMM_PER_M;
}
