/*
 * bxcan.h - register-level driver for the STM32F4 bxCAN controller (CAN1 of the
 * STM32F405), the first piece of the Cortex-M4F HAL (hal/cortex_m4f/).
 *
 * The driver touches the controller only through a bxcan_regs_t pointer, so the host tests
 * (tests/test_bxcan.c) run it against a register block in RAM and play the hardware. It
 * includes no OS header, never allocates, and never waits without a bound.
 *
 * Typical use on the board (CAN1 at 0x40006400, APB1 = 42 MHz):
 *
 *     static bxcan_t can1;
 *     bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 100000u, NULL, NULL};
 *     bxcan_init(&can1, (bxcan_regs_t *)0x40006400u, &cfg);
 *     bxcan_set_filters(&can1, ids, n_ids);
 *     void CAN1_RX0_IRQHandler(void) { bxcan_rx0_irq(&can1, board_time_us()); }
 *     void CAN1_SCE_IRQHandler(void) { bxcan_sce_irq(&can1); }
 *     ... main loop: bxcan_receive(&can1, &f), bxcan_send(&can1, &f)
 *
 * Register layout and bit positions: RM0090 rev 19, section 32.9 (bxCAN registers).
 * Return codes are those of hal/hal.h: 0 or a negative HAL_E* value.
 */
#ifndef NAVECU_BXCAN_H
#define NAVECU_BXCAN_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

/* ---- register block (RM0090 32.9.5, offsets from the CAN base address) ---- */

typedef struct {
    volatile uint32_t TIR;  /* identifier, IDE, RTR, TXRQ */
    volatile uint32_t TDTR; /* DLC, TGT, TIME */
    volatile uint32_t TDLR; /* data bytes 0..3, byte 0 in bits 7:0 */
    volatile uint32_t TDHR; /* data bytes 4..7 */
} bxcan_tx_mailbox_t;

typedef struct {
    volatile uint32_t RIR;  /* identifier, IDE, RTR */
    volatile uint32_t RDTR; /* DLC, FMI, TIME */
    volatile uint32_t RDLR; /* data bytes 0..3 */
    volatile uint32_t RDHR; /* data bytes 4..7 */
} bxcan_rx_mailbox_t;

typedef struct {
    volatile uint32_t FR1;
    volatile uint32_t FR2;
} bxcan_filter_bank_t;

#define BXCAN_N_FILTER_BANKS 28u

typedef struct {
    volatile uint32_t MCR;                  /* 0x000 master control */
    volatile uint32_t MSR;                  /* 0x004 master status */
    volatile uint32_t TSR;                  /* 0x008 transmit status */
    volatile uint32_t RF0R;                 /* 0x00C receive FIFO 0 */
    volatile uint32_t RF1R;                 /* 0x010 receive FIFO 1 */
    volatile uint32_t IER;                  /* 0x014 interrupt enable */
    volatile uint32_t ESR;                  /* 0x018 error status */
    volatile uint32_t BTR;                  /* 0x01C bit timing */
    volatile uint32_t reserved0[88];        /* 0x020..0x17F */
    bxcan_tx_mailbox_t tx[3];               /* 0x180, 0x190, 0x1A0 */
    bxcan_rx_mailbox_t rx[2];               /* 0x1B0 FIFO 0, 0x1C0 FIFO 1 */
    volatile uint32_t reserved1[12];        /* 0x1D0..0x1FF */
    volatile uint32_t FMR;                  /* 0x200 filter master */
    volatile uint32_t FM1R;                 /* 0x204 filter mode: 1 = identifier list */
    volatile uint32_t reserved2;            /* 0x208 */
    volatile uint32_t FS1R;                 /* 0x20C filter scale: 0 = dual 16-bit */
    volatile uint32_t reserved3;            /* 0x210 */
    volatile uint32_t FFA1R;                /* 0x214 filter FIFO assignment: 0 = FIFO 0 */
    volatile uint32_t reserved4;            /* 0x218 */
    volatile uint32_t FA1R;                 /* 0x21C filter activation */
    volatile uint32_t reserved5[8];         /* 0x220..0x23F */
    bxcan_filter_bank_t fb[BXCAN_N_FILTER_BANKS]; /* 0x240..0x31F */
} bxcan_regs_t;

