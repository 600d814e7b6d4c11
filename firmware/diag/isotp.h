/*
 * isotp.h - the diagnostic transport: ISO 15765-2 (ISO-TP, DoCAN) on classic CAN, for the
 * UDS server of issue #16. Only the transport: messages of 1..ISOTP_MAX_LEN bytes over one
 * pair of 11-bit identifiers, normal addressing (no address byte in the payload).
 *
 * One isotp_t is one channel: it receives segmented requests on cfg.rx_id (the physical
 * request ID) and sends responses on cfg.tx_id (the response ID); reception and
 * transmission run at the same time (full duplex), so the flow control frames of a
 * response arrive on rx_id while a request may be in reception.
 *
 * Frames (byte 0 is the protocol control information, PCI; docs/can.md, "Diagnostic
 * transport (ISO-TP)", has the byte layouts, timing and what is counted):
 *   SF  0x0L d1..dL               single frame, L = 1..7 data bytes
 *   FF  0x1H LL d1..d6            first frame, length 0xHLL = 8..4095
 *   CF  0x2N d..                  consecutive frame, N = sequence number 1, 2, .. 15, 0, ..
 *   FC  0x3S BS STmin             flow control, S = 0 CTS, 1 WAIT, 2 OVFLW
 * Frames sent have DLC 8, unused bytes cfg.pad_byte (0xCC by default), or with
 * cfg.padding = 0 the shortest DLC for their content. Frames received may be shorter where
 * the standard allows it (an SF of DLC >= L + 1, the last CF of DLC >= 1 + its data, an FC
 * of DLC >= 3; an FF and every other CF must have DLC 8); padding bytes are not checked.
 *
 * Time: every call that may start or check a timer takes the caller's time now_us, in
 * microseconds on any monotonic clock (the ECU's: its IMU sample count, or the HAL clock);
 * nothing here reads a clock, so a sequence of calls with the same arguments always gives
 * the same frames and results. A time that goes backwards counts as no time elapsed.
 * Timeouts (ISO 15765-2 names; each configurable, default ISOTP_DEFAULT_TIMEOUT_US):
 *   N_As  a frame of a transmission not accepted by the transmit function within n_as_us
 *         of the moment it was due (the CAN driver's queue stayed full)
 *   N_Ar  the same for a flow control frame the receiver has to send
 *   N_Bs  no flow control within n_bs_us after a first frame, after the last consecutive
 *         frame of a block, or after an FC WAIT
 *   N_Cr  no consecutive frame within n_cr_us after the ECU's FC CTS or the previous CF
 * Each aborts the reception or transmission, which ends with the result below; a reception
 * that ends other than ISOTP_N_OK drops the message (its bytes never reach isotp_receive).
 * Timers are checked at the start of isotp_on_frame and of isotp_poll.
 *
 * Memory: no allocation, no recursion, no global state; an isotp_t is the receive buffer
 * (ISOTP_MAX_LEN bytes) and 185 bytes of state on the Cortex-M4F: 4,280 bytes with the
 * default ISOTP_MAX_LEN (201 bytes of state on a 64-bit host). A message being sent is not
 * copied: isotp_send keeps a pointer to the caller's bytes, which must stay valid and
 * unchanged until isotp_tx_busy() returns 0. Not reentrant: one caller (the main loop).
 */
#ifndef NAVECU_ISOTP_H
#define NAVECU_ISOTP_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

/* Longest message, received or sent: the classic ISO-TP maximum (FF_DL is 12 bits). A
 * build for less RAM may define it smaller (8..4095); longer messages are then refused
 * with FC OVFLW (received) or HAL_EINVAL (sent). */
#ifndef ISOTP_MAX_LEN
#define ISOTP_MAX_LEN 4095u
#endif

