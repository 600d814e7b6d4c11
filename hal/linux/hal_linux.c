/*
 * hal_linux.c - the HAL of hal.h on a Linux host (contracts in hal_linux.h).
 *
 * The RX log's lines are read and parsed by hal/common/candump.c (shared with the QEMU
 * board's semihosting HAL); here: the files, the NVM file, the clock of a replay and the
 * emulated watchdog.
 */
#include "hal_linux.h"
#include "candump.h"
#include "nvm_flash.h"
#include "hal_socketcan.h"

#include <errno.h>
#include <inttypes.h>
#include <string.h>

#define US_PER_S UINT64_C(1000000)
#define STD_ID_MAX UINT32_C(0x7FF)
#define EXT_ID_MAX UINT32_C(0x1FFFFFFF)

static const char default_iface[] = "can0";

static uint32_t sat_inc_u32(uint32_t n)
{
    return n == UINT32_MAX ? n : n + 1u;
}

/* printable ASCII other than space: what an interface name may hold */
static int is_graph_ascii(char c)
{
    return c > ' ' && c <= '~';
}

/* candump_read's byte source: a stdio stream */
static int file_next_byte(void *ctx)
{
    FILE *fp = ctx;
    const int c = getc(fp);
    if (c != EOF) {
        return c;
    }
    return ferror(fp) ? CANDUMP_SRC_ERROR : CANDUMP_SRC_END;
}

int hal_can_receive(hal_t *hal, hal_can_frame_t *f)
{
    if (hal == NULL || f == NULL) {
        return HAL_EINVAL;
    }
    if (hal->can_fd >= 0) {
        return hal_socketcan_receive(hal, f);
    }
    if (hal->rx == NULL) {
        return HAL_ENODATA;
    }
    return candump_replay(&hal->rx_log, file_next_byte, hal->rx, hal->line, HAL_LINUX_LINE_MAX, f);
}

uint32_t hal_can_rx_lost(const hal_t *hal)
{
    /* a log's malformed lines (saturating); a live socket's drops (wrapping) and its
     * controller's receive overflows too */
    return hal->rx_log.malformed + hal->can_rx_dropped + hal->can_rx_overflow;
}

uint32_t hal_faults(hal_t *hal)
{
    /* no watchdog on the host; a live controller's bus-off is an error frame */
    uint32_t f = 0u;
    if (hal->can_bus_off != hal->can_bus_off_told) {
        hal->can_bus_off_told = hal->can_bus_off;
        f = HAL_FAULT_BUS_OFF;
    }
    return f;
}

uint64_t hal_time_us(const hal_t *hal)
{
    return hal->can_fd >= 0 ? hal_socketcan_time_us() : hal->rx_log.t_us;
}

int hal_can_send(hal_t *hal, const hal_can_frame_t *f)
{
    char line[CANDUMP_FORMAT_MAX];

    if (hal == NULL || f == NULL || f->dlc > 8u || f->extended > 1u ||
        f->id > (f->extended != 0u ? EXT_ID_MAX : STD_ID_MAX)) {
        return HAL_EINVAL;
    }
    if (hal->can_fd >= 0) {
        const int rc = hal_socketcan_send(hal, f);
        if (rc != 0) {
            return rc;
        }
    }
    if (hal->tx == NULL) {
        hal->tx_frames = sat_inc_u32(hal->tx_frames);
        return 0;
    }
    const size_t len = candump_format_line(line, sizeof line, hal_time_us(hal), hal->iface, f);
    if (len == 0u) {
        return HAL_EIO; /* cannot happen: the frame and the name were checked */
    }
    /* ferror also reports a failed flush of earlier, buffered lines */
    if (fwrite(line, 1u, len, hal->tx) != len || ferror(hal->tx)) {
        return HAL_EIO;
    }
    hal->tx_frames = sat_inc_u32(hal->tx_frames);
    return 0;
}

size_t hal_nvm_size(const hal_t *hal)
{
    (void)hal;
    return HAL_LINUX_NVM_SIZE;
}

