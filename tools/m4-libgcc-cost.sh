#!/usr/bin/env bash
# Instruction counts of the libgcc soft-float routines a Cortex-M4F build would call for
# double precision or 64-bit integer conversion (static body length, from the disassembly;
# docs/numeric-design.md). Needs gcc-arm-none-eabi.
set -euo pipefail
lib=$(arm-none-eabi-gcc -mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard -mthumb -print-libgcc-file-name)
arm-none-eabi-objdump -d "$lib" | awk '
  /^[0-9a-f]+ <[^>]+>:$/ { name = substr($2, 2, length($2) - 3); if (name in n) name = ""; else n[name] = 0; next }
  /^ +[0-9a-f]+:\t/ && name != "" { n[name]++ }
  END {
    split("__adddf3 __aeabi_dmul __aeabi_ddiv __aeabi_f2d __aeabi_d2f __aeabi_f2lz __aeabi_l2f", want, " ")
    printf "%-14s %s\n", "routine", "instructions"
    for (i = 1; i in want; i++) printf "%-14s %d\n", want[i], n[want[i]]
  }'
