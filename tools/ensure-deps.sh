#!/usr/bin/env bash
# Install the system packages the build and tests need, if they are missing.
# Debian/Ubuntu; installs only when running as root (CI), otherwise says what to install.
set -euo pipefail

need=()
[ -f /usr/include/cmocka.h ] || need+=(libcmocka-dev)
command -v cc >/dev/null 2>&1 || need+=(gcc)
command -v make >/dev/null 2>&1 || need+=(make)
command -v arm-none-eabi-gcc >/dev/null 2>&1 || need+=(gcc-arm-none-eabi)
[ -f /usr/lib/arm-none-eabi/newlib/nano.specs ] || need+=(libnewlib-arm-none-eabi)
# the Cortex-M4F image on an emulated STM32F405 (make target-test, target-bench)
command -v qemu-system-arm >/dev/null 2>&1 || need+=(qemu-system-arm)
# live CAN tests: real SocketCAN vcan inside User-Mode Linux (docs/PLATFORM notes), can-utils
command -v linux.uml >/dev/null 2>&1 || [ -x /usr/bin/linux ] || need+=(user-mode-linux)
command -v insmod >/dev/null 2>&1 || need+=(kmod)
command -v cansend >/dev/null 2>&1 || need+=(can-utils)
# static analysis (make lint, docs/misra.md): cppcheck with its MISRA C:2012 addon, clang-tidy
command -v cppcheck >/dev/null 2>&1 || need+=(cppcheck)
command -v clang-tidy >/dev/null 2>&1 || need+=(clang-tidy)
# libFuzzer harnesses (make fuzz, tests/fuzz/): clang and its fuzzer runtime
command -v clang >/dev/null 2>&1 || need+=(clang)
compgen -G '/usr/lib/llvm-14/lib/clang/14*/lib/linux/libclang_rt.fuzzer-x86_64.a' >/dev/null || need+=(libclang-rt-14-dev)

if [ ${#need[@]} -eq 0 ]; then
    exit 0
fi
if [ "$(id -u)" -ne 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "missing packages: ${need[*]} - install them (Debian: sudo apt-get install ${need[*]})" >&2
    exit 1
fi
echo "installing: ${need[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq "${need[@]}" >/dev/null
