/* isotp.c - ISO 15765-2 transport on classic CAN, normal addressing; see isotp.h. */
#include "isotp.h"

#include <string.h>

#define PCI_SF 0u
#define PCI_FF 1u
#define PCI_CF 2u
#define PCI_FC 3u

#define CAN_ID_STD_MAX 0x7FFu
#define SF_MAX 7u     /* data bytes of a single frame */
#define FF_DATA 6u    /* data bytes of a first frame */
#define CF_DATA 7u    /* data bytes of a consecutive frame */
#define FF_DL_MAX 4095u
#define ST_MIN_RESERVED_US 127000u

_Static_assert(ISOTP_MAX_LEN >= 8u && ISOTP_MAX_LEN <= FF_DL_MAX,
               "ISOTP_MAX_LEN must be 8..4095 (a classic first frame's 12-bit FF_DL)");

/* count_up, rx_end and tx_end out of line (noinline): GCC inlined them at each of their
 * 30, 6 and 6 calls, 160 bytes more of the ECU's flash (docs/target.md); they run on
 * diagnostic traffic only. count_up takes the counter's address: a call passes one
 * pointer instead of loading the value and storing the result (32 B less in the
 * application image, 20 B more in the bootloader's, which has the room). */
__attribute__((noinline)) static void count_up(uint32_t *n)
{
    if (*n != UINT32_MAX) {
        (*n)++;
    }
}

/* now - since, 0 when the time went backwards */
static uint64_t elapsed(uint64_t now_us, uint64_t since_us)
{
    return (now_us >= since_us) ? (now_us - since_us) : 0u;
}

static int st_min_valid(uint8_t raw)
{
    return (raw <= 0x7Fu) || ((raw >= 0xF1u) && (raw <= 0xF9u));
}

uint32_t isotp_st_min_us(uint8_t raw)
{
    uint32_t us = ST_MIN_RESERVED_US;
    if (raw <= 0x7Fu) {
        us = (uint32_t)raw * 1000u;
    } else if ((raw >= 0xF1u) && (raw <= 0xF9u)) {
        us = ((uint32_t)raw - 0xF0u) * 100u;
    } else {
        /* reserved: the longest STmin, 127 ms */
    }
    return us;
}

void isotp_config_defaults(isotp_config_t *cfg, uint32_t rx_id, uint32_t tx_id)
{
    if (cfg == NULL) {
        return;
    }
    (void)memset(cfg, 0, sizeof *cfg);
    cfg->rx_id = rx_id;
    cfg->tx_id = tx_id;
    cfg->padding = 1u;
    cfg->pad_byte = ISOTP_DEFAULT_PAD_BYTE;
    cfg->block_size = ISOTP_DEFAULT_BLOCK_SIZE;
    cfg->st_min = ISOTP_DEFAULT_ST_MIN;
    cfg->wft_max = ISOTP_DEFAULT_WFT_MAX;
    cfg->wait_rx_max = 0u;
    cfg->wait_period_us = ISOTP_DEFAULT_WAIT_PERIOD_US;
    cfg->n_as_us = ISOTP_DEFAULT_TIMEOUT_US;
    cfg->n_ar_us = ISOTP_DEFAULT_TIMEOUT_US;
    cfg->n_bs_us = ISOTP_DEFAULT_TIMEOUT_US;
    cfg->n_cr_us = ISOTP_DEFAULT_TIMEOUT_US;
}

int isotp_init(isotp_t *c, const isotp_config_t *cfg)
{
    if ((c == NULL) || (cfg == NULL) || (cfg->rx_id > CAN_ID_STD_MAX) ||
        (cfg->tx_id > CAN_ID_STD_MAX) || (cfg->rx_id == cfg->tx_id) ||
        (st_min_valid(cfg->st_min) == 0) || (cfg->padding > 1u) ||
        (cfg->wait_period_us == 0u) || (cfg->n_as_us == 0u) || (cfg->n_ar_us == 0u) ||
        (cfg->n_bs_us == 0u) || (cfg->n_cr_us == 0u)) {
        return HAL_EINVAL;
    }
    (void)memset(c, 0, sizeof *c);
    c->cfg = *cfg;
    c->rx_result = ISOTP_N_NONE;
    c->tx_result = ISOTP_N_NONE;
    c->rx_state = ISOTP_RX_IDLE;
    c->tx_state = ISOTP_TX_IDLE;
    c->tx_data = NULL;
    return 0;
}

