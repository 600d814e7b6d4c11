/*
 * bxcan.c - register-level STM32F4 bxCAN driver (bxcan.h). Register and bit references
 * are to RM0090 section 32.
 */
#include "bxcan.h"

#include <stdatomic.h>

#define BXCAN_CAN1_BANKS 14u /* banks 0..13 belong to CAN1 at the reset FMR.CAN2SB */
#define BXCAN_STD_ID_MAX 0x7FFu
#define BXCAN_EXT_ID_MAX 0x1FFFFFFFu

/* Poll MSR until (MSR & mask) == want, at most cfg->timeout_polls times. */
static int wait_msr(const bxcan_t *dev, const bxcan_config_t *cfg, uint32_t mask,
                    uint32_t want)
{
    for (uint32_t i = 0; i < cfg->timeout_polls; i++) {
        if (i > 0u && cfg->wait_hook != NULL) {
            cfg->wait_hook(cfg->hook_ctx);
        }
        if ((dev->regs->MSR & mask) == want) {
            return 0;
        }
    }
    return HAL_EIO;
}

int bxcan_btr_compute(uint32_t pclk_hz, uint32_t bitrate_bps, uint32_t sample_permille,
                      uint32_t *btr)
{
    if (btr == NULL || pclk_hz == 0u || bitrate_bps == 0u || sample_permille == 0u ||
        sample_permille >= 1000u) {
        return HAL_EINVAL;
    }
    /* the bit must be a whole number of kernel clocks: prescaler x quanta */
    if (pclk_hz % bitrate_bps != 0u) {
        return HAL_EINVAL;
    }
    uint32_t clocks_per_bit = pclk_hz / bitrate_bps;
    uint32_t want_ppm = sample_permille * 1000u;
    uint32_t best_err = UINT32_MAX;
    uint32_t best = 0;
    for (uint32_t brp = 1; brp <= 1024u; brp++) {
        if (clocks_per_bit % brp != 0u) {
            continue;
        }
        uint32_t ntq = clocks_per_bit / brp;
        if (ntq < 8u || ntq > 25u) {
            continue;
        }
        for (uint32_t ts2 = 1; ts2 <= 8u; ts2++) {
            if (ntq < ts2 + 2u) {
                break;
            }
            uint32_t ts1 = ntq - 1u - ts2;
            if (ts1 > 16u) {
                continue;
            }
            /* sample point in millionths against the target, both as integers */
            uint32_t sp_ppm = (1u + ts1) * 1000000u / ntq;
            uint32_t err = sp_ppm > want_ppm ? sp_ppm - want_ppm : want_ppm - sp_ppm;
            /* brp rises, so the first of equal errors has the most quanta */
            if (err < best_err) {
                best_err = err;
                best = ((ts2 - 1u) << BXCAN_BTR_TS2_SHIFT) |
                       ((ts1 - 1u) << BXCAN_BTR_TS1_SHIFT) |
                       ((brp - 1u) << BXCAN_BTR_BRP_SHIFT);
            }
        }
    }
    if (best_err == UINT32_MAX) {
        return HAL_EINVAL;
    }
    *btr = best;
    return 0;
}

int bxcan_init(bxcan_t *dev, bxcan_regs_t *regs, const bxcan_config_t *cfg)
{
    if (dev == NULL || regs == NULL || cfg == NULL || cfg->timeout_polls == 0u) {
        return HAL_EINVAL;
    }
    dev->regs = regs;
    dev->ring_head = 0;
    dev->ring_tail = 0;
    dev->rx_frames = 0;
    dev->rx_ring_overruns = 0;
    dev->rx_fifo_overruns = 0;
    dev->rx_dropped_rtr = 0;
    dev->bus_off_events = 0;
    dev->bus_off = 0;

    /* after reset the controller sleeps: wake it and enter initialization mode */
    regs->MCR = (regs->MCR & ~BXCAN_MCR_SLEEP) | BXCAN_MCR_INRQ;
    if (wait_msr(dev, cfg, BXCAN_MSR_INAK | BXCAN_MSR_SLAK, BXCAN_MSR_INAK) != 0) {
        return HAL_EIO;
    }
    /* BTR is writable only in initialization mode */
    regs->MCR = BXCAN_MCR_DBF | BXCAN_MCR_ABOM | BXCAN_MCR_TXFP | BXCAN_MCR_INRQ;
    regs->BTR = cfg->btr;
    regs->IER = BXCAN_IER_FMPIE0 | BXCAN_IER_FOVIE0 | BXCAN_IER_BOFIE | BXCAN_IER_ERRIE;

    regs->MCR = BXCAN_MCR_DBF | BXCAN_MCR_ABOM | BXCAN_MCR_TXFP;
    if (wait_msr(dev, cfg, BXCAN_MSR_INAK, 0u) != 0) {
        return HAL_EIO;
    }
    return 0;
}

