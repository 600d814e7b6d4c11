/* vehicle_checksum.c - car makers' frame checksums; see vehicle_checksum.h. */
#include "vehicle_checksum.h"

int vehicle_checksum_toyota(uint32_t id, const uint8_t *data, uint8_t dlc)
{
    if (dlc == 0u || dlc > 8u) {
        return 0;
    }
    uint32_t sum = (id >> 8) + (id & 0xFFu) + dlc;
    for (uint8_t i = 0u; i + 1u < dlc; i++) {
        sum += data[i];
    }
    return (uint8_t)(sum & 0xFFu) == data[dlc - 1u];
}

int vehicle_checksum_subaru(uint32_t id, const uint8_t *data, uint8_t dlc)
{
    if (dlc == 0u || dlc > 8u) {
        return 0;
    }
    uint32_t sum = (id >> 8) + (id & 0xFFu);
    for (uint8_t i = 1u; i < dlc; i++) {
        sum += data[i];
    }
    return (uint8_t)(sum & 0xFFu) == data[0];
}

int vehicle_checksum_honda(uint32_t id, const uint8_t *data, uint8_t dlc)
{
    if (dlc == 0u || dlc > 8u || id > 0x7FFu) {
        return 0;
    }
    uint32_t sum = (id >> 8) + ((id >> 4) & 0xFu) + (id & 0xFu);
    for (uint8_t i = 0u; i + 1u < dlc; i++) {
        sum += (uint32_t)(data[i] >> 4) + (data[i] & 0xFu);
    }
    sum += (uint32_t)(data[dlc - 1u] >> 4); /* the last byte's high nibble; the low one is it */
    return ((8u - sum) & 0xFu) == (data[dlc - 1u] & 0xFu);
}

/* one byte into a CRC-8H2F, most significant bit first */
static uint8_t crc8h2f_byte(uint8_t crc_in, uint8_t byte)
{
    uint8_t crc = (uint8_t)(crc_in ^ byte);
    for (unsigned bit = 0u; bit < 8u; bit++) {
        const uint8_t top = (uint8_t)(crc & 0x80u);
        crc = (uint8_t)(crc << 1);
        if (top != 0u) {
            crc = (uint8_t)(crc ^ 0x2Fu);
        }
    }
    return crc;
}

int vehicle_checksum_vw_mqb(uint32_t id, const uint8_t *data, uint8_t dlc,
                            const uint8_t data_id[VEHICLE_VW_DATA_IDS])
{
    (void)id; /* the identifier is in the data ID, which the profile gives */
    if (dlc < 2u || dlc > 8u) {
        return 0;
    }
    uint8_t crc = 0xFFu;
    for (uint8_t i = 1u; i < dlc; i++) {
        crc = crc8h2f_byte(crc, data[i]);
    }
    crc = (uint8_t)(crc8h2f_byte(crc, data_id[data[1] & 0x0Fu]) ^ 0xFFu);
    return crc == data[0];
}

/* the bits set in a byte (no table: one byte at a time, 8 steps) */
static uint32_t bits_set(uint8_t b)
{
    uint32_t n = 0u;
    for (uint8_t v = b; v != 0u; v = (uint8_t)(v >> 1)) {
        if ((v & 1u) != 0u) {
            n++;
        }
    }
    return n;
}

int vehicle_checksum_hkg_whl_spd(uint32_t id, const uint8_t *data, uint8_t dlc)
{
    (void)id; /* not in it */
    if (dlc != 8u) {
        return 0;
    }
    uint32_t ones = 0u;
    for (uint8_t i = 0u; i < 8u; i++) {
        /* bytes 1, 3, 5, 7: their top 2 bits are the counter's and the checksum's */
        const uint8_t keep = (i & 1u) != 0u ? (uint8_t)0x3Fu : (uint8_t)0xFFu;
        ones += bits_set((uint8_t)(data[i] & keep));
    }
    const uint32_t sent = ((uint32_t)(data[7] >> 6) << 2) | (uint32_t)(data[5] >> 6);
    return ((ones ^ 9u) & 0xFu) == sent;
}
