/*
 * memcpy.c - the C library's memcpy for the Cortex-M4F images, small.
 *
 * newlib-nano's memcpy for the M4 is its speed-tuned assembly (308 bytes: word and
 * 16-byte block copies). The firmware calls it for struct and buffer copies that are
 * small (a GNSS fix, a CAN frame) or rare (an ISO-TP message of at most 512 bytes, the NVM
 * record, the configuration at start-up); GCC copies fixed small sizes inline without it.
 * A word loop when both buffers are word-aligned, else bytes: the same bytes copied, in 86
 * bytes of flash (a byte loop alone, 24 bytes, cost 0.02 % more CPU in make target-bench).
 * Built with -fno-tree-loop-distribute-patterns (Makefile), so that GCC does not make the
 * loop a call of memcpy itself.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

void *memcpy(void *restrict dst, const void *restrict src, size_t n)
{
    unsigned char *d = (unsigned char *)dst;
    const unsigned char *s = (const unsigned char *)src;
    size_t i = 0u;
    if ((((uintptr_t)dst | (uintptr_t)src) & 3u) == 0u) {
        /* both word-aligned (most struct copies): a word at a time, as 4 bytes */
        for (; (n - i) >= 4u; i += 4u) {
            uint32_t w;
            __builtin_memcpy(&w, &s[i], 4u);
            __builtin_memcpy(&d[i], &w, 4u);
        }
    }
    for (; i < n; i++) {
        d[i] = s[i];
    }
    return dst;
}
