/* fuzz_fail.c - fuzz_fail for the libFuzzer harnesses: print and abort (fuzz_fail.h). */
#include "fuzz_fail.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

void fuzz_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    (void)fputs("FUZZ INVARIANT VIOLATED: ", stderr);
    (void)vfprintf(stderr, fmt, ap);
    (void)fputc('\n', stderr);
    va_end(ap);
    abort();
}
