/* test_vehicle_checksum.c - the car makers' frame checksums (firmware/vehicle/vehicle_checksum.c)
 * on known frames: a real one of the RAV4's bus for Toyota's, frames summed by hand from the
 * definitions for Subaru's and Honda's (no recording of either car in the project), frames
 * whose CRC opendbc's own implementation computed for Volkswagen's, and for Hyundai/Kia's a
 * frame counted by hand and filled by opendbc's own function (test_vehicle_load.py runs it
 * against the project's encoder on 2,000 frames). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "vehicle_checksum.h"

typedef int (*checksum_fn)(uint32_t id, const uint8_t *data, uint8_t dlc);

/* every single-bit error of the frame is caught (a byte sum changes by +-2^b) */
static void assert_single_bit_errors_caught(checksum_fn fn, uint32_t id, uint8_t *d, uint8_t dlc)
{
    for (uint8_t byte = 0u; byte < dlc; byte++) {
        for (unsigned bit = 0u; bit < 8u; bit++) {
            d[byte] ^= (uint8_t)(1u << bit);
            assert_false(fn(id, d, dlc));
            d[byte] ^= (uint8_t)(1u << bit);
        }
    }
    assert_true(fn(id, d, dlc));
}

/* data/comma2k19-rav4/car_bus.log, its first KINEMATICS frame: 024#01FE01D541F980BB
 * (0x00 + 0x24 + 8 + 0x01 + 0xFE + 0x01 + 0xD5 + 0x41 + 0xF9 + 0x80 = 0x3BB) */
static void test_toyota_recorded_frame(void **state)
{
    (void)state;
    uint8_t d[8] = {0x01, 0xFE, 0x01, 0xD5, 0x41, 0xF9, 0x80, 0xBB};
    assert_true(vehicle_checksum_toyota(0x024u, d, 8u));
    assert_false(vehicle_checksum_toyota(0x025u, d, 8u)); /* the identifier is summed */
    assert_false(vehicle_checksum_toyota(0x024u, d, 7u)); /* so is the DLC */
    assert_single_bit_errors_caught(vehicle_checksum_toyota, 0x024u, d, 8u);
    assert_false(vehicle_checksum_toyota(0x024u, d, 0u));
    assert_false(vehicle_checksum_toyota(0x024u, d, 9u));
}

/* Subaru: the first byte, over the identifier's bytes and bytes 1..dlc-1, no DLC:
 * 0x13A (Wheel_Speeds): 0x01 + 0x3A + (1 + 2 + ... + 7) = 0x57;
 * 0x048 (Transmission): 0x00 + 0x48 + 0x0A + 0x79 = 0xCB */
static void test_subaru_frames(void **state)
{
    (void)state;
    uint8_t w[8] = {0x57, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07};
    assert_true(vehicle_checksum_subaru(0x13Au, w, 8u));
    assert_false(vehicle_checksum_subaru(0x13Bu, w, 8u));  /* the identifier is summed */
    assert_false(vehicle_checksum_toyota(0x13Au, w, 8u));  /* not Toyota's: other byte, no DLC */
    assert_single_bit_errors_caught(vehicle_checksum_subaru, 0x13Au, w, 8u);
    uint8_t g[8] = {0xCB, 0x0A, 0x00, 0x79, 0x00, 0x00, 0x00, 0x00};
    assert_true(vehicle_checksum_subaru(0x048u, g, 8u));
    assert_single_bit_errors_caught(vehicle_checksum_subaru, 0x048u, g, 8u);
    /* a shorter frame sums only its own bytes: 0x00 + 0x48 + 0x0A = 0x52 */
    uint8_t s[2] = {0x52, 0x0A};
    assert_true(vehicle_checksum_subaru(0x048u, s, 2u));
    assert_false(vehicle_checksum_subaru(0x048u, w, 0u));
    assert_false(vehicle_checksum_subaru(0x048u, w, 9u));
}

/* Honda: the last byte's low nibble is 8 - (the identifier's nibbles + every other data
 * nibble), modulo 16:
 * 0x1D0 (WHEEL_SPEEDS), data 0: 8 - (1 + 0xD) = -6 = 0xA;
 * 0x1D0, 12 34 56 78 9A BC DE F_: 8 - (14 + (1 + 2 + ... + 14) + 15) = -126 = 0x2;
 * 0x191 (GEARBOX_CVT), 7 bytes of 0: 8 - (1 + 9 + 1) = -3 = 0xD */
static void test_honda_frames(void **state)
{
    (void)state;
    uint8_t z[8] = {0, 0, 0, 0, 0, 0, 0, 0x0A};
    assert_true(vehicle_checksum_honda(0x1D0u, z, 8u));
    assert_false(vehicle_checksum_honda(0x1D1u, z, 8u)); /* the identifier is summed */
    uint8_t w[8] = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF2};
    assert_true(vehicle_checksum_honda(0x1D0u, w, 8u));
    uint8_t g[7] = {0, 0, 0, 0, 0, 0, 0x0D};
    assert_true(vehicle_checksum_honda(0x191u, g, 7u));
    /* a nibble sum: a bit flipped anywhere changes it by +-2^b, b < 4, never 0 mod 16 */
    assert_single_bit_errors_caught(vehicle_checksum_honda, 0x1D0u, w, 8u);
    assert_false(vehicle_checksum_honda(0x1D0u, w, 0u));
    assert_false(vehicle_checksum_honda(0x1D0u, w, 9u));
    assert_false(vehicle_checksum_honda(0x800u, z, 8u)); /* not a standard identifier */
}