size_t hal_nvm_sector_size(const hal_t *hal)
{
    (void)hal;
    return HAL_LINUX_NVM_SECTOR_SIZE;
}

/* write src[0..len) to the NVM file at offset, if there is a file; 0 or HAL_EIO */
static int nvm_file_write(hal_t *hal, size_t offset, const void *src, size_t len)
{
    if (hal->nvm_file == NULL) {
        return 0;
    }
    /* offset <= 4096 fits a long */
    if (fseek(hal->nvm_file, (long)offset, SEEK_SET) != 0 ||
        fwrite(src, 1u, len, hal->nvm_file) != len || fflush(hal->nvm_file) != 0) {
        return HAL_EIO;
    }
    return 0;
}

int hal_nvm_read(hal_t *hal, size_t offset, void *buf, size_t len)
{
    if (hal == NULL || !nvm_flash_args_ok(HAL_LINUX_NVM_SIZE, offset, buf, len)) {
        return HAL_EINVAL;
    }
    if (len > 0u) {
        memcpy(buf, hal->nvm + offset, len);
    }
    return 0;
}

int hal_nvm_write(hal_t *hal, size_t offset, const void *buf, size_t len)
{
    uint8_t programmed[HAL_LINUX_NVM_SIZE];

    if (hal == NULL || !nvm_flash_args_ok(HAL_LINUX_NVM_SIZE, offset, buf, len)) {
        return HAL_EINVAL;
    }
    if (len == 0u) {
        return 0;
    }
    /* flash programming only clears bits: what a write over programmed bytes leaves */
    const int verify_failed = nvm_flash_program(programmed, &hal->nvm[offset], buf, len);
    /* file first: the mirror only changes once the data is stored */
    const int rc = nvm_file_write(hal, offset, programmed, len);
    if (rc != 0) {
        return rc;
    }
    memcpy(hal->nvm + offset, programmed, len);
    return verify_failed ? HAL_EIO : 0;
}

int hal_nvm_erase_sector(hal_t *hal, size_t sector)
{
    uint8_t erased[HAL_LINUX_NVM_SECTOR_SIZE];

    if (hal == NULL || sector >= HAL_LINUX_NVM_SIZE / HAL_LINUX_NVM_SECTOR_SIZE) {
        return HAL_EINVAL;
    }
    memset(erased, 0xFF, sizeof erased);
    const size_t offset = sector * HAL_LINUX_NVM_SECTOR_SIZE;
    const int rc = nvm_file_write(hal, offset, erased, sizeof erased);
    if (rc != 0) {
        return rc;
    }
    memcpy(hal->nvm + offset, erased, sizeof erased);
    return 0;
}

int hal_nvm_erase(hal_t *hal)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    for (size_t k = 0u; k < HAL_LINUX_NVM_SIZE / HAL_LINUX_NVM_SECTOR_SIZE; k++) {
        const int rc = hal_nvm_erase_sector(hal, k);
        if (rc != 0) {
            return rc;
        }
    }
    return 0;
}

void hal_watchdog_kick(hal_t *hal)
{
    hal->watchdog_kicks++;
    hal->last_kick_us = hal_time_us(hal);
}

int hal_bootloader(hal_t *hal, int go)
{
    (void)hal;
    (void)go;
    return HAL_EIO; /* the host has no bootloader (host_sim/boot_main.c is its own program) */
}

/* Open or create the NVM file and load it into hal->nvm. 0 or HAL_EIO. */
static int nvm_open(hal_t *hal, const char *path)
{
    hal->nvm_file = fopen(path, "r+b");
    if (hal->nvm_file == NULL) {
        if (errno != ENOENT) {
            return HAL_EIO;
        }
        /* "w+x": fail rather than truncate a file that appeared meanwhile */
        hal->nvm_file = fopen(path, "w+bx");
        if (hal->nvm_file == NULL) {
            return HAL_EIO;
        }
        return nvm_file_write(hal, 0u, hal->nvm, sizeof hal->nvm);
    }
    if (fread(hal->nvm, 1u, sizeof hal->nvm, hal->nvm_file) != sizeof hal->nvm ||
        getc(hal->nvm_file) != EOF || ferror(hal->nvm_file)) {
        hal->open_failed = HAL_LINUX_FILE_NVM_SIZE;
        return HAL_EIO; /* short, long, or unreadable: not an NVM image of ours */
    }
    return 0;
}

