/*
 * host_sim/boot_main.c - the bootloader's logic (firmware/boot/boot.c) as a host program:
 * build/host/navecu-boot, the peer of tools/navecu_flash.py in its tests and for trying the
 * flash sequence without an ECU (docs/target.md, "The bootloader").
 *
 *   navecu-boot --flash FILE [--request] [--cut-after BYTES] [--cut-in-erase N]
 *
 * FILE is the application region (sectors 3 and 4, 80 KiB, absolute address 0x0800C000 at
 * offset 0), created erased when missing; every erase and write goes to it at once, so the
 * file is the flash whenever the program ends. Frames come in on stdin as candump lines
 * (their timestamps are the bootloader's clock), the frames it sends go out on stdout,
 * one flushed line each. At start and after each ECUReset the image is checked as the ECU
 * does: a valid one "starts" (said on stderr); the program then stands in for the
 * application in the one thing the flash sequence needs from it: a 10 02 request is
 * answered 7F 10 78 and the bootloader starts as after hal_bootloader (the request word
 * set), answering 50 02. Without a valid image it serves UDS on 0x7A0/0x7A8 at once.
 * --request starts as after the application's programming request. A power cut: --cut-after N ends the program (exit 3) when N
 * more bytes would be programmed, the bytes before written; --cut-in-erase N ends it half
 * way through the N-th sector erase (the first half erased). End of input: exit 0.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "boot.h"
#include "candump.h"

#define EXIT_CUT 3

static FILE *flash_file;
static uint8_t mem[BOOT_APP_SIZE];
static long cut_after = -1;   /* bytes still programmed before the cut; < 0: none */
static long cut_in_erase = -1; /* erases before the cut one; < 0: none */
static uint64_t now_us;

static void persist(uint32_t off, size_t len)
{
    if (fseek(flash_file, (long)off, SEEK_SET) != 0 || fwrite(&mem[off], 1, len, flash_file) != len ||
        fflush(flash_file) != 0) {
        fprintf(stderr, "navecu-boot: cannot write the flash file\n");
        exit(1);
    }
}

static int fl_read(void *ctx, uint32_t addr, uint8_t *buf, size_t len)
{
    (void)ctx;
    if (addr < BOOT_APP_START || addr - BOOT_APP_START + len > BOOT_APP_SIZE) {
        return HAL_EINVAL;
    }
    memcpy(buf, &mem[addr - BOOT_APP_START], len);
    return 0;
}

static int fl_write(void *ctx, uint32_t addr, const uint8_t *buf, size_t len)
{
    (void)ctx;
    if (addr < BOOT_APP_START || addr - BOOT_APP_START + len > BOOT_APP_SIZE) {
        return HAL_EINVAL;
    }
    const uint32_t off = addr - BOOT_APP_START;
    size_t n = len;
    if (cut_after >= 0 && (long)len > cut_after) {
        n = (size_t)cut_after;
    }
    for (size_t k = 0u; k < n; k++) {
        mem[off + k] &= buf[k]; /* NOR flash: programming clears bits only */
    }
    persist(off, n);
    if (n < len) {
        fprintf(stderr, "navecu-boot: power cut after %zu of %zu bytes at 0x%08X\n", n, len,
                (unsigned)addr);
        exit(EXIT_CUT);
    }
    if (cut_after >= 0) {
        cut_after -= (long)len;
    }
    return 0;
}

static int fl_erase(void *ctx, size_t sector)
{
    (void)ctx;
    if (sector >= BOOT_N_SECTORS) {
        return HAL_EINVAL;
    }
    const uint32_t off = boot_sectors[sector].addr - BOOT_APP_START;
    const uint32_t size = boot_sectors[sector].size;
    if (cut_in_erase == 0) {
        memset(&mem[off], 0xFF, size / 2u);
        persist(off, size / 2u);
        fprintf(stderr, "navecu-boot: power cut half way through erasing sector %zu\n",
                sector);
        exit(EXIT_CUT);
    }
    if (cut_in_erase > 0) {
        cut_in_erase--;
    }
    memset(&mem[off], 0xFF, size);
    persist(off, size);
    return 0;
}

