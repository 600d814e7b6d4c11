/*
 * test_bxcan.c - the STM32F4 bxCAN driver (hal/cortex_m4f/bxcan.c) against a register
 * block in RAM. The test plays the hardware: it loads the reset values of RM0090 32.9,
 * acknowledges mode requests from the driver's wait hook (MSR.INAK follows MCR.INRQ,
 * MSR.SLAK follows MCR.SLEEP), places frames in the FIFO 0 output mailbox with RF0R.FMP0,
 * and sets TSR/ESR as the controller would.
 *
 * A RAM register keeps the last value written: a write of RFOM0 to RF0R therefore reads
 * back as exactly RFOM0 (FMP0 = 0, as the hardware shows once the last frame is
 * released), and rc_w1 clears read back as the bit written.
 *
 * Expected values are written from RM0090's bit positions (32.9.2..32.9.5), not from the
 * driver's macros: STID at TIR/RIR bits 31:21, EXID at 31:3, IDE bit 2, RTR bit 1, TXRQ
 * bit 0; DLC at TDTR/RDTR bits 3:0; data byte 0 at TDLR/RDLR bits 7:0; a 16-bit filter
 * entry holds STID at bits 15:5.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "bxcan.h"

static bxcan_regs_t regs;
static bxcan_t dev;
static unsigned hook_calls;

/* reset values, RM0090 32.9.2..32.9.4 */
static void regs_reset(void)
{
    memset((void *)&regs, 0, sizeof regs);
    regs.MCR = 0x00010002u;  /* DBF, SLEEP */
    regs.MSR = 0x00000C02u;  /* SLAK, SAMP, RX */
    regs.TSR = 0x1C000000u;  /* TME0..2 */
    regs.BTR = 0x01230000u;
    regs.FMR = 0x2A1C0E01u;  /* CAN2SB = 14, FINIT */
    regs.FM1R = 0u;
    regs.FS1R = 0u;
    regs.FFA1R = 0u;
    regs.FA1R = 0u;
}

/* the hardware: acknowledge the requested mode at once */
static void hw_ack(void *ctx)
{
    (void)ctx;
    hook_calls++;
    uint32_t msr = regs.MSR & ~0x3u;
    if ((regs.MCR & 0x1u) != 0u) {
        msr |= 0x1u; /* INAK */
    }
    if ((regs.MCR & 0x2u) != 0u) {
        msr |= 0x2u; /* SLAK */
    }
    regs.MSR = msr;
}

/* hardware that never answers */
static void hw_dead(void *ctx)
{
    (void)ctx;
    hook_calls++;
}

/* hardware that enters initialization but never leaves it (no 11 recessive bits) */
static void hw_stuck_in_init(void *ctx)
{
    (void)ctx;
    hook_calls++;
    regs.MSR = (regs.MSR & ~0x3u) | 0x1u;
}

static int setup(void **state)
{
    (void)state;
    regs_reset();
    memset(&dev, 0, sizeof dev);
    hook_calls = 0;
    bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 100u, hw_ack, NULL};
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), 0);
    hook_calls = 0;
    return 0;
}

/* place one frame in the FIFO 0 output mailbox, FMP0 = 1 */
static void hw_put_rx(uint32_t rir, uint32_t rdtr, uint32_t rdlr, uint32_t rdhr)
{
    regs.rx[0].RIR = rir;
    regs.rx[0].RDTR = rdtr;
    regs.rx[0].RDLR = rdlr;
    regs.rx[0].RDHR = rdhr;
    regs.RF0R = 1u;
}

static bxcan_stats_t stats(void)
{
    bxcan_stats_t s;
    assert_int_equal(bxcan_stats(&dev, &s), 0);
    return s;
}

/* ---- layout and bit timing ---- */