/* ---------------------------------------------------------------- reception */

__attribute__((noinline)) static void rx_end(isotp_t *c, isotp_result_t result)
{
    c->rx_state = ISOTP_RX_IDLE;
    c->rx_len = 0u;
    c->rx_pos = 0u;
    c->rx_waits = 0u;
    c->rx_result = result;
}

/* an FC is due now (out of line, noinline: inlined at its calls, 8 bytes more) */
__attribute__((noinline)) static void rx_fc_due(isotp_t *c, uint8_t fs, uint64_t now_us)
{
    c->rx_state = ISOTP_RX_FC;
    c->rx_fc = fs;
    c->rx_fc_due_us = now_us;
}

/* an SF or FF arrives: a reception in progress (including a pending FC) is interrupted */
static void rx_interrupt(isotp_t *c)
{
    if (c->rx_state != ISOTP_RX_IDLE) {
        count_up(&c->cnt.rx_unexpected);
        rx_end(c, ISOTP_N_UNEXP_PDU);
    }
}

static void on_sf(isotp_t *c, const hal_can_frame_t *f)
{
    const uint8_t sf_dl = (uint8_t)(f->data[0] & 0x0Fu);
    if ((sf_dl == 0u) || (sf_dl > SF_MAX) || (sf_dl > (uint8_t)(f->dlc - 1u))) {
        count_up(&c->cnt.rx_invalid);
        return;
    }
    rx_interrupt(c);
    if (c->ready_len != 0u) {
        count_up(&c->cnt.rx_busy); /* no flow control for an SF: dropped */
        return;
    }
    (void)memcpy(c->rx_buf, &f->data[1], sf_dl);
    c->ready_len = sf_dl;
    count_up(&c->cnt.rx_msgs);
    rx_end(c, ISOTP_N_OK);
}

static void on_ff(isotp_t *c, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->dlc != 8u) {
        count_up(&c->cnt.rx_invalid);
        return;
    }
    uint32_t ff_dl = ((uint32_t)f->data[0] & 0x0Fu) << 8;
    ff_dl |= (uint32_t)f->data[1];
    if (ff_dl == 0u) {
        /* escape sequence (ISO 15765-2:2016): a 32-bit FF_DL, used only above 4095 */
        const uint32_t dl32 = ((uint32_t)f->data[2] << 24) | ((uint32_t)f->data[3] << 16) |
                              ((uint32_t)f->data[4] << 8) | (uint32_t)f->data[5];
        if (dl32 <= FF_DL_MAX) {
            count_up(&c->cnt.rx_invalid);
            return;
        }
        ff_dl = dl32;
    } else if (ff_dl <= SF_MAX) {
        count_up(&c->cnt.rx_invalid); /* fits a single frame */
        return;
    } else {
        /* a 12-bit FF_DL of 8..4095 */
    }
    rx_interrupt(c);
    if (ff_dl > ISOTP_MAX_LEN) {
        count_up(&c->cnt.rx_overflow);
        c->rx_result = ISOTP_N_BUFFER_OVFLW;
        rx_fc_due(c, ISOTP_FS_OVFLW, now_us);
        return;
    }
    c->rx_len = (uint16_t)ff_dl;
    c->rx_sn = 1u;
    c->rx_waits = 0u;
    if (c->ready_len != 0u) {
        /* the buffer still holds an unread message: keep the FF's data, send WAITs */
        (void)memcpy(c->rx_head, &f->data[2], FF_DATA);
        c->rx_pos = 0u;
        c->rx_state = ISOTP_RX_WAIT_BUF;
        c->rx_timer_us = now_us; /* the first WAIT (or OVFLW) is due at once */
        return;
    }
    (void)memcpy(c->rx_buf, &f->data[2], FF_DATA);
    c->rx_pos = (uint16_t)FF_DATA;
    rx_fc_due(c, ISOTP_FS_CTS, now_us);
}

