/*
 * test_boot.c - the bootloader's logic (firmware/boot/boot.c) on a RAM-backed flash of
 * the STM32F405's first 128 KiB: bootloader sector, NVM sectors, application sectors.
 * The flash behaves as NOR flash: programming only clears bits, an erase sets a sector to
 * 0xFF; a power cut after N programmed bytes (or in the middle of an erase) stops it, and
 * every later operation fails until the "reboot" (a new boot_t on the same memory).
 *
 * The requests are written byte for byte from ISO 14229-1 (docs/can.md, "Programming (the
 * bootloader)"), not produced by the code under test. Every test ends by checking that the
 * bootloader and NVM sectors were never written or erased.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "boot.h"
#include "e2e.h"
#include "navecu_can.h"
#include "crc32.h"

#define FLASH_BASE 0x08000000u
#define FLASH_LEN (BOOT_APP_START + BOOT_APP_SIZE - FLASH_BASE)

typedef struct {
    uint8_t mem[FLASH_LEN];
    uint8_t snapshot[FLASH_LEN]; /* bootloader and NVM content at the start */
    long cut_after;              /* programmed bytes until the power cut; < 0: none */
    int erase_cut;               /* 1: the next erase stops half-way (power cut) */
    int dead;                    /* the power is off: everything fails */
    long programmed;
    int writes;
    int outside;                 /* a write or erase outside the application */
} sim_t;

static sim_t sim;
static boot_t boot;
static uint8_t rsp[64];
static int frames_sent;
static uint8_t last_frame[8];

static int sim_read(void *ctx, uint32_t addr, uint8_t *buf, size_t len)
{
    sim_t *s = ctx;
    if (s->dead || addr < FLASH_BASE || addr - FLASH_BASE + len > FLASH_LEN) {
        return HAL_EIO;
    }
    memcpy(buf, &s->mem[addr - FLASH_BASE], len);
    return 0;
}

static int sim_write(void *ctx, uint32_t addr, const uint8_t *buf, size_t len)
{
    sim_t *s = ctx;
    if (addr < BOOT_APP_START || addr + len > BOOT_APP_START + BOOT_APP_SIZE) {
        s->outside++;
        return HAL_EINVAL;
    }
    if (s->dead) {
        return HAL_EIO;
    }
    s->writes++;
    for (size_t k = 0u; k < len; k++) {
        if (s->cut_after >= 0 && s->programmed >= s->cut_after) {
            s->dead = 1;
            return HAL_EIO;
        }
        s->mem[addr - FLASH_BASE + k] &= buf[k];
        s->programmed++;
    }
    return 0;
}

static int sim_erase(void *ctx, size_t sector)
{
    sim_t *s = ctx;
    if (sector >= BOOT_N_SECTORS) {
        s->outside++;
        return HAL_EINVAL;
    }
    if (s->dead) {
        return HAL_EIO;
    }
    const uint32_t off = boot_sectors[sector].addr - FLASH_BASE;
    const uint32_t n = s->erase_cut ? boot_sectors[sector].size / 2u : boot_sectors[sector].size;
    memset(&s->mem[off], 0xFF, n);
    if (s->erase_cut) {
        s->dead = 1;
        return HAL_EIO;
    }
    return 0;
}

static const boot_flash_t fl = {&sim, sim_read, sim_write, sim_erase};

/* the bootloader's NAV_Heartbeat frames, kept apart from the UDS answers */
static hal_can_frame_t hb[8];
static int n_hb;

static int refuse_tx; /* 1: the CAN driver's queue is full (refuses all but heartbeats) */
static hal_can_frame_t sent_log[64];
static int n_sent_log;
static int tx(void *user, const hal_can_frame_t *f)
{
    (void)user;
    if (refuse_tx && f->id != NAVECU_CAN_NAV_HEARTBEAT_FRAME_ID) {
        return HAL_ENOSPC;
    }
    if (f->id != NAVECU_CAN_NAV_HEARTBEAT_FRAME_ID && n_sent_log < 64) {
        sent_log[n_sent_log++] = *f;
    }
    if (f->id == NAVECU_CAN_NAV_HEARTBEAT_FRAME_ID) {
        if (n_hb < 8) {
            hb[n_hb] = *f;
        }
        n_hb++;
        return 0;
    }
    frames_sent++;
    memcpy(last_frame, f->data, 8u);
    return 0;
}

