/*
 * nav_types.h - the numeric type switch of the navigation core.
 *
 * The core is written once against nav_real_t. The firmware build uses
 * float32 (the Cortex-M4F FPU is single precision); the same sources built
 * with -DNAV_REAL_DOUBLE give the double "reference" variant used by tests to
 * separate algorithm error from rounding error. In the reference variant every
 * public symbol gets the suffix _f64 (NAV_SYM), so both variants can be linked
 * into one test program.
 *
 * Position is not a nav_real_t: it is accumulated in 64-bit fixed point in
 * both variants (see geo_pos_t in earth.h and docs/numeric-design.md).
 *
 * Errors: functions return 0 or a negative errno-style code from this file.
 * The values equal Linux errno numbers, defined here so the core needs no
 * hosted headers.
 */
#ifndef NAVECU_NAV_TYPES_H
#define NAVECU_NAV_TYPES_H

#include <math.h>
#include <stdint.h>

/* A constant of type nav_real_t; the cast of a constant expression folds at compile time,
 * so no double arithmetic reaches the float32 build. */
#define NAV_C(x) ((nav_real_t)(x))

#define NAV_PI NAV_C(3.14159265358979323846)
#define NAV_DEG_PER_RAD NAV_C(57.29577951308232)

#if defined(NAV_REAL_DOUBLE)
typedef double nav_real_t;
#define NAV_SYM(name) name##_f64      /* symbol of the reference variant */
#define nav_sqrt(x) sqrt(x)
#define nav_sin(x) sin(x)
#define nav_cos(x) cos(x)
#define nav_atan2(y, x) atan2((y), (x))
#define nav_asin(x) asin(x)
#define nav_fabs(x) fabs(x)
#define nav_isfinite(x) isfinite(x)
#else
typedef float nav_real_t;
#define NAV_SYM(name) name
#define nav_sqrt(x) sqrtf(x)
/* the firmware's own trig (nav_trig.c): the same bits on the host and the Cortex-M4F */
#define nav_sin(x) navf_sin(x)
#define nav_cos(x) navf_cos(x)
#define nav_atan2(y, x) navf_atan2((y), (x))
#define nav_asin(x) navf_asin(x)
float navf_sin(float x);
float navf_cos(float x);
float navf_atan2(float y, float x);
float navf_asin(float x);
#define nav_fabs(x) fabsf(x)
#define nav_isfinite(x) isfinite(x)
#endif

#define NAV_OK 0
#define NAV_EINVAL (-22)  /* an argument is out of its documented range */
#define NAV_ERANGE (-34)  /* a result would leave its representable range */

#endif /* NAVECU_NAV_TYPES_H */