/* Volkswagen MQB, Getriebe_11 (0x0AD): byte 0 the CRC-8H2F of bytes 1..7 and the data ID
 * of byte 1's low nibble. Each CRC is what opendbc 0.3.1's volkswagen_mqb_meb_checksum
 * (car/volkswagen/mqbcan.py) returns for the frame, 0x0AD and its
 * VOLKSWAGEN_MQB_MEB_CONSTANTS, the data IDs of vehicles/vw_mqb.toml. */
static const uint8_t GETRIEBE_11_IDS[VEHICLE_VW_DATA_IDS] = {
    0x3F, 0x69, 0x39, 0xDC, 0x94, 0xF9, 0x14, 0x64,
    0xD8, 0x6A, 0x34, 0xCE, 0xA2, 0x55, 0xB5, 0x2C};

static int vw_getriebe_11(uint32_t id, const uint8_t *data, uint8_t dlc)
{
    return vehicle_checksum_vw_mqb(id, data, dlc, GETRIEBE_11_IDS);
}

static void test_vw_mqb_frames(void **state)
{
    (void)state;
    uint8_t a[8] = {0x4A, 0x05, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06}; /* counter 5 */
    uint8_t z[8] = {0x66, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}; /* counter 0 */
    uint8_t f[8] = {0x1C, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}; /* counter 15 */
    uint8_t h[8] = {0xAF, 0x30, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}; /* counter 0 */
    assert_true(vw_getriebe_11(0x0ADu, a, 8u));
    assert_true(vw_getriebe_11(0x0ADu, z, 8u));
    assert_true(vw_getriebe_11(0x0ADu, f, 8u));
    assert_true(vw_getriebe_11(0x0ADu, h, 8u));
    /* a CRC catches every single-bit error; the counter's bits choose the data ID too */
    assert_single_bit_errors_caught(vw_getriebe_11, 0x0ADu, a, 8u);
    assert_single_bit_errors_caught(vw_getriebe_11, 0x0ADu, f, 8u);
    /* the data ID is the message's: another message's (ESP_02's 0xAA for every counter)
     * refuses the frame */
    static const uint8_t esp_02[VEHICLE_VW_DATA_IDS] = {
        0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA,
        0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA, 0xAA};
    assert_false(vehicle_checksum_vw_mqb(0x0ADu, a, 8u, esp_02));
    assert_false(vw_getriebe_11(0x0ADu, a, 1u));
    assert_false(vw_getriebe_11(0x0ADu, a, 9u));
}

/* Hyundai/Kia WHL_SPD11 (0x386): the four wheels at 50 km/h (raw 1600 = 0x640 in each
 * 14-bit field), counter 6 (AliveCounter_MSB 1 in byte 3's top bits, _LSB 2 in byte 1's):
 * 40 86 40 46 40 46 40 46. Bits set but the top 2 of bytes 1, 3, 5, 7: 1+2+1+2+1+2+1+2 = 12;
 * 12 XOR 9 = 5: Checksum_LSB 01 (byte 5's top bits), _MSB 01 (byte 7's); opendbc's test
 * function gives the same frame. Every single-bit error outside the counter's four bits is
 * caught (the count moves by one, or the checksum's own bits change); the counter's are not
 * covered (its own check sees them). */
static void test_hyundai_kia_whl_spd_frame(void **state)
{
    (void)state;
    uint8_t d[8] = {0x40, 0x86, 0x40, 0x46, 0x40, 0x46, 0x40, 0x46};
    assert_true(vehicle_checksum_hkg_whl_spd(0x386u, d, 8u));
    assert_true(vehicle_checksum_hkg_whl_spd(0x387u, d, 8u)); /* the identifier is not in it */
    assert_false(vehicle_checksum_hkg_whl_spd(0x386u, d, 7u));
    for (uint8_t byte = 0u; byte < 8u; byte++) {
        for (unsigned bit = 0u; bit < 8u; bit++) {
            const int counter_bit = (byte == 1u || byte == 3u) && bit >= 6u;
            d[byte] ^= (uint8_t)(1u << bit);
            assert_int_equal(vehicle_checksum_hkg_whl_spd(0x386u, d, 8u), counter_bit);
            d[byte] ^= (uint8_t)(1u << bit);
        }
    }
    d[5] = (uint8_t)((d[5] & 0x3Fu) | 0x80u); /* checksum 6: off by one */
    assert_false(vehicle_checksum_hkg_whl_spd(0x386u, d, 8u));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_toyota_recorded_frame),
        cmocka_unit_test(test_subaru_frames),
        cmocka_unit_test(test_honda_frames),
        cmocka_unit_test(test_vw_mqb_frames),
        cmocka_unit_test(test_hyundai_kia_whl_spd_frame),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