static uint32_t filter16(uint32_t id)
{
    return id << BXCAN_FILTER16_STID_SHIFT; /* RTR = 0, IDE = 0, EXID[17:15] = 0 */
}

int bxcan_set_filters(bxcan_t *dev, const uint32_t *ids, size_t n)
{
    if (dev == NULL || dev->regs == NULL || (ids == NULL && n > 0u) ||
        n > BXCAN_MAX_FILTER_IDS) {
        return HAL_EINVAL;
    }
    for (size_t i = 0; i < n; i++) {
        if (ids[i] > BXCAN_STD_ID_MAX) {
            return HAL_EINVAL;
        }
    }
    bxcan_regs_t *r = dev->regs;
    uint32_t n_banks = (uint32_t)((n + 3u) / 4u);
    uint32_t can1_mask = (1u << BXCAN_CAN1_BANKS) - 1u;
    uint32_t used_mask = (1u << n_banks) - 1u;

    r->FMR |= BXCAN_FMR_FINIT;
    /* a bank may only be changed while inactive */
    r->FA1R &= ~can1_mask;
    for (uint32_t b = 0; b < n_banks; b++) {
        uint32_t e[4];
        for (uint32_t k = 0; k < 4u; k++) {
            size_t i = (size_t)(b * 4u + k);
            e[k] = filter16(ids[i < n ? i : n - 1u]);
        }
        r->fb[b].FR1 = e[0] | (e[1] << 16);
        r->fb[b].FR2 = e[2] | (e[3] << 16);
    }
    r->FM1R = (r->FM1R & ~can1_mask) | used_mask;  /* identifier list */
    r->FS1R &= ~can1_mask;                         /* dual 16-bit scale */
    r->FFA1R &= ~can1_mask;                        /* FIFO 0 */
    r->FA1R = (r->FA1R & ~can1_mask) | used_mask;
    r->FMR &= ~BXCAN_FMR_FINIT;
    return 0;
}

static void read_rx_mailbox(const bxcan_rx_mailbox_t *mb, hal_can_frame_t *f,
                            uint32_t rir, uint64_t t_us)
{
    uint32_t rdtr = mb->RDTR;
    uint32_t lo = mb->RDLR;
    uint32_t hi = mb->RDHR;
    if ((rir & BXCAN_IR_IDE) != 0u) {
        f->id = rir >> BXCAN_IR_EXID_SHIFT;
        f->extended = 1u;
    } else {
        f->id = rir >> BXCAN_IR_STID_SHIFT;
        f->extended = 0u;
    }
    uint8_t dlc = (uint8_t)(rdtr & BXCAN_DTR_DLC_MASK);
    /* a DLC of 9..15 still means 8 data bytes in classic CAN */
    f->dlc = dlc > 8u ? 8u : dlc;
    for (unsigned k = 0; k < 4u; k++) {
        f->data[k] = (uint8_t)(lo >> (8u * k));
        f->data[4u + k] = (uint8_t)(hi >> (8u * k));
    }
    f->t_us = t_us;
}

void bxcan_rx0_irq(bxcan_t *dev, uint64_t t_us)
{
    bxcan_regs_t *r = dev->regs;
    uint32_t rf0r = r->RF0R;
    if ((rf0r & BXCAN_RF0R_FOVR0) != 0u) {
        dev->rx_fifo_overruns++;
        r->RF0R = BXCAN_RF0R_FOVR0; /* rc_w1: only this flag is cleared */
    }
    uint32_t pending = rf0r & BXCAN_RF0R_FMP0_MASK;
    for (uint32_t i = 0; i < pending; i++) {
        const bxcan_rx_mailbox_t *mb = &r->rx[0];
        uint32_t rir = mb->RIR;
        if ((rir & BXCAN_IR_RTR) != 0u) {
            dev->rx_dropped_rtr++;
        } else if (dev->ring_head - dev->ring_tail >= BXCAN_RX_RING_LEN) {
            dev->rx_ring_overruns++;
        } else {
            uint32_t head = dev->ring_head;
            read_rx_mailbox(mb, &dev->ring[head & (BXCAN_RX_RING_LEN - 1u)], rir, t_us);
            /* the frame is complete before the consumer can see the new head */
            atomic_signal_fence(memory_order_release);
            dev->ring_head = head + 1u;
            dev->rx_frames++;
        }
        r->RF0R = BXCAN_RF0R_RFOM0;
    }
}

int bxcan_receive(bxcan_t *dev, hal_can_frame_t *f)
{
    if (dev == NULL || f == NULL) {
        return HAL_EINVAL;
    }
    uint32_t tail = dev->ring_tail;
    if (dev->ring_head == tail) {
        return HAL_EAGAIN;
    }
    atomic_signal_fence(memory_order_acquire);
    *f = dev->ring[tail & (BXCAN_RX_RING_LEN - 1u)];
    /* the slot is copied out before the producer may reuse it */
    atomic_signal_fence(memory_order_release);
    dev->ring_tail = tail + 1u;
    return 0;
}