int hal_linux_open(hal_t *hal, const char *rx_log_path, const char *tx_log_path,
                   const char *nvm_path)
{
    if (hal == NULL) {
        return HAL_EINVAL;
    }
    memset(hal, 0, sizeof *hal);
    hal->can_fd = -1;
    memcpy(hal->iface, default_iface, sizeof default_iface);
    memset(hal->nvm, 0xFF, sizeof hal->nvm);

    int rc = 0;
    if (rx_log_path != NULL) {
        hal->rx = fopen(rx_log_path, "rb");
        if (hal->rx == NULL) {
            hal->open_failed = HAL_LINUX_FILE_RX;
            rc = HAL_EIO;
        }
    }
    if (rc == 0 && tx_log_path != NULL) {
        hal->tx = fopen(tx_log_path, "wb");
        if (hal->tx == NULL) {
            hal->open_failed = HAL_LINUX_FILE_TX;
            rc = HAL_EIO;
        }
    }
    if (rc == 0 && nvm_path != NULL) {
        hal->open_failed = HAL_LINUX_FILE_NVM; /* unless nvm_open says more */
        rc = nvm_open(hal, nvm_path);
        if (rc == 0) {
            hal->open_failed = HAL_LINUX_FILE_NONE;
        }
    }
    if (rc != 0) {
        hal_linux_close(hal);
        memset(hal->nvm, 0xFF, sizeof hal->nvm);
    }
    return rc;
}

hal_linux_file_t hal_linux_open_failed(const hal_t *hal)
{
    return hal != NULL ? hal->open_failed : HAL_LINUX_FILE_NONE;
}

void hal_linux_close(hal_t *hal)
{
    if (hal == NULL) {
        return;
    }
    hal_socketcan_close(hal);
    if (hal->rx != NULL) {
        (void)fclose(hal->rx);
        hal->rx = NULL;
    }
    if (hal->tx != NULL) {
        (void)fclose(hal->tx); /* flushes */
        hal->tx = NULL;
    }
    if (hal->nvm_file != NULL) {
        (void)fclose(hal->nvm_file);
        hal->nvm_file = NULL;
    }
    hal->rx_log.eof = 1u;
}

void hal_linux_set_iface(hal_t *hal, const char *name)
{
    if (name == NULL || name[0] == '\0') {
        memcpy(hal->iface, default_iface, sizeof default_iface);
        return;
    }
    size_t n = 0u;
    while (n < HAL_LINUX_IFACE_MAX && name[n] != '\0') {
        hal->iface[n] = is_graph_ascii(name[n]) ? name[n] : '_';
        n++;
    }
    hal->iface[n] = '\0';
}

int hal_linux_watchdog_expired(const hal_t *hal)
{
    if (hal->watchdog_kicks == 0u) {
        return 0; /* armed by the first kick, as the main loop starts it */
    }
    const uint64_t now = hal_time_us(hal);
    return now > hal->last_kick_us && now - hal->last_kick_us > HAL_LINUX_WATCHDOG_TIMEOUT_US;
}

uint64_t hal_linux_watchdog_kicks(const hal_t *hal)
{
    return hal->watchdog_kicks;
}

uint32_t hal_linux_rx_frames(const hal_t *hal)
{
    return hal->rx_log.frames;
}

uint32_t hal_linux_rx_malformed(const hal_t *hal)
{
    return hal->rx_log.malformed;
}

uint32_t hal_linux_tx_frames(const hal_t *hal)
{
    return hal->tx_frames;
}
