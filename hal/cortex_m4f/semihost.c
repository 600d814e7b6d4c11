/*
 * semihost.c - the semihosting calls of semihost.h (parameter blocks of the ARM
 * semihosting specification v2.0, section 5: SYS_OPEN, SYS_READ, ...).
 */
#include "semihost.h"

int32_t semihost_open(const char *path, uint32_t mode)
{
    size_t len = 0u;
    while (path[len] != '\0') {
        len++;
    }
    const uint32_t params[3] = {(uint32_t)(uintptr_t)path, mode, (uint32_t)len};
    return semihost_call(SEMIHOST_SYS_OPEN, params);
}

int32_t semihost_close(int32_t handle)
{
    const uint32_t params[1] = {(uint32_t)handle};
    return semihost_call(SEMIHOST_SYS_CLOSE, params);
}

int32_t semihost_read(int32_t handle, void *buf, size_t len)
{
    const uint32_t params[3] = {(uint32_t)handle, (uint32_t)(uintptr_t)buf, (uint32_t)len};
    /* the call returns the number of bytes NOT read */
    const int32_t left = semihost_call(SEMIHOST_SYS_READ, params);
    if (left < 0 || (uint32_t)left > (uint32_t)len) {
        return -1;
    }
    return (int32_t)((uint32_t)len - (uint32_t)left);
}

int32_t semihost_write(int32_t handle, const void *buf, size_t len)
{
    const uint32_t params[3] = {(uint32_t)handle, (uint32_t)(uintptr_t)buf, (uint32_t)len};
    /* the call returns the number of bytes NOT written */
    return semihost_call(SEMIHOST_SYS_WRITE, params) == 0 ? 0 : -1;
}

void semihost_puts(const char *s)
{
    (void)semihost_call(SEMIHOST_SYS_WRITE0, s);
}

int32_t semihost_cmdline(char *buf, size_t cap)
{
    uint32_t params[2] = {(uint32_t)(uintptr_t)buf, (uint32_t)cap};
    if (cap == 0u || semihost_call(SEMIHOST_SYS_GET_CMDLINE, params) != 0) {
        return -1;
    }
    buf[params[1] < cap ? params[1] : cap - 1u] = '\0';
    return 0;
}

void semihost_exit(uint32_t code)
{
    /* ADP_Stopped_ApplicationExit with an exit code (SYS_EXIT_EXTENDED) */
    const uint32_t params[2] = {0x20026u, code};
    for (;;) {
        (void)semihost_call(SEMIHOST_SYS_EXIT_EXTENDED, params);
    }
}