static void test_register_offsets(void **state)
{
    (void)state;
    assert_int_equal(offsetof(bxcan_regs_t, BTR), 0x01C);
    assert_int_equal(offsetof(bxcan_regs_t, tx[0].TIR), 0x180);
    assert_int_equal(offsetof(bxcan_regs_t, tx[2].TIR), 0x1A0);
    assert_int_equal(offsetof(bxcan_regs_t, rx[0].RIR), 0x1B0);
    assert_int_equal(offsetof(bxcan_regs_t, rx[0].RDLR), 0x1B8);
    assert_int_equal(offsetof(bxcan_regs_t, FMR), 0x200);
    assert_int_equal(offsetof(bxcan_regs_t, FA1R), 0x21C);
    assert_int_equal(offsetof(bxcan_regs_t, fb[1].FR1), 0x248);
    assert_int_equal(offsetof(bxcan_regs_t, fb[13].FR2), 0x2AC);
}

/* 42 MHz / 500 kbit/s = 84 clocks = BRP 6 x 14 quanta (1 + TS1 11 + TS2 2), sample
 * point 12/14 = 85.7 %, the nearest to 87.5 % that 84 clocks allow */
static void test_btr_500k_at_42mhz(void **state)
{
    (void)state;
    uint32_t btr = 0;
    assert_int_equal(bxcan_btr_compute(42000000u, 500000u, 875u, &btr), 0);
    assert_int_equal(btr, 0x001A0005u);
    assert_int_equal(BXCAN_BTR_42MHZ_500K, 0x001A0005u);
    uint32_t brp = (btr & 0x3FFu) + 1u;         /* bits 9:0 */
    uint32_t ts1 = ((btr >> 16) & 0xFu) + 1u;   /* bits 19:16 */
    uint32_t ts2 = ((btr >> 20) & 0x7u) + 1u;   /* bits 22:20 */
    uint32_t sjw = ((btr >> 24) & 0x3u) + 1u;   /* bits 25:24 */
    assert_int_equal(brp, 6);
    assert_int_equal(ts1, 11);
    assert_int_equal(ts2, 2);
    assert_int_equal(sjw, 1);
    assert_int_equal(42000000u / (brp * (1u + ts1 + ts2)), 500000u);
    assert_int_equal(1000u * (1u + ts1) / (1u + ts1 + ts2), 857u);

    /* 250 kbit/s: 168 clocks = BRP 21 x 8 quanta (1 + TS1 6 + TS2 1), exactly 87.5 % */
    assert_int_equal(bxcan_btr_compute(42000000u, 250000u, 875u, &btr), 0);
    assert_int_equal(btr, (0u << 20) | (5u << 16) | 20u);
    /* 1 Mbit/s: 42 clocks = BRP 3 x 14 quanta */
    assert_int_equal(bxcan_btr_compute(42000000u, 1000000u, 875u, &btr), 0);
    assert_int_equal(btr, 0x001A0002u);
}

static void test_btr_invalid(void **state)
{
    (void)state;
    uint32_t btr = 0xDEADBEEFu;
    assert_int_equal(bxcan_btr_compute(42000000u, 0u, 875u, &btr), HAL_EINVAL);
    assert_int_equal(bxcan_btr_compute(0u, 500000u, 875u, &btr), HAL_EINVAL);
    assert_int_equal(bxcan_btr_compute(42000000u, 500000u, 1000u, &btr), HAL_EINVAL);
    assert_int_equal(bxcan_btr_compute(42000000u, 500000u, 875u, NULL), HAL_EINVAL);
    /* 42 MHz / 7 Mbit/s = 6 clocks: fewer than 8 quanta at any prescaler */
    assert_int_equal(bxcan_btr_compute(42000000u, 7000000u, 875u, &btr), HAL_EINVAL);
    assert_int_equal(btr, 0xDEADBEEFu);
}

/* ---- initialization ---- */

static void test_init_handshake(void **state)
{
    (void)state;
    regs_reset();
    hook_calls = 0;
    bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 100u, hw_ack, NULL};
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), 0);
    /* one poll misses for each of the two mode changes, then the hook acknowledges */
    assert_int_equal(hook_calls, 2);
    /* DBF bit 16, ABOM bit 6, TXFP bit 2; INRQ (0), SLEEP (1), NART (4), RFLM (3) clear */
    assert_int_equal(regs.MCR, (1u << 16) | (1u << 6) | (1u << 2));
    assert_int_equal(regs.MSR & 0x3u, 0u);
    assert_int_equal(regs.BTR, 0x001A0005u);
    /* FMPIE0 bit 1, FOVIE0 bit 3, BOFIE bit 10, ERRIE bit 15 */
    assert_int_equal(regs.IER, (1u << 1) | (1u << 3) | (1u << 10) | (1u << 15));
    bxcan_stats_t s = stats();
    assert_int_equal(s.rx_frames + s.rx_ring_overruns + s.rx_fifo_overruns +
                         s.rx_dropped_rtr + s.bus_off_events, 0);
}

