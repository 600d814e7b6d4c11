/* e2e.c - see e2e.h. */
#include "e2e.h"

uint8_t e2e_crc8_update(uint8_t crc_in, const uint8_t *data, uint32_t len)
{
    uint8_t crc = crc_in;
    for (uint32_t i = 0; i < len; i++) {
        crc = (uint8_t)(crc ^ data[i]);
        for (int b = 0; b < 8; b++) {
            const unsigned shifted = ((unsigned)crc << 1) & 0xFFu;
            crc = (uint8_t)((crc & 0x80u) ? (shifted ^ 0x1Du) : shifted);
        }
    }
    return crc;
}

uint8_t e2e_frame_crc(uint32_t can_id, const uint8_t data[8])
{
    const uint8_t id_bytes[2] = {(uint8_t)(can_id & 0xFFu), (uint8_t)((can_id >> 8) & 0xFFu)};
    uint8_t crc = e2e_crc8_update(0xFFu, id_bytes, 2u);
    crc = e2e_crc8_update(crc, data, 7u);
    return (uint8_t)(crc ^ 0xFFu);
}

void e2e_protect(uint32_t can_id, uint8_t data[8])
{
    data[7] = e2e_frame_crc(can_id, data);
}

uint8_t e2e_pair_crc(uint32_t second_id, const uint8_t first[8], const uint8_t second[8])
{
    const uint8_t id_bytes[2] = {(uint8_t)(second_id & 0xFFu),
                                 (uint8_t)((second_id >> 8) & 0xFFu)};
    uint8_t crc = e2e_crc8_update(0xFFu, id_bytes, 2u);
    crc = e2e_crc8_update(crc, first, 8u);
    crc = e2e_crc8_update(crc, second, 7u);
    return (uint8_t)(crc ^ 0xFFu);
}

int e2e_crc_ok(uint32_t can_id, const uint8_t data[8])
{
    return data[7] == e2e_frame_crc(can_id, data);
}

int e2e_counter_step(e2e_counter_t *c, uint8_t counter)
{
    if (counter > E2E_COUNTER_MAX) {
        return -1;
    }
    if (!c->valid) {
        c->valid = 1u;
        c->last = counter;
        return 1;
    }
    const int step = ((int)counter - (int)c->last + 15) % 15;
    if (step == 0) {
        return 0;
    }
    c->last = counter;
    return step;
}

uint8_t e2e_counter_next(uint8_t counter)
{
    return (uint8_t)(counter >= E2E_COUNTER_MAX ? 0u : counter + 1u);
}
