/* crc32.c - CRC-32 (IEEE 802.3); see crc32.h. */
#include "crc32.h"

uint32_t crc32_update(uint32_t crc, const uint8_t *data, size_t len)
{
    /* CRC of each nibble value, reflected polynomial 0xEDB88320 */
    static const uint32_t table[16] = {
        0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
        0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
        0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
    };
    uint32_t c = crc;
    for (size_t k = 0u; k < len; k++) {
        c ^= data[k];
        c = (c >> 4) ^ table[c & 0xFu];
        c = (c >> 4) ^ table[c & 0xFu];
    }
    return c;
}

uint32_t crc32_final(uint32_t crc)
{
    return crc ^ 0xFFFFFFFFu;
}

uint32_t crc32_of(const uint8_t *data, size_t len)
{
    return crc32_final(crc32_update(CRC32_INIT, data, len));
}
