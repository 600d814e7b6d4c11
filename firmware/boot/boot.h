/*
 * boot.h - the bootloader's logic (issue #19): the UDS server of firmware/diag/uds.c with
 * the programming services plugged in (uds_if_t.session_change and .service), on the
 * ISO-TP channel of firmware/diag/isotp.c, the application's flash through boot_flash_t.
 * Pure: no HAL clock, no allocation, no recursion, no global state; the same code runs on
 * the STM32F405 (boards/stm32f405/boot_main.c, register-level flash driver), on the host
 * (host_sim/boot_main.c, a file as the flash) and in the unit tests (tests/test_boot.c, RAM
 * as the flash with a power cut after N programmed bytes).
 *
 * Services (docs/can.md, "Programming (the bootloader)", has every byte):
 *   0x10 01 default, 02 programming, 03 extended; 0x11 01 (unlocked); 0x3E 00;
 *   0x27 01/02 as the application (uds.c: the same seed and key)
 *   0x22 F180 (bootSoftwareIdentification), F186 (the session)
 *   0x31 01 FF00 eraseMemory (44 addr size), 0x31 01 FF01 checkProgrammingDependencies
 *        (the image's CRC-32):
 *        programming session, unlocked
 *   0x34 RequestDownload (00 44 addr size), 0x36 TransferData, 0x37 RequestTransferExit:
 *        programming session, unlocked
 * The image becomes valid only when FF01 found the written flash's CRC-32 equal to
 * the tester's and the vectors sane (initial SP in RAM, reset vector a Thumb address in the
 * image); the marker (boot_image.h) is then the last thing written. eraseMemory erases the
 * marker's sector first. Anything interrupted (a power cut, a reset, a session change, S3)
 * leaves no marker: the bootloader stays and answers.
 */
#ifndef NAVECU_BOOT_H
#define NAVECU_BOOT_H

#include <stddef.h>
#include <stdint.h>

#include "boot_image.h"
#include "isotp.h"
#include "uds.h"

#define BOOT_RID_ERASE 0xFF00u   /* eraseMemory (ISO 14229-1 Annex F range) */
#define BOOT_RID_CHECK 0xFF01u   /* checkProgrammingDependencies: the image's CRC-32 */
#define BOOT_DID_VERSION 0xF180u /* bootSoftwareIdentification */
#define BOOT_DID_SESSION 0xF186u /* activeDiagnosticSession */
#define BOOT_DID_COUNTERS 0xFD00u /* its counts, 6 x uint32 big-endian (ISO 14229-1
                                   0xFD00-0xFEFF: system supplier specific) */
#define BOOT_ALFID 0x44u         /* addressAndLengthFormatIdentifier: 4 + 4 bytes */
#define BOOT_VERSION_STRING "navecu-boot 2" /* 2: DID 0xFD00 */

#define UDS_SID_REQUEST_DOWNLOAD 0x34u
#define UDS_SID_TRANSFER_DATA 0x36u
#define UDS_SID_TRANSFER_EXIT 0x37u
#define UDS_NRC_UPLOAD_DOWNLOAD_NOT_ACCEPTED 0x70u
#define UDS_NRC_TRANSFER_DATA_SUSPENDED 0x71u
#define UDS_NRC_WRONG_BLOCK_SEQUENCE_COUNTER 0x73u

/* Longest TransferData request (SID, counter, data) announced in the 0x34 response:
 * 512, the ECU's ISO-TP buffer (M4_DEFS), on every build, so that the host build
 * (ISOTP_MAX_LEN 4095) answers a tester byte for byte as the ECU and QEMU builds do. */
#if ISOTP_MAX_LEN > 512u
#define BOOT_MAX_BLOCK 512u
#else
#define BOOT_MAX_BLOCK ((uint32_t)ISOTP_MAX_LEN)
#endif
#define BOOT_RSP_LEN 64u /* the bootloader's responses are short */

/* The application's flash. Addresses are absolute (BOOT_APP_START ..); the logic only
 * ever passes ranges inside [BOOT_APP_START, BOOT_APP_START + BOOT_APP_SIZE).
 *   read   copy len bytes at addr: 0, or a negative HAL code
 *   write  program buf[0..len) at addr (erased before): 0, or a negative HAL code (a
 *          power cut: the bytes may be partly programmed)
 *   erase  erase application sector index (0: sector 3, 1: sector 4): 0 or a negative code */
typedef struct {
    void *ctx;
    int (*read)(void *ctx, uint32_t addr, uint8_t *buf, size_t len);
    int (*write)(void *ctx, uint32_t addr, const uint8_t *buf, size_t len);
    int (*erase)(void *ctx, size_t sector);
} boot_flash_t;

/* The application's erase sectors (absolute address, size), the marker's first. */
#define BOOT_N_SECTORS 2u
typedef struct {
    uint32_t addr;
    uint32_t size;
} boot_sector_t;
extern const boot_sector_t boot_sectors[BOOT_N_SECTORS];

