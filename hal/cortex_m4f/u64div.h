/*
 * u64div.h - 64-bit unsigned division with the Cortex-M4's 32-bit UDIV, for the M4F images.
 *
 * A C division or remainder of 64-bit integers compiles to the run-time helpers
 * __aeabi_uldivmod/__aeabi_ldivmod (ARM RTABI 4.3.1); libgcc's wrappers of those (which
 * keep the division by zero, the signs and the register convention) call __udivmoddi4,
 * 700 bytes of generic C in libgcc. The firmware divides 64-bit time stamps and sample
 * counts (microseconds to milliseconds and seconds, counts modulo an output rate), so
 * u64div.c defines __udivmoddi4 for the M4F images, linked before libgcc: the same
 * quotient and remainder (the division is exact integer arithmetic: one right answer) in
 * a third of the flash, with UDIV doing 16-bit digits (Hacker's Delight 9-3, divlu and
 * divDu).
 */
#ifndef NAVECU_U64DIV_H
#define NAVECU_U64DIV_H

#include <stdint.h>

/* n / d, and n % d into *rem when rem is not NULL; d must not be 0 (the RTABI wrappers
 * deal with a zero divisor before they call it) */
uint64_t u64_divmod(uint64_t n, uint64_t d, uint64_t *rem);

#endif /* NAVECU_U64DIV_H */
