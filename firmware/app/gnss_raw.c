/* gnss_raw.c - raw GNSS epoch assembly; see gnss_raw.h. */
#include "gnss_raw.h"

#include <string.h>

void gnss_raw_init(gnss_raw_asm_t *g)
{
    (void)memset(g, 0, sizeof *g);
}

static void start_epoch(gnss_raw_asm_t *g, uint8_t epoch)
{
    (void)memset(g->parts, 0, sizeof g->parts);
    g->epoch = epoch;
    g->open = 1u;
}

gnss_raw_frame_t gnss_raw_frame(gnss_raw_asm_t *g, const rx_input_t *in)
{
    const struct rx_raw_sat *r = &in->u.raw_sat;
    gnss_raw_frame_t result = GNSS_RAW_TAKEN;
    if (g->open == 0u) {
        start_epoch(g, r->epoch);
    } else if (r->epoch != g->epoch) {
        start_epoch(g, r->epoch); /* the previous epoch never closed */
        result = GNSS_RAW_DROPPED;
    } else {
        /* the epoch in assembly goes on */
    }
    const uint8_t slot = (uint8_t)(r->slot % GNSS_RAW_MAX_SATS); /* 4 bits: always < 16 */
    if ((g->parts[slot] & r->part) != 0u) {
        return GNSS_RAW_REPEAT;
    }
    gnss_raw_sat_t *s = &g->sat[slot];
    if (r->part == RX_RAW_PART_RANGE) {
        s->pr_lsb = r->pr_lsb;
        s->system = r->system;
        s->sv_id = r->sv_id;
        s->elevation_deg = r->elevation_deg;
        s->pr_valid = r->pr_valid;
    } else if (r->part == RX_RAW_PART_RATE) {
        s->rr_lsb = r->rr_lsb;
        s->pr_sigma_lsb = r->pr_sigma_lsb;
        s->rr_sigma_lsb = r->rr_sigma_lsb;
        s->cn0_dbhz = r->cn0_dbhz;
        s->rr_valid = r->rr_valid;
    } else {
        int axis = 2;
        if (r->part == RX_RAW_PART_X) {
            axis = 0;
        } else if (r->part == RX_RAW_PART_Y) {
            axis = 1;
        } else {
            /* RX_RAW_PART_Z */
        }
        s->pos_lsb[axis] = r->pos_lsb;
        s->vel_lsb[axis] = r->vel_lsb;
    }
    g->parts[slot] = (uint8_t)(g->parts[slot] | r->part);
    return result;
}

gnss_raw_close_t gnss_raw_close(gnss_raw_asm_t *g, const rx_input_t *in)
{
    const struct rx_raw_epoch *e = &in->u.raw_epoch;
    gnss_raw_close_t c;
    (void)memset(&c, 0, sizeof c);
    if (g->open != 0u && e->epoch != g->epoch) {
        c.mismatch = 1u; /* the satellites in assembly are another epoch's */
        (void)memset(g->parts, 0, sizeof g->parts);
        g->open = 0u;
        return c;
    }
    if (g->open == 0u) {
        (void)memset(g->parts, 0, sizeof g->parts); /* none of this epoch came */
    }
    g->open = 0u;
    if (g->have_tow != 0u && e->tow_ms == g->last_tow_ms) {
        c.repeat = 1u;
        (void)memset(g->parts, 0, sizeof g->parts);
        return c;
    }
    g->last_tow_ms = e->tow_ms;
    g->have_tow = 1u;
    for (uint8_t i = 0u; i < (uint8_t)GNSS_RAW_MAX_SATS; i++) {
        if (i < e->n_meas) {
            if (g->parts[i] == RX_RAW_PARTS_ALL) {
                c.n_sats++;
                c.complete = (uint16_t)(c.complete | (1u << i));
            } else {
                c.incomplete++;
                g->parts[i] = 0u;
            }
        } else if (g->parts[i] != 0u) {
            c.extra++;
            g->parts[i] = 0u;
        } else {
            /* an unused slot */
        }
    }
    /* one satellite in two slots: which is right cannot be told, and fused twice it would
     * weigh double (and outvote the others in the fault exclusion): both dropped */
    uint16_t dup = 0u;
    for (uint8_t i = 0u; i < (uint8_t)GNSS_RAW_MAX_SATS; i++) {
        for (uint8_t j = (uint8_t)(i + 1u); j < (uint8_t)GNSS_RAW_MAX_SATS; j++) {
            const uint16_t both = (uint16_t)((uint16_t)(1u << i) | (uint16_t)(1u << j));
            if ((c.complete & both) == both && g->sat[i].system == g->sat[j].system &&
                g->sat[i].sv_id == g->sat[j].sv_id) {
                dup = (uint16_t)(dup | both);
            }
        }
    }
    c.complete = (uint16_t)(c.complete & (uint16_t)~dup);
    for (; dup != 0u; dup = (uint16_t)(dup & (dup - 1u))) {
        c.duplicate++;
        c.n_sats--;
    }
    c.usable = c.n_sats > 0u ? 1u : 0u;
    return c;
}