/* GIVEN a controller that never sets INAK WHEN init runs THEN it gives up after
 * timeout_polls polls with HAL_EIO, leaving INRQ requested and BTR untouched */
static void test_init_enter_timeout(void **state)
{
    (void)state;
    regs_reset();
    hook_calls = 0;
    bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 50u, hw_dead, NULL};
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), HAL_EIO);
    assert_int_equal(hook_calls, 49);
    assert_int_equal(regs.MCR & 0x3u, 0x1u); /* INRQ set, SLEEP cleared */
    assert_int_equal(regs.BTR, 0x01230000u);

    /* without a hook the bound holds too */
    regs_reset();
    cfg.wait_hook = NULL;
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), HAL_EIO);
    cfg.timeout_polls = 0u;
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), HAL_EINVAL);
    assert_int_equal(bxcan_init(NULL, &regs, &cfg), HAL_EINVAL);
}

static void test_init_leave_timeout(void **state)
{
    (void)state;
    regs_reset();
    hook_calls = 0;
    bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 20u, hw_stuck_in_init, NULL};
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), HAL_EIO);
    assert_int_equal(hook_calls, 1u + 19u); /* entering: 1 miss; leaving: all 19 */
    assert_int_equal(regs.BTR, 0x001A0005u);
    assert_int_equal(regs.MCR & 0x1u, 0u); /* leave was requested */
}

/* ---- filters ---- */

static void test_filters_10_ids(void **state)
{
    (void)state;
    /* banks of CAN2 (14..27) and stale settings of CAN1 banks 3..13 */
    regs.FM1R = 0xFFFFC000u | (1u << 5);
    regs.FS1R = 0x0000C000u | (1u << 0) | (1u << 7);
    regs.FFA1R = 0x00004000u | (1u << 1);
    regs.FA1R = 0x0000C000u | (1u << 9);
    const uint32_t ids[10] = {0x100, 0x101, 0x120, 0x121, 0x7FF,
                              0x000, 0x0A5, 0x3E8, 0x555, 0x2AA};
    assert_int_equal(bxcan_set_filters(&dev, ids, 10), 0);

    /* bank 0: 0x100 << 5 = 0x2000, 0x101 << 5 = 0x2020, 0x120 << 5 = 0x2400,
     * 0x121 << 5 = 0x2420; the second identifier of a register in bits 31:16 */
    assert_int_equal(regs.fb[0].FR1, 0x20202000u);
    assert_int_equal(regs.fb[0].FR2, 0x24202400u);
    /* bank 1: 0x7FF << 5 = 0xFFE0, 0, 0x0A5 << 5 = 0x14A0, 0x3E8 << 5 = 0x7D00 */
    assert_int_equal(regs.fb[1].FR1, 0x0000FFE0u);
    assert_int_equal(regs.fb[1].FR2, 0x7D0014A0u);
    /* bank 2: 0x555 << 5 = 0xAAA0, 0x2AA << 5 = 0x5540, then 0x2AA repeated */
    assert_int_equal(regs.fb[2].FR1, 0x5540AAA0u);
    assert_int_equal(regs.fb[2].FR2, 0x55405540u);
    assert_int_equal(regs.fb[3].FR1, 0u);

    /* banks 0..2: list mode, 16-bit scale, FIFO 0, active; other CAN1 banks inactive and
     * back to mask mode; CAN2's banks 14..27 untouched */
    assert_int_equal(regs.FM1R, 0xFFFFC000u | 0x7u);
    assert_int_equal(regs.FS1R, 0x0000C000u);
    assert_int_equal(regs.FFA1R, 0x00004000u);
    assert_int_equal(regs.FA1R, 0x0000C000u | 0x7u);
    /* filter init mode left (FINIT bit 0), CAN2SB (bits 13:8) kept */
    assert_int_equal(regs.FMR, 0x2A1C0E00u);

    /* no identifiers: every CAN1 bank inactive */
    assert_int_equal(bxcan_set_filters(&dev, NULL, 0), 0);
    assert_int_equal(regs.FA1R, 0x0000C000u);
    assert_int_equal(regs.FM1R, 0xFFFFC000u);
}

