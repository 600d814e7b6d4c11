/*
 * app_slot.c - the bootloader's validity marker slot in the application image: 16 erased
 * bytes right after the vector table (stm32f405.ld places .boot_marker there and checks
 * the address, firmware/boot/boot_image.h BOOT_MARKER_ADDR). The image carries them as
 * 0xFF, so the bootloader can program the marker into them after it checked the image
 * (or tools/navecu_pkg.py into a factory image for `make flash`).
 */
#include <stdint.h>

extern const uint8_t boot_marker_slot[16];
__attribute__((section(".boot_marker"), used)) const uint8_t boot_marker_slot[16] = {
    0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu,
    0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu, 0xFFu,
};