static int tx(void *user, const hal_can_frame_t *f)
{
    (void)user;
    char line[CANDUMP_FORMAT_MAX + 1u];
    const size_t n = candump_format_line(line, sizeof line, now_us, "can0", f);
    if (n == 0u) {
        return HAL_EINVAL;
    }
    fwrite(line, 1, n, stdout);
    fflush(stdout);
    return 0;
}

static const boot_flash_t flash = {NULL, fl_read, fl_write, fl_erase};
static boot_t boot;
static int app_running; /* the "application" runs: only 10 02 is answered */

/* the ECU's reset: check the image, "start" it (exit) or serve */
static void power_on(int request)
{
    const boot_image_t st = request ? BOOT_IMAGE_NO_MARKER : boot_image_check(&flash);
    if (!request && st == BOOT_IMAGE_OK) {
        uint32_t len;
        memcpy(&len, &mem[BOOT_MARKER_ADDR - BOOT_APP_START + 4u], sizeof len);
        fprintf(stderr, "navecu-boot: application valid (%u bytes): started\n", (unsigned)len);
        app_running = 1;
        return;
    }
    app_running = 0;
    fprintf(stderr, "navecu-boot: %s: the bootloader serves UDS\n",
            request ? "programming requested" : "no valid application");
    if (boot_init(&boot, &flash, 0x7A0u, 0x7A8u, tx, NULL, (uint32_t)now_us ^ 0x1234567u) != 0) {
        exit(1);
    }
    if (request) {
        boot_programming_requested(&boot, now_us);
    }
}

static int usage(void)
{
    fprintf(stderr, "usage: navecu-boot --flash FILE [--request] [--cut-after BYTES] "
                    "[--cut-in-erase N]\n");
    return 2;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    int request = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--flash") == 0 && i + 1 < argc) {
            path = argv[++i];
        } else if (strcmp(argv[i], "--request") == 0) {
            request = 1;
        } else if (strcmp(argv[i], "--cut-after") == 0 && i + 1 < argc) {
            cut_after = strtol(argv[++i], NULL, 0);
        } else if (strcmp(argv[i], "--cut-in-erase") == 0 && i + 1 < argc) {
            cut_in_erase = strtol(argv[++i], NULL, 0);
        } else {
            return usage();
        }
    }
    if (path == NULL) {
        return usage();
    }
    memset(mem, 0xFF, sizeof mem);
    flash_file = fopen(path, "r+b");
    if (flash_file == NULL) {
        flash_file = fopen(path, "w+b");
        if (flash_file == NULL) {
            fprintf(stderr, "navecu-boot: cannot open %s\n", path);
            return 1;
        }
        persist(0u, sizeof mem);
    } else if (fread(mem, 1, sizeof mem, flash_file) != sizeof mem) {
        fprintf(stderr, "navecu-boot: %s is not a %u-byte flash image\n", path,
                (unsigned)sizeof mem);
        return 1;
    }
    power_on(request);
    char line[256];
    while (fgets(line, sizeof line, stdin) != NULL) {
        hal_can_frame_t f;
        if (candump_parse_line(line, strcspn(line, "\r\n"), &f) != CANDUMP_FRAME) {
            continue;
        }
        if (f.t_us > now_us) {
            now_us = f.t_us;
        }
        if (app_running) {
            /* the application's part (app_uds.c session_change): 10 02 -> 7F 10 78, then
             * the reset into the bootloader with the request set */
            if (!f.extended && f.id == 0x7A0u && f.dlc >= 3u && f.data[0] == 0x02u &&
                f.data[1] == 0x10u && f.data[2] == 0x02u) {
                const hal_can_frame_t p = {0x7A8u, 0u, 8u, {0x03, 0x7F, 0x10, 0x78, 0xCC, 0xCC, 0xCC, 0xCC}, 0u};
                (void)tx(NULL, &p);
                power_on(1);
            }
            continue;
        }
        if (!f.extended && f.id == boot.tp.cfg.rx_id) {
            boot_frame(&boot, &f, now_us);
        }
        if (boot_poll(&boot, now_us)) {
            power_on(0); /* ECUReset */
        }
    }
    return 0;
}