static void test_filters_invalid(void **state)
{
    (void)state;
    const uint32_t bad[3] = {0x100, 0x800, 0x101};
    static uint32_t many[BXCAN_MAX_FILTER_IDS + 1u];
    assert_int_equal(bxcan_set_filters(&dev, bad, 3), HAL_EINVAL);
    assert_int_equal(bxcan_set_filters(&dev, many, BXCAN_MAX_FILTER_IDS + 1u), HAL_EINVAL);
    assert_int_equal(bxcan_set_filters(&dev, NULL, 1), HAL_EINVAL);
    assert_int_equal(regs.FMR, 0x2A1C0E01u); /* untouched */
    assert_int_equal(regs.FA1R, 0u);
    assert_int_equal(regs.fb[0].FR1, 0u);
    /* 56 identifiers fill banks 0..13 */
    for (uint32_t i = 0; i < BXCAN_MAX_FILTER_IDS; i++) {
        many[i] = 0x200u + i;
    }
    assert_int_equal(bxcan_set_filters(&dev, many, BXCAN_MAX_FILTER_IDS), 0);
    assert_int_equal(regs.FA1R, 0x3FFFu);
    assert_int_equal(regs.fb[13].FR2, ((0x237u << 5) << 16) | (0x236u << 5));
}

/* ---- receive ---- */

static void test_receive_standard(void **state)
{
    (void)state;
    hal_can_frame_t f;
    assert_int_equal(bxcan_receive(&dev, &f), HAL_EAGAIN);
    /* STID 0x123 at bits 31:21; DLC 8, FMI 2 (bits 15:8), TIME 0xBEEF (31:16) */
    hw_put_rx(0x24600000u, 0xBEEF0208u, 0x44332211u, 0x88776655u);
    bxcan_rx0_irq(&dev, 123456789u);
    assert_int_equal(regs.RF0R, 1u << 5); /* RFOM0 written: mailbox released */

    memset(&f, 0xA5, sizeof f);
    assert_int_equal(bxcan_receive(&dev, &f), 0);
    assert_int_equal(f.id, 0x123);
    assert_int_equal(f.extended, 0);
    assert_int_equal(f.dlc, 8);
    const uint8_t want[8] = {0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88};
    assert_memory_equal(f.data, want, 8);
    assert_int_equal(f.t_us, 123456789u);
    assert_int_equal(bxcan_receive(&dev, &f), HAL_EAGAIN);
    assert_int_equal(stats().rx_frames, 1);
}

static void test_receive_extended_short(void **state)
{
    (void)state;
    hal_can_frame_t f;
    /* EXID 0x18FF1234 at bits 31:3 = 0xC7F891A0, IDE bit 2; DLC 3 */
    hw_put_rx(0xC7F891A4u, 0x00000003u, 0x00CCBBAAu, 0u);
    bxcan_rx0_irq(&dev, 7u);
    /* STID 0x7FF, DLC 15 (classic CAN: 8 bytes) */
    hw_put_rx(0xFFE00000u, 0x0000000Fu, 0x03020100u, 0x07060504u);
    bxcan_rx0_irq(&dev, 8u);

    assert_int_equal(bxcan_receive(&dev, &f), 0);
    assert_int_equal(f.id, 0x18FF1234u);
    assert_int_equal(f.extended, 1);
    assert_int_equal(f.dlc, 3);
    assert_int_equal(f.data[0], 0xAA);
    assert_int_equal(f.data[2], 0xCC);
    assert_int_equal(f.t_us, 7u);
    assert_int_equal(bxcan_receive(&dev, &f), 0);
    assert_int_equal(f.id, 0x7FF);
    assert_int_equal(f.dlc, 8);
    assert_int_equal(f.data[7], 7);
    assert_int_equal(f.t_us, 8u);
}