/* power on: a fresh bootloader on the same flash */
static void reboot(void)
{
    sim.dead = 0;
    sim.cut_after = -1;
    sim.erase_cut = 0;
    sim.programmed = 0;
    assert_int_equal(boot_init(&boot, &fl, 0x7A0u, 0x7A8u, tx, NULL, 99u), 0);
}

static int setup(void **state)
{
    (void)state;
    for (size_t k = 0u; k < FLASH_LEN; k++) {
        sim.mem[k] = (uint8_t)(k * 7u + 3u); /* bootloader and NVM: a pattern */
    }
    memset(&sim.mem[BOOT_APP_START - FLASH_BASE], 0xFF, BOOT_APP_SIZE);
    memcpy(sim.snapshot, sim.mem, FLASH_LEN);
    sim.outside = 0;
    sim.writes = 0;
    frames_sent = 0;
    n_hb = 0;
    reboot();
    return 0;
}

/* the bootloader and NVM sectors are as they were, nothing was asked outside */
static int teardown(void **state)
{
    (void)state;
    assert_int_equal(sim.outside, 0);
    assert_memory_equal(sim.mem, sim.snapshot, BOOT_APP_START - FLASH_BASE);
    return 0;
}

#define B(...) ((const uint8_t[]){__VA_ARGS__}), sizeof((const uint8_t[]){__VA_ARGS__})

static uint64_t now_us = 1000u;

/* the response to a request (1 ms later than the last) */
static size_t req(const uint8_t *r, size_t len)
{
    now_us += 1000u;
    return boot_handle(&boot, r, len, now_us, rsp, sizeof rsp);
}

static void expect_rsp(const uint8_t *r, size_t len, const uint8_t *want, size_t want_len)
{
    const size_t n = req(r, len);
    assert_int_equal(n, want_len);
    assert_memory_equal(rsp, want, want_len);
}

static void expect_nrc(const uint8_t *r, size_t len, uint8_t nrc)
{
    const size_t n = req(r, len);
    assert_int_equal(n, 3u);
    assert_int_equal(rsp[0], 0x7F);
    assert_int_equal(rsp[1], r[0]);
    assert_int_equal(rsp[2], nrc);
}

static void unlock(void)
{
    expect_rsp(B(0x10, 0x02), B(0x50, 0x02, 0x00, 0x32, 0x01, 0xF4));
    assert_int_equal(req(B(0x27, 0x01)), 6u);
    const uint32_t seed = ((uint32_t)rsp[2] << 24) | ((uint32_t)rsp[3] << 16) |
                          ((uint32_t)rsp[4] << 8) | rsp[5];
    const uint32_t key = uds_key_of_seed(seed);
    expect_rsp(B(0x27, 0x02, (uint8_t)(key >> 24), (uint8_t)(key >> 16), (uint8_t)(key >> 8),
                 (uint8_t)key),
               B(0x67, 0x02));
}

/* an application image of len bytes: SP at the top of RAM, reset vector at 0x201 (Thumb),
 * the marker slot erased, the rest a pattern of seed */
static uint8_t img[BOOT_APP_SIZE];
static void make_image(size_t len, uint8_t seed)
{
    for (size_t k = 0u; k < len; k++) {
        img[k] = (uint8_t)(k * 13u + seed + (k >> 8));
    }
    const uint32_t sp = BOOT_RAM_START + BOOT_RAM_SIZE - 16u;
    const uint32_t pc = BOOT_APP_START + 0x201u;
    for (unsigned i = 0u; i < 4u; i++) {
        img[i] = (uint8_t)(sp >> (8u * i));
        img[4u + i] = (uint8_t)(pc >> (8u * i));
    }
    memset(&img[BOOT_VECTORS_LEN], 0xFF, BOOT_MARKER_LEN);
}