#define ISOTP_DEFAULT_TIMEOUT_US 1000000u /* N_As, N_Ar, N_Bs, N_Cr: ISO 15765-2 1000 ms */
#define ISOTP_DEFAULT_PAD_BYTE 0xCCu
#define ISOTP_DEFAULT_BLOCK_SIZE 8u      /* CFs per FC announced (docs/can.md: why 8) */
#define ISOTP_DEFAULT_ST_MIN 0u          /* STmin announced: 0 ms */
#define ISOTP_DEFAULT_WFT_MAX 10u        /* FC WAITs sent in a row before giving up */
#define ISOTP_DEFAULT_WAIT_PERIOD_US 100000u /* between two FC WAITs sent (N_Br) */
#define ISOTP_POLL_BURST 16u             /* most frames one isotp_poll hands over */

/* What a channel is configured with (isotp_config_defaults, then change what differs). */
typedef struct {
    uint32_t rx_id;          /* physical request ID received, 11-bit (<= 0x7FF) */
    uint32_t tx_id;          /* response ID sent, 11-bit, != rx_id */
    uint8_t padding;         /* 1: every frame sent has DLC 8, 0: the shortest DLC */
    uint8_t pad_byte;        /* value of the unused bytes of a padded frame */
    uint8_t block_size;      /* BS announced in FC CTS: CFs per block, 0 = all at once */
    uint8_t st_min;          /* STmin announced, as sent: 0x00..0x7F ms, 0xF1..0xF9 100..900 us */
    uint8_t wft_max;         /* N_WFTmax: FC WAITs the ECU sends in a row while its receive
                                buffer still holds an unread message; then FC OVFLW (0: no
                                WAIT, FC OVFLW at once) */
    uint16_t wait_rx_max;    /* FC WAITs accepted in a row while sending before the
                                transmission is given up (ISOTP_N_WFT_OVRN); 0: no limit */
    uint32_t wait_period_us; /* time between two FC WAITs sent (N_Br); > 0 */
    uint32_t n_as_us;        /* N_As, > 0 */
    uint32_t n_ar_us;        /* N_Ar, > 0 */
    uint32_t n_bs_us;        /* N_Bs, > 0 */
    uint32_t n_cr_us;        /* N_Cr, > 0 */
} isotp_config_t;

/* How the last reception or transmission ended (ISO 15765-2's N_Result names). */
typedef enum {
    ISOTP_N_OK = 0,       /* complete */
    ISOTP_N_TIMEOUT_A,    /* N_As (sending) or N_Ar (receiving): the driver refused our frame */
    ISOTP_N_TIMEOUT_BS,   /* no flow control in time */
    ISOTP_N_TIMEOUT_CR,   /* no consecutive frame in time: the message is dropped */
    ISOTP_N_WRONG_SN,     /* a consecutive frame with the wrong sequence number (lost CF) */
    ISOTP_N_INVALID_FS,   /* a flow control with a flow status other than 0..2 */
    ISOTP_N_UNEXP_PDU,    /* a new SF or FF arrived while a message was in reception */
    ISOTP_N_WFT_OVRN,     /* the WAIT limit was reached (wft_max sent, wait_rx_max received) */
    ISOTP_N_BUFFER_OVFLW, /* the peer answered FC OVFLW, or the ECU had to */
    ISOTP_N_NONE          /* nothing has ended yet since isotp_init */
} isotp_result_t;

/* Every event counted, each saturating at UINT32_MAX (never decreasing). */
typedef struct {
    uint32_t rx_msgs;        /* messages received complete (SF or FF + CFs) */
    uint32_t tx_msgs;        /* messages sent complete */
    uint32_t rx_invalid;     /* frames on rx_id ignored as malformed: DLC 0, unknown PCI
                                type 4..15, SF_DL 0 or > 7 or > DLC - 1, FF with DLC < 8 or
                                FF_DL < 8 (or an escape FF_DL <= 4095), a CF shorter than
                                its data, an FC with DLC < 3 */
    uint32_t rx_unexpected;  /* PDUs out of turn: an SF or FF interrupting a reception (which
                                is dropped: ISOTP_N_UNEXP_PDU), a CF when none is awaited,
                                an FC when no transmission waits for one */
    uint32_t rx_wrong_sn;    /* receptions dropped for a wrong sequence number */
    uint32_t rx_timeout_cr;  /* receptions dropped on N_Cr */
    uint32_t rx_timeout_ar;  /* receptions dropped on N_Ar (our FC could not be sent) */
    uint32_t rx_overflow;    /* first frames longer than ISOTP_MAX_LEN: FC OVFLW sent */
    uint32_t rx_busy;        /* messages refused because an unread one holds the buffer:
                                an SF dropped, an FF answered with FC OVFLW (wft_max 0) */
    uint32_t rx_wft_ovrn;    /* receptions given up after wft_max WAITs: FC OVFLW sent */
    uint32_t wait_sent;      /* FC WAIT sent */
    uint32_t tx_timeout_as;  /* transmissions aborted on N_As */
    uint32_t tx_timeout_bs;  /* transmissions aborted on N_Bs */
    uint32_t tx_overflow;    /* transmissions aborted by the peer's FC OVFLW */
    uint32_t tx_invalid_fs;  /* transmissions aborted by an FC with flow status 3..15 */
    uint32_t tx_wft_ovrn;    /* transmissions aborted after more than wait_rx_max WAITs */
    uint32_t wait_received;  /* FC WAIT received */
    uint32_t tx_refused;     /* times the transmit function refused a frame (retried) */
} isotp_counters_t;

