/*
 * vehicle_checksum.h - the car makers' own frame checksums that a vehicle profile may name
 * for a message it reads ("checksum" in a vehicles/ profile); called by the generated
 * vehicle_profile.c.
 */
#ifndef NAVECU_VEHICLE_CHECKSUM_H
#define NAVECU_VEHICLE_CHECKSUM_H

#include <stdint.h>

/* Toyota: the last byte is (ID >> 8) + (ID & 0xFF) + DLC + the sum of the other bytes,
 * modulo 256. 1 if data[0..dlc) carries it (dlc 1..8), else 0. Checked on the RAV4's
 * recorded bus: every frame of the 87 identifiers that carry it passes (data/comma2k19-rav4). */
int vehicle_checksum_toyota(uint32_t id, const uint8_t *data, uint8_t dlc);

/* Subaru (global platform, opendbc's subaru_global_* DBCs, signal CHECKSUM): the first byte
 * is (ID >> 8) + (ID & 0xFF) + the sum of the other bytes, modulo 256 (no DLC, unlike
 * Toyota's). 1 if data[0..dlc) carries it (dlc 1..8), else 0. Not checked on a recording
 * (the project has none of a Subaru): from opendbc's definition of the checksum. */
int vehicle_checksum_subaru(uint32_t id, const uint8_t *data, uint8_t dlc);

/* Honda: the low 4 bits of the last byte are 8 minus the sum of every other 4-bit nibble
 * of the frame (the identifier's three nibbles, the data's but that one), modulo 16.
 * 1 if data[0..dlc) carries it (dlc 1..8, a standard identifier), else 0. From opendbc's
 * definition of the checksum; no Honda recording in the project. */
int vehicle_checksum_honda(uint32_t id, const uint8_t *data, uint8_t dlc);

/* The E2E data IDs of a Volkswagen MQB message, one per value of its 4-bit counter. */
#define VEHICLE_VW_DATA_IDS 16u

/* Volkswagen MQB (opendbc's vw_mqb DBC, signal CHECKSUM, byte 0): AUTOSAR E2E profile 2's
 * CRC-8H2F (polynomial 0x2F, MSB first, initial value and final XOR 0xFF) over bytes
 * 1..dlc-1 and then the message's data ID for the frame's counter (byte 1's low nibble),
 * data_id[that counter] (the profile's checksum_data_ids, from opendbc's
 * VOLKSWAGEN_MQB_MEB_CONSTANTS). 1 if data[0..dlc) carries it (dlc 2..8), else 0. No
 * Volkswagen recording in the project: tested against opendbc's own implementation. */
int vehicle_checksum_vw_mqb(uint32_t id, const uint8_t *data, uint8_t dlc,
                            const uint8_t data_id[VEHICLE_VW_DATA_IDS]);

/* Hyundai/Kia WHL_SPD11 (opendbc's hyundai_kia_generic DBC, 0x386, 8 bytes): a 4-bit
 * checksum split over the top 2 bits of byte 5 (WHL_SPD_Checksum_LSB) and of byte 7
 * (_MSB): the number of bits set in the frame but the top 2 bits of bytes 1, 3, 5 and 7
 * (the rolling counter's two halves and the checksum's), XOR 9, modulo 16. The counter is
 * not covered (the profile checks it apart). 1 if data[0..8) carries it (dlc 8), else 0.
 * From opendbc's definition (its safety code and the checksum of its safety tests); no
 * Hyundai or Kia recording in the project. */
int vehicle_checksum_hkg_whl_spd(uint32_t id, const uint8_t *data, uint8_t dlc);

#endif /* NAVECU_VEHICLE_CHECKSUM_H */