static void test_receive_rtr_dropped(void **state)
{
    (void)state;
    hal_can_frame_t f;
    hw_put_rx(0x24600002u, 0x00000008u, 0u, 0u); /* RTR bit 1 */
    bxcan_rx0_irq(&dev, 1u);
    assert_int_equal(regs.RF0R, 1u << 5);
    assert_int_equal(bxcan_receive(&dev, &f), HAL_EAGAIN);
    assert_int_equal(stats().rx_dropped_rtr, 1);
    assert_int_equal(stats().rx_frames, 0);
}

static void test_irq_without_frames(void **state)
{
    (void)state;
    regs.RF0R = 0u;
    regs.rx[0].RIR = 0x24600000u;
    bxcan_rx0_irq(&dev, 1u);
    assert_int_equal(regs.RF0R, 0u); /* nothing released */
    bxcan_stats_t s = stats();
    assert_int_equal(s.rx_frames + s.rx_fifo_overruns + s.rx_ring_overruns, 0);
}

/* GIVEN a ring of 64 frames that nobody reads WHEN a 65th arrives THEN it is dropped,
 * counted, and its mailbox still released; the 64 come out in order */
static void test_ring_overrun(void **state)
{
    (void)state;
    hal_can_frame_t f;
    for (uint32_t i = 0; i < BXCAN_RX_RING_LEN; i++) {
        hw_put_rx((0x100u + i) << 21, 1u, i, 0u);
        bxcan_rx0_irq(&dev, i);
    }
    assert_int_equal(stats().rx_ring_overruns, 0);
    hw_put_rx(0x7FFu << 21, 1u, 0xEEu, 0u);
    bxcan_rx0_irq(&dev, 999u);
    assert_int_equal(regs.RF0R, 1u << 5);
    assert_int_equal(stats().rx_ring_overruns, 1);
    assert_int_equal(stats().rx_frames, BXCAN_RX_RING_LEN);
    for (uint32_t i = 0; i < BXCAN_RX_RING_LEN; i++) {
        assert_int_equal(bxcan_receive(&dev, &f), 0);
        assert_int_equal(f.id, 0x100u + i);
        assert_int_equal(f.data[0], (uint8_t)i);
        assert_int_equal(f.t_us, i);
    }
    assert_int_equal(bxcan_receive(&dev, &f), HAL_EAGAIN);
    /* room again: the ring wraps around */
    hw_put_rx(0x321u << 21, 0u, 0u, 0u);
    bxcan_rx0_irq(&dev, 1000u);
    assert_int_equal(bxcan_receive(&dev, &f), 0);
    assert_int_equal(f.id, 0x321u);
    assert_int_equal(stats().rx_ring_overruns, 1);
}

static void test_fifo_overrun(void **state)
{
    (void)state;
    hal_can_frame_t f;
    /* FOVR0 (bit 4) with FULL0 (bit 3), frames already taken: only the flag is cleared */
    regs.RF0R = (1u << 4) | (1u << 3);
    bxcan_rx0_irq(&dev, 1u);
    assert_int_equal(stats().rx_fifo_overruns, 1);
    assert_int_equal(regs.RF0R, 1u << 4); /* rc_w1 write of FOVR0 alone */
    /* FOVR0 with a frame pending: counted and the frame received */
    hw_put_rx(0x055u << 21, 2u, 0xBBAAu, 0u);
    regs.RF0R |= (1u << 4);
    bxcan_rx0_irq(&dev, 2u);
    assert_int_equal(stats().rx_fifo_overruns, 2);
    assert_int_equal(regs.RF0R, 1u << 5);
    assert_int_equal(bxcan_receive(&dev, &f), 0);
    assert_int_equal(f.id, 0x055u);
    /* no flag, no count */
    hw_put_rx(0x056u << 21, 0u, 0u, 0u);
    bxcan_rx0_irq(&dev, 3u);
    assert_int_equal(stats().rx_fifo_overruns, 2);
}

/* ---- transmit ---- */

