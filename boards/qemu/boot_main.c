/*
 * boards/qemu/boot_main.c - the bootloader's logic (firmware/boot/boot.c) on the Cortex-M4F
 * under QEMU (netduinoplus2 emulates no flash controller and no CAN controller): the
 * application's flash is a host file read and rewritten through semihosting, the CAN bus
 * a candump log in and out (hal_semihost.h), as the QEMU application's.
 *
 *   qemu-system-arm -M netduinoplus2 ... -kernel build/target/boot-qemu.elf \
 *       -semihosting-config enable=on,target=native,arg=boot,arg=IN.log,arg=OUT.log,arg=FLASH
 *       [,arg=request] [,arg=cut-in-erase=N]
 *
 * FLASH: the application region (80 KiB from 0x0800C000; erased when missing), written
 * back whole after every erase and write, so the file is the flash whenever QEMU stops. At
 * start the image is checked as on the ECU: valid, the program says so and exits 0 (the
 * harness starts the application: the ECU's boot.elf with FLASH loaded at 0x0800C000);
 * else the bootloader serves UDS on 0x7A0/0x7A8 to the tester's frames of IN.log, its
 * answers to OUT.log, until an ECUReset (the image checked again: exit 0) or the end of
 * IN.log (exit 0: the power goes). Exit 1: a file could not be opened or written.
 * request: start as after the application's programming request (hal_bootloader: the
 * image is not started, the programming session is open), as the host build's --request.
 * cut-in-erase=N: the power goes half way through the N-th sector erase (0 the first):
 * the first half of that sector erased, the rest as it was, the file saved, exit 0 (as
 * the host build's --cut-in-erase N).
 */
#include <stdint.h>
#include <string.h>

#include "bench_trace.h"
#include "boot.h"
#include "hal_semihost.h"
#include "semihost.h"

static hal_t qb_hal;
static boot_t qb_boot;
static uint8_t qb_mem[BOOT_APP_SIZE];
static const char *flash_path;
static int32_t cut_in_erase = -1; /* erases before the cut one; < 0: none */

void board_main(void) __attribute__((noreturn));
void board_fault(void);

void board_fault(void)
{
    bench_puts("boot-qemu: fault exception\n");
    semihost_exit(3u);
}

static int qb_save(void)
{
    const int32_t h = semihost_open(flash_path, SEMIHOST_MODE_WB);
    if (h < 0) {
        return HAL_EIO;
    }
    const int32_t rc = semihost_write(h, qb_mem, sizeof qb_mem);
    (void)semihost_close(h);
    return rc == 0 ? 0 : HAL_EIO;
}

static int qb_read(void *ctx, uint32_t addr, uint8_t *buf, size_t len)
{
    (void)ctx;
    if (addr < BOOT_APP_START || (size_t)(addr - BOOT_APP_START) + len > sizeof qb_mem) {
        return HAL_EINVAL;
    }
    (void)memcpy(buf, &qb_mem[addr - BOOT_APP_START], len);
    return 0;
}

static int qb_write(void *ctx, uint32_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    if (addr < BOOT_APP_START || (size_t)(addr - BOOT_APP_START) + len > sizeof qb_mem) {
        return HAL_EINVAL;
    }
    for (size_t k = 0u; k < len; k++) {
        qb_mem[(size_t)(addr - BOOT_APP_START) + k] &= buf[k]; /* NOR: clears bits only */
    }
    return qb_save();
}

static int qb_erase(void *ctx, size_t sector)
{
    (void)ctx;
    if (sector >= BOOT_N_SECTORS) {
        return HAL_EINVAL;
    }
    uint8_t *start = &qb_mem[boot_sectors[sector].addr - BOOT_APP_START];
    if (cut_in_erase == 0) {
        (void)memset(start, 0xFF, boot_sectors[sector].size / 2u);
        (void)qb_save();
        (void)hal_semihost_close(&qb_hal);
        bench_puts("boot-qemu: power cut half way through an erase\n");
        semihost_exit(0u);
    }
    if (cut_in_erase > 0) {
        cut_in_erase--;
    }
    (void)memset(start, 0xFF, boot_sectors[sector].size);
    return qb_save();
}

