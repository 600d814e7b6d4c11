/*
 * uml_xstate_shim.c - an LD_PRELOAD shim for Debian's UML kernel (6.1) on hosts whose CPU
 * has a larger XSAVE area than the kernel was built for (tools/vcan/with_vcan.sh).
 *
 * UML saves and restores its guest processes' FPU state with ptrace(PTRACE_GETREGSET /
 * PTRACE_SETREGSET, NT_X86_XSTATE) through a buffer of its own fixed size (2,696 bytes:
 * x87, SSE, AVX, AVX-512 and PKRU). A host kernel takes a SETREGSET only with the whole
 * XSAVE buffer of the host (arch/x86/kernel/fpu/regset.c, xstateregs_set: "A whole
 * standard-format XSAVE buffer is needed"); on a CPU with AMX that is 11,008 bytes, the
 * SETREGSET fails with EFAULT and UML panics at its first process ("userspace - ptrace
 * set fp regs failed, errno = 14").
 *
 * The shim passes every ptrace call through, except a SETREGSET of NT_X86_XSTATE shorter
 * than the host's buffer: it is given the host's size, UML's bytes first and zeros after,
 * with every state component that does not lie wholly inside UML's bytes marked as in its
 * initial state (its XSTATE_BV bit cleared; the component offsets from CPUID leaf 0xD).
 * UML's guests cannot use those components (AMX needs a permission request no guest
 * makes through UML), so nothing of theirs is lost. Test infrastructure only: not part of
 * the firmware.
 */
#define _GNU_SOURCE
#include <cpuid.h>
#include <dlfcn.h>
#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <string.h>
#include <sys/ptrace.h>
#include <sys/types.h>
#include <sys/uio.h>

#define NT_X86_XSTATE_NOTE 0x202
#define XSTATE_BV_OFFSET 512u
#define HOST_MAX 65536u

typedef long (*ptrace_fn)(int, pid_t, void *, void *);

static ptrace_fn real_ptrace(void)
{
    static ptrace_fn fn;
    if (fn == NULL) {
        fn = (ptrace_fn)dlsym(RTLD_NEXT, "ptrace");
    }
    return fn;
}

/* the host's XSAVE buffer size for ptrace (0 if it cannot be read) */
static size_t host_xstate_size(pid_t pid)
{
    static size_t size;
    static unsigned char probe[HOST_MAX];
    if (size == 0u) {
        struct iovec iov = {probe, sizeof probe};
        if (real_ptrace()(PTRACE_GETREGSET, pid, (void *)(uintptr_t)NT_X86_XSTATE_NOTE, &iov) ==
            0) {
            size = iov.iov_len;
        }
    }
    return size;
}

/* the components (bits) that do not lie wholly inside the first len bytes of the
 * standard format (CPUID leaf 0xD: size in EAX, offset in EBX), read once per len (a
 * CPUID under a hypervisor is slow, and a SETREGSET comes at every UML context switch) */
static uint64_t outside_mask(size_t len)
{
    static size_t for_len;
    static uint64_t mask;
    if (for_len != len) {
        mask = 0u;
        for (unsigned i = 2u; i < 64u; i++) {
            unsigned eax = 0u, ebx = 0u, ecx = 0u, edx = 0u;
            __cpuid_count(0xD, i, eax, ebx, ecx, edx);
            if (eax == 0u || (size_t)ebx + (size_t)eax > len) {
                mask |= 1ull << i;
            }
        }
        for_len = len;
    }
    return mask;
}

/* clear the XSTATE_BV bits of the components not wholly inside the first len bytes */
static void clear_outside(unsigned char *buf, size_t len)
{
    uint64_t bv;
    memcpy(&bv, buf + XSTATE_BV_OFFSET, sizeof bv);
    bv &= ~outside_mask(len);
    memcpy(buf + XSTATE_BV_OFFSET, &bv, sizeof bv);
}

long ptrace(enum __ptrace_request req, ...)
{
    va_list ap;
    va_start(ap, req);
    const pid_t pid = va_arg(ap, pid_t);
    void *addr = va_arg(ap, void *);
    void *data = va_arg(ap, void *);
    va_end(ap);
    if (req == PTRACE_SETREGSET && (uintptr_t)addr == NT_X86_XSTATE_NOTE && data != NULL) {
        const struct iovec *in = data;
        const size_t host = host_xstate_size(pid);
        if (host > in->iov_len && host <= HOST_MAX && in->iov_len > XSTATE_BV_OFFSET + 8u) {
            static unsigned char full[HOST_MAX];
            memset(full, 0, host);
            memcpy(full, in->iov_base, in->iov_len);
            clear_outside(full, in->iov_len);
            struct iovec iov = {full, host};
            return real_ptrace()(req, pid, addr, &iov);
        }
    }
    return real_ptrace()(req, pid, addr, data);
}