static hal_can_frame_t frame(uint32_t id, uint8_t ext, uint8_t dlc)
{
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = id;
    f.extended = ext;
    f.dlc = dlc;
    for (uint8_t i = 0; i < 8u; i++) {
        f.data[i] = (uint8_t)(i + 1u);
    }
    return f;
}

static void test_send_encodes_mailbox(void **state)
{
    (void)state;
    /* all empty: mailbox 0 */
    hal_can_frame_t f = frame(0x321u, 0u, 5u);
    assert_int_equal(bxcan_send(&dev, &f), 0);
    assert_int_equal(regs.tx[0].TIR, 0x64200001u); /* 0x321 << 21 | TXRQ */
    assert_int_equal(regs.tx[0].TDTR, 5u);
    assert_int_equal(regs.tx[0].TDLR, 0x04030201u);
    assert_int_equal(regs.tx[0].TDHR, 0x08070605u);
    /* mailbox 0 pending (TME0 bit 26 clear): mailbox 1, extended */
    regs.TSR = (1u << 27) | (1u << 28);
    f = frame(0x18FF1234u, 1u, 8u);
    assert_int_equal(bxcan_send(&dev, &f), 0);
    assert_int_equal(regs.tx[1].TIR, 0xC7F891A5u); /* 0x18FF1234 << 3 | IDE | TXRQ */
    assert_int_equal(regs.tx[1].TDTR, 8u);
    assert_int_equal(regs.tx[1].TDHR, 0x08070605u);
    /* only mailbox 2 empty */
    regs.TSR = 1u << 28;
    f = frame(0x000u, 0u, 0u);
    assert_int_equal(bxcan_send(&dev, &f), 0);
    assert_int_equal(regs.tx[2].TIR, 0x00000001u);
    assert_int_equal(regs.tx[2].TDTR, 0u);
    assert_int_equal(regs.tx[0].TIR, 0x64200001u); /* others untouched */
}

static void test_send_all_full(void **state)
{
    (void)state;
    regs.TSR = 0u; /* TME0..2 clear: three requests pending */
    for (unsigned k = 0; k < 3u; k++) {
        regs.tx[k].TIR = 0xA5A5A5A5u;
        regs.tx[k].TDTR = 0xA5A5A5A5u;
    }
    hal_can_frame_t f = frame(0x123u, 0u, 8u);
    assert_int_equal(bxcan_send(&dev, &f), HAL_ENOSPC);
    for (unsigned k = 0; k < 3u; k++) {
        assert_int_equal(regs.tx[k].TIR, 0xA5A5A5A5u);
        assert_int_equal(regs.tx[k].TDTR, 0xA5A5A5A5u);
    }
    /* other TSR bits (RQCP/TXOK of earlier requests, CODE) do not count as empty */
    regs.TSR = 0x03030303u;
    assert_int_equal(bxcan_send(&dev, &f), HAL_ENOSPC);
}

static void test_send_invalid(void **state)
{
    (void)state;
    hal_can_frame_t f = frame(0x123u, 0u, 9u);
    assert_int_equal(bxcan_send(&dev, &f), HAL_EINVAL);
    f = frame(0x800u, 0u, 8u);
    assert_int_equal(bxcan_send(&dev, &f), HAL_EINVAL);
    f = frame(0x20000000u, 1u, 8u);
    assert_int_equal(bxcan_send(&dev, &f), HAL_EINVAL);
    assert_int_equal(bxcan_send(&dev, NULL), HAL_EINVAL);
    assert_int_equal(regs.tx[0].TIR, 0u);
}

/* ---- errors ---- */