int bxcan_send(bxcan_t *dev, const hal_can_frame_t *f)
{
    if (dev == NULL || dev->regs == NULL || f == NULL || f->dlc > 8u ||
        f->id > (f->extended ? BXCAN_EXT_ID_MAX : BXCAN_STD_ID_MAX)) {
        return HAL_EINVAL;
    }
    bxcan_regs_t *r = dev->regs;
    uint32_t tsr = r->TSR;
    unsigned k = 0;
    while (k < 3u && (tsr & (BXCAN_TSR_TME0 << k)) == 0u) {
        k++;
    }
    if (k == 3u) {
        return HAL_ENOSPC;
    }
    bxcan_tx_mailbox_t *mb = &r->tx[k];
    uint32_t lo = 0;
    uint32_t hi = 0;
    for (unsigned i = 0; i < 4u; i++) {
        lo |= (uint32_t)f->data[i] << (8u * i);
        hi |= (uint32_t)f->data[4u + i] << (8u * i);
    }
    mb->TDTR = f->dlc;
    mb->TDLR = lo;
    mb->TDHR = hi;
    uint32_t tir = f->extended ? ((f->id << BXCAN_IR_EXID_SHIFT) | BXCAN_IR_IDE)
                               : (f->id << BXCAN_IR_STID_SHIFT);
    /* TXRQ last, in the same write as the identifier: the mailbox is complete */
    mb->TIR = tir | BXCAN_TIR_TXRQ;
    return 0;
}

/* Read ESR, count a transition into bus-off; returns the ESR value. A poll sees a bus-off
 * end only if it reads ESR after the recovery (MCR.ABOM clears BOFF without an interrupt),
 * so the interrupt does not rely on the latch (bxcan_sce_irq). */
static uint32_t poll_esr(bxcan_t *dev)
{
    uint32_t esr = dev->regs->ESR;
    uint8_t boff = (esr & BXCAN_ESR_BOFF) != 0u ? 1u : 0u;
    if (boff != 0u && dev->bus_off == 0u) {
        dev->bus_off_events++;
    }
    dev->bus_off = boff;
    return esr;
}

void bxcan_sce_irq(bxcan_t *dev)
{
    /* With only BOFIE of the error interrupts enabled, ERRI is set when BOFF is set: a
     * bus-off began. Counted from ERRI, not from BOFF now (reviews): the latch of a poll
     * that nothing on the ECU runs missed every bus-off after the first; BOFF is already
     * clear when the interrupt comes after the recovery (3 ms at 500 kbit/s, shorter than
     * a flash erase's stall); and a run of the handler before its clear reached the
     * peripheral finds ERRI clear the second time (the clear is read back). */
    volatile bxcan_regs_t *regs = dev->regs;
    if ((regs->MSR & BXCAN_MSR_ERRI) != 0u) {
        dev->bus_off_events++;
        regs->MSR = BXCAN_MSR_ERRI; /* rc_w1: only ERRI is cleared */
        (void)regs->MSR;            /* the write done before the return */
    }
    dev->bus_off = (regs->ESR & BXCAN_ESR_BOFF) != 0u ? 1u : 0u; /* a poll's latch */
}

int bxcan_error_state(bxcan_t *dev, bxcan_error_t *e)
{
    if (dev == NULL || dev->regs == NULL || e == NULL) {
        return HAL_EINVAL;
    }
    uint32_t esr = poll_esr(dev);
    if ((esr & BXCAN_ESR_BOFF) != 0u) {
        e->state = BXCAN_ERR_BUS_OFF;
    } else if ((esr & BXCAN_ESR_EPVF) != 0u) {
        e->state = BXCAN_ERR_PASSIVE;
    } else if ((esr & BXCAN_ESR_EWGF) != 0u) {
        e->state = BXCAN_ERR_WARNING;
    } else {
        e->state = BXCAN_ERR_ACTIVE;
    }
    e->tec = (uint8_t)(esr >> BXCAN_ESR_TEC_SHIFT);
    e->rec = (uint8_t)(esr >> BXCAN_ESR_REC_SHIFT);
    e->lec = (uint8_t)((esr & BXCAN_ESR_LEC_MASK) >> BXCAN_ESR_LEC_SHIFT);
    e->bus_off_events = dev->bus_off_events;
    return 0;
}

int bxcan_stats(const bxcan_t *dev, bxcan_stats_t *s)
{
    if (dev == NULL || s == NULL) {
        return HAL_EINVAL;
    }
    s->rx_frames = dev->rx_frames;
    s->rx_ring_overruns = dev->rx_ring_overruns;
    s->rx_fifo_overruns = dev->rx_fifo_overruns;
    s->rx_dropped_rtr = dev->rx_dropped_rtr;
    s->bus_off_events = dev->bus_off_events;
    return 0;
}

int bxcan_rx_pending(const bxcan_t *dev)
{
    return dev != NULL && dev->ring_head != dev->ring_tail;
}
