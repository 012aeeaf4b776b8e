#include "simulated_hand.h"

#include <math.h>

void simulated_hand_init(simulated_hand* hand, const double start[3], double mass, double stiffness) {
    int k;
    for (k = 0; k < 3; ++k) {
        hand->x[k] = hand->target[k] = start[k];
        hand->v[k] = 0.0;
    }
    hand->mass = mass;
    hand->stiffness = stiffness;
    hand->damping = 2.0 * sqrt(stiffness * mass);
}

void simulated_hand_move(simulated_hand* hand, const double target[3], double dt, const double force[3]) {
    int k;
    for (k = 0; k < 3; ++k) {
        const double target_velocity = (target[k] - hand->target[k]) / dt;
        const double f = hand->stiffness * (hand->target[k] - hand->x[k]) +
                         hand->damping * (target_velocity - hand->v[k]) + force[k];
        hand->v[k] += dt * f / hand->mass;
        hand->x[k] += dt * hand->v[k];
        hand->target[k] = target[k];
    }
}