/* Counted, saturating. */
typedef struct {
    uint32_t blocks_written; /* TransferData blocks programmed */
    uint32_t blocks_repeated;/* a repeat of the last block, acknowledged, not rewritten */
    uint32_t erases;         /* sectors erased */
    uint32_t checks_failed;  /* the check routine (FF01) refused (CRC, vectors, marker write) */
    uint32_t flash_errors;   /* erase/write/read that returned an error */
    uint32_t pending_sent;   /* 7F xx 78 sent before an erase or the check */
    uint32_t returns;        /* back to the default session with the application whole:
                                reset into it (boot_poll) */
} boot_counters_t;

/* Why the application is (not) started: boot_image_check. */
typedef enum {
    BOOT_IMAGE_OK = 0,
    BOOT_IMAGE_NO_MARKER,   /* erased or interrupted: no or a broken marker */
    BOOT_IMAGE_BAD_LENGTH,  /* the marker's length is outside the application region */
    BOOT_IMAGE_BAD_CRC,     /* the flash does not match the marker's CRC */
    BOOT_IMAGE_BAD_VECTORS, /* initial SP not in RAM or reset vector not in the image */
    BOOT_IMAGE_READ_ERROR
} boot_image_t;

/* The bootloader: the ISO-TP channel, the UDS server, the download state. Caller-owned. */
typedef struct {
    isotp_t tp;
    uds_t srv;
    boot_flash_t fl;
    boot_counters_t cnt;
    isotp_tx_fn tx;          /* the CAN transmit function and its argument */
    void *tx_user;
    uint64_t now_us;         /* time of the request being served */
    uint32_t erased_end;     /* the application is erased in [BOOT_APP_START, erased_end) */
    uint32_t dl_len;         /* RequestDownload's size */
    uint32_t dl_pos;         /* bytes of it programmed */
    uint32_t last_pos;       /* where the last accepted block started, its length */
    uint32_t last_len;
    uint8_t dl_state;        /* 0 none, 1 transferring, 2 exited (FF01 may run) */
    uint8_t bsc;             /* the next block sequence counter expected */
    uint8_t reset_due;       /* ECUReset accepted: the board resets once it went out */
    uint8_t session_seen;    /* the session at the end of the last boot_poll */
    uint8_t hb_sent;         /* NAV_Heartbeat (Mode Bootloader) sent since the start */
    uint8_t hb_counter;      /* its E2E alive counter, the next one */
    uint32_t hb_uptime_s;    /* the uptime of the last one */
    uint64_t start_us;       /* the first boot_poll: uptime 0 */
    uint8_t req[ISOTP_MAX_LEN];
    uint8_t rsp[BOOT_RSP_LEN];
} boot_t;

/* Check the application in flash: marker, length, CRC over the flash, vectors. */
boot_image_t boot_image_check(const boot_flash_t *fl);

/* The marker bytes for an image of len bytes with CRC crc (the package tool writes the
 * same into a factory image: `make flash`). */
void boot_marker_encode(uint32_t len, uint32_t crc, uint8_t out[BOOT_MARKER_LEN]);

/* Start: channel on (rx_id, tx_id) with ISO-TP's defaults, the server in the default
 * session, locked. Returns 0, or -1 for a bad argument. */
int boot_init(boot_t *b, const boot_flash_t *fl, uint32_t rx_id, uint32_t tx_id, isotp_tx_fn tx,
              void *tx_user, uint32_t entropy);

/* Started by the application's programming request: the programming session, and its
 * positive response (50 02 P2 P2*) sent as the answer the application left pending. */
void boot_programming_requested(boot_t *b, uint64_t now_us);

/* One UDS request req[0..len) at now_us (without the transport): the response at rsp (cap
 * bytes), its length (0: none). What boot_frame / boot_poll call; the unit tests call it. */
size_t boot_handle(boot_t *b, const uint8_t *req, size_t len, uint64_t now_us, uint8_t *rsp,
                   size_t cap);

/* One received CAN frame (others than the request ID are ignored), then the serving. */
void boot_frame(boot_t *b, const hal_can_frame_t *f, uint64_t now_us);

/* Timers and the serving: call from the main loop. Sends NAV_Heartbeat (0x314, Mode
 * Bootloader) at the first call and at each whole second after it, so that a bootloader
 * that stays says so on the bus (the application's heartbeat, docs/can.md). Returns 1 once
 * an accepted ECUReset's response has left, or when the session fell back to the default
 * (S3: the tester gone, or its 10 01) while the application is still whole (nothing
 * erased): the board resets now and, the image valid, the application starts; else 0. */
int boot_poll(boot_t *b, uint64_t now_us);

#endif /* NAVECU_BOOT_H */
