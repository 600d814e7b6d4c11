/*
 * crc32.h - CRC-32 (IEEE 802.3, reflected polynomial 0xEDB88320, as zlib.crc32), a nibble
 * table of 64 bytes: the calibration store's records (calstore.c) and the bootloader's image
 * check (firmware/boot) use this one. Pure, no state.
 */
#ifndef NAVECU_CRC32_H
#define NAVECU_CRC32_H

#include <stddef.h>
#include <stdint.h>

#define CRC32_INIT 0xFFFFFFFFu

/* The running register after data[0..len) (start from CRC32_INIT) */
uint32_t crc32_update(uint32_t crc, const uint8_t *data, size_t len);

/* The CRC-32 of a running register: crc ^ 0xFFFFFFFF */
uint32_t crc32_final(uint32_t crc);

/* The CRC-32 of data[0..len) in one call */
uint32_t crc32_of(const uint8_t *data, size_t len);

#endif /* NAVECU_CRC32_H */
