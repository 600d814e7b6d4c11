/* dtc.c - the fault memory's status bytes (ISO 14229-1 Annex D); see dtc.h. */
#include "dtc.h"

#include <string.h>

/* the stored byte of a status byte: bits 2..5, pendingDTC as at the end of this cycle */
static uint8_t stored_of(uint8_t st)
{
    uint8_t out = (uint8_t)(st & DTC_STORED_MASK);
    if ((st & DTC_TFTOC) == 0u && (st & DTC_TNCTOC) == 0u) {
        out = (uint8_t)(out & (uint8_t)~DTC_PDTC); /* tested, never failed this cycle */
    }
    return out;
}

static int stored_valid(uint8_t b)
{
    if ((b & (uint8_t)~DTC_STORED_MASK) != 0u) {
        return 0;
    }
    if ((b & (DTC_PDTC | DTC_CDTC)) != 0u && (b & DTC_TFSLC) == 0u) {
        return 0; /* pending or confirmed, yet never failed since the clear */
    }
    if ((b & DTC_TNCSLC) != 0u && (b & DTC_TFSLC) != 0u) {
        return 0; /* failed since the clear, yet never tested since it */
    }
    return 1;
}

static void start_cleared(dtc_t *d, size_t i)
{
    d->status[i] = DTC_STATUS_CLEARED;
    d->stored[i] = stored_of(DTC_STATUS_CLEARED);
    d->pending_at_start[i] = 0u;
    d->fail_start_us[i] = DTC_NO_CONDITION;
}

void dtc_init(dtc_t *d)
{
    (void)memset(d, 0, sizeof *d);
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        start_cleared(d, i);
    }
}

size_t dtc_load(dtc_t *d, const uint8_t *stored, size_t n)
{
    size_t refused = 0u;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        if (stored == NULL || i >= n) {
            start_cleared(d, i);
            continue;
        }
        const uint8_t b = stored[i];
        if (b == DTC_STORED_NONE) {
            start_cleared(d, i); /* never stored: not a refusal */
            continue;
        }
        if (!stored_valid(b)) {
            start_cleared(d, i);
            refused++;
            if (d->load_rejected != UINT32_MAX) {
                d->load_rejected++;
            }
            continue;
        }
        /* a new operation cycle: TF and TFTOC clear, TNCTOC set */
        d->status[i] = (uint8_t)(b | DTC_TNCTOC);
        d->stored[i] = b;
        d->pending_at_start[i] = (b & DTC_PDTC) != 0u ? 1u : 0u;
        d->fail_start_us[i] = DTC_NO_CONDITION;
    }
    return refused;
}

uint32_t dtc_update(dtc_t *d, uint32_t health_flags, uint64_t now_us)
{
    return dtc_update_tested(d, health_flags, UINT32_MAX, now_us);
}

uint32_t dtc_update_tested(dtc_t *d, uint32_t health_flags, uint32_t tested, uint64_t now_us)
{
    uint32_t changed = 0u;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        const dtc_def_t *def = &dtc_table[i];
        uint8_t st = d->status[i];
        if ((health_flags & tested & def->health_mask) == 0u) {
            /* passed, or not tested: a condition lasts while it is tested, and an events
             * one through a pass shorter than DTC_PASS_HOLD_US (on the clock's low 32 bits:
             * time going backwards ends it) */
            if ((def->confirm_ds & DTC_EVENTS) != 0u && d->fail_start_us[i] != DTC_NO_CONDITION &&
                (tested & def->health_mask) != 0u &&
                (uint32_t)now_us - d->last_fail_us[i] < DTC_PASS_HOLD_US) {
                continue;
            }
            d->fail_start_us[i] = DTC_NO_CONDITION;
            if ((tested & def->health_mask) == 0u) {
                continue;
            }
            st = (uint8_t)(st & (uint8_t)~(DTC_TF | DTC_TNCTOC | DTC_TNCSLC));
        } else {
            const uint32_t t_us = (uint32_t)now_us;
            if (d->fail_start_us[i] == DTC_NO_CONDITION) {
                d->fail_start_us[i] = t_us; /* the condition starts */
            }
            d->last_fail_us[i] = t_us;
            /* at most 0x3FFF x 0.1 s = 1.64e9 us, below 2^31: time going backwards (a
             * difference of 2^31 or more) counts as no time (dtc.h) */
            const uint32_t confirm_us = (uint32_t)(def->confirm_ds & DTC_CONFIRM_DS_MASK) * 100000u;
            const uint32_t since_us = t_us - d->fail_start_us[i];
            const uint8_t lasted = since_us < 0x80000000u && since_us >= confirm_us ? 1u : 0u;
            if (lasted == 0u && (def->confirm_ds & DTC_DEBOUNCED) != 0u) {
                continue; /* debounced: not completed yet */
            }
            st = (uint8_t)(st | DTC_TF | DTC_TFTOC | DTC_PDTC | DTC_TFSLC);
            st = (uint8_t)(st & (uint8_t)~(DTC_TNCTOC | DTC_TNCSLC));
            if (lasted != 0u || d->pending_at_start[i] != 0u) {
                st = (uint8_t)(st | DTC_CDTC);
            }
        }
        d->status[i] = st;
        const uint8_t keep = stored_of(st);
        if (keep != d->stored[i]) {
            d->stored[i] = keep;
            changed |= (uint32_t)1u << i;
        }
    }
    return changed;
}

uint32_t dtc_clear_all(dtc_t *d)
{
    uint32_t changed = 0u;
    for (size_t i = 0u; i < (size_t)DTC_N; i++) {
        const uint8_t before = d->stored[i];
        start_cleared(d, i);
        if (d->stored[i] != before) {
            changed |= (uint32_t)1u << i;
        }
    }
    if (d->clears != UINT32_MAX) {
        d->clears++;
    }
    return changed;
}

uint8_t dtc_status(const dtc_t *d, size_t i)
{
    return i < (size_t)DTC_N ? d->status[i] : 0u;
}

uint8_t dtc_stored(const dtc_t *d, size_t i)
{
    return i < (size_t)DTC_N ? d->stored[i] : 0u;
}
