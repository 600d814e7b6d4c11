/* boot.c - the bootloader's logic; see boot.h and docs/can.md ("Programming"). */
#include "boot.h"

#include <string.h>

#include "crc32.h"
#include "e2e.h"
#include "navecu_can.h"
#include "navecu_protocol.h"

const boot_sector_t boot_sectors[BOOT_N_SECTORS] = {
    {BOOT_APP_START, BOOT_APP_SECTOR3_SIZE},
    {BOOT_APP_START + BOOT_APP_SECTOR3_SIZE, BOOT_APP_SECTOR4_SIZE},
};

#define DL_NONE 0u
#define DL_TRANSFER 1u
#define DL_EXITED 2u
#define CHUNK 64u /* bytes read at a time for the CRC and the repeat comparison */

static void boot_count(uint32_t *c)
{
    if (*c != UINT32_MAX) {
        (*c)++;
    }
}

static uint32_t boot_get_u32be(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

static uint32_t boot_get_u32le(const uint8_t *p)
{
    return ((uint32_t)p[3] << 24) | ((uint32_t)p[2] << 16) | ((uint32_t)p[1] << 8) | p[0];
}

static void boot_put_u32le(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

void boot_marker_encode(uint32_t len, uint32_t crc, uint8_t out[BOOT_MARKER_LEN])
{
    boot_put_u32le(&out[0], BOOT_MARKER_MAGIC);
    boot_put_u32le(&out[4], len);
    boot_put_u32le(&out[8], crc);
    boot_put_u32le(&out[12], ~(BOOT_MARKER_MAGIC ^ len ^ crc));
}

/* the CRC-32 of the flash [BOOT_APP_START, + len) with the marker slot read as erased */
static int image_crc(const boot_flash_t *fl, uint32_t len, uint32_t *crc)
{
    uint8_t buf[CHUNK];
    uint32_t c = CRC32_INIT;
    uint32_t pos = 0u;
    while (pos < len) {
        const uint32_t n = (len - pos) < CHUNK ? (len - pos) : CHUNK;
        const uint32_t addr = BOOT_APP_START + pos;
        if (fl->read(fl->ctx, addr, buf, n) != 0) {
            return -1;
        }
        for (uint32_t k = 0u; k < n; k++) {
            if (addr + k >= BOOT_MARKER_ADDR && addr + k < BOOT_MARKER_ADDR + BOOT_MARKER_LEN) {
                buf[k] = 0xFFu;
            }
        }
        c = crc32_update(c, buf, n);
        pos += n;
    }
    *crc = crc32_final(c);
    return 0;
}

/* initial SP in RAM (word-aligned, the end of RAM included), reset vector a Thumb address
 * past the vector table inside the image */
static boot_image_t vectors_ok(const boot_flash_t *fl, uint32_t len)
{
    uint8_t v[8];
    if (fl->read(fl->ctx, BOOT_APP_START, v, sizeof v) != 0) {
        return BOOT_IMAGE_READ_ERROR;
    }
    const uint32_t sp = boot_get_u32le(&v[0]);
    const uint32_t pc = boot_get_u32le(&v[4]);
    const uint32_t entry = pc & ~1u;
    if (sp < BOOT_RAM_START + 8u || sp > BOOT_RAM_START + BOOT_RAM_SIZE || (sp & 3u) != 0u ||
        (pc & 1u) == 0u || entry < BOOT_APP_START + BOOT_VECTORS_LEN + BOOT_MARKER_LEN ||
        entry >= BOOT_APP_START + len) {
        return BOOT_IMAGE_BAD_VECTORS;
    }
    return BOOT_IMAGE_OK;
}

static int len_ok(uint32_t len)
{
    return (len >= BOOT_VECTORS_LEN + BOOT_MARKER_LEN + 4u && len <= BOOT_APP_SIZE) ? 1 : 0;
}

boot_image_t boot_image_check(const boot_flash_t *fl)
{
    uint8_t m[BOOT_MARKER_LEN];
    if (fl->read(fl->ctx, BOOT_MARKER_ADDR, m, sizeof m) != 0) {
        return BOOT_IMAGE_READ_ERROR;
    }
    const uint32_t magic = boot_get_u32le(&m[0]);
    const uint32_t len = boot_get_u32le(&m[4]);
    const uint32_t crc = boot_get_u32le(&m[8]);
    if (magic != BOOT_MARKER_MAGIC || boot_get_u32le(&m[12]) != ~(magic ^ len ^ crc)) {
        return BOOT_IMAGE_NO_MARKER;
    }
    if (!len_ok(len)) {
        return BOOT_IMAGE_BAD_LENGTH;
    }
    uint32_t actual = 0u;
    if (image_crc(fl, len, &actual) != 0) {
        return BOOT_IMAGE_READ_ERROR;
    }
    if (actual != crc) {
        return BOOT_IMAGE_BAD_CRC;
    }
    return vectors_ok(fl, len);
}

/* ---- the transport's part: 7F SID 78 before a long operation ---- */

/* a single frame that leaves at once or, refused by the CAN driver (its queue full), is
 * given up (the channel keeps no pointer to p; the final response follows the work
 * alone); sent, it makes the final response due even when suppressed */
static void boot_send_pending(boot_t *b, uint8_t sid)
{
    const uint8_t p[3] = {UDS_NEGATIVE, sid, UDS_NRC_RESPONSE_PENDING};
    if (isotp_send_now(&b->tp, p, sizeof p, b->now_us, b->tx, b->tx_user) == 0) {
        boot_count(&b->cnt.pending_sent);
        uds_pending_sent(&b->srv);
    }
}

static void abort_download(boot_t *b)
{
    b->dl_state = DL_NONE;
    b->dl_len = 0u;
    b->dl_pos = 0u;
    b->last_len = 0u;
}

/* ---- 0x31 routines ---- */

/* 31 01 FF00 44 addr(4) size(4): erase the sectors covering [addr, addr + size), which
 * must start at the application; the marker's sector always first */
static uint8_t erase_memory(boot_t *b, const uint8_t *data, size_t len)
{
    if (len != 9u || data[0] != BOOT_ALFID) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    const uint32_t addr = boot_get_u32be(&data[1]);
    const uint32_t size = boot_get_u32be(&data[5]);
    if (addr != BOOT_APP_START || size == 0u || size > BOOT_APP_SIZE) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE;
    }
    abort_download(b);
    b->erased_end = BOOT_APP_START;
    boot_send_pending(b, UDS_SID_ROUTINE);
    for (size_t i = 0u; i < BOOT_N_SECTORS && boot_sectors[i].addr < addr + size; i++) {
        if (b->fl.erase(b->fl.ctx, i) != 0) {
            boot_count(&b->cnt.flash_errors);
            return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
        }
        boot_count(&b->cnt.erases);
        b->erased_end = boot_sectors[i].addr + boot_sectors[i].size;
    }
    return UDS_NRC_OK;
}

/* 31 01 FF01 crc(4): the downloaded image's CRC-32 (big-endian) against the flash, the
 * vectors; then the marker, the last thing written */
static uint8_t check_memory(boot_t *b, const uint8_t *data, size_t len)
{
    if (len != 4u) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    if (b->dl_state != DL_EXITED) {
        return UDS_NRC_REQUEST_SEQUENCE_ERROR;
    }
    const uint32_t want = boot_get_u32be(data);
    const uint32_t n = b->dl_len;
    abort_download(b); /* one check per download, whatever its result */
    boot_send_pending(b, UDS_SID_ROUTINE);
    uint32_t crc = 0u;
    if (image_crc(&b->fl, n, &crc) != 0) {
        boot_count(&b->cnt.flash_errors);
        boot_count(&b->cnt.checks_failed);
        return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
    }
    if (crc != want || !len_ok(n) || vectors_ok(&b->fl, n) != BOOT_IMAGE_OK) {
        boot_count(&b->cnt.checks_failed);
        return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
    }
    uint8_t m[BOOT_MARKER_LEN];
    boot_marker_encode(n, crc, m);
    if (b->fl.write(b->fl.ctx, BOOT_MARKER_ADDR, m, sizeof m) != 0 ||
        boot_image_check(&b->fl) != BOOT_IMAGE_OK) {
        boot_count(&b->cnt.flash_errors);
        boot_count(&b->cnt.checks_failed);
        return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
    }
    return UDS_NRC_OK;
}

static int boot_has_routine(void *user, uint16_t rid)
{
    (void)user;
    return rid == BOOT_RID_ERASE || rid == BOOT_RID_CHECK;
}

static uint8_t boot_start_routine(void *user, uint16_t rid, const uint8_t *data, size_t len)
{
    boot_t *b = (boot_t *)user;
    if (b->srv.session != UDS_SESSION_PROGRAMMING) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT; /* the extended session has no routines */
    }
    if (rid == BOOT_RID_ERASE) {
        return erase_memory(b, data, len);
    }
    return check_memory(b, data, len); /* the other of boot_has_routine's */
}

