/*
 * nvm_flash.c - NOR-flash rules for RAM-backed NVM regions (contracts in nvm_flash.h).
 */
#include "nvm_flash.h"

int nvm_flash_args_ok(size_t size, size_t offset, const void *buf, size_t len)
{
    /* written so that offset + len cannot overflow */
    return (buf != NULL || len == 0u) && offset <= size && len <= size - offset;
}

int nvm_flash_program(uint8_t *out, const uint8_t *old, const uint8_t *src, size_t len)
{
    int verify_failed = 0;
    for (size_t k = 0u; k < len; k++) {
        out[k] = (uint8_t)(old[k] & src[k]);
        if (out[k] != src[k]) {
            verify_failed = 1;
        }
    }
    return verify_failed;
}
