/*
 * e2e.h - end-to-end protection of CAN frames, AUTOSAR E2E Profile 1 style (docs/can.md).
 *
 * CRC: CRC8 SAE J1850 (polynomial 0x1D, initial value 0xFF, final XOR 0xFF, not reflected)
 * over the CAN identifier (2 bytes, low byte first) followed by payload bytes 0..6; the CRC
 * is payload byte 7. Alive counter: 4 bits, 0..14, +1 per frame of a message, 15 invalid.
 */
#ifndef NAVECU_E2E_H
#define NAVECU_E2E_H

#include <stdint.h>

/* CRC8 SAE J1850 over len bytes, continuing from crc_in (start with 0xFF, then XOR the final
 * value with 0xFF); the plain CRC of "123456789" is 0x4B. */
uint8_t e2e_crc8_update(uint8_t crc_in, const uint8_t *data, uint32_t len);

/* The E2E CRC of an 8-byte frame with identifier can_id (byte 7 excluded). */
uint8_t e2e_frame_crc(uint32_t can_id, const uint8_t data[8]);

/* Store the CRC in data[7]. */
void e2e_protect(uint32_t can_id, uint8_t data[8]);

/* 1 if data[7] holds the right CRC, else 0. */
int e2e_crc_ok(uint32_t can_id, const uint8_t data[8]);

/*
 * The CRC of a data element sent as two frames (the IMU sample: IMU_Rate, then IMU_Accel):
 * over the second frame's identifier (2 bytes, low first), all 8 bytes of the first frame
 * and bytes 0..6 of the second; it goes in byte 7 of the second frame.
 */
uint8_t e2e_pair_crc(uint32_t second_id, const uint8_t first[8], const uint8_t second[8]);

typedef struct {
    uint8_t last;  /* last accepted counter */
    uint8_t valid; /* a counter has been accepted since init or resync */
} e2e_counter_t;

#define E2E_COUNTER_MAX 14u

/*
 * Check an alive counter against the last one accepted. Returns the step (1 = the next
 * frame, 2..14 = step - 1 frames were lost), 0 for a repeated counter (the frame is a
 * duplicate and must be dropped), or -1 for the invalid value 15. The first counter after
 * init is accepted with step 1. A step or 1..14 updates the state; 0 and -1 do not.
 */
int e2e_counter_step(e2e_counter_t *c, uint8_t counter);

/* Next counter to send after `counter` (0..14 wrapping). */
uint8_t e2e_counter_next(uint8_t counter);

#endif