static void put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static void erase(uint32_t size, uint8_t want_nrc)
{
    uint8_t r[13] = {0x31, 0x01, 0xFF, 0x00, 0x44};
    put_be32(&r[5], BOOT_APP_START);
    put_be32(&r[9], size);
    if (want_nrc == 0u) {
        expect_rsp(r, sizeof r, B(0x71, 0x01, 0xFF, 0x00));
    } else {
        expect_nrc(r, sizeof r, want_nrc);
    }
}

static void request_download(uint32_t addr, uint32_t size, uint8_t want_nrc)
{
    uint8_t r[11] = {0x34, 0x00, 0x44};
    put_be32(&r[3], addr);
    put_be32(&r[7], size);
    if (want_nrc == 0u) {
        const uint8_t want[4] = {0x74, 0x20, (uint8_t)(BOOT_MAX_BLOCK >> 8),
                                 (uint8_t)BOOT_MAX_BLOCK};
        expect_rsp(r, sizeof r, want, sizeof want);
    } else {
        expect_nrc(r, sizeof r, want_nrc);
    }
}

/* TransferData of img[pos, pos + n) with counter bsc: the response length (2 or 3) */
static uint8_t block_req[BOOT_MAX_BLOCK];
static size_t transfer(uint8_t bsc, const uint8_t *data, size_t n)
{
    block_req[0] = 0x36;
    block_req[1] = bsc;
    memcpy(&block_req[2], data, n);
    return req(block_req, n + 2u);
}

static void check(uint32_t crc, uint8_t want_nrc)
{
    uint8_t r[8] = {0x31, 0x01, 0xFF, 0x01};
    put_be32(&r[4], crc);
    if (want_nrc == 0u) {
        expect_rsp(r, sizeof r, B(0x71, 0x01, 0xFF, 0x01));
    } else {
        expect_nrc(r, sizeof r, want_nrc);
    }
}

/* the whole sequence, unlocked, blocks of `block` bytes; stops at the first negative
 * response and returns its NRC (0: every step positive) */
static uint8_t flash_image(size_t len, size_t block)
{
    erase((uint32_t)len, 0u);
    request_download(BOOT_APP_START, (uint32_t)len, 0u);
    uint8_t bsc = 1u;
    for (size_t pos = 0u; pos < len; pos += block) {
        const size_t n = len - pos < block ? len - pos : block;
        if (transfer(bsc, &img[pos], n) != 2u) {
            return rsp[2];
        }
        assert_int_equal(rsp[0], 0x76);
        assert_int_equal(rsp[1], bsc);
        bsc++;
    }
    expect_rsp(B(0x37), B(0x77));
    now_us += 1000u;
    uint8_t r[8] = {0x31, 0x01, 0xFF, 0x01};
    put_be32(&r[4], crc32_of(img, len));
    const size_t n = boot_handle(&boot, r, sizeof r, now_us, rsp, sizeof rsp);
    return n == 3u ? rsp[2] : 0u;
}

/* erase, RequestDownload of size bytes, img[0..size) in blocks of `block`, TransferExit:
 * each positive */
static void download(uint32_t size, size_t block)
{
    erase(size, 0u);
    request_download(BOOT_APP_START, size, 0u);
    uint8_t bsc = 1u;
    for (size_t pos = 0u; pos < size; pos += block) {
        const size_t n = size - pos < block ? size - pos : block;
        assert_int_equal(transfer(bsc, &img[pos], n), 2u);
        bsc++;
    }
    expect_rsp(B(0x37), B(0x77));
}

static void test_empty_flash_stays(void **state)
{
    (void)state;
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    expect_rsp(B(0x22, 0xF1, 0x80), B(0x62, 0xF1, 0x80, 'n', 'a', 'v', 'e', 'c', 'u', '-', 'b',
                                      'o', 'o', 't', ' ', '2'));
    expect_rsp(B(0x3E, 0x00), B(0x7E, 0x00));
}

