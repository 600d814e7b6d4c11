/*
 * semihost.h - ARM semihosting calls (ARM "Semihosting for AArch32 and AArch64", v2.0):
 * the program asks the debugger or emulator (QEMU with -semihosting) to do file I/O on
 * the host. Only in the QEMU image (make target-test, make target-bench): on a real ECU
 * without a debugger the BKPT instruction would fault.
 */
#ifndef NAVECU_SEMIHOST_H
#define NAVECU_SEMIHOST_H

#include <stddef.h>
#include <stdint.h>

/* operation numbers */
#define SEMIHOST_SYS_OPEN 0x01u
#define SEMIHOST_SYS_CLOSE 0x02u
#define SEMIHOST_SYS_WRITE0 0x04u
#define SEMIHOST_SYS_WRITE 0x05u
#define SEMIHOST_SYS_READ 0x06u
#define SEMIHOST_SYS_GET_CMDLINE 0x15u
#define SEMIHOST_SYS_EXIT_EXTENDED 0x20u

/* SYS_OPEN modes (ISO C fopen): "rb" and "wb" */
#define SEMIHOST_MODE_RB 1u
#define SEMIHOST_MODE_WB 5u

/* one semihosting call: op in r0, the parameter block's address in r1, result in r0 */
static inline int32_t semihost_call(uint32_t op, const void *params)
{
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = params;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return (int32_t)r0;
}

/* Open a host file; returns a handle >= 0 or -1. */
int32_t semihost_open(const char *path, uint32_t mode);
/* Close a handle; 0 or -1. */
int32_t semihost_close(int32_t handle);
/* Read up to len bytes; returns the number read (0 at end of file) or -1. */
int32_t semihost_read(int32_t handle, void *buf, size_t len);
/* Write len bytes; 0 when all were written, else -1. */
int32_t semihost_write(int32_t handle, const void *buf, size_t len);
/* Write a NUL-terminated string to the emulator's console (stderr of QEMU's process). */
void semihost_puts(const char *s);
/* The command line the emulator was given (-semihosting-config arg=...), NUL-terminated
 * in buf[0..cap); returns 0 or -1. */
int32_t semihost_cmdline(char *buf, size_t cap);
/* End the program: the emulator exits with status code. */
void semihost_exit(uint32_t code) __attribute__((noreturn));

#endif /* NAVECU_SEMIHOST_H */
