/*
 * memcmp.c - the C library's memcmp for the Cortex-M4F images, small.
 *
 * newlib-nano's memcmp is its word-at-a-time C version (96 bytes of flash). The firmware
 * compares only in the NVM store (calstore.c, nvstore.c): 4-byte magics and commit marks,
 * a record read back after it was written, the DTC status bytes, at start-up and when a
 * record is saved, never per sample. A byte loop: the same result (the difference of the
 * first differing bytes as unsigned char, 0 when equal) in a third of the flash.
 */
#include <stddef.h>
#include <string.h>

int memcmp(const void *a, const void *b, size_t n)
{
    const unsigned char *x = (const unsigned char *)a;
    const unsigned char *y = (const unsigned char *)b;
    for (size_t i = 0u; i < n; i++) {
        if (x[i] != y[i]) {
            return (int)x[i] - (int)y[i];
        }
    }
    return 0;
}