static void test_flash_whole_image_and_start(void **state)
{
    (void)state;
    make_image(5000u, 1u);
    unlock();
    assert_int_equal(flash_image(5000u, BOOT_MAX_BLOCK - 2u), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
    /* the flash holds the image, the marker in its slot */
    uint8_t m[BOOT_MARKER_LEN];
    boot_marker_encode(5000u, crc32_of(img, 5000u), m);
    assert_memory_equal(&sim.mem[BOOT_APP_START - FLASH_BASE], img, BOOT_VECTORS_LEN);
    assert_memory_equal(&sim.mem[BOOT_MARKER_ADDR - FLASH_BASE], m, sizeof m);
    assert_memory_equal(&sim.mem[BOOT_MARKER_ADDR + BOOT_MARKER_LEN - FLASH_BASE],
                        &img[BOOT_VECTORS_LEN + BOOT_MARKER_LEN],
                        5000u - BOOT_VECTORS_LEN - BOOT_MARKER_LEN);
    /* erase and check sent 7F 31 78 before their work */
    assert_int_equal(boot.cnt.pending_sent, 2u);
    assert_int_equal(boot.cnt.erases, 1u); /* 5000 bytes: sector 3 only */
    /* ECUReset: positive, and the board resets once the response left */
    expect_rsp(B(0x11, 0x01), B(0x51, 0x01));
    assert_int_equal(boot_poll(&boot, now_us), 1);
    reboot();
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
}

static void test_security_and_session_required(void **state)
{
    (void)state;
    /* default session: the programming services are not in it */
    expect_nrc(B(0x34, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x7F);
    expect_nrc(B(0x36, 0x01, 0xAA), 0x7F);
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x7F);
    /* programming session, locked: 0x33 */
    expect_rsp(B(0x10, 0x02), B(0x50, 0x02, 0x00, 0x32, 0x01, 0xF4));
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x33);
    expect_nrc(B(0x34, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x33);
    expect_nrc(B(0x36, 0x01, 0xAA), 0x33);
    expect_nrc(B(0x37), 0x33);
    expect_nrc(B(0x11, 0x01), 0x33);
    assert_int_equal(boot.cnt.erases, 0u);
    assert_int_equal(sim.writes, 0);
    /* the extended session has no routines */
    unlock();
    expect_rsp(B(0x10, 0x03), B(0x50, 0x03, 0x00, 0x32, 0x01, 0xF4));
    expect_nrc(B(0x10, 0x04), 0x12);
    expect_nrc(B(0x85, 0x02), 0x11);
}

static void test_erase_range_checked(void **state)
{
    (void)state;
    unlock();
    /* the NVM's address, the bootloader's, past the application, size 0, format */
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0x40, 0x00, 0, 0, 0x40, 0), 0x31);
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0x00, 0x00, 0, 0, 0x40, 0), 0x31);
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 1, 0x40, 1), 0x31);
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0, 0), 0x31);
    expect_nrc(B(0x31, 0x01, 0xFF, 0x00, 0x24, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x13);
    expect_nrc(B(0x31, 0x01, 0x12, 0x34), 0x31); /* unknown routine */
    assert_int_equal(boot.cnt.erases, 0u);
    erase(BOOT_APP_SIZE, 0u);
    assert_int_equal(boot.cnt.erases, 2u);
}

static void test_sequence_errors(void **state)
{
    (void)state;
    make_image(3000u, 2u);
    unlock();
    expect_nrc(B(0x36, 0x01, 0xAA), 0x24);          /* no download */
    expect_nrc(B(0x36, 0x01), 0x13);                /* no data: the length first (ISO) */
    expect_nrc(B(0x37), 0x24);
    check(crc32_of(img, 3000u), 0x24);              /* nothing downloaded */
    request_download(BOOT_APP_START, 3000u, 0x70);  /* not erased */
    erase(3000u, 0u);
    request_download(BOOT_APP_START + 4u, 3000u, 0x31); /* not the application's start */
    request_download(BOOT_APP_START, 0x4001u, 0x70);    /* more than erased (sector 3) */
    expect_nrc(B(0x34, 0x11, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10, 0), 0x31); /* compressed */
    expect_nrc(B(0x34, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0, 0, 0x10), 0x13);
    request_download(BOOT_APP_START, 3000u, 0u);
    request_download(BOOT_APP_START, 3000u, 0x22);  /* one already running */
    assert_int_equal(transfer(1u, img, 500u), 2u);
    assert_int_equal(transfer(2u, &img[500], 500u), 2u);
    expect_nrc(B(0x37), 0x24);                      /* 2000 bytes missing */
    check(crc32_of(img, 3000u), 0x24);
    assert_int_equal(transfer(3u, &img[1000], 500u), 2u);
    assert_int_equal(transfer(4u, &img[1500], 500u), 2u);
    assert_int_equal(transfer(5u, &img[2000], 500u), 2u);
    assert_int_equal(transfer(6u, &img[2500], 501u), 3u); /* one byte too many */
    assert_int_equal(rsp[2], 0x71);
    assert_int_equal(transfer(6u, &img[2500], 500u), 2u);
    expect_rsp(B(0x37), B(0x77));
    expect_nrc(B(0x37), 0x24);
    /* a second download needs a new erase: flash is programmed once */
    request_download(BOOT_APP_START, 3000u, 0x70);
    check(crc32_of(img, 3000u), 0u);
    check(crc32_of(img, 3000u), 0x24); /* one check per download */
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
}