/* ---- 0x34, 0x36, 0x37 ---- */

/* 34 00 44 addr(4) size(4): 74 20 max(2) */
static uint8_t request_download(boot_t *b, const uint8_t *req, size_t len, uint8_t *rsp,
                                size_t *rsp_len)
{
    if (len != 11u) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    if (req[1] != 0x00u || req[2] != BOOT_ALFID) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE; /* compression, encryption, other formats */
    }
    const uint32_t addr = boot_get_u32be(&req[3]);
    const uint32_t size = boot_get_u32be(&req[7]);
    if (addr != BOOT_APP_START || size == 0u || size > BOOT_APP_SIZE) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE;
    }
    if (b->dl_state == DL_TRANSFER) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    if (addr + size > b->erased_end) {
        return UDS_NRC_UPLOAD_DOWNLOAD_NOT_ACCEPTED; /* not erased (eraseMemory first) */
    }
    b->erased_end = BOOT_APP_START; /* one download per erase: flash is programmed once */
    b->dl_state = DL_TRANSFER;
    b->dl_len = size;
    b->dl_pos = 0u;
    b->last_len = 0u;
    b->bsc = 1u;
    rsp[1] = 0x20u; /* lengthFormatIdentifier: 2 bytes of maxNumberOfBlockLength */
    rsp[2] = (uint8_t)(BOOT_MAX_BLOCK >> 8);
    rsp[3] = (uint8_t)BOOT_MAX_BLOCK;
    *rsp_len = 4u;
    return UDS_NRC_OK;
}

