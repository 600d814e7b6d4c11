/*
 * f2l.h - float to and from 64-bit integer conversion without double precision or software
 * floating point, for the Cortex-M4F.
 *
 * A C conversion of a float to int64_t/uint64_t compiles to the run-time helpers
 * __aeabi_f2lz/__aeabi_f2ulz (ARM RTABI 4.1.2). libgcc implements them through
 * double-precision software floating point (__aeabi_f2d, __aeabi_dmul, __aeabi_dsub:
 * hundreds of cycles, and "no double on the per-sample path" is a budget rule of
 * docs/target.md), and the firmware needs them per sample: the 64-bit fixed-point
 * position (earth.c) and the codec's unsigned signal encoders. f2l.c defines both helpers
 * from the float's bits with integer operations only; the M4F images link them before
 * libgcc. The conversions are exact and truncate toward zero, as C requires; where C
 * leaves the result undefined (NaN, out of range) they saturate like the M4's VCVT
 * (NaN -> 0, below the range -> the minimum, above -> the maximum).
 */
#ifndef NAVECU_F2L_H
#define NAVECU_F2L_H

#include <stdint.h>

int64_t f2l_to_i64(float x);
uint64_t f2l_to_u64(float x);

/*
 * The other way, __aeabi_l2f/__aeabi_ul2f (ARM RTABI 4.1.2): libgcc's live in its software
 * single-precision adder (_arm_addsubsf3.o, 540 bytes of flash the FPU makes useless).
 * These convert with the FPU's 32-bit VCVT and an exact scaling by a power of two, and
 * round as C and IEEE 754 require (to nearest, ties to even): the float the host's
 * conversion gives, for every input.
 */
float f2l_from_i64(int64_t x);
float f2l_from_u64(uint64_t x);

#endif /* NAVECU_F2L_H */
