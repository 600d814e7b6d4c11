/* vehicle_counter.c - a car message's rolling counter; see vehicle_counter.h. */
#include "vehicle_counter.h"

int vehicle_counter_step(vehicle_counters_t *c, vehicle_kind_t kind, uint8_t counter,
                         uint16_t modulus)
{
    if ((unsigned)kind == (unsigned)VEHICLE_MSG_NONE || (unsigned)kind >= (unsigned)VEHICLE_MSG_N ||
        modulus < 2u || modulus > 256u || counter >= modulus) {
        return -1;
    }
    const unsigned k = (unsigned)kind - 1u;
    const uint8_t bit = (uint8_t)(1u << k);
    if ((c->seen & bit) == 0u) {
        c->seen = (uint8_t)(c->seen | bit);
        c->last[k] = counter;
        return 1;
    }
    const int step = ((int)counter - (int)c->last[k] + (int)modulus) % (int)modulus;
    if (step == 0) {
        return 0;
    }
    c->last[k] = counter;
    return step;
}