static void on_cf(isotp_t *c, const hal_can_frame_t *f, uint64_t now_us)
{
    if (c->rx_state != ISOTP_RX_WAIT_CF) {
        count_up(&c->cnt.rx_unexpected); /* ignored */
        return;
    }
    const uint16_t left = (uint16_t)(c->rx_len - c->rx_pos);
    const uint16_t n = (left < CF_DATA) ? left : (uint16_t)CF_DATA;
    if ((uint16_t)f->dlc < (uint16_t)(n + 1u)) {
        count_up(&c->cnt.rx_invalid); /* too short for its data: ignored */
        return;
    }
    if ((uint8_t)(f->data[0] & 0x0Fu) != c->rx_sn) {
        count_up(&c->cnt.rx_wrong_sn);
        rx_end(c, ISOTP_N_WRONG_SN); /* a lost or repeated CF: the message is dropped */
        return;
    }
    (void)memcpy(&c->rx_buf[c->rx_pos], &f->data[1], n);
    c->rx_pos = (uint16_t)(c->rx_pos + n);
    c->rx_sn = (uint8_t)((c->rx_sn + 1u) & 0x0Fu);
    c->rx_timer_us = now_us;
    if (c->rx_pos == c->rx_len) {
        c->ready_len = c->rx_len;
        count_up(&c->cnt.rx_msgs);
        rx_end(c, ISOTP_N_OK);
        return;
    }
    if (c->cfg.block_size != 0u) {
        c->rx_block_left = (uint8_t)(c->rx_block_left - 1u);
        if (c->rx_block_left == 0u) {
            rx_fc_due(c, ISOTP_FS_CTS, now_us); /* the block is complete: the next FC */
        }
    }
}

/* ---------------------------------------------------------------- transmission */

__attribute__((noinline)) static void tx_end(isotp_t *c, isotp_result_t result)
{
    c->tx_state = ISOTP_TX_IDLE;
    c->tx_data = NULL;
    c->tx_len = 0u;
    c->tx_pos = 0u;
    c->tx_waits = 0u;
    c->tx_result = result;
}

static void on_fc(isotp_t *c, const hal_can_frame_t *f, uint64_t now_us)
{
    if (f->dlc < 3u) {
        count_up(&c->cnt.rx_invalid);
        return;
    }
    if (c->tx_state != ISOTP_TX_WAIT_FC) {
        count_up(&c->cnt.rx_unexpected); /* ignored */
        return;
    }
    const uint8_t fs = (uint8_t)(f->data[0] & 0x0Fu);
    if (fs == ISOTP_FS_CTS) {
        c->tx_block_size = f->data[1];
        c->tx_block_left = f->data[1];
        c->tx_st_min_us = isotp_st_min_us(f->data[2]);
        c->tx_waits = 0u;
        c->tx_state = ISOTP_TX_SEND;
        c->tx_due_us = now_us; /* the first CF of a block may go at once */
    } else if (fs == ISOTP_FS_WAIT) {
        count_up(&c->cnt.wait_received);
        c->tx_waits = (c->tx_waits == UINT16_MAX) ? c->tx_waits : (uint16_t)(c->tx_waits + 1u);
        if ((c->cfg.wait_rx_max != 0u) && (c->tx_waits > c->cfg.wait_rx_max)) {
            count_up(&c->cnt.tx_wft_ovrn);
            tx_end(c, ISOTP_N_WFT_OVRN);
        } else {
            c->tx_timer_us = now_us; /* N_Bs starts again */
        }
    } else if (fs == ISOTP_FS_OVFLW) {
        count_up(&c->cnt.tx_overflow);
        tx_end(c, ISOTP_N_BUFFER_OVFLW);
    } else {
        count_up(&c->cnt.tx_invalid_fs);
        tx_end(c, ISOTP_N_INVALID_FS);
    }
}