_Static_assert(offsetof(bxcan_regs_t, MCR) == 0x000u, "MCR offset");
_Static_assert(offsetof(bxcan_regs_t, MSR) == 0x004u, "MSR offset");
_Static_assert(offsetof(bxcan_regs_t, TSR) == 0x008u, "TSR offset");
_Static_assert(offsetof(bxcan_regs_t, RF0R) == 0x00Cu, "RF0R offset");
_Static_assert(offsetof(bxcan_regs_t, RF1R) == 0x010u, "RF1R offset");
_Static_assert(offsetof(bxcan_regs_t, IER) == 0x014u, "IER offset");
_Static_assert(offsetof(bxcan_regs_t, ESR) == 0x018u, "ESR offset");
_Static_assert(offsetof(bxcan_regs_t, BTR) == 0x01Cu, "BTR offset");
_Static_assert(offsetof(bxcan_regs_t, tx) == 0x180u, "TI0R offset");
_Static_assert(offsetof(bxcan_regs_t, tx[1].TIR) == 0x190u, "TI1R offset");
_Static_assert(offsetof(bxcan_regs_t, tx[2].TDHR) == 0x1ACu, "TDH2R offset");
_Static_assert(offsetof(bxcan_regs_t, rx) == 0x1B0u, "RI0R offset");
_Static_assert(offsetof(bxcan_regs_t, rx[0].RDHR) == 0x1BCu, "RDH0R offset");
_Static_assert(offsetof(bxcan_regs_t, rx[1].RIR) == 0x1C0u, "RI1R offset");
_Static_assert(offsetof(bxcan_regs_t, FMR) == 0x200u, "FMR offset");
_Static_assert(offsetof(bxcan_regs_t, FM1R) == 0x204u, "FM1R offset");
_Static_assert(offsetof(bxcan_regs_t, FS1R) == 0x20Cu, "FS1R offset");
_Static_assert(offsetof(bxcan_regs_t, FFA1R) == 0x214u, "FFA1R offset");
_Static_assert(offsetof(bxcan_regs_t, FA1R) == 0x21Cu, "FA1R offset");
_Static_assert(offsetof(bxcan_regs_t, fb) == 0x240u, "F0R1 offset");
_Static_assert(offsetof(bxcan_regs_t, fb[27].FR2) == 0x31Cu, "F27R2 offset");
_Static_assert(sizeof(bxcan_regs_t) == 0x320u, "bxCAN register block size");

/* ---- bit positions (RM0090 32.9.2 .. 32.9.4) ---- */

