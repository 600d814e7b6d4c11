/*
 * test_bxcan_profile.c - the ECU's receive filters for a vehicle profile: the identifiers
 * the application receives on the 2017 RAV4 (its profile, vehicles/toyota_rav4_2017.toml)
 * programmed into the bxCAN filter banks by the driver, against a register block in RAM.
 * Built with the RAV4's generated vehicle layer (build/vehicle/toyota_rav4_2017/).
 *
 * GIVEN the RAV4 profile's identifiers (navecu's inputs, GNSS_Height moved to 0x124, and
 * GNSS_Time 0x125, the car's WHEEL_SPEEDS 0x0AA, GEAR_PACKET 0x3BC, KINEMATICS 0x024)
 * WHEN the board sets the filters from app_rx_ids as boards/stm32f405/main.c does
 * THEN the banks in 16-bit list mode hold exactly those identifiers, so the radar bus's
 * 0x123 and every other frame of the car are kept out in hardware.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "app.h"
#include "bxcan.h"
#include "vehicle.h"

static bxcan_regs_t regs;
static bxcan_t dev;

static void hw_ack(void *ctx)
{
    (void)ctx;
    uint32_t msr = regs.MSR & ~0x3u;
    msr |= (regs.MCR & 0x1u) != 0u ? 0x1u : 0u;
    msr |= (regs.MCR & 0x2u) != 0u ? 0x2u : 0u;
    regs.MSR = msr;
}

/* the standard identifiers the active 16-bit list-mode banks of CAN1 (0..13) accept */
static size_t accepted(uint32_t *out, size_t max)
{
    size_t n = 0u;
    for (unsigned b = 0u; b < 14u; b++) {
        if ((regs.FA1R & (1u << b)) == 0u) {
            continue;
        }
        assert_true((regs.FM1R & (1u << b)) != 0u);  /* list mode */
        assert_true((regs.FS1R & (1u << b)) == 0u);  /* 16-bit scale */
        const uint32_t r[2] = {regs.fb[b].FR1, regs.fb[b].FR2};
        for (int k = 0; k < 4; k++) {
            const uint32_t id = ((r[k / 2] >> (16u * (unsigned)(k % 2))) & 0xFFFFu) >> 5;
            int dup = 0;
            for (size_t j = 0u; j < n; j++) {
                dup |= out[j] == id;
            }
            if (!dup && n < max) {
                out[n++] = id;
            }
        }
    }
    return n;
}

static int has(const uint32_t *ids, size_t n, uint32_t id)
{
    for (size_t i = 0u; i < n; i++) {
        if (ids[i] == id) {
            return 1;
        }
    }
    return 0;
}

static void test_rav4_filter_banks(void **state)
{
    (void)state;
    assert_string_equal(vehicle_profile.name, "toyota_rav4_2017");
    memset((void *)&regs, 0, sizeof regs);
    regs.MCR = 0x00010002u;
    regs.MSR = 0x00000C02u;
    regs.TSR = 0x1C000000u;
    regs.FMR = 0x2A1C0E01u;
    const bxcan_config_t cfg = {BXCAN_BTR_42MHZ_500K, 100u, hw_ack, NULL};
    assert_int_equal(bxcan_init(&dev, &regs, &cfg), 0);

    const app_config_t acfg = app_default_config();
    uint32_t ids[32];
    const size_t n = app_rx_ids(acfg.can_ids, ids, 32u);
    assert_int_equal(bxcan_set_filters(&dev, ids, n), 0);

    static const uint32_t expected[] = {0x100u, 0x101u, 0x102u, 0x110u, 0x120u, 0x121u, 0x122u, 0x124u,
                                        0x125u, 0x131u, 0x132u, 0x133u, 0x134u, 0x135u, 0x136u,
                                        0x200u, 0x201u, 0x202u, 0x0AAu, 0x3BCu, 0x024u};
    const size_t n_exp = sizeof expected / sizeof expected[0];
    uint32_t got[64];
    const size_t n_got = accepted(got, 64u);
    assert_int_equal(n_got, n_exp);
    for (size_t i = 0u; i < n_exp; i++) {
        assert_true(has(got, n_got, expected[i]));
    }
    /* the radar bus's 0x123, navecu's own outputs, and a busy powertrain frame stay out */
    assert_false(has(got, n_got, 0x123u));
    assert_false(has(got, n_got, 0x300u));
    assert_false(has(got, n_got, 0x025u)); /* STEER_ANGLE_SENSOR, 83 Hz */
    /* ceil(21 / 4) banks in use, the rest inactive */
    assert_int_equal(regs.FA1R & 0x3FFFu, 0x3Fu);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rav4_filter_banks),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