/* 1 when the flash at addr holds data[0..n) */
static int flash_equals(const boot_flash_t *fl, uint32_t addr, const uint8_t *data, uint32_t n)
{
    uint8_t buf[CHUNK];
    uint32_t pos = 0u;
    while (pos < n) {
        const uint32_t k = (n - pos) < CHUNK ? (n - pos) : CHUNK;
        if (fl->read(fl->ctx, addr + pos, buf, k) != 0 || memcmp(buf, &data[pos], k) != 0) {
            return 0;
        }
        pos += k;
    }
    return 1;
}

/* 36 bsc data..: 76 bsc */
static uint8_t transfer_data(boot_t *b, const uint8_t *req, size_t len, uint8_t *rsp,
                             size_t *rsp_len)
{
    if (len < 3u || len > BOOT_MAX_BLOCK) {
        return UDS_NRC_INCORRECT_LENGTH; /* ISO 14229-1: the length before the sequence */
    }
    if (b->dl_state != DL_TRANSFER) {
        return UDS_NRC_REQUEST_SEQUENCE_ERROR;
    }
    const uint8_t bsc = req[1];
    const uint32_t n = (uint32_t)len - 2u;
    const uint8_t *data = &req[2];
    rsp[1] = bsc;
    *rsp_len = 2u;
    if (b->last_len > 0u && bsc == (uint8_t)(b->bsc - 1u)) {
        /* the last block again (its response was lost): acknowledged, not rewritten,
         * when it is the same block */
        if (n == b->last_len && flash_equals(&b->fl, BOOT_APP_START + b->last_pos, data, n)) {
            boot_count(&b->cnt.blocks_repeated);
            return UDS_NRC_OK;
        }
        return UDS_NRC_WRONG_BLOCK_SEQUENCE_COUNTER;
    }
    if (bsc != b->bsc) {
        return UDS_NRC_WRONG_BLOCK_SEQUENCE_COUNTER;
    }
    if (n > b->dl_len - b->dl_pos) {
        return UDS_NRC_TRANSFER_DATA_SUSPENDED; /* more than RequestDownload's size */
    }
    const uint32_t addr = BOOT_APP_START + b->dl_pos;
    for (uint32_t k = 0u; k < n; k++) {
        if (addr + k >= BOOT_MARKER_ADDR && addr + k < BOOT_MARKER_ADDR + BOOT_MARKER_LEN &&
            data[k] != 0xFFu) {
            abort_download(b);
            return UDS_NRC_REQUEST_OUT_OF_RANGE; /* the marker slot is the bootloader's */
        }
    }
    if (b->fl.write(b->fl.ctx, addr, data, n) != 0) {
        boot_count(&b->cnt.flash_errors);
        abort_download(b); /* the flash is in an unknown state: erase again */
        return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
    }
    boot_count(&b->cnt.blocks_written);
    b->last_pos = b->dl_pos;
    b->last_len = n;
    b->dl_pos += n;
    b->bsc = (uint8_t)(b->bsc + 1u); /* 0xFF wraps to 0x00 */
    return UDS_NRC_OK;
}