/* CAN_MCR */
#define BXCAN_MCR_INRQ (1u << 0)   /* initialization request */
#define BXCAN_MCR_SLEEP (1u << 1)  /* sleep mode request (set after reset) */
#define BXCAN_MCR_TXFP (1u << 2)   /* TX priority by request order, not by identifier */
#define BXCAN_MCR_RFLM (1u << 3)   /* receive FIFO locked against overrun */
#define BXCAN_MCR_NART (1u << 4)   /* no automatic retransmission */
#define BXCAN_MCR_AWUM (1u << 5)   /* automatic wakeup */
#define BXCAN_MCR_ABOM (1u << 6)   /* automatic bus-off management (recovery) */
#define BXCAN_MCR_TTCM (1u << 7)   /* time-triggered communication */
#define BXCAN_MCR_RESET (1u << 15) /* software master reset */
#define BXCAN_MCR_DBF (1u << 16)   /* CAN frozen while the core is halted by a debugger */
/* CAN_MSR */
#define BXCAN_MSR_INAK (1u << 0)  /* initialization acknowledge */
#define BXCAN_MSR_SLAK (1u << 1)  /* sleep acknowledge */
#define BXCAN_MSR_ERRI (1u << 2)  /* error interrupt (rc_w1) */
/* CAN_TSR */
#define BXCAN_TSR_TME0 (1u << 26) /* transmit mailbox k empty: TME0 << k */
#define BXCAN_TSR_TME1 (1u << 27)
#define BXCAN_TSR_TME2 (1u << 28)
/* CAN_RF0R */
#define BXCAN_RF0R_FMP0_MASK 0x3u  /* frames pending in FIFO 0, 0..3 */
#define BXCAN_RF0R_FULL0 (1u << 3) /* FIFO full (rc_w1) */
#define BXCAN_RF0R_FOVR0 (1u << 4) /* FIFO overrun: a frame was lost (rc_w1) */
#define BXCAN_RF0R_RFOM0 (1u << 5) /* release the output mailbox (set by software) */
/* CAN_IER */
#define BXCAN_IER_TMEIE (1u << 0)
#define BXCAN_IER_FMPIE0 (1u << 1) /* FIFO 0 message pending -> CAN1_RX0 interrupt */
#define BXCAN_IER_FFIE0 (1u << 2)
#define BXCAN_IER_FOVIE0 (1u << 3) /* FIFO 0 overrun -> CAN1_RX0 interrupt */
#define BXCAN_IER_EWGIE (1u << 8)
#define BXCAN_IER_EPVIE (1u << 9)
#define BXCAN_IER_BOFIE (1u << 10) /* bus-off -> ERRI -> CAN1_SCE interrupt */
#define BXCAN_IER_LECIE (1u << 11)
#define BXCAN_IER_ERRIE (1u << 15) /* ERRI on any enabled error condition */
/* CAN_ESR */
#define BXCAN_ESR_EWGF (1u << 0) /* error warning: TEC or REC >= 96 */
#define BXCAN_ESR_EPVF (1u << 1) /* error passive: TEC or REC > 127 */
#define BXCAN_ESR_BOFF (1u << 2) /* bus-off: TEC > 255 */
#define BXCAN_ESR_LEC_SHIFT 4u   /* last error code, bits 6:4 */
#define BXCAN_ESR_LEC_MASK (0x7u << BXCAN_ESR_LEC_SHIFT)
#define BXCAN_ESR_TEC_SHIFT 16u  /* transmit error counter, bits 23:16 */
#define BXCAN_ESR_REC_SHIFT 24u  /* receive error counter, bits 31:24 */
/* CAN_BTR */
#define BXCAN_BTR_BRP_SHIFT 0u   /* baud rate prescaler - 1, bits 9:0 */
#define BXCAN_BTR_TS1_SHIFT 16u  /* time segment 1 - 1, bits 19:16 */
#define BXCAN_BTR_TS2_SHIFT 20u  /* time segment 2 - 1, bits 22:20 */
#define BXCAN_BTR_SJW_SHIFT 24u  /* resync jump width - 1, bits 25:24 */
#define BXCAN_BTR_LBKM (1u << 30) /* loop back (bench tests) */
#define BXCAN_BTR_SILM (1u << 31) /* silent */
/* CAN_TIxR / CAN_RIxR */
#define BXCAN_TIR_TXRQ (1u << 0) /* transmit request */
#define BXCAN_IR_RTR (1u << 1)   /* remote frame */
#define BXCAN_IR_IDE (1u << 2)   /* extended identifier */
#define BXCAN_IR_EXID_SHIFT 3u   /* 29-bit identifier, bits 31:3 */
#define BXCAN_IR_STID_SHIFT 21u  /* 11-bit identifier, bits 31:21 */
/* CAN_TDTxR / CAN_RDTxR */
#define BXCAN_DTR_DLC_MASK 0xFu  /* data length code, bits 3:0 */
/* CAN_FMR */
#define BXCAN_FMR_FINIT (1u << 0) /* filter init mode: banks may be changed */
/* a 16-bit filter entry: STID[10:0] in bits 15:5, RTR bit 4, IDE bit 3, EXID[17:15] 2:0 */
#define BXCAN_FILTER16_STID_SHIFT 5u

/*
 * Bit timing for APB1 = 42 MHz (the STM32F405 at 168 MHz, APB1 prescaler 4), 500 kbit/s:
 *   one bit = 42 MHz / 500 kHz = 84 clocks = prescaler x (1 + TS1 + TS2) time quanta.
 *   The bxCAN allows 1 <= TS1 <= 16 and 1 <= TS2 <= 8, so 4..25 quanta per bit; the
 *   divisors of 84 that give that many are 21 (prescaler 4), 14 (6), 12 (7), 7 (12),
 *   6 (14) and 4 (21) quanta. The sample point is (1 + TS1) / (1 + TS1 + TS2); 87.5 %
 *   exactly would need a multiple of 8 quanta, which 84 clocks do not give. The nearest
 *   is 12/14 = 85.7 % (or 6/7): prescaler 6 -> 7 MHz, 14 quanta = 1 sync + TS1 11 + TS2 2,
 *   SJW 1 quantum. Check: 42 MHz / (6 x 14) = 500 000 bit/s exactly.
 *   BTR = (SJW-1) << 24 | (TS2-1) << 20 | (TS1-1) << 16 | (BRP-1)
 *       = 0 << 24 | 1 << 20 | 10 << 16 | 5 = 0x001A0005.
 * bxcan_btr_compute(42000000, 500000, 875, &btr) finds the same value.
 */
#define BXCAN_BTR_42MHZ_500K 0x001A0005u

