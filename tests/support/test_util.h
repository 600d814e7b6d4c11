/* test_util.h - small helpers for cmocka tests (include after cmocka.h). */
#ifndef NAVECU_TEST_UTIL_H
#define NAVECU_TEST_UTIL_H

#include <math.h>

/* Fail unless |actual - expected| <= tol, printing all three (cmocka 1.1.5 has no double
 * comparison). A NaN actual fails. */
#define assert_near(actual, expected, tol)                                                   \
    do {                                                                                     \
        const double a_ = (double)(actual), e_ = (double)(expected), t_ = (double)(tol);     \
        if (!(fabs(a_ - e_) <= t_)) {                                                        \
            fail_msg("%s = %.12g, expected %.12g +- %.3g (off by %.3g)", #actual, a_, e_,    \
                     t_, a_ - e_);                                                           \
        }                                                                                    \
    } while (0)

#endif
