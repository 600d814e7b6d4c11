/*
 * memset.c - the C library's memset for the Cortex-M4F images, small.
 *
 * newlib-nano's memset is its word-and-block C version (162 bytes of flash: an unrolled
 * 16-byte loop, a word loop, bytes). The firmware's calls clear structs and buffers at
 * start-up and on a reset, the 26 x 26 covariance at a filter reset, a CAN frame or an
 * ISO-TP block before it is filled; GCC sets fixed small sizes inline without it. A word
 * loop when the destination is word-aligned (most structs are), else bytes: the same bytes
 * written, in a third of the flash. Built with
 * -fno-tree-loop-distribute-patterns (Makefile), so that GCC does not make the loop a
 * call of memset itself.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

void *memset(void *dst, int c, size_t n)
{
    unsigned char *d = (unsigned char *)dst;
    const unsigned char b = (unsigned char)c;
    size_t i = 0u;
    if ((((uintptr_t)dst) & 3u) == 0u) {
        /* word-aligned (most structs and buffers): a word at a time, as 4 bytes */
        const uint32_t w = 0x01010101u * b;
        for (; (n - i) >= 4u; i += 4u) {
            __builtin_memcpy(&d[i], &w, 4u);
        }
    }
    for (; i < n; i++) {
        d[i] = b;
    }
    return dst;
}