/* Reception states (isotp_t.rx_state). */
typedef enum {
    ISOTP_RX_IDLE = 0,  /* no reception in progress */
    ISOTP_RX_FC,        /* a flow control (rx_fc) is due to be sent */
    ISOTP_RX_WAIT_BUF,  /* FF received while the buffer holds an unread message: FC WAITs */
    ISOTP_RX_WAIT_CF    /* FC CTS sent: consecutive frames awaited */
} isotp_rx_state_t;

/* Transmission states (isotp_t.tx_state). */
typedef enum {
    ISOTP_TX_IDLE = 0,  /* nothing to send */
    ISOTP_TX_SEND,      /* the next SF, FF or CF is due at tx_due_us */
    ISOTP_TX_WAIT_FC    /* FF or a block sent: flow control awaited */
} isotp_tx_state_t;

/* Flow status of an FC frame (byte 0 low nibble). */
#define ISOTP_FS_CTS 0u
#define ISOTP_FS_WAIT 1u
#define ISOTP_FS_OVFLW 2u

/* The channel. Caller-owned; fields are read by the tests and the fuzzer, changed only
 * here. */
typedef struct {
    isotp_config_t cfg;
    isotp_counters_t cnt;
    isotp_result_t rx_result;  /* how the last reception ended */
    isotp_result_t tx_result;  /* how the last transmission ended */
    /* reception */
    isotp_rx_state_t rx_state;
    uint8_t rx_fc;             /* flow status of the FC due in ISOTP_RX_FC */
    uint8_t rx_sn;             /* sequence number of the next CF, 0..15 */
    uint8_t rx_block_left;     /* CFs left in the current block (block_size != 0) */
    uint8_t rx_waits;          /* FC WAITs sent in a row for this FF */
    uint8_t rx_head[6];        /* the FF's data while it waits for the buffer */
    uint16_t rx_len;           /* length of the message in reception (FF_DL) */
    uint16_t rx_pos;           /* bytes of it received */
    uint16_t ready_len;        /* > 0: rx_buf holds a complete unread message this long */
    uint64_t rx_fc_due_us;     /* when the FC became due (N_Ar) */
    uint64_t rx_timer_us;      /* WAIT_CF: N_Cr start; WAIT_BUF: when the next WAIT is due */
    /* transmission */
    isotp_tx_state_t tx_state;
    const uint8_t *tx_data;    /* the caller's message (not copied) */
    uint16_t tx_len;           /* its length */
    uint16_t tx_pos;           /* bytes of it sent */
    uint8_t tx_sn;             /* sequence number of the next CF */
    uint8_t tx_block_size;     /* BS of the last FC CTS */
    uint8_t tx_block_left;     /* CFs left before the next FC (tx_block_size != 0) */
    uint16_t tx_waits;         /* FC WAITs received in a row */
    uint32_t tx_st_min_us;     /* STmin of the last FC CTS, decoded */
    uint64_t tx_due_us;        /* when the next frame may go (STmin) and N_As start */
    uint64_t tx_timer_us;      /* N_Bs start */
    uint8_t rx_buf[ISOTP_MAX_LEN];
} isotp_t;