/* 37: 77 */
static uint8_t transfer_exit(boot_t *b, size_t len, size_t *rsp_len)
{
    if (len != 1u) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    if (b->dl_state != DL_TRANSFER || b->dl_pos != b->dl_len) {
        return UDS_NRC_REQUEST_SEQUENCE_ERROR; /* none, or not every byte yet */
    }
    b->dl_state = DL_EXITED;
    *rsp_len = 1u;
    return UDS_NRC_OK;
}

static uint8_t boot_service(void *user, uint8_t session, uint8_t unlocked, const uint8_t *req,
                       size_t len, uint8_t *rsp, size_t cap, size_t *rsp_len)
{
    boot_t *b = (boot_t *)user;
    const uint8_t sid = req[0];
    (void)cap; /* every response here is at most 4 bytes, cap >= 8 (uds_handle) */
    if (sid != UDS_SID_REQUEST_DOWNLOAD && sid != UDS_SID_TRANSFER_DATA &&
        sid != UDS_SID_TRANSFER_EXIT) {
        return UDS_NRC_SERVICE_NOT_SUPPORTED;
    }
    if (session != UDS_SESSION_PROGRAMMING) {
        abort_download(b);
        return UDS_NRC_NOT_IN_ACTIVE_SESSION;
    }
    if (!unlocked) {
        return UDS_NRC_SECURITY_ACCESS_DENIED;
    }
    if (sid == UDS_SID_REQUEST_DOWNLOAD) {
        return request_download(b, req, len, rsp, rsp_len);
    }
    if (sid == UDS_SID_TRANSFER_DATA) {
        return transfer_data(b, req, len, rsp, rsp_len);
    }
    return transfer_exit(b, len, rsp_len);
}

