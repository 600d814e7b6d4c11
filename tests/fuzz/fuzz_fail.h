/*
 * fuzz_fail.h - how a fuzz invariant reports a violation.
 *
 * The libFuzzer harnesses link tests/fuzz/fuzz_fail.c: print the message and abort(), so
 * libFuzzer saves the input and prints the stack. The regression tests
 * (tests/test_fuzz_regressions.c) define their own fuzz_fail that fails the cmocka test.
 */
#ifndef NAVECU_FUZZ_FAIL_H
#define NAVECU_FUZZ_FAIL_H

#if defined(__GNUC__)
#define FUZZ_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define FUZZ_PRINTF(a, b)
#endif

/* Report an invariant violation; does not return. */
_Noreturn void fuzz_fail(const char *fmt, ...) FUZZ_PRINTF(1, 2);

#endif