/* ---------------------------------------------------------------- timers */

static void check_timers(isotp_t *c, uint64_t now_us)
{
    if ((c->rx_state == ISOTP_RX_WAIT_CF) &&
        (elapsed(now_us, c->rx_timer_us) > c->cfg.n_cr_us)) {
        count_up(&c->cnt.rx_timeout_cr);
        rx_end(c, ISOTP_N_TIMEOUT_CR);
    } else if ((c->rx_state == ISOTP_RX_FC) &&
               (elapsed(now_us, c->rx_fc_due_us) > c->cfg.n_ar_us)) {
        count_up(&c->cnt.rx_timeout_ar);
        rx_end(c, ISOTP_N_TIMEOUT_A);
    } else {
        /* no reception timer ran out */
    }
    if ((c->tx_state == ISOTP_TX_WAIT_FC) &&
        (elapsed(now_us, c->tx_timer_us) > c->cfg.n_bs_us)) {
        count_up(&c->cnt.tx_timeout_bs);
        tx_end(c, ISOTP_N_TIMEOUT_BS);
    } else if ((c->tx_state == ISOTP_TX_SEND) &&
               (elapsed(now_us, c->tx_due_us) > c->cfg.n_as_us)) {
        count_up(&c->cnt.tx_timeout_as);
        tx_end(c, ISOTP_N_TIMEOUT_A);
    } else {
        /* no transmission timer ran out */
    }
}

/* ---------------------------------------------------------------- frames sent */

/* f := a frame on tx_id with the first n bytes of body, padded (or DLC n) */
static void frame_make(const isotp_t *c, hal_can_frame_t *f, const uint8_t *body, uint8_t n)
{
    (void)memset(f, 0, sizeof *f);
    f->id = c->cfg.tx_id;
    f->extended = 0u;
    (void)memset(f->data, c->cfg.pad_byte, sizeof f->data);
    (void)memcpy(f->data, body, n);
    f->dlc = (c->cfg.padding != 0u) ? 8u : n;
}

/* the reception's due FC; 1 when tx accepted it */
static int rx_send_fc(isotp_t *c, uint64_t now_us, isotp_tx_fn tx, void *user)
{
    uint8_t body[3];
    body[0] = (uint8_t)(0x30u | c->rx_fc);
    body[1] = c->cfg.block_size;
    body[2] = c->cfg.st_min;
    if (c->rx_fc != ISOTP_FS_CTS) {
        body[1] = 0u; /* BS and STmin matter only with CTS */
        body[2] = 0u;
    }
    hal_can_frame_t f;
    frame_make(c, &f, body, 3u);
    if (tx(user, &f) != 0) {
        count_up(&c->cnt.tx_refused);
        return 0;
    }
    if (c->rx_fc == ISOTP_FS_CTS) {
        c->rx_state = ISOTP_RX_WAIT_CF;
        c->rx_timer_us = now_us; /* N_Cr from the FC on */
        c->rx_block_left = c->cfg.block_size;
    } else if (c->rx_fc == ISOTP_FS_WAIT) {
        count_up(&c->cnt.wait_sent);
        c->rx_waits = (uint8_t)(c->rx_waits + 1u);
        c->rx_state = ISOTP_RX_WAIT_BUF;
        c->rx_timer_us = now_us + c->cfg.wait_period_us;
    } else {
        c->rx_state = ISOTP_RX_IDLE; /* OVFLW: the reception ended when it was decided */
        c->rx_len = 0u;
        c->rx_pos = 0u;
    }
    return 1;
}

