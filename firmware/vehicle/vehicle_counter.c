/* vehicle_counter.c - a car message's rolling counter; see vehicle_counter.h. */
#include "vehicle_counter.h"

int vehicle_counter_step(vehicle_counters_t *c, vehicle_kind_t kind, uint8_t counter,
                         uint16_t modulus)
{
    const unsigned k = (unsigned)kind - 1u; /* kind NONE wraps to a large k */
    if (k >= (unsigned)VEHICLE_MSG_N - 1u || modulus < 2u || modulus > 256u ||
        counter >= modulus) {
        return -1;
    }
    const unsigned last1 = c->last[k]; /* the last counter + 1, 0 for none yet */
    /* unsigned: modulo a power of two (the usual modulus) is a mask */
    const unsigned step = last1 != 0u ? ((unsigned)counter + 1u + modulus - last1) % modulus : 1u;
    if (step != 0u) {
        const unsigned next1 = (unsigned)counter + 1u;
        c->last[k] = (uint16_t)next1;
    }
    return (int)step;
}
