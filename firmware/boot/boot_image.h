/*
 * boot_image.h - where the application lives and how the bootloader knows it is whole
 * (docs/target.md "The bootloader"). One definition for the C side; tools/navecu_pkg.py is
 * the Python side and tests/python/test_flash_tool.py checks that the two agree.
 *
 * Flash of the STM32F405 (RM0090 3.3):
 *   0x08000000  sector 0 (16 KiB)        the bootloader
 *   0x08004000  sectors 1, 2 (2 x 16 KiB) NVM: calibration and parameters, never erased or
 *                                       written by the bootloader
 *   0x0800C000  sector 3 (16 KiB)        the application: its vector table first (VTOR),
 *               sector 4 (64 KiB)        then the validity marker slot, then its code
 *
 * The validity marker (BOOT_MARKER_LEN bytes at BOOT_MARKER_ADDR, four little-endian u32):
 *   magic BOOT_MARKER_MAGIC, the image length, the image's CRC-32, and
 *   ~(magic ^ length ^ crc). The application is linked with the slot erased (0xFF bytes:
 *   boards/stm32f405/app_slot.c), so the image's CRC-32 (IEEE 802.3, as zlib.crc32) is over
 *   [BOOT_APP_START, BOOT_APP_START + length) with the slot reading 0xFF. The bootloader
 *   programs the marker last, after checking that CRC over the written flash; an erase of
 *   the application erases the slot's sector first. The bootloader starts the application
 *   only with a marker whose CRC matches the flash at this boot.
 *
 * The package (a file, tools/navecu_pkg.py): a BOOT_PKG_HEADER_LEN-byte header, little-endian,
 *   0  magic "NVPK" (BOOT_PKG_MAGIC as u32)   4  format version (u16) BOOT_PKG_VERSION
 *   6  header length (u16)                    8  load address (u32), BOOT_APP_START
 *   12 image length (u32)                     16 image CRC-32 (u32), as the marker's
 *   20 software version (u32, informative)    24 reserved, 0 (u32)
 *   28 CRC-32 of bytes 0..27
 * followed by the image bytes.
 */
#ifndef NAVECU_BOOT_IMAGE_H
#define NAVECU_BOOT_IMAGE_H

#define BOOT_LOADER_START 0x08000000u
#define BOOT_LOADER_SIZE 0x4000u          /* sector 0 */
#define BOOT_NVM_START 0x08004000u
#define BOOT_NVM_SIZE 0x8000u             /* sectors 1, 2 */
#define BOOT_APP_START 0x0800C000u
#define BOOT_APP_SIZE 0x14000u            /* sectors 3 (16 KiB) and 4 (64 KiB) */
#define BOOT_APP_SECTOR3_SIZE 0x4000u
#define BOOT_APP_SECTOR4_SIZE 0x10000u
#define BOOT_VECTORS_LEN 392u             /* 16 + 82 vectors of 4 bytes (startup.c) */
#define BOOT_MARKER_ADDR (BOOT_APP_START + BOOT_VECTORS_LEN)
#define BOOT_MARKER_LEN 16u
#define BOOT_MARKER_MAGIC 0x4F42564Eu     /* "NVBO" little-endian */
#define BOOT_RAM_START 0x20000000u
#define BOOT_RAM_SIZE 0x20000u            /* 128 KiB */

/* The request to stay in the bootloader, in RAM the startup code leaves alone (the last
 * 16 bytes of SRAM, above the stack: stm32f405.ld, boot.ld): BOOT_REQUEST_MAGIC and its
 * complement, written by the application before it resets for a programming session. */
#define BOOT_REQUEST_ADDR (BOOT_RAM_START + BOOT_RAM_SIZE - 16u)
#define BOOT_REQUEST_MAGIC 0xB007F1A5u

#define BOOT_PKG_MAGIC 0x4B50564Eu        /* "NVPK" little-endian */
#define BOOT_PKG_VERSION 1u
#define BOOT_PKG_HEADER_LEN 32u

#endif /* NAVECU_BOOT_IMAGE_H */