/* a reception waiting for the buffer: CTS once it is free, else WAIT or give up */
static void rx_wait_buf(isotp_t *c, uint64_t now_us)
{
    if (c->ready_len == 0u) {
        (void)memcpy(c->rx_buf, c->rx_head, FF_DATA);
        c->rx_pos = (uint16_t)FF_DATA;
        c->rx_waits = 0u;
        rx_fc_due(c, ISOTP_FS_CTS, now_us);
    } else if (now_us >= c->rx_timer_us) {
        if (c->rx_waits < c->cfg.wft_max) {
            rx_fc_due(c, ISOTP_FS_WAIT, now_us);
        } else {
            if (c->cfg.wft_max == 0u) {
                count_up(&c->cnt.rx_busy);
            } else {
                count_up(&c->cnt.rx_wft_ovrn);
            }
            c->rx_result = ISOTP_N_WFT_OVRN;
            rx_fc_due(c, ISOTP_FS_OVFLW, now_us);
        }
    } else {
        /* the next WAIT is not due yet */
    }
}

/* the transmission's next frame (SF, FF or CF); 1 when tx accepted it */
static int tx_send_next(isotp_t *c, uint64_t now_us, isotp_tx_fn tx, void *user)
{
    uint8_t body[8];
    uint8_t n;
    uint16_t take;
    if (c->tx_pos == 0u) {
        if (c->tx_len <= SF_MAX) {
            body[0] = (uint8_t)c->tx_len;
            take = c->tx_len;
        } else {
            body[0] = (uint8_t)(0x10u | ((uint32_t)c->tx_len >> 8));
            body[1] = (uint8_t)(c->tx_len & 0xFFu);
            take = (uint16_t)FF_DATA;
        }
    } else {
        body[0] = (uint8_t)(0x20u | c->tx_sn);
        const uint16_t left = (uint16_t)(c->tx_len - c->tx_pos);
        take = (left < CF_DATA) ? left : (uint16_t)CF_DATA;
    }
    const uint8_t hdr = ((c->tx_pos == 0u) && (c->tx_len > SF_MAX)) ? 2u : 1u;
    (void)memcpy(&body[hdr], &c->tx_data[c->tx_pos], take);
    n = (uint8_t)(hdr + take);
    hal_can_frame_t f;
    frame_make(c, &f, body, n);
    if (tx(user, &f) != 0) {
        count_up(&c->cnt.tx_refused);
        return 0;
    }
    const uint8_t first = (c->tx_pos == 0u) ? 1u : 0u;
    c->tx_pos = (uint16_t)(c->tx_pos + take);
    if (c->tx_pos == c->tx_len) {
        count_up(&c->cnt.tx_msgs);
        tx_end(c, ISOTP_N_OK);
    } else if (first != 0u) {
        c->tx_sn = 1u;
        c->tx_state = ISOTP_TX_WAIT_FC; /* after the FF */
        c->tx_timer_us = now_us;
    } else {
        c->tx_sn = (uint8_t)((c->tx_sn + 1u) & 0x0Fu);
        c->tx_due_us = now_us + c->tx_st_min_us;
        if (c->tx_block_size != 0u) {
            c->tx_block_left = (uint8_t)(c->tx_block_left - 1u);
            if (c->tx_block_left == 0u) {
                c->tx_state = ISOTP_TX_WAIT_FC; /* the block is sent */
                c->tx_timer_us = now_us;
            }
        }
    }
    return 1;
}

/* ---------------------------------------------------------------- the API */