static const boot_flash_t qb_flash = {NULL, qb_read, qb_write, qb_erase};

static int qb_tx(void *user, const hal_can_frame_t *f)
{
    return hal_can_send((hal_t *)user, f);
}

/* the ECU's decision at reset: a valid image ends this run (the harness starts it) */
static void check_and_start(void)
{
    if (boot_image_check(&qb_flash) == BOOT_IMAGE_OK) {
        (void)hal_semihost_close(&qb_hal);
        bench_puts("boot-qemu: application valid: started\n");
        semihost_exit(0u);
    }
}

void board_main(void)
{
    const char *argv[6] = {NULL, NULL, NULL, NULL, NULL, NULL};
    const size_t argc = bench_args(argv, 6u);
    if (argc < 4u) {
        bench_puts("usage: boot-qemu IN.log OUT.log FLASH [request] [cut-in-erase=N] "
                   "(semihosting arguments)\n");
        semihost_exit(2u);
    }
    flash_path = argv[3];
    int request = 0;
    for (size_t i = 4u; i < argc; i++) {
        if (strcmp(argv[i], "request") == 0) {
            request = 1;
        } else if (strncmp(argv[i], "cut-in-erase=", 13u) == 0 && argv[i][13] >= '0' &&
                   argv[i][13] <= '9' && argv[i][14] == '\0') {
            const int32_t digit = (int32_t)argv[i][13];
            cut_in_erase = digit - (int32_t)'0';
        } else {
            bench_puts("boot-qemu: unknown argument\n");
            semihost_exit(2u);
        }
    }
    (void)memset(qb_mem, 0xFF, sizeof qb_mem);
    const int32_t h = semihost_open(flash_path, SEMIHOST_MODE_RB);
    if (h >= 0) {
        (void)semihost_read(h, qb_mem, sizeof qb_mem); /* shorter: the rest stays erased */
        (void)semihost_close(h);
    } else if (qb_save() != 0) {
        bench_puts("boot-qemu: cannot create the flash file\n");
        semihost_exit(1u);
    } else {
        /* a new, erased flash */
    }
    if (hal_semihost_open(&qb_hal, argv[1], argv[2]) != 0) {
        bench_puts("boot-qemu: cannot open the input or output log\n");
        semihost_exit(1u);
    }
    if (request == 0) {
        check_and_start();
    }
    bench_puts(request != 0 ? "boot-qemu: programming requested: the bootloader serves UDS\n"
                            : "boot-qemu: no valid application: the bootloader serves UDS\n");
    /* the host build's entropy (host_sim/boot_main.c, time 0 at start): the same seeds */
    (void)boot_init(&qb_boot, &qb_flash, 0x7A0u, 0x7A8u, qb_tx, &qb_hal,
                    (uint32_t)hal_time_us(&qb_hal) ^ 0x1234567u);
    if (request != 0) {
        boot_programming_requested(&qb_boot, hal_time_us(&qb_hal));
    }
    for (;;) {
        hal_can_frame_t f;
        const int rc = hal_can_receive(&qb_hal, &f);
        if (rc == 0) {
            boot_frame(&qb_boot, &f, hal_time_us(&qb_hal));
        }
        if (boot_poll(&qb_boot, hal_time_us(&qb_hal))) {
            check_and_start(); /* ECUReset */
            bench_puts("boot-qemu: reset, no valid application\n");
            (void)boot_init(&qb_boot, &qb_flash, 0x7A0u, 0x7A8u, qb_tx, &qb_hal,
                            (uint32_t)hal_time_us(&qb_hal) ^ 0x1234567u);
        }
        if (rc != 0) {
            break;
        }
    }
    const int close_rc = hal_semihost_close(&qb_hal);
    bench_puts("boot-qemu: end of the log (power off)\n");
    semihost_exit(close_rc == 0 ? 0u : 1u);
}