static uint8_t boot_session_change(void *user, uint8_t session)
{
    boot_t *b = (boot_t *)user;
    abort_download(b); /* a download never survives a session change */
    b->erased_end = BOOT_APP_START;
    (void)session;
    return UDS_NRC_OK;
}

/* ---- data identifiers: read-only ---- */

static size_t boot_read_did(void *user, uint16_t did, uint8_t *buf, size_t cap)
{
    const boot_t *b = (const boot_t *)user;
    if (did == BOOT_DID_VERSION) {
        static const char v[] = BOOT_VERSION_STRING;
        const size_t n = sizeof v - 1u;
        if (n <= cap) {
            (void)memcpy(buf, v, n);
        }
        return n;
    }
    if (did == BOOT_DID_SESSION) {
        if (cap >= 1u) {
            buf[0] = b->srv.session;
        }
        return 1u;
    }
    if (did == BOOT_DID_COUNTERS) {
        /* the counts in boot_counters_t's order, each big-endian, since the bootloader
         * started; not `returns`, counted on the way into a reset that clears it */
        const uint32_t c[6] = {b->cnt.blocks_written, b->cnt.blocks_repeated, b->cnt.erases,
                               b->cnt.checks_failed,  b->cnt.flash_errors,    b->cnt.pending_sent};
        if (cap >= sizeof c) {
            for (size_t i = 0u; i < 6u; i++) {
                uds_put_u32(&buf[4u * i], c[i]);
            }
        }
        return sizeof c;
    }
    return 0u;
}

static uint8_t boot_write_did(void *user, uint16_t did, const uint8_t *data, size_t len)
{
    (void)user;
    (void)did;
    (void)data;
    (void)len;
    return UDS_NRC_REQUEST_OUT_OF_RANGE;
}

static int boot_is_writable(void *user, uint16_t did)
{
    (void)user;
    (void)did;
    return 0;
}

int boot_init(boot_t *b, const boot_flash_t *fl, uint32_t rx_id, uint32_t tx_id, isotp_tx_fn tx,
              void *tx_user, uint32_t entropy)
{
    if (b == NULL || fl == NULL || fl->read == NULL || fl->write == NULL || fl->erase == NULL) {
        return -1;
    }
    (void)memset(b, 0, sizeof *b);
    b->fl = *fl;
    b->tx = tx;
    b->tx_user = tx_user;
    b->erased_end = BOOT_APP_START;
    b->session_seen = UDS_SESSION_DEFAULT;
    const uds_if_t itf = {
        .user = b,
        .read_did = boot_read_did,
        .write_did = boot_write_did,
        .is_writable = boot_is_writable,
        .start_routine = boot_start_routine,
        .has_routine = boot_has_routine,
        .session_change = boot_session_change,
        .service = boot_service,
    };
    isotp_config_t c;
    isotp_config_defaults(&c, rx_id, tx_id);
    if (uds_init(&b->srv, &itf, entropy) != 0 || isotp_init(&b->tp, &c) != 0) {
        return -1;
    }
    return 0;
}

size_t boot_handle(boot_t *b, const uint8_t *req, size_t len, uint64_t now_us, uint8_t *rsp,
                   size_t cap)
{
    b->now_us = now_us;
    const size_t n = uds_handle(&b->srv, req, len, now_us, rsp, cap);
    if (b->srv.session != UDS_SESSION_PROGRAMMING) {
        abort_download(b); /* S3 ran out before this request, or the session changed */
    }
    if (uds_take_reset(&b->srv)) {
        b->reset_due = 1u;
    }
    return n;
}

void boot_programming_requested(boot_t *b, uint64_t now_us)
{
    uds_set_session(&b->srv, UDS_SESSION_PROGRAMMING, now_us);
    const size_t n = uds_session_response(UDS_SESSION_PROGRAMMING, b->rsp);
    if (isotp_send(&b->tp, b->rsp, n, now_us) == 0 && b->tx != NULL) {
        (void)isotp_poll(&b->tp, now_us, b->tx, b->tx_user);
    }
}