static void test_block_counter_wrong_repeat_and_wrap(void **state)
{
    (void)state;
    /* 300 blocks of 20 bytes: the counter runs 1..255, 0, 1..44 */
    make_image(6000u, 3u);
    unlock();
    erase(6000u, 0u);
    request_download(BOOT_APP_START, 6000u, 0u);
    assert_int_equal(transfer(2u, img, 20u), 3u);     /* the first must be 1 */
    assert_int_equal(rsp[2], 0x73);
    assert_int_equal(transfer(0u, img, 20u), 3u);
    assert_int_equal(rsp[2], 0x73);
    uint8_t bsc = 1u;
    for (size_t pos = 0u; pos < 6000u; pos += 20u) {
        assert_int_equal(transfer(bsc, &img[pos], 20u), 2u);
        if (pos == 100u) {
            /* the same block again (its response was lost): acknowledged, not rewritten */
            const int writes = sim.writes;
            assert_int_equal(transfer(bsc, &img[pos], 20u), 2u);
            assert_int_equal(rsp[1], bsc);
            assert_int_equal(sim.writes, writes);
            assert_int_equal(boot.cnt.blocks_repeated, 1u);
            /* a different block under the last counter: wrong */
            assert_int_equal(transfer(bsc, &img[pos + 20u], 20u), 3u);
            assert_int_equal(rsp[2], 0x73);
            /* one ahead: wrong */
            assert_int_equal(transfer((uint8_t)(bsc + 2u), &img[pos + 20u], 20u), 3u);
            assert_int_equal(rsp[2], 0x73);
        }
        bsc++;
    }
    assert_int_equal(bsc, 45u); /* wrapped: 300 mod 256 + 1 */
    assert_int_equal(boot.cnt.blocks_written, 300u);
    expect_rsp(B(0x37), B(0x77));
    check(crc32_of(img, 6000u), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
    /* the counts on the bus (22 FD 00): 300 blocks written, 1 repeated, one sector erased
     * (6,000 bytes in sector 3), no failed check or flash error, two responsePendings
     * (before the erase and before the check) */
    const uint32_t want[6] = {300u, 1u, 1u, 0u, 0u, 2u};
    assert_int_equal(req(B(0x22, 0xFD, 0x00)), 3u + 24u);
    assert_memory_equal(rsp, ((const uint8_t[]){0x62, 0xFD, 0x00}), 3u);
    for (size_t i = 0u; i < 6u; i++) {
        const uint8_t *p = &rsp[3u + 4u * i];
        assert_int_equal(((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) |
                             ((uint32_t)p[2] << 8) | p[3],
                         want[i]);
    }
}

static void test_corrupt_truncated_wrong_digest_refused(void **state)
{
    (void)state;
    make_image(4000u, 4u);
    const uint32_t good = crc32_of(img, 4000u);
    unlock();
    /* a byte corrupted on the way: the check over the flash finds it */
    img[3000] ^= 0x01u;
    download(4000u, 500u);
    check(good, 0x72);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    img[3000] ^= 0x01u;
    /* truncated: 3500 of the 4000 bytes, checked against the whole image's CRC */
    download(3500u, 500u);
    check(good, 0x72);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    /* the right bytes, a wrong digest */
    download(4000u, 500u);
    check(good ^ 0x80000000u, 0x72);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    assert_int_equal(boot.cnt.checks_failed, 3u);
    /* and a good one after all that */
    assert_int_equal(flash_image(4000u, 500u), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
}

static void test_bad_vectors_refused(void **state)
{
    (void)state;
    make_image(2000u, 5u);
    img[3] = 0x30u; /* initial SP 0x30.. : not RAM */
    unlock();
    assert_int_equal(flash_image(2000u, 256u), 0x72u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    make_image(2000u, 5u);
    img[4] = 0x00u; /* reset vector even: not Thumb */
    assert_int_equal(flash_image(2000u, 256u), 0x72u);
    make_image(2000u, 5u);
    img[5] = 0x10u; /* reset vector 0x08001001: not in the image */
    assert_int_equal(flash_image(2000u, 256u), 0x72u);
    /* and bytes for the marker slot in the image: refused */
    make_image(2000u, 5u);
    img[BOOT_VECTORS_LEN + 3u] = 0x00u;
    assert_int_equal(flash_image(2000u, 256u), 0x31u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
}

static void test_session_change_and_s3_abort_download(void **state)
{
    (void)state;
    make_image(2000u, 6u);
    unlock();
    erase(2000u, 0u);
    request_download(BOOT_APP_START, 2000u, 0u);
    assert_int_equal(transfer(1u, img, 500u), 2u);
    /* S3: 5 s without a request -> default session, locked, the download gone */
    now_us += UDS_S3_US;
    expect_nrc(B(0x36, 0x02, 0xAA), 0x7F);
    unlock();
    expect_nrc(B(0x36, 0x02, 0xAA), 0x24);
    request_download(BOOT_APP_START, 2000u, 0x70); /* and an erase is needed again */
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
}

static void test_programming_request_answered(void **state)
{
    (void)state;
    boot_programming_requested(&boot, 5000u);
    assert_int_equal(boot.srv.session, UDS_SESSION_PROGRAMMING);
    assert_int_equal(boot.srv.unlocked, 0);
    assert_int_equal(frames_sent, 1);
    const uint8_t sf[8] = {0x06, 0x50, 0x02, 0x00, 0x32, 0x01, 0xF4, 0xCC};
    assert_memory_equal(last_frame, sf, 8u);
}

/* A bootloader that stays says so on the bus: NAV_Heartbeat (the application's 0x314) with
 * Mode Bootloader at its first poll and at each whole second of its uptime after it, E2E
 * counter and CRC as the application's, the sensors all missing; none between seconds. */
static void test_heartbeat_says_bootloader(void **state)
{
    (void)state;
    const uint64_t t0 = 7000000u;
    const uint64_t at[] = {t0, t0 + 500000u, t0 + 999999u, t0 + 1000000u, t0 + 2700000u};
    for (size_t k = 0u; k < sizeof at / sizeof at[0]; k++) {
        (void)boot_poll(&boot, at[k]);
    }
    assert_int_equal(n_hb, 3);
    for (int k = 0; k < 3; k++) {
        struct navecu_can_nav_heartbeat_t m;
        assert_int_equal(hb[k].dlc, 8u);
        assert_true(e2e_crc_ok(hb[k].id, hb[k].data));
        assert_int_equal(navecu_can_nav_heartbeat_unpack(&m, hb[k].data, 8u), 0);
        assert_int_equal(m.mode, NAVECU_CAN_NAV_HEARTBEAT_MODE_BOOTLOADER_CHOICE);
        assert_int_equal(m.uptime, (uint32_t)k);
        assert_int_equal(m.nav_counter, (uint8_t)k);
        assert_int_equal(m.imu_missing + m.gnss_missing + m.wheels_missing, 3);
    }
    assert_int_equal(frames_sent, 0); /* no UDS answer without a request */
}

/* The application's programming request, then the tester gone: after S3 (5 s without a
 * request) the session falls back to the default and, the application untouched and
 * valid, boot_poll says reset (the board starts it again) instead of leaving the ECU in its
 * bootloader; with the application erased it stays. */
/* a whole application flashed, then the bootloader started by the application's
 * programming request at t */
static void programming_requested_over_a_valid_application(uint64_t t)
{
    make_image(3000u, 5u);
    unlock();
    assert_int_equal(flash_image(3000u, 500u), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
    reboot();
    boot_programming_requested(&boot, t);
}

static void test_abandoned_programming_returns_to_the_application(void **state)
{
    (void)state;
    const uint64_t t = 20000000u;
    programming_requested_over_a_valid_application(t);
    assert_int_equal(boot_poll(&boot, t + 1000000u), 0);
    assert_int_equal(boot_poll(&boot, t + 4900000u), 0);
    assert_int_equal(boot_poll(&boot, t + 5100000u), 1);
    assert_int_equal(boot.cnt.returns, 1u);
    /* erased: the tester went away after the erase, the bootloader stays */
    reboot();
    boot_programming_requested(&boot, t);
    unlock();
    expect_rsp(B(0x31, 0x01, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0x00, 0x00, 0x10,
                 0x00), B(0x71, 0x01, 0xFF, 0x00));
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    for (uint64_t dt = 1000000u; dt <= 12000000u; dt += 1000000u) {
        assert_int_equal(boot_poll(&boot, t + dt), 0);
    }
    assert_int_equal(boot.cnt.returns, 0u);
}

/* the old image is valid; a new one is flashed with the power cut after every block
 * boundary (and half-way into each block, and in the marker): the next boot finds no
 * valid image, and the bootloader then takes the whole new image */
static void test_power_cut_at_every_block_boundary(void **state)
{
    (void)state;
    const size_t len = 4096u;
    const size_t block = 510u; /* 9 blocks, the last short */
    make_image(len, 7u);
    unlock();
    assert_int_equal(flash_image(len, block), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
    const uint32_t old_crc = crc32_of(img, len);
    make_image(len, 8u);
    assert_true(crc32_of(img, len) != old_crc);
    int cuts = 0;
    for (long cut = 0; cut <= (long)len + (long)BOOT_MARKER_LEN; cut += (long)block / 2) {
        reboot();
        unlock();
        sim.cut_after = cut > (long)len ? (long)len + 8 : cut; /* the last: in the marker */
        (void)flash_image(len, block);
        assert_true(sim.dead || cut >= (long)len);
        reboot();
        assert_int_not_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
        cuts++;
    }
    printf("power cut at %d points of a %zu-byte image (every block boundary, every half "
           "block, in the marker): never a valid image after it\n", cuts, len);
    /* an erase cut half-way: no image either */
    unlock();
    sim.erase_cut = 1;
    erase((uint32_t)len, 0x72u);
    reboot();
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
    /* and the complete re-flash works */
    unlock();
    assert_int_equal(flash_image(len, block), 0u);
    reboot();
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
}

static void test_marker_and_crc_checked_at_boot(void **state)
{
    (void)state;
    make_image(3000u, 9u);
    unlock();
    assert_int_equal(flash_image(3000u, 300u), 0u);
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_OK);
    /* a bit of the image lost afterwards (programmed 1 -> 0): the CRC at boot refuses it */
    sim.mem[BOOT_APP_START - FLASH_BASE + 2000u] &= 0x7Fu;
    if (img[2000] & 0x80u) {
        assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_BAD_CRC);
    }
    /* a broken marker check word */
    sim.mem[BOOT_MARKER_ADDR - FLASH_BASE + 12u] ^= 0x01u;
    assert_int_equal(boot_image_check(&fl), BOOT_IMAGE_NO_MARKER);
}


/* ---- found by a review (each failed before its fix) ---- */
static void frame_in(const uint8_t *d, uint8_t n, uint64_t t)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = 0x7A0u; f.dlc = 8u; memset(f.data, 0xCC, 8u); memcpy(f.data, d, n);
    boot_frame(&boot, &f, t);
}
static void dump_sent(const char *tag, int from)
{
    print_message("%s:", tag);
    for (int i = from; i < n_sent_log; i++) {
        print_message(" [");
        for (int k = 0; k < 8; k++) print_message("%02X", sent_log[i].data[k]);
        print_message("]");
    }
    print_message("\n");
}

/* 10 01 received as the boards receive it (boot_frame, then boot_poll) with the
 * application whole: the bootloader resets into it */
static void test_default_session_request_returns_to_the_application(void **state)
{
    (void)state;
    const uint64_t t = 20000000u;
    programming_requested_over_a_valid_application(t);
    assert_int_equal(boot_poll(&boot, t + 1000u), 0);
    frame_in((const uint8_t[]){0x02, 0x10, 0x01}, 3u, t + 2000u); /* 10 01: 50 01 sent */
    assert_int_equal(boot.srv.session, UDS_SESSION_DEFAULT);
    assert_int_equal(boot_poll(&boot, t + 3000u), 1); /* the next poll resets */
    assert_int_equal(boot.cnt.returns, 1u);
}

/* eraseMemory's 7F 31 78 refused by the CAN driver: given up, not left in the channel
 * (a pointer to a stack array; the final response refused); the final response goes out */
static void test_pending_refused_by_a_full_can_queue(void **state)
{
    (void)state;
    unlock();
    const uint64_t t = now_us + 1000u;
    n_sent_log = 0;
    /* 31 01 FF 00 44 08 00 C0 00 00 00 10 00: FF + 1 CF */
    frame_in((const uint8_t[]){0x10, 0x0D, 0x31, 0x01, 0xFF, 0x00, 0x44, 0x08}, 8u, t);
    (void)boot_poll(&boot, t);
    refuse_tx = 1;
    frame_in((const uint8_t[]){0x21, 0x00, 0xC0, 0x00, 0x00, 0x00, 0x10, 0x00}, 8u, t + 1000u);
    refuse_tx = 0;
    for (int i = 0; i < 5; i++) (void)boot_poll(&boot, t + 2000u + 1000u * (uint64_t)i);
    dump_sent("frames sent (FC, then after the queue drained)", 0);
    int final = 0;
    for (int i = 0; i < n_sent_log; i++)
        if (memcmp(sent_log[i].data, "\x04\x71\x01\xFF\x00", 5) == 0) final = 1;
    assert_int_equal(final, 1);
}

/* eraseMemory with the suppress bit: after its 7F 31 78 the final response goes out */
static void test_suppressed_erase_after_its_pending(void **state)
{
    (void)state;
    unlock();
    n_sent_log = 0;
    const size_t n = req(B(0x31, 0x81, 0xFF, 0x00, 0x44, 0x08, 0x00, 0xC0, 0x00, 0x00, 0x00,
                           0x10, 0x00));
    dump_sent("frames sent during 31 81 FF00", 0);
    print_message("final response length %zu\n", n);
    assert_int_equal(n, 4u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_default_session_request_returns_to_the_application, setup, teardown),
        cmocka_unit_test_setup_teardown(test_pending_refused_by_a_full_can_queue, setup, teardown),
        cmocka_unit_test_setup_teardown(test_suppressed_erase_after_its_pending, setup, teardown),
        cmocka_unit_test_setup_teardown(test_empty_flash_stays, setup, teardown),
        cmocka_unit_test_setup_teardown(test_heartbeat_says_bootloader, setup, teardown),
        cmocka_unit_test_setup_teardown(test_abandoned_programming_returns_to_the_application,
                                        setup, teardown),
        cmocka_unit_test_setup_teardown(test_flash_whole_image_and_start, setup, teardown),
        cmocka_unit_test_setup_teardown(test_security_and_session_required, setup, teardown),
        cmocka_unit_test_setup_teardown(test_erase_range_checked, setup, teardown),
        cmocka_unit_test_setup_teardown(test_sequence_errors, setup, teardown),
        cmocka_unit_test_setup_teardown(test_block_counter_wrong_repeat_and_wrap, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_corrupt_truncated_wrong_digest_refused, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_bad_vectors_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_session_change_and_s3_abort_download, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_programming_request_answered, setup, teardown),
        cmocka_unit_test_setup_teardown(test_power_cut_at_every_block_boundary, setup, teardown),
        cmocka_unit_test_setup_teardown(test_marker_and_crc_checked_at_boot, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