static void test_bus_off_counted_and_reported(void **state)
{
    (void)state;
    bxcan_error_t e;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_ACTIVE);
    assert_int_equal(e.bus_off_events, 0);

    /* TEC 0x68 = 104 (bits 23:16), REC 0 (31:24), EWGF bit 0, LEC 5 = bit dominant */
    regs.ESR = (0x68u << 16) | (5u << 4) | 0x1u;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_WARNING);
    assert_int_equal(e.tec, 0x68);
    assert_int_equal(e.lec, 5);
    /* error passive: TEC 0x90, REC 0x81, EPVF bit 1 */
    regs.ESR = (0x81u << 24) | (0x90u << 16) | (3u << 4) | 0x3u;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_PASSIVE);
    assert_int_equal(e.rec, 0x81);
    assert_int_equal(e.lec, 3);

    /* bus-off, BOFF bit 2, signalled through the SCE interrupt */
    regs.ESR = (0xF8u << 16) | (3u << 4) | 0x7u;
    regs.MSR |= 1u << 2; /* ERRI */
    bxcan_sce_irq(&dev);
    assert_int_equal(regs.MSR, 1u << 2); /* rc_w1 write of ERRI alone */
    assert_int_equal(stats().bus_off_events, 1);
    regs.MSR &= ~(1u << 2); /* the hardware's rc_w1: ERRI cleared */
    /* the handler run again in the same bus-off (its clear late): not a new event */
    bxcan_sce_irq(&dev);
    assert_int_equal(stats().bus_off_events, 1);
    /* the same bus-off polled again is not a new event */
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_BUS_OFF);
    assert_int_equal(e.tec, 0xF8);
    assert_int_equal(e.bus_off_events, 1);
    /* recovery (MCR.ABOM stays set), then a second bus-off seen by polling alone */
    assert_int_equal(regs.MCR & (1u << 6), 1u << 6);
    regs.ESR = 0u;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_ACTIVE);
    assert_int_equal(e.bus_off_events, 1);
    regs.ESR = 0x7u;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_BUS_OFF);
    assert_int_equal(e.bus_off_events, 2);
    assert_int_equal(stats().bus_off_events, 2);
    assert_int_equal(bxcan_error_state(&dev, NULL), HAL_EINVAL);
}

/* As on the ECU, where nothing polls: bus-offs signalled by the SCE interrupt alone, each
 * recovered silently (MCR.ABOM clears BOFF, no interrupt): every one is counted. */
static void test_bus_offs_by_interrupt_alone(void **state)
{
    (void)state;
    for (uint32_t k = 1u; k <= 3u; k++) {
        regs.ESR = (0xF8u << 16) | 0x7u; /* BOFF */
        regs.MSR |= 1u << 2;             /* ERRI */
        bxcan_sce_irq(&dev);
        assert_int_equal(stats().bus_off_events, k);
        regs.MSR &= ~(1u << 2); /* rc_w1 */
        regs.ESR = 0u;          /* recovered: no interrupt, no poll */
    }
    /* an interrupt served late, after the recovery (a flash erase stalls the CPU for up to
     * 500 ms, the recovery takes 3 ms): BOFF clear, ERRI still says a bus-off began */
    regs.MSR |= 1u << 2;
    bxcan_sce_irq(&dev);
    assert_int_equal(stats().bus_off_events, 4);
    bxcan_error_t e;
    assert_int_equal(bxcan_error_state(&dev, &e), 0);
    assert_int_equal(e.state, BXCAN_ERR_ACTIVE);
    assert_int_equal(e.bus_off_events, 4); /* the poll after it counts nothing more */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_register_offsets),
        cmocka_unit_test(test_btr_500k_at_42mhz),
        cmocka_unit_test(test_btr_invalid),
        cmocka_unit_test(test_init_handshake),
        cmocka_unit_test(test_init_enter_timeout),
        cmocka_unit_test(test_init_leave_timeout),
        cmocka_unit_test_setup(test_filters_10_ids, setup),
        cmocka_unit_test_setup(test_filters_invalid, setup),
        cmocka_unit_test_setup(test_receive_standard, setup),
        cmocka_unit_test_setup(test_receive_extended_short, setup),
        cmocka_unit_test_setup(test_receive_rtr_dropped, setup),
        cmocka_unit_test_setup(test_irq_without_frames, setup),
        cmocka_unit_test_setup(test_ring_overrun, setup),
        cmocka_unit_test_setup(test_fifo_overrun, setup),
        cmocka_unit_test_setup(test_send_encodes_mailbox, setup),
        cmocka_unit_test_setup(test_send_all_full, setup),
        cmocka_unit_test_setup(test_send_invalid, setup),
        cmocka_unit_test_setup(test_bus_off_counted_and_reported, setup),
        cmocka_unit_test_setup(test_bus_offs_by_interrupt_alone, setup),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