/* A transmit function: queue one frame on the bus. 0 when accepted; anything else (e.g.
 * HAL_ENOSPC: queue full) leaves the frame to be offered again at the next isotp_poll.
 * hal_can_send has this form once its hal_t is passed as user. */
typedef int (*isotp_tx_fn)(void *user, const hal_can_frame_t *f);

/* cfg := the defaults above for the pair (rx_id, tx_id): padding on with 0xCC, BS 8,
 * STmin 0, wft_max 10 WAITs 100 ms apart, no limit on WAITs received, 1000 ms timeouts. */
void isotp_config_defaults(isotp_config_t *cfg, uint32_t rx_id, uint32_t tx_id);

/* Decoded STmin of a raw FC byte, in microseconds: 0x00..0x7F ms, 0xF1..0xF9 100..900 us,
 * every reserved value (0x80..0xF0, 0xFA..0xFF) 127 ms, as ISO 15765-2 prescribes. */
uint32_t isotp_st_min_us(uint8_t raw);

/* Start the channel idle with cfg (copied), every counter 0, both results ISOTP_N_NONE.
 * Returns 0, or HAL_EINVAL (c unchanged) for a NULL argument, an ID above 0x7FF, equal
 * IDs, a reserved st_min, a zero timeout or wait period, padding not 0 or 1. */
int isotp_init(isotp_t *c, const isotp_config_t *cfg);

/*
 * One received CAN frame. Frames not on cfg.rx_id (another ID, or an extended one) are
 * left alone: 0. A frame on rx_id returns 1 whatever it was: taken into the reception,
 * taken as flow control for the transmission, or ignored and counted (isotp_counters_t
 * says which). HAL_EINVAL for a NULL argument or a DLC above 8.
 */
int isotp_on_frame(isotp_t *c, const hal_can_frame_t *f, uint64_t now_us);

/*
 * Send what is due: a flow control of the reception, then the transmission's frames while
 * STmin and the block allow, at most ISOTP_POLL_BURST frames. A frame refused by tx (return
 * not 0) is offered again at the next call (until N_As / N_Ar). Returns the number of
 * frames tx accepted, or HAL_EINVAL for a NULL c or tx. Call it often: at least every
 * STmin, and after every isotp_on_frame and isotp_receive.
 */
int isotp_poll(isotp_t *c, uint64_t now_us, isotp_tx_fn tx, void *user);

/*
 * Start sending data[0..len) (not copied: keep it unchanged until isotp_tx_busy is 0).
 * The first frame goes at the next isotp_poll. Returns 0; HAL_EAGAIN while a transmission
 * is in progress; HAL_EINVAL for NULL arguments or len not in 1..ISOTP_MAX_LEN.
 */
int isotp_send(isotp_t *c, const uint8_t *data, size_t len, uint64_t now_us);

/*
 * Take the complete message received, if any: copied to buf, its length in *len, and the
 * buffer is free for the next one. Returns 0; HAL_EAGAIN when none is complete;
 * HAL_ENOSPC when cap is smaller than the message (it stays); HAL_EINVAL for NULLs.
 */
int isotp_receive(isotp_t *c, uint8_t *buf, size_t cap, size_t *len);

/* 1 while a transmission is in progress (its data still in use), else 0. */
int isotp_tx_busy(const isotp_t *c);

/*
 * Send a single-frame message (len 1..7) at once, e.g. a 7F SID 78 before a long operation:
 * it leaves in this call or, refused by tx (a full driver queue; it would be stale once the
 * work it announces is done), is given up with the result ISOTP_N_TIMEOUT_A. data need not
 * stay valid after the call. Returns 0 when tx took the frame; HAL_EAGAIN while a
 * transmission is in progress or when tx refused it; HAL_EINVAL for NULLs or another len.
 */
int isotp_send_now(isotp_t *c, const uint8_t *data, size_t len, uint64_t now_us,
                   isotp_tx_fn tx, void *user);

/* 1 while a segmented reception is in progress, else 0. */
int isotp_rx_busy(const isotp_t *c);

#endif /* NAVECU_ISOTP_H */