static void boot_serve(boot_t *b, uint64_t now_us)
{
    if (b->tx == NULL) {
        return;
    }
    (void)isotp_poll(&b->tp, now_us, b->tx, b->tx_user);
    if (isotp_tx_busy(&b->tp)) {
        return; /* the response buffer is in use */
    }
    size_t len = 0u;
    if (isotp_receive(&b->tp, b->req, sizeof b->req, &len) != 0) {
        return;
    }
    const size_t n = boot_handle(b, b->req, len, now_us, b->rsp, sizeof b->rsp);
    if (n > 0u && isotp_send(&b->tp, b->rsp, n, now_us) == 0) {
        (void)isotp_poll(&b->tp, now_us, b->tx, b->tx_user);
    }
}

void boot_frame(boot_t *b, const hal_can_frame_t *f, uint64_t now_us)
{
    (void)isotp_on_frame(&b->tp, f, now_us);
    boot_serve(b, now_us);
}

/* NAV_Heartbeat with Mode Bootloader, once per whole second of the bootloader's uptime */
static void heartbeat(boot_t *b, uint64_t now_us)
{
    if (b->hb_sent == 0u) {
        b->start_us = now_us;
    }
    const uint64_t up = now_us > b->start_us ? (now_us - b->start_us) / 1000000u : 0u;
    const uint32_t up_s = up > NAVECU_NAV_HEARTBEAT_UPTIME_RAW_MAX
                              ? (uint32_t)NAVECU_NAV_HEARTBEAT_UPTIME_RAW_MAX
                              : (uint32_t)up;
    if (b->hb_sent != 0u && up_s == b->hb_uptime_s) {
        return;
    }
    b->hb_sent = 1u;
    b->hb_uptime_s = up_s;
    struct navecu_can_nav_heartbeat_t m;
    (void)memset(&m, 0, sizeof m);
    m.mode = NAVECU_CAN_NAV_HEARTBEAT_MODE_BOOTLOADER_CHOICE;
    m.imu_missing = 1u;
    m.gnss_missing = 1u;
    m.wheels_missing = 1u;
    m.uptime = up_s;
    m.nav_counter = b->hb_counter;
    b->hb_counter = e2e_counter_next(b->hb_counter);
    hal_can_frame_t f;
    (void)memset(&f, 0, sizeof f);
    f.id = NAVECU_CAN_NAV_HEARTBEAT_FRAME_ID;
    f.dlc = 8u;
    (void)navecu_can_nav_heartbeat_pack(f.data, &m, sizeof f.data);
    e2e_protect(f.id, f.data);
    (void)b->tx(b->tx_user, &f);
}

int boot_poll(boot_t *b, uint64_t now_us)
{
    heartbeat(b, now_us);
    boot_serve(b, now_us);
    uds_poll(&b->srv, now_us);
    if (b->srv.session != UDS_SESSION_PROGRAMMING) {
        abort_download(b);
    }
    if (b->reset_due && !isotp_tx_busy(&b->tp)) {
        b->reset_due = 0u;
        return 1;
    }
    /* back in the default session (the tester gone: S3, or its 10 01, served here or by
     * boot_frame since the last poll) with the application still whole (nothing erased
     * yet): reset once the 50 01 left, and the application starts again, rather than an
     * ECU left in its bootloader until the next power cycle */
    const uint8_t session = b->srv.session;
    if (session == UDS_SESSION_DEFAULT && b->session_seen != UDS_SESSION_DEFAULT) {
        if (isotp_tx_busy(&b->tp)) {
            return 0;
        }
        b->session_seen = session;
        if (boot_image_check(&b->fl) == BOOT_IMAGE_OK) {
            boot_count(&b->cnt.returns);
            return 1;
        }
        return 0;
    }
    b->session_seen = session;
    return 0;
}