int isotp_on_frame(isotp_t *c, const hal_can_frame_t *f, uint64_t now_us)
{
    if ((c == NULL) || (f == NULL) || (f->dlc > 8u)) {
        return HAL_EINVAL;
    }
    if ((f->extended != 0u) || (f->id != c->cfg.rx_id)) {
        return 0;
    }
    check_timers(c, now_us);
    if (f->dlc == 0u) {
        count_up(&c->cnt.rx_invalid);
        return 1;
    }
    const uint8_t pci = (uint8_t)(f->data[0] >> 4);
    if (pci == PCI_SF) {
        on_sf(c, f);
    } else if (pci == PCI_FF) {
        on_ff(c, f, now_us);
    } else if (pci == PCI_CF) {
        on_cf(c, f, now_us);
    } else if (pci == PCI_FC) {
        on_fc(c, f, now_us);
    } else {
        count_up(&c->cnt.rx_invalid); /* PCI type 4..15: reserved */
    }
    return 1;
}

int isotp_poll(isotp_t *c, uint64_t now_us, isotp_tx_fn tx, void *user)
{
    if ((c == NULL) || (tx == NULL)) {
        return HAL_EINVAL;
    }
    check_timers(c, now_us);
    int sent = 0;
    if (c->rx_state == ISOTP_RX_WAIT_BUF) {
        rx_wait_buf(c, now_us);
    }
    if (c->rx_state == ISOTP_RX_FC) {
        sent += rx_send_fc(c, now_us, tx, user);
    }
    while ((sent < (int)ISOTP_POLL_BURST) && (c->tx_state == ISOTP_TX_SEND) &&
           (now_us >= c->tx_due_us)) {
        if (tx_send_next(c, now_us, tx, user) == 0) {
            break; /* refused: offered again at the next call */
        }
        sent++;
    }
    return sent;
}

/* Out of line (noinline), as count_up: the link inlined it at its calls (the server's
 * response, isotp_send_now), 16 bytes more of the application's flash and 20 of the
 * bootloader's (docs/target.md); per diagnostic response only. */
__attribute__((noinline)) int isotp_send(isotp_t *c, const uint8_t *data, size_t len,
                                         uint64_t now_us)
{
    if ((c == NULL) || (data == NULL) || (len == 0u) || (len > ISOTP_MAX_LEN)) {
        return HAL_EINVAL;
    }
    if (c->tx_state != ISOTP_TX_IDLE) {
        return HAL_EAGAIN;
    }
    c->tx_data = data;
    c->tx_len = (uint16_t)len;
    c->tx_pos = 0u;
    c->tx_sn = 0u;
    c->tx_waits = 0u;
    c->tx_block_size = 0u;
    c->tx_block_left = 0u;
    c->tx_st_min_us = 0u;
    c->tx_state = ISOTP_TX_SEND;
    c->tx_due_us = now_us;
    return 0;
}

int isotp_receive(isotp_t *c, uint8_t *buf, size_t cap, size_t *len)
{
    if ((c == NULL) || (buf == NULL) || (len == NULL)) {
        return HAL_EINVAL;
    }
    if (c->ready_len == 0u) {
        return HAL_EAGAIN;
    }
    if (cap < c->ready_len) {
        return HAL_ENOSPC;
    }
    (void)memcpy(buf, c->rx_buf, c->ready_len);
    *len = c->ready_len;
    c->ready_len = 0u;
    return 0;
}

int isotp_tx_busy(const isotp_t *c)
{
    return ((c != NULL) && (c->tx_state != ISOTP_TX_IDLE)) ? 1 : 0;
}

int isotp_rx_busy(const isotp_t *c)
{
    return ((c != NULL) && (c->rx_state != ISOTP_RX_IDLE)) ? 1 : 0;
}

int isotp_send_now(isotp_t *c, const uint8_t *data, size_t len, uint64_t now_us,
                   isotp_tx_fn tx, void *user)
{
    if ((tx == NULL) || (len > SF_MAX)) {
        return HAL_EINVAL;
    }
    const int r = isotp_send(c, data, len, now_us);
    if (r != 0) {
        return r;
    }
    (void)isotp_poll(c, now_us, tx, user);
    if (c->tx_state != ISOTP_TX_IDLE) {
        tx_end(c, ISOTP_N_TIMEOUT_A); /* refused: given up */
        return HAL_EAGAIN;
    }
    return 0;
}