/*
 * Compute a CAN_BTR value (normal mode, SJW = 1 quantum) for a CAN kernel clock pclk_hz
 * and a bit rate bitrate_bps, with the sample point closest to sample_permille (875 for
 * 87.5 %). Among timings with an exact bit rate and 8..25 quanta per bit, the one whose
 * sample point is nearest wins; on a tie the one with more quanta (finer resync).
 * Returns 0 and *btr; HAL_EINVAL when btr is NULL, an argument is 0, sample_permille is
 * not below 1000, or no prescaler 1..1024 gives the bit rate exactly.
 */
int bxcan_btr_compute(uint32_t pclk_hz, uint32_t bitrate_bps, uint32_t sample_permille,
                      uint32_t *btr);

/* ---- driver instance ---- */

/* RX ring length in frames; a power of two (indices are free-running and masked). At
 * 64 frames it holds 128 ms of a 500 frames/s bus while the main loop is busy. */
#define BXCAN_RX_RING_LEN 64u
_Static_assert((BXCAN_RX_RING_LEN & (BXCAN_RX_RING_LEN - 1u)) == 0u,
               "BXCAN_RX_RING_LEN must be a power of two");

typedef struct {
    /* CAN_BTR value, e.g. BXCAN_BTR_42MHZ_500K (may include LBKM/SILM for bench tests) */
    uint32_t btr;
    /* bound of each mode-change handshake wait, in polls of MSR (> 0) */
    uint32_t timeout_polls;
    /* optional: called once per poll while waiting (a delay, a watchdog kick; the host
     * tests play the hardware here); NULL for none */
    void (*wait_hook)(void *ctx);
    void *hook_ctx;
} bxcan_config_t;

/* Counters since bxcan_init; wrap at 2^32. */
typedef struct {
    uint32_t rx_frames;         /* frames put into the ring */
    uint32_t rx_ring_overruns;  /* frames lost because the ring was full */
    uint32_t rx_fifo_overruns;  /* FOVR0 events: the 3-deep hardware FIFO overflowed
                                   (at least one frame lost each) */
    uint32_t rx_dropped_rtr;    /* remote frames received and dropped */
    uint32_t bus_off_events;    /* transitions into bus-off seen in ESR */
} bxcan_stats_t;

typedef enum {
    BXCAN_ERR_ACTIVE = 0,  /* TEC and REC < 96 */
    BXCAN_ERR_WARNING = 1, /* EWGF: TEC or REC >= 96 */
    BXCAN_ERR_PASSIVE = 2, /* EPVF: TEC or REC > 127 */
    BXCAN_ERR_BUS_OFF = 3, /* BOFF: off the bus; recovers by itself (MCR.ABOM) after
                              128 x 11 recessive bits */
} bxcan_err_state_t;

typedef struct {
    bxcan_err_state_t state;
    uint8_t tec;             /* transmit error counter (ESR bits 23:16) */
    uint8_t rec;             /* receive error counter (ESR bits 31:24) */
    uint8_t lec;             /* last error code 0..7 (ESR bits 6:4; 0 = none, 1 stuff,
                                2 form, 3 ack, 4 bit recessive, 5 bit dominant, 6 CRC) */
    uint32_t bus_off_events; /* as in bxcan_stats_t */
} bxcan_error_t;

/*
 * One controller. Caller-owned (static on the board); all fields are private to the
 * driver. The ring is written only by bxcan_rx0_irq and read only by bxcan_receive
 * (single producer, single consumer on one core: no lock needed).
 */
typedef struct {
    bxcan_regs_t *regs;
    hal_can_frame_t ring[BXCAN_RX_RING_LEN];
    volatile uint32_t ring_head; /* written by the RX interrupt */
    volatile uint32_t ring_tail; /* written by bxcan_receive */
    volatile uint32_t rx_frames;
    volatile uint32_t rx_ring_overruns;
    volatile uint32_t rx_fifo_overruns;
    volatile uint32_t rx_dropped_rtr;
    volatile uint32_t bus_off_events;
    volatile uint8_t bus_off; /* BOFF as last seen, for counting transitions */
} bxcan_t;

