/* vehicle_pair.c - one sample of four wheels from two axles' messages; see vehicle_pair.h. */
#include "vehicle_pair.h"

int vehicle_pair_half(vehicle_pair_t *p, vehicle_axle_t axle, nav_real_t left_mps,
                      nav_real_t right_mps, nav_real_t wheel_mps[4])
{
    const uint8_t mine = (uint8_t)(1u + (unsigned)axle);
    if (p->held == 0u || p->held == mine) {
        p->left_mps = left_mps; /* held, or replacing this axle's older half */
        p->right_mps = right_mps;
        p->held = mine;
        return 0;
    }
    /* the other axle's half is held: the two make one sample */
    const unsigned here = 2u * (unsigned)axle; /* this half's left wheel: FL 0, RL 2 */
    const unsigned there = 2u - here;
    wheel_mps[here] = left_mps;
    wheel_mps[here + 1u] = right_mps;
    wheel_mps[there] = p->left_mps;
    wheel_mps[there + 1u] = p->right_mps;
    p->held = 0u;
    return 1;
}