/*
 * Initialize the controller at regs and the instance *dev (counters and ring cleared):
 *  1. leave sleep and request initialization (MCR.SLEEP = 0, MCR.INRQ = 1), wait for
 *     MSR.INAK = 1 and MSR.SLAK = 0;
 *  2. MCR = DBF | ABOM (automatic bus-off recovery) | TXFP (frames leave in request
 *     order) | INRQ; automatic retransmission on; FIFO not locked (on overrun the newest
 *     frame replaces the last one); BTR = cfg->btr;
 *  3. enable the FIFO 0 message-pending and overrun interrupts (CAN1_RX0) and the
 *     bus-off error interrupt (CAN1_SCE): IER = FMPIE0 | FOVIE0 | BOFIE | ERRIE;
 *  4. leave initialization (MCR.INRQ = 0) and wait for MSR.INAK = 0 (the controller
 *     has seen 11 recessive bits on the bus).
 * Each wait polls MSR at most cfg->timeout_polls times, calling cfg->wait_hook before
 * each poll after the first. Filters are not touched: call bxcan_set_filters (until then
 * the reset filter configuration applies).
 * Returns 0; HAL_EINVAL (NULL pointer, timeout_polls 0); HAL_EIO when a handshake timed
 * out (the controller is then left in whatever mode it reached; call again to retry).
 */
int bxcan_init(bxcan_t *dev, bxcan_regs_t *regs, const bxcan_config_t *cfg);

/*
 * Accept exactly the standard (11-bit) data frames with the n identifiers ids[0..n-1],
 * all into FIFO 0: identifier-list mode, 16-bit scale, 4 identifiers per bank, banks
 * 0..ceil(n/4)-1. Bank k holds ids[4k] (FR1 bits 15:0), ids[4k+1] (FR1 31:16),
 * ids[4k+2] (FR2 15:0), ids[4k+3] (FR2 31:16), each as id << 5 with RTR = IDE = 0, so
 * remote and extended frames do not match; unused entries of the last bank repeat its
 * last identifier. The other banks of CAN1 (0..13: the reset split FMR.CAN2SB = 14,
 * which is kept) are deactivated; n = 0 receives nothing. Done in filter init mode
 * (FMR.FINIT), allowed while the controller runs.
 * Returns 0; HAL_EINVAL (NULL dev, NULL ids with n > 0, n > 4 x 14 = 56, an identifier
 * > 0x7FF) with the filters unchanged.
 */
#define BXCAN_MAX_FILTER_IDS 56u
int bxcan_set_filters(bxcan_t *dev, const uint32_t *ids, size_t n);

/*
 * The CAN1_RX0 interrupt handler's body: count and clear a FIFO 0 overrun (RF0R.FOVR0),
 * then move the frames pending in FIFO 0 (RF0R.FMP0, at most 3) into the ring, stamped
 * t_us (the board's microsecond clock, as hal_time_us), releasing each mailbox with
 * RF0R.RFOM0. A frame that finds the ring full is dropped and counted
 * (rx_ring_overruns); a remote frame is dropped and counted (rx_dropped_rtr). Frames
 * arriving meanwhile keep FMP0 non-zero and so re-trigger the interrupt: the handler
 * does a bounded amount of work.
 */
void bxcan_rx0_irq(bxcan_t *dev, uint64_t t_us);

/*
 * Take the oldest received frame from the ring into *f. Never blocks.
 * Returns 0; HAL_EAGAIN when the ring is empty; HAL_EINVAL (NULL pointer).
 */
int bxcan_receive(bxcan_t *dev, hal_can_frame_t *f);

/*
 * Put *f into the first empty transmit mailbox (TSR.TME0..2, lowest number first):
 * TDTR = DLC, TDLR/TDHR = data (byte 0 in TDLR bits 7:0), then TIR = identifier
 * (standard: id << 21; extended: id << 3 | IDE) | TXRQ. f->t_us is ignored.
 * Returns 0; HAL_EINVAL (NULL pointer, dlc > 8, identifier out of range); HAL_ENOSPC
 * when all three mailboxes are pending (nothing written; never blocks).
 */
int bxcan_send(bxcan_t *dev, const hal_can_frame_t *f);

/*
 * The CAN1_SCE interrupt handler's body: read ESR (counting a new bus-off) and clear
 * MSR.ERRI. Recovery from bus-off is automatic (MCR.ABOM).
 */
void bxcan_sce_irq(bxcan_t *dev);

/*
 * Report the error state from ESR into *e (also counts a new bus-off, so polling works
 * without the SCE interrupt). Returns 0, HAL_EINVAL (NULL pointer).
 */
int bxcan_error_state(bxcan_t *dev, bxcan_error_t *e);

/* The counters. Returns 0, HAL_EINVAL (NULL pointer). */
int bxcan_stats(const bxcan_t *dev, bxcan_stats_t *s);

/* 1 when the ring holds a frame for bxcan_receive (the main loop checks it with interrupts
 * masked before it sleeps), else 0 (also for NULL). */
int bxcan_rx_pending(const bxcan_t *dev);

#endif /* NAVECU_BXCAN_H */
